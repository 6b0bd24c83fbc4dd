"""A gap in a log's stamps (a pause in the recording, two logs joined, a clock jump): the motion
restarts after a step longer than ``motion.max_gap`` in both presets, and every file a run writes
reads back with lmsbench's own readers."""

from __future__ import annotations

import gzip
import itertools
import re
from pathlib import Path

import numpy as np
import pytest

from lms200 import InputError, read_tum, write_tum

GAP_S = 3e9  # (was 1e11: a log's stamps now lie in 0 .. 2^32 s, lms200.records.MAX_STAMP_S; MIT's are ~1.13e9 s)


@pytest.fixture(scope="module")
def gap_log(tmp_path_factory, shared_data) -> Path:
    """MIT CSAIL's first 50 FLASER scans (the robot at rest), the second half stamped 3e9 s later."""
    with gzip.open(shared_data / "mit-csail.clf.gz", "rt") as f:
        lines = list(itertools.islice((ln for ln in f if ln.startswith("FLASER ")), 50))
    out = []
    for k, line in enumerate(lines):
        w = line.split()
        if k >= 25:  # FLASER ... ipc_timestamp ipc_hostname logger_timestamp
            w[-3], w[-1] = f"{float(w[-3]) + GAP_S:.6f}", f"{float(w[-1]) + GAP_S:.6f}"
        out.append(" ".join(w) + "\n")
    path = tmp_path_factory.mktemp("gap") / "gap.clf"
    path.write_text("".join(out))
    return path


@pytest.mark.parametrize("preset", ["paper", "default"])
def test_a_huge_gap_restarts_the_motion_and_the_trajectory_reads_back(gap_log, tmp_path, capsys, preset):
    from experiments.cli import main

    out = tmp_path / "o"
    assert main(["slam", str(gap_log), "--out", str(out), "--quiet", "--preset", preset]) == 0
    # the paper preset wrote x = 1.2e11 m at the third scan after the gap, which read_tum refused
    stamps, poses = read_tum(out / "trajectory.tum")
    assert stamps.size == 50 and stamps[25] - stamps[24] == pytest.approx(GAP_S, rel=1e-9)
    assert np.abs(poses[:, :2]).max() < 0.1  # the robot is at rest in these scans
    if (out / "keyframes.tum").exists():
        read_tum(out / "keyframes.tum")
    err = capsys.readouterr().err
    assert ("warning: " + str(gap_log) + ": 1 of 49 steps are longer than motion.max_gap, 60 s (scan 25 is stamped "
            "3e+09 s after scan 24, the one kept before it): the motion restarts from the last pose with zero velocity after each") in err
    import json

    m = json.loads((out / "metrics.json").read_text())
    assert m["consistency"]["healthy"] is True and m["consistency"]["diverged_at"] is None


def test_the_paper_filter_restarts_its_velocity_after_a_gap():
    from slam import SlamConfig
    from slam.filter import SlamFilter
    from slam.observations import Observations

    f = SlamFilter(SlamConfig(preset="paper"))
    empty = Observations()  # no lines: the prediction alone moves the filter
    f.step(0.0, empty)
    f.ekf.x[3, 0], f.ekf.x[4, 0] = 2.0, 0.3  # a moving robot
    f.step(1.0, empty)  # an ordinary step: constant velocity
    assert f.pose[0] == pytest.approx(1.989, abs=1e-3)  # 2 m along a 0.3 rad/s arc
    before = f.pose
    f.step(1.0 + 61.0, empty)  # longer than motion.max_gap (60 s): no extrapolation of 122 m
    np.testing.assert_array_equal(f.pose, before)
    assert f.ekf.x[3, 0] == 0.0 and f.ekf.x[4, 0] == 0.0 and f.restarts == [2]  # the scan after the gap
    np.testing.assert_allclose(np.diag(f.ekf.P)[3:5], [0.25, 0.25])
    assert not f.ekf.P[3:5, :3].any()


