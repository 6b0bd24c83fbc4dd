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


def _step(matched: bool = True, weak: float = 50.0, sigma: float = 0.1, keyframe: bool = True,
          predicted: float = 1.0, scale: float = 1.0) -> ScanStep:
    return ScanStep(keyframe=0, matched=matched, weak=weak, weak_sigma=sigma, new_keyframe=keyframe,
                    prediction_sigma=predicted, factor_scale=scale)


def test_degenerate_drift_sums_the_keyframes_of_one_stretch():
    """Each degenerate keyframe adds its std along the weak axis; a matched step that is not
    degenerate ends the stretch; an unmatched step neither adds nor ends it; a scan between
    keyframes adds nothing to the stretch (it matches the same local map) but counts what a
    keyframe there would reach."""
    from slam.scanslam import degenerate_drift

    steps = [_step(weak=3.0, sigma=0.2), _step(weak=3.0, sigma=0.2, keyframe=False), _step(weak=3.0, sigma=0.2),
             _step(),  # ends the first stretch at 0.4 m
             _step(weak=9.0, sigma=0.1), _step(matched=False, weak=50.0), _step(weak=1.0, sigma=0.25),
             _step(weak=2.0, sigma=0.3)]
    drift, at = degenerate_drift(steps, 10.0)
    assert drift == pytest.approx(0.65) and at == 7
    assert degenerate_drift(steps, 2.0) == (pytest.approx(0.25), 6)
    assert degenerate_drift(steps[:3], 10.0) == (pytest.approx(0.4), 1)  # 0.6 at 2 if scan 1 were added
    assert degenerate_drift([_step(), _step(weak=float("nan"))], 10.0) == (0.0, None)


def test_the_warning_names_the_degenerate_stretch():
    """The stamp is the scan where the stretch's sum peaked (it said "ending at", then "reaching it at", which named no antecedent)."""
    from experiments.commands.slam import _health_warning

    m = {"n_scans": 600, "consistency": {"diverged": False, "healthy": False, "degenerate_drift": 1.1879,
                                         "degenerate_drift_at": 61.2}}
    assert _health_warning(m, SlamConfig()) == (
        "the run is not healthy: a stretch of degenerate matches (the weakest direction held by fewer than 10 "
        "points' worth, as along a corridor) may have drifted 1.19 m along its weak axis by t=61.2 (the stds along "
        "it of its keyframes and of that scan, each at most its predictions', summed; consistency.max_degenerate_drift 0.3 m) (metrics.json: "
        "consistency.healthy false)")


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


def _bare_corridor(odometry: bool):
    """60 noise-free scans (361 beams, 5 scans/s) along two endless walls 2 m apart, driving at
    0.5 m/s: nothing fixes the position along the axis (the match's Hessian is singular there)."""
    from lms200 import Record
    from sim import simulate_records

    template = simulate_records("corridor", seed=0, duration=13.0, rate_hz=5.0)[:60]
    out = []
    for k, r in enumerate(template):
        x, y = 0.1 * k, 0.1
        s = np.sin(r.scan.angle_min + r.scan.angle_increment * np.arange(r.scan.ranges.size))
        with np.errstate(divide="ignore"):
            ranges = np.where(s > 1e-9, (1 - y) / s, np.where(s < -1e-9, (-1 - y) / s, np.inf))
        ranges = np.where(ranges <= 8.0, ranges, 0.0).astype(r.scan.ranges.dtype)
        out.append(Record(r.scan.replace(ranges=ranges), truth=(x, y, 0.0), odom=(x, y, 0.0) if odometry else None))
    return out


def test_a_free_axis_counts_what_the_prediction_held():
    """Along an axis nothing fixes, the match's std is Match.covariance's regularisation, 1/sqrt(1e-9)
    = 31,622.78 m: with a keyframe at every scan the 59 summed to 1,865,743.8 m ("may have drifted
    1865743.82 m"). What holds the pose there is the prediction: each keyframe counts at most the
    predictions' stds since the previous one (constant velocity: 1 m/s^2 * dt^2 + 0.01 m a scan,
    dt = 0.213 s; with odometry 0.1 of the step + 0.01 m). The trajectory is unchanged."""
    from experiments.commands.slam import _health_warning

    config = SlamConfig(keyframes={"min_inliers": 1.0})  # every scan a keyframe (none explains all its points)
    records = _bare_corridor(False)
    result = run_slam(records, config)
    d = result.diagnostics
    assert d["n_keyframes"] == 60 and d["degenerate_fraction"] == 1.0
    assert d["weak_sigma"][1] == pytest.approx(31622.78, abs=0.01)
    dt = records[1].scan.stamp - records[0].scan.stamp
    assert d["degenerate_drift"] == pytest.approx(59 * (dt**2 + 0.01), rel=1e-6)
    assert d["degenerate_drift"] == pytest.approx(3.275, abs=0.001) and not d["healthy"]
    assert np.abs(result.trajectory[:, 1]).max() < 1e-9  # it stood still on the map: the truth went 5.9 m
    m = {"n_scans": 60, "consistency": {"diverged": False, "healthy": False, "degenerate_drift": d["degenerate_drift"],
                                        "degenerate_drift_at": d["degenerate_drift_at"]}}
    assert "may have drifted 3.28 m along it" in _health_warning(m, config)
    d = run_slam(_bare_corridor(True), SlamConfig(motion={"use_odometry": True})).diagnostics
    # the odometry's 56 steps up to the last keyframe, and the 3 scans after it held to it by their matches
    assert d["n_keyframes"] == 17 and d["degenerate_drift_at"] == records[59].scan.stamp
    assert d["degenerate_drift"] == pytest.approx(59 * (0.1 * 0.1 + 0.01))


