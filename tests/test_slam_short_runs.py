"""`lmsbench slam` on a run cut shorter than every relation: results are written, nothing raises."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from experiments.options import SLAM_OUTPUTS as SLAM_ORDER

from lms200 import read_tum, write_log


@pytest.fixture(scope="module")
def short_log(tmp_path_factory) -> Path:
    """A 2 s simulated office log (odometry on every record) and relations that all lie after its first 10
    scans (the runs below keep at most 8), within the log: the log's own, past the cut (relations after
    the whole log are another log's, refused: test_slam_cli)."""
    from sim import simulate_records
    from sim.records import OdometryConfig

    out = tmp_path_factory.mktemp("short")
    records = simulate_records("office", seed=1, duration=2.0, odometry=OdometryConfig(), rate_hz=10.0)
    write_log(out / "run.clf", records)
    t = [r.scan.stamp for r in records]
    (out / "run.relations").write_text(f"{t[10]:.3f} {t[12]:.3f} 0.5 0 0 0 0 0.1\n"
                                       f"{t[13]:.3f} {t[17]:.3f} 1.0 0 0 0 0 0.0\n")
    return out / "run.clf"


def test_no_relation_inside_the_run_is_recorded_not_raised(short_log, tmp_path, capsys):
    from experiments.cli import main

    out = tmp_path / "o"
    assert main(["slam", str(short_log), "--out", str(out), "--quiet", "--max-scans", "8"]) == 0
    stamps, _ = read_tum(out / "trajectory.tum")
    assert stamps.size == 8
    m = json.loads((out / "metrics.json").read_text())
    assert m["relations"]["n"] == 0 and m["relations"]["n_skipped"] == 2
    assert "none of the 2 relations" in m["relations"]["note"]
    assert all("relations_trans_mean" not in row for row in m["table"])
    assert "relations:" in capsys.readouterr().out


def test_trajectory_and_map_are_written_before_scoring(short_log, tmp_path, monkeypatch):
    import experiments.slamrun as slamrun
    from slam import SlamConfig

    def broken(*args, **kwargs):
        raise RuntimeError("scoring failed")

    monkeypatch.setattr(slamrun, "score", broken)
    data = slamrun.load_input(short_log, max_scans=5)
    with pytest.raises(RuntimeError, match="scoring failed"):
        slamrun.run(data, SlamConfig(), progress=False, out=tmp_path / "o")
    stamps, _ = read_tum(tmp_path / "o" / "trajectory.tum")
    np.testing.assert_allclose(stamps, [r.scan.stamp for r in data.records], atol=1e-6)
    assert "lines" in json.loads((tmp_path / "o" / "map.json").read_text())


def test_a_run_stopped_after_its_trajectory_leaves_no_earlier_runs_scores_beside_it(short_log, tmp_path, monkeypatch):
    """Ctrl-C during `lmsbench slam RUN --out DIR`'s baselines, DIR holding an earlier run: the new
    trajectory.tum and map.json were written, but the earlier run's metrics.json, config.yaml and
    slam.png stayed beside them, read as this trajectory's scores and settings. Now the run's own
    config.yaml is written with its trajectory and the earlier scores and figure are removed (the
    CLI's replace_earlier; the earlier run's default-preset keyframes.tum too, as the paper preset
    writes none)."""
    import yaml

    import experiments.slamrun as slamrun
    from slam import SlamConfig

    out = tmp_path / "o"
    data = slamrun.load_input(short_log, max_scans=5)
    earlier = slamrun.run(data, SlamConfig(), progress=False, paper_baseline=False, odometry_baseline=False)
    slamrun.write_outputs(out, data, SlamConfig(), earlier)
    assert slamrun.earlier_run_files(out) == set(slamrun.OUTPUTS) and slamrun.foreign_outputs(out) == []

    def ctrl_c(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(slamrun, "score", ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        slamrun.run(data, SlamConfig(preset="paper"), progress=False, out=out, replace_earlier=True)
    assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "map.json", "trajectory.tum"]
    written = yaml.safe_load((out / "config.yaml").read_text())
    assert written["slam"]["preset"] == "paper" and written["input"] == data.sources


def test_a_run_into_a_folder_touches_only_the_files_it_writes(short_log, tmp_path, monkeypatch):
    """0e69180's slamrun.run(data, config, out=DIR) deleted DIR's metrics.json and slam.png as soon
    as SLAM ended, which run() never writes back, and `lmsbench slam SIM --out DIR` stopped there
    (exit 130) lost a user's own metrics.json ("my notes") and slam.png (review of 0e69180). Now
    run() writes trajectory.tum, map.json, config.yaml and (default preset) keyframes.tum and leaves
    the rest; with replace_earlier it removes only what an earlier lmsbench slam run wrote."""
    import experiments.slamrun as slamrun
    from slam import SlamConfig

    data = slamrun.load_input(short_log, max_scans=5)
    mine = {"metrics.json": b"my notes\n", "slam.png": b"\x89PNG\r\n\x1a\nmine", "keyframes.tum": b"0 0 0 0 0 0 0 1\n"}

    def ctrl_c(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(slamrun, "score", ctrl_c)
    for replace_earlier in (False, True):
        out = tmp_path / f"o{replace_earlier}"
        out.mkdir()
        for name, content in mine.items():
            (out / name).write_bytes(content)
        assert slamrun.earlier_run_files(out) == set()
        assert slamrun.foreign_outputs(out) == ["keyframes.tum", "metrics.json", "slam.png"]
        with pytest.raises(KeyboardInterrupt):
            slamrun.run(data, SlamConfig(preset="paper"), progress=False, out=out, replace_earlier=replace_earlier)
        assert {name: (out / name).read_bytes() for name in mine} == mine, replace_earlier
        assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "keyframes.tum", "map.json", "metrics.json",
                                                         "slam.png", "trajectory.tum"]


@pytest.mark.parametrize("name, content, told", [
    ("config.yaml", "input: {scans: a.clf}\nslam: {preset: paper}\n", True),
    ("config.yaml", "preset: paper\n", False),  # a flat SLAM config of the user's (--config takes it)
    ("config.yaml", "input: {}\nslam: {preset: paper}\nnotes: mine\n", False),
    ("metrics.json", '{"input": {}, "n_scans": 5, "consistency": {}}', True),
    ("metrics.json", "my notes", False),
    ("metrics.json", '{"n_scans": 5}', False),
    ("map.json", '{"frame": "world", "lines": [], "corners": []}', True),
    ("map.json", "[]", False),
    ("slam.png", "\x89PNG", False),  # no record of a run beside it
])
def test_an_earlier_run_is_told_by_what_it_left(tmp_path, name, content, told):
    from experiments.slamrun import earlier_run_files, foreign_outputs

    (tmp_path / name).write_text(content)
    (tmp_path / "trajectory.tum").write_text("0 0 0 0 0 0 0 1\n")
    assert earlier_run_files(tmp_path) == ({name, "trajectory.tum"} if told else set())
    assert foreign_outputs(tmp_path) == ([] if told else sorted([name, "trajectory.tum"], key=SLAM_ORDER.index))
