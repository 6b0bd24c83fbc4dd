"""`lmsbench slam` on a run cut shorter than every relation: results are written, nothing raises."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from lms200 import read_tum, write_log


@pytest.fixture(scope="module")
def short_log(tmp_path_factory) -> Path:
    """A 1 s simulated office log (odometry on every record) and relations that all start after it."""
    from sim import simulate_records
    from sim.records import OdometryConfig

    out = tmp_path_factory.mktemp("short")
    records = simulate_records("office", seed=1, duration=1.0, odometry=OdometryConfig(), rate_hz=10.0)
    write_log(out / "run.clf", records)
    end = records[-1].scan.stamp
    (out / "run.relations").write_text(f"{end + 5:.3f} {end + 6:.3f} 0.5 0 0 0 0 0.1\n"
                                       f"{end + 7:.3f} {end + 9:.3f} 1.0 0 0 0 0 0.0\n")
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
    config.yaml is written with its trajectory and the earlier scores and figure are removed."""
    import yaml

    import experiments.slamrun as slamrun
    from slam import SlamConfig

    out = tmp_path / "o"
    out.mkdir()
    for name in ("metrics.json", "slam.png", "config.yaml"):
        (out / name).write_text("an earlier run's\n")

    def ctrl_c(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(slamrun, "score", ctrl_c)
    data = slamrun.load_input(short_log, max_scans=5)
    with pytest.raises(KeyboardInterrupt):
        slamrun.run(data, SlamConfig(preset="paper"), progress=False, out=out)
    assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "map.json", "trajectory.tum"]
    written = yaml.safe_load((out / "config.yaml").read_text())
    assert written["slam"]["preset"] == "paper" and written["input"] == data.sources


def test_the_shipped_mit_csail_config_loads_and_sets_the_cm_mode_noise():
    """configs/slam-mit-csail.yaml, which the README's MIT CSAIL command uses, is a valid SlamConfig."""
    import yaml
    from pathlib import Path

    from slam import SlamConfig

    path = Path(__file__).resolve().parents[1] / "configs" / "slam-mit-csail.yaml"
    cfg = SlamConfig.from_dict(yaml.safe_load(path.read_text()))
    assert cfg.extractor_params == {"sigma_r": 0.02}
    assert cfg.extractor == SlamConfig().extractor
