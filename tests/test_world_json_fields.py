"""A world.json's plain fields of the wrong kind (``sim.world._check_plain_fields``): ``seed`` beyond a
world's 32 bits, ``name`` that is no text, ``corners`` rows that are no corner. Each was taken: the
400-digit seed kept and written again into simulate's world.json and drawn in map.png's title, a
list as name drawn as "['x']", corners holding "x" read, exit 0 (by ``simulate --world``,
``compare`` and ``slam`` of a simulate folder)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from lms200 import InputError, LmsbenchError
from sim import World, make_world

CORNER_RULE = ("a corner must be a list of x, y (m), angle_rad (finite numbers) and convex (true or false), as "
               "World.to_json writes it")


@pytest.fixture(scope="module")
def world_dict() -> dict:
    return make_world("office", seed=0).to_dict()


@pytest.mark.parametrize("change, message", [
    ({"seed": int("9" * 400)}, "seed: must be a whole number >= 0 and at most 2^64 - 1 (64 bits), "
                               "got 9999999999999999999999999999999999999999...99999999 (400 characters)"),
    ({"seed": 2**64}, "seed: must be a whole number >= 0 and at most 2^64 - 1 (64 bits), got 18446744073709551616"),
    ({"seed": -1}, "seed: must be a whole number >= 0, got -1"),
    ({"name": ["x"]}, "name: must be text (the world's name), got ['x']"),
    ({"corners": "x"}, f"corners: must be a list of corners ({CORNER_RULE}), got 'x'"),
    ({"corners": [[1.0, 2.0, 1.5, True], "x"]}, f"corners: corner 1 is 'x': {CORNER_RULE}"),
    ({"corners": [[1.0, 2.0]]}, f"corners: corner 0 is [1.0, 2.0]: {CORNER_RULE}"),
    ({"corners": [[1.0, 2.0, 1.5, 1]]}, f"corners: corner 0 is [1.0, 2.0, 1.5, 1]: {CORNER_RULE}"),
    ({"corners": [[1.0, int("9" * 400), 1.5, True]]},
     "corners: corner 0 is [1.0, " + "9" * 34 + "...5, True] (418 characters): " + CORNER_RULE),
])
def test_simulate_refuses_a_field_of_the_wrong_kind_naming_the_file_and_field(tmp_path: Path, world_dict: dict,
                                                                               change: dict, message: str,
                                                                               capsys: pytest.CaptureFixture[str]) -> None:
    from experiments.cli import main

    path = tmp_path / "w.json"
    path.write_text(json.dumps({**world_dict, **change}))
    with pytest.raises(LmsbenchError) as info:
        World.from_json(path)
    assert str(info.value) == f"{path}: not a world.json ({message})"
    out = tmp_path / "run"
    assert main(["simulate", "--world", str(path), "--duration", "0.1", "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"lmsbench simulate: error: {path}: not a world.json ({message})"]
    assert not out.exists() or not any(out.iterdir())


def test_slam_reads_a_simulate_folders_world_json_the_same_way(tmp_path: Path, world_dict: dict) -> None:
    """slam's reader of a simulate folder (its walls score the map) took corners holding "x"."""
    from experiments.slamrun import load_input
    from lms200 import Record, write_log

    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "world.json").write_text(json.dumps({**world_dict, "corners": ["x"]}))
    from sim import simulate_records

    write_log(folder / "scans.clf", [Record(r.scan) for r in simulate_records("office", seed=0, duration=0.2, rate_hz=10)])
    with pytest.raises(LmsbenchError) as info:
        load_input(folder)
    assert str(info.value) == f"{folder / 'world.json'}: not a world.json (corners: corner 0 is 'x': {CORNER_RULE})"


def test_what_a_world_writes_reads_back(world_dict: dict) -> None:
    """The largest seed, a world's own corners and a walls-only file (no corners, seed, name) read. A
    world made with seed 2^40 (simulate --config took it) wrote a world.json its reader refused (32 bits):
    both now take the simulator's one rule, lms200.finite.check_seed's 64 bits."""
    text = json.dumps({**world_dict, "seed": 2**64 - 1})
    world = World.from_json("w.json", data=text.encode())
    assert world.seed == 2**64 - 1 and world.to_dict()["corners"] == world_dict["corners"]
    big = make_world("office", seed=2**40)
    assert World.from_json("w.json", data=json.dumps(big.to_dict()).encode()).seed == 2**40
    with pytest.raises(InputError, match=r"^seed: must be a whole number >= 0 and at most 2\^64 - 1"):
        make_world("office", seed=2**64)
    walls_only = {"walls": [[0, 0, 0, 4], [0, 4, 4, 4], [4, 4, 4, 0], [4, 0, 0, 0]], "route_nodes": [[2, 2]]}
    rebuilt = World.from_json("w.json", data=json.dumps(walls_only).encode())
    assert (rebuilt.name, rebuilt.seed, len(rebuilt.walls) > 0) == ("w", 0, True)
