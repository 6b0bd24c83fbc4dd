"""A simulate folder's world.json as slam and compare read it (a fuzzing round): nested too deeply for
``json`` (slam's internal RecursionError), larger than any world (slam read 3 GB whole: MemoryError),
and a pipe or a device in its place (compare dropped the truth and compared the scans as a log,
exit 0). Each is one line naming the file, exit 2, before any work."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from sim_folder import write_sim_folder


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    from sim import simulate_records

    return write_sim_folder(tmp_path_factory.mktemp("sim"), simulate_records("office", seed=0, duration=1.0,
                                                                              rate_hz=3.0), world_seed=0)


def _with_world(folder: Path, tmp_path: Path, make) -> Path:  # noqa: ANN001 - make(world_path)
    out = tmp_path / "run"
    out.mkdir()
    for name in ("scans.clf", "groundtruth.tum"):
        (out / name).write_bytes((folder / name).read_bytes())
    make(out / "world.json")
    return out


def test_slam_refuses_a_world_json_nested_too_deeply(folder, tmp_path, capsys) -> None:
    from experiments.cli import main

    run = _with_world(folder, tmp_path, lambda p: p.write_text("[" * 100_000 + "]" * 100_000))
    assert main(["slam", str(run), "--out", str(tmp_path / "out"), "--quiet"]) == 2  # old: 1, RecursionError
    assert capsys.readouterr().err == (f"lmsbench slam: error: {run / 'world.json'}: not a world.json (nested too "
                                       "deeply to parse)\n")


def test_slam_refuses_a_world_json_beyond_its_bound_unread(folder, tmp_path, capsys) -> None:
    from experiments.cli import main
    from sim.world import MAX_WORLD_JSON_BYTES

    def sparse(p: Path) -> None:
        with p.open("wb") as fh:
            fh.truncate(MAX_WORLD_JSON_BYTES + 1)

    run = _with_world(folder, tmp_path, sparse)
    assert main(["slam", str(run), "--out", str(tmp_path / "out"), "--quiet"]) == 2  # old: read whole (3 GB: MemoryError)
    assert capsys.readouterr().err == (f"lmsbench slam: error: {run / 'world.json'}: 33,554,433 bytes, more than the "
                                       "33,554,432 a world.json may hold (refused unread; the mit world's is 0.5 MB)\n")


@pytest.mark.parametrize("kind", ["fifo", "dev_zero"])
def test_compare_refuses_a_world_json_that_is_no_regular_file(folder, tmp_path, capsys, kind) -> None:
    from experiments.cli import main

    run = _with_world(folder, tmp_path, lambda p: os.mkfifo(p) if kind == "fifo" else p.symlink_to("/dev/zero"))
    out = tmp_path / "out"
    assert main(["compare", str(run), "--methods", "sensor", "--out", str(out), "--no-progress"]) == 2  # old: 0
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench compare: error: {re.escape(str(run / 'world.json'))}: a world.json must be a "
                        r"regular file, not a device or pipe\n", err)
    assert not out.exists()  # refused before any work (old: its scans compared as a log's, the truth dropped)


@pytest.mark.parametrize("name, shown", [(None, "None"), ([1, 2], "[1, 2]"), (3, "3")])
def test_a_world_json_name_that_is_no_string_is_refused(folder, tmp_path, name, shown) -> None:
    """simulate took str() of it: null became the world "None", a list its text (exit 0)."""
    import json

    from lms200 import LmsbenchError
    from sim import World

    d = json.loads((folder / "world.json").read_text())
    World.from_json(folder / "world.json")  # as written: it reads
    d["name"] = name
    (tmp_path / "w.json").write_text(json.dumps(d))
    with pytest.raises(LmsbenchError) as err:
        World.from_json(tmp_path / "w.json")
    assert str(err.value) == (f"{tmp_path / 'w.json'}: not a world.json (name: must be text (the world's name), "
                              f"got {shown})")


def test_a_world_json_number_of_too_many_digits_names_no_python_setting(tmp_path) -> None:
    """json's own error said "... use sys.set_int_max_str_digits() to increase the limit", advice for a
    Python program, not for a world.json (whose numbers are metres and a seed)."""
    import sys

    from lms200 import LmsbenchError
    from sim import World

    (tmp_path / "w.json").write_text('{"seed": ' + "9" * 5000 + ', "walls": []}')
    with pytest.raises(LmsbenchError) as err:
        World.from_json(tmp_path / "w.json")
    assert str(err.value) == (f"{tmp_path / 'w.json'}: not a world.json (a whole number of more than "
                              f"{sys.get_int_max_str_digits()} digits, which no field takes)")


def test_a_world_json_number_written_nonzero_that_reads_as_zero_is_refused(tmp_path) -> None:
    """1e-400 in a world.json was read as 0 without a word (a wall end, a radius), as YAML's was before
    round 11; a zero written as one, 0e-400, reads as before."""
    from lms200 import LmsbenchError
    from sim import World

    (tmp_path / "w.json").write_text('{"walls": [[0, 0, 4, 1e-400], [4, 0, 4, 3]]}')
    with pytest.raises(LmsbenchError) as err:
        World.from_json(tmp_path / "w.json")
    assert str(err.value) == (f"{tmp_path / 'w.json'}: not a world.json (1e-400 rounds to 0 in float64 (its smallest "
                              "nonzero number is 4.9e-324); write 0 for zero)")
    (tmp_path / "w.json").write_text('{"walls": [[0, 0e-400, 4, 0.001], [4, 0, 4, 3]]}')
    assert len(World.from_json(tmp_path / "w.json").walls) >= 2


def test_a_world_json_is_utf8_with_or_without_a_byte_order_mark(folder, tmp_path) -> None:
    """fuzz4: a world.json saved with a byte-order mark (a Windows editor), or naming its world "Büro", was
    "'ascii' codec can't decode byte 0xef in position 0" for simulate and compare (read as ASCII), and the
    mark "Unexpected UTF-8 BOM" for slam (read as UTF-8); JSON is UTF-8, and the other readers skip a mark.
    Bytes that are not UTF-8 (latin-1) are named so."""
    import json

    import numpy as np

    from experiments.slamrun import load_input
    from lms200 import LmsbenchError
    from sim import World

    raw = (folder / "world.json").read_bytes()
    plain = World.from_json(folder / "world.json")
    d = json.loads(raw)
    d["name"] = "Büro"
    for name, data in (("bom.json", b"\xef\xbb\xbf" + raw), ("name.json", json.dumps(d, ensure_ascii=False).encode())):
        world = World.from_json(tmp_path / name, data=data)
        assert np.array_equal(world.walls, plain.walls) and world.name == ("Büro" if name == "name.json" else plain.name)
    run = _with_world(folder, tmp_path, lambda p: p.write_bytes(b"\xef\xbb\xbf" + raw))
    assert np.array_equal(load_input(run).walls, plain.walls)
    with pytest.raises(LmsbenchError, match=r"w\.json: not a world\.json \(not UTF-8 text \(byte 11 is not UTF-8\)\)$"):
        World.from_json(tmp_path / "w.json", data=json.dumps(d, ensure_ascii=False).encode("latin-1"))
