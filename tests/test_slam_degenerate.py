"""The health flag on runs that lose track along a corridor: stretches of degenerate matches (the
weakest position direction held by a few points' worth) and the drift they may have left
(``consistency.max_degenerate_drift``). Simulated runs with exact truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slam import SlamConfig, run_slam
from slam.metrics import ate
from slam.scanslam import ScanStep


def _run(world: str, seed: int, resolution_deg: float, duration: float = 120.0):
    from sim import simulate_records
    from sim.sensor import SensorConfig

    sensor = SensorConfig(n_beams={0.5: 361, 1.0: 181}[resolution_deg], resolution=math.radians(resolution_deg))
    records = simulate_records(world, seed=seed, duration=duration, rate_hz=5.0, sensor=sensor)
    result = run_slam(records, SlamConfig())
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    return ate(result.trajectory, truth).rmse, result.diagnostics


def test_a_corridor_lost_at_one_degree_is_not_healthy():
    """The bare corridor scanned at 1 degree (181 beams) slides along its axis: 2 m off the truth,
    and it was reported healthy (no step ambiguous, every step matched). Its matches hold the axis
    by a few points' worth on most steps, and a stretch of them may have drifted 1.2 m."""
    err, d = _run("corridor", 211, 1.0)
    assert err == pytest.approx(2.035, abs=0.01)
    assert d["ambiguous_fraction"] == 0.0 and d["matched_fraction"] == 1.0 and not d["diverged"]
    assert not d["healthy"]
    assert d["degenerate_fraction"] == pytest.approx(0.85, abs=0.05)
    assert d["degenerate_drift"] == pytest.approx(1.188, abs=0.01)


def test_a_tracked_run_stays_healthy():
    """The office at 0.5 degree is tracked to 1 cm: no stretch of degenerate matches near the bound."""
    err, d = _run("office", 0, 0.5, duration=90.0)
    assert err < 0.02
    assert d["degenerate_drift"] < 0.1 and d["healthy"]


def _step(matched: bool = True, weak: float = 50.0, sigma: float = 0.1, keyframe: bool = True) -> ScanStep:
    return ScanStep(keyframe=0, matched=matched, weak=weak, weak_sigma=sigma, new_keyframe=keyframe)


def test_degenerate_drift_sums_the_keyframes_of_one_stretch():
    """Each degenerate keyframe adds its std along the weak axis; a matched step that is not
    degenerate ends the stretch; an unmatched step neither adds nor ends it; scans between
    keyframes add nothing (they match the same local map)."""
    from slam.scanslam import degenerate_drift

    steps = [_step(weak=3.0, sigma=0.2), _step(weak=3.0, sigma=0.2, keyframe=False), _step(weak=3.0, sigma=0.2),
             _step(),  # ends the first stretch at 0.4 m
             _step(weak=9.0, sigma=0.1), _step(matched=False, weak=50.0), _step(weak=1.0, sigma=0.25),
             _step(weak=2.0, sigma=0.3)]
    drift, at = degenerate_drift(steps, 10.0)
    assert drift == pytest.approx(0.65) and at == 7
    assert degenerate_drift(steps, 2.0) == (pytest.approx(0.25), 6)
    assert degenerate_drift([_step(), _step(weak=float("nan"))], 10.0) == (0.0, None)


def test_the_warning_names_the_degenerate_stretch():
    from experiments.commands.slam import _health_warning

    m = {"n_scans": 600, "consistency": {"diverged": False, "healthy": False, "degenerate_drift": 1.1879,
                                         "degenerate_drift_at": 61.2}}
    assert _health_warning(m, SlamConfig()) == (
        "the run is not healthy: a stretch of degenerate matches (the weakest direction held by fewer than 10 "
        "points' worth, as along a corridor) ending at t=61.2 may have drifted 1.19 m along it (its keyframes' std "
        "there, summed; consistency.max_degenerate_drift 0.3 m) (metrics.json: consistency.healthy false)")


def test_correlation_length_scales_a_keyframe_factor_by_its_points_per_square():
    """``keyframes.correlation_length`` (off by default): 12 explained points in 3 squares of 1 m
    count as 3 measurements, so the factor's covariance is 4 times the match's; never below 1."""
    from slam.config import SlamConfigError
    from slam.scanslam import correlated_scale

    wall = np.array([[0.1 * k, 2.5] for k in range(1, 10)] + [[1.5, 0.5], [2.4, 0.6], [2.6, 0.7]])  # squares (0, 2), (1, 0), (2, 0)
    assert correlated_scale(wall, 1.0, 1.0) == pytest.approx(4.0)
    assert correlated_scale(wall, 0.5, 1.0) == pytest.approx(2.0)
    assert correlated_scale(wall, 1.0, 0.01) == 1.0 and correlated_scale(np.zeros((0, 2)), 1.0, 1.0) == 1.0
    assert SlamConfig().keyframes.correlation_length == 0.0
    with pytest.raises(SlamConfigError, match=r"keyframes.correlation_length: must be 0 \(off\) or in \[0.001, 10000\] m, got 1e-300"):
        SlamConfig.from_dict({"keyframes": {"correlation_length": 1e-300}})


def test_correlation_length_widens_the_keyframe_factors_only():
    """With the option the graph's factors are wider (the keyframes' marginals grow), the matches the same."""
    import dataclasses

    from sim import simulate_records

    records = simulate_records("office", seed=0, duration=20.0, rate_hz=5.0)
    base = SlamConfig(loop_closure=dataclasses.replace(SlamConfig().loop_closure, enabled=False))
    wide = dataclasses.replace(base, keyframes=dataclasses.replace(base.keyframes, correlation_length=1.0))
    a, b = run_slam(records, base), run_slam(records, wide)
    np.testing.assert_allclose(a.trajectory, b.trajectory, atol=1e-9)  # no closure: the chain is the matches
    ratio = np.trace(b.covariances[-1][:2, :2]) / np.trace(a.covariances[-1][:2, :2])
    assert ratio > 2.0