def test_a_stretch_that_makes_no_keyframe_is_counted():
    """With the default keyframe rules the estimate stood still from the first scan (the truth drove
    5.9 m along the bare corridor), so no keyframe followed the first one and the check, which summed
    keyframes only, read a drift of 0 and the run healthy. A scan between keyframes now counts what a
    keyframe there would add: the 59 predictions' stds the last scan's match stands on."""
    records = _bare_corridor(False)
    result = run_slam(records, SlamConfig())
    d = result.diagnostics
    assert d["n_keyframes"] == 1 and d["degenerate_fraction"] == 1.0
    assert np.abs(result.trajectory[:, 1]).max() < 1e-9
    dt = records[1].scan.stamp - records[0].scan.stamp
    assert d["degenerate_drift"] == pytest.approx(59 * (dt**2 + 0.01), rel=1e-6)
    assert d["degenerate_drift_at"] == records[59].scan.stamp and not d["healthy"]


def test_a_keyframe_counts_at_most_the_predictions_since_the_previous_one():
    """A keyframe adds the smaller of its factor's std along the weak axis and the predictions'
    stds summed since the previous keyframe (or since a matched step that held every direction)."""
    from slam.scanslam import degenerate_drift

    free = 31622.78
    steps = [_step(weak=0.0, sigma=free, keyframe=False, predicted=0.05),
             _step(weak=0.0, sigma=free, predicted=0.05),  # 0.1 m: two predictions
             _step(weak=3.0, sigma=0.02, predicted=0.05),  # the match's own 0.02 m is smaller
             _step(matched=False, keyframe=False, predicted=0.05),  # unmatched: its prediction still counts
             _step(weak=0.0, sigma=free, predicted=0.05)]
    assert degenerate_drift(steps, 10.0) == (pytest.approx(0.22), 4)
    held = [_step(weak=0.0, sigma=free, keyframe=False, predicted=0.05), _step(keyframe=False, predicted=0.05),
            _step(weak=0.0, sigma=free, predicted=0.05)]  # the matched step in between held every direction
    assert degenerate_drift(held, 10.0) == (pytest.approx(0.05), 0)  # reached at the first scan, not first at the keyframe


def test_degenerate_drift_uses_the_keyframe_factors_scaled_std(monkeypatch):
    """With keyframes.correlation_length on a keyframe factor's covariance is its match's times a
    scale (the run records it); the drift sums the factor's std, sqrt(scale) times the match's
    (it summed the match's)."""
    import dataclasses

    import slam.scanslam as scanslam
    from sim import simulate_records

    steps = [_step(weak=3.0, sigma=0.1, scale=4.0), _step(weak=3.0, sigma=0.1, scale=1.0)]
    assert scanslam.degenerate_drift(steps, 10.0) == (pytest.approx(0.3), 1)
    seen: dict[object, list[ScanStep]] = {}  # a run's DegenerateDrift (kept: no id reused) -> the steps it was fed
    add = scanslam.DegenerateDrift.add
    monkeypatch.setattr(scanslam.DegenerateDrift, "add", lambda self, i: (seen.setdefault(self, []).append(i), add(self, i)))
    records = simulate_records("office", seed=0, duration=10.0, rate_hz=5.0)
    base = SlamConfig(loop_closure=dataclasses.replace(SlamConfig().loop_closure, enabled=False))
    wide = dataclasses.replace(base, keyframes=dataclasses.replace(base.keyframes, correlation_length=1.0))
    run_slam(records, base), run_slam(records, wide)
    scales = [[i.factor_scale for i in infos if i.new_keyframe and i.matched] for infos in seen.values()]
    assert scales[0] and set(scales[0]) == {1.0}
    assert min(scales[1]) >= 1.0 and np.median(scales[1]) > 2.0


def test_the_degenerate_check_has_its_intervals():
    """consistency.degenerate_points 0 made no step degenerate (the check off, silently) and 1e300
    every matched one; max_degenerate_drift 0 flagged any degenerate keyframe, 1e300 was taken.
    Now each has an interval, and max_degenerate_drift at its largest, 1e6 m, turns the check off."""
    from slam.config import SlamConfigError

    with pytest.raises(SlamConfigError, match=r"^consistency.degenerate_points: must be in \[1, 8192\] points' worth "
                                              r"\(half the most beams of a scan\), got 0$"):
        SlamConfig(consistency={"degenerate_points": 0})
    with pytest.raises(SlamConfigError, match=r"^consistency.degenerate_points: .*got 1e\+300$"):
        SlamConfig(consistency={"degenerate_points": 1e300})
    with pytest.raises(SlamConfigError, match=r"^consistency.max_degenerate_drift: must be in \[0.001, 1e\+06\] m "
                                              r"\(1e\+06: the check off\), got 0$"):
        SlamConfig(consistency={"max_degenerate_drift": 0})
    with pytest.raises(SlamConfigError, match=r"^keyframes.correlation_length: must be 0 \(off\) or in"):
        SlamConfig(keyframes={"correlation_length": -1})
    cc = SlamConfig().consistency
    assert cc.degenerate_stretch_flagged(0.31) and not cc.degenerate_stretch_flagged(0.3)
    off = SlamConfig(consistency={"max_degenerate_drift": 1e6}).consistency
    assert not off.degenerate_stretch_flagged(1e7)