def test_write_tum_refuses_what_read_tum_refuses(tmp_path):
    with pytest.raises(InputError, match=r"poses: row 1: pose \(1\.2e\+11, 0\) m lies beyond \+-1e\+09 m .* which read_tum refuses"):
        write_tum(tmp_path / "t.tum", np.array([0.0, 1.0]), np.array([[0.0, 0.0, 0.0], [1.2e11, 0.0, 0.0]]))
    assert not (tmp_path / "t.tum").exists()


def test_a_pose_lost_beyond_the_readers_bound_is_nan_and_the_run_unhealthy(monkeypatch, tmp_path):
    """Whatever else makes the filter diverge, its trajectory reads back: a pose beyond +-1e9 m
    (read_tum's bound) is a lost pose, nan, written as nan."""
    from slam import SlamConfig
    from slam.filter import SlamFilter
    from slam.observations import Observations
    from slam.run import run_observations

    real = SlamFilter.pose
    monkeypatch.setattr(SlamFilter, "pose", property(lambda self: real.fget(self) + (1.2e11 if self.scan_no >= 2 else 0.0)))
    res = run_observations([0.0, 0.1, 0.2, 0.3], [Observations()] * 4, SlamConfig(preset="paper"))
    assert np.isfinite(res.trajectory[:2, 1:]).all() and np.isnan(res.trajectory[2:, 1:]).all()
    assert res.diagnostics["healthy"] is False and res.diagnostics["diverged_at"] == 0.2
    write_tum(tmp_path / "t.tum", res.trajectory[:, 0], res.trajectory[:, 1:])
    stamps, poses = read_tum(tmp_path / "t.tum", allow_nan=True)
    assert stamps.tolist() == [0.0, 0.1, 0.2, 0.3] and np.isnan(poses[2:]).all()


@pytest.mark.parametrize("gap", [1e-300, 1e-3, 0.0099])
def test_a_max_gap_shorter_than_any_scanners_step_is_refused(gap):
    """``motion.max_gap: 1e-300`` was taken: every step was a gap, the motion restarted at each and
    the model never ran (exit 0, one warning); every scanner steps more slowly than 100 scans/s."""
    from slam import SlamConfig
    from slam.config import SlamConfigError

    with pytest.raises(SlamConfigError, match=re.escape(
            f"motion.max_gap: must be in [0.01, 1e+06] s (100 scans/s, faster than any scanner's, to about 12 days: "
            f"a shorter gap makes every step a gap), got {gap}")):
        SlamConfig.from_dict({"motion": {"max_gap": gap}})
    assert SlamConfig.from_dict({"motion": {"max_gap": 0.01}}).motion.max_gap == 0.01  # the bound itself is taken


@pytest.mark.parametrize("name, bad, message", [
    ("max_range", 1e-300, "alignment.max_range: must be in [0.1, 10000] m, got 1e-300"),
    ("max_range", 0.05, "alignment.max_range: must be in [0.1, 10000] m, got 0.05"),
    ("max_correspondence", 1e-300, "alignment.max_correspondence: must be in [0.001, 0.5] m (the LMS200's range quantum "
                                   "to the cell of the scan matcher's search grid), got 1e-300"),
    ("fine_correspondence", 1e-300, "alignment.fine_correspondence: must be in [0.001, 0.5] m"),
    ("inlier_distance", 1e-4, "alignment.inlier_distance: must be in [0.001, 1] m (a shorter one pairs no point)")])
def test_a_match_reach_that_pairs_no_point_is_refused(name, bad, message):
    """``alignment.max_range`` / ``max_correspondence`` / ``fine_correspondence`` / ``inlier_distance``
    of 1e-300 were taken: no beam was paired, none of the steps matched, and the run ended exit 0
    with a "not healthy" warning after its whole length."""
    from slam import SlamConfig
    from slam.config import SlamConfigError

    with pytest.raises(SlamConfigError, match="^" + re.escape(message)):
        SlamConfig.from_dict({"alignment": {name: bad}})
    ok = SlamConfig.from_dict({"alignment": {"max_range": 0.1, "max_correspondence": 0.001, "fine_correspondence": 0.001,
                                             "inlier_distance": 0.001}}).alignment
    assert (ok.max_range, ok.max_correspondence, ok.inlier_distance) == (0.1, 0.001, 0.001)  # the bounds are taken
