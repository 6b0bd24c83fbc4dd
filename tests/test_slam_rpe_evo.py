"""Our RPE with evo's pairing rule agrees with evo itself (``evo.core.metrics.RPE``, what
``evo_rpe --delta 1 --delta_unit m`` computes) on the same trajectories; the default rule pairs
every pose and is checked on a case worked out by hand."""

from __future__ import annotations

import numpy as np
import pytest

from slam.metrics import rpe


def _trajectories(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A true 2-D path (t, x, y, theta) at 10 Hz and an estimate that drifts from it."""
    rng = np.random.default_rng(seed)
    n = 400
    t = np.arange(n) * 0.1
    theta = np.cumsum(rng.normal(0.0, 0.03, n))
    speed = 0.3 + 0.2 * np.sin(t / 3.0) ** 2
    x = np.cumsum(speed * 0.1 * np.cos(theta))
    y = np.cumsum(speed * 0.1 * np.sin(theta))
    truth = np.column_stack((t, x, y, theta))
    est = truth.copy()
    est[:, 1:3] += np.cumsum(rng.normal(0.0, 0.004, (n, 2)), axis=0)
    est[:, 3] += np.cumsum(rng.normal(0.0, 0.002, n))
    return est, truth


def _se3(poses: np.ndarray) -> list[np.ndarray]:
    out = []
    for x, y, th in poses:
        m = np.eye(4)
        m[:2, :2] = [[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]
        m[:2, 3] = x, y
        out.append(m)
    return out


@pytest.mark.parametrize("seed, delta", [(0, 1.0), (1, 0.5), (2, 2.0)])
def test_evo_pairing_agrees_with_evo_rpe(seed, delta):
    evo_metrics = pytest.importorskip("evo.core.metrics")
    from evo.core.trajectory import PoseTrajectory3D

    est, truth = _trajectories(seed)
    ref = PoseTrajectory3D(poses_se3=_se3(truth[:, 1:]), timestamps=truth[:, 0])
    traj = PoseTrajectory3D(poses_se3=_se3(est[:, 1:]), timestamps=est[:, 0])
    for relation, ours in ((evo_metrics.PoseRelation.translation_part, "trans"),
                           (evo_metrics.PoseRelation.rotation_angle_rad, "rot")):
        metric = evo_metrics.RPE(relation, delta=delta, delta_unit=evo_metrics.Unit.meters, all_pairs=False)
        metric.process_data((ref, traj))
        stats = metric.get_all_statistics()
        got = rpe(est, truth, delta, pairs="evo")
        assert got.n == len(metric.error)
        assert getattr(got, f"{ours}_rmse") == pytest.approx(stats["rmse"], rel=1e-9, abs=1e-12)
        assert getattr(got, f"{ours}_mean") == pytest.approx(stats["mean"], rel=1e-9, abs=1e-12)


def test_the_two_rules_on_a_straight_line_worked_by_hand():
    # truth: x = 0, 0.5, ..., 3.0 m along a line; the estimate overshoots each 0.5 m step by 1 cm
    x = np.arange(7) * 0.5
    truth = np.column_stack((np.arange(7.0), x, np.zeros(7), np.zeros(7)))
    est = truth.copy()
    est[:, 1] = np.arange(7) * 0.51
    every = rpe(est, truth, 1.0)  # pairs (0,2), (1,3), ..., (4,6): 5 pairs, each 2 cm off
    evo = rpe(est, truth, 1.0, pairs="evo")  # kept 0, 2, 4, 6: pairs (0,2), (2,4), (4,6)
    assert every.n == 5 and evo.n == 3
    assert every.trans_rmse == pytest.approx(0.02) and evo.trans_rmse == pytest.approx(0.02)
    with pytest.raises(ValueError, match="pairs"):
        rpe(est, truth, 1.0, pairs="all")
