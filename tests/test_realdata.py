"""Real-data measures (features.realdata) against scans whose lines are known exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from features.realdata import RealDataConfig, ray_residuals, repeat_counts, scan_measures
from features.types import FeatureSet, Line
from lms200 import Scan


def wall_scan(rho: float = 3.0, alpha: float = 0.0, noise: float = 0.0, seed: int = 0) -> Scan:
    """361 beams at 0.5 deg seeing the wall x cos(alpha) + y sin(alpha) = rho where it lies ahead
    within 60 deg of its normal (inf elsewhere)."""
    b = np.deg2rad(np.linspace(-90, 90, 361))
    cos = np.cos(b - alpha)
    with np.errstate(divide="ignore"):
        r = np.where(cos > 0.5, rho / cos, np.inf)
    r = r + np.random.default_rng(seed).normal(0, noise, r.size) * np.isfinite(r)
    return Scan.lms200(r, range_max=80.0)


def line(rho: float, alpha: float, first: int, last: int, scan: Scan) -> Line:
    b0, b1 = scan.angles[first], scan.angles[last]
    p0 = rho / math.cos(b0 - alpha) * np.array([math.cos(b0), math.sin(b0)])
    p1 = rho / math.cos(b1 - alpha) * np.array([math.cos(b1), math.sin(b1)])
    return Line(rho, alpha, tuple(p0), tuple(p1), first, last)


def test_exact_line_explains_every_beam_it_covers() -> None:
    scan = wall_scan()
    covered = np.flatnonzero(scan.valid)
    fs = FeatureSet([line(3.0, 0.0, covered[0], covered[-1], scan)])
    m = scan_measures(fs, scan, sigma_r=0.01)
    assert m.explained_tol == 1.0 and m.explained_sigma == 1.0 and m.ray_rmse_m < 1e-12 and m.n_lines == 1
    assert m.mean_segment_m == pytest.approx(2 * 3.0 * math.tan(math.radians(60)), rel=0.02)
    half = FeatureSet([line(3.0, 0.0, covered[0], 180, scan)])  # covers the beams up to straight ahead
    assert scan_measures(half, scan, 0.01).explained_tol == pytest.approx((180 - covered[0] + 1) / covered.size)


def test_offset_line_ray_residual_is_the_error_along_each_beam() -> None:
    scan = wall_scan()
    covered = np.flatnonzero(scan.valid)
    fs = FeatureSet([line(3.02, 0.0, covered[0], covered[-1], scan)])  # 2 cm behind the wall
    res = ray_residuals(fs, scan)[covered]
    expected = 0.02 / np.cos(scan.angles[covered])  # along the beam, not along the normal
    np.testing.assert_allclose(res, expected, rtol=1e-9)
    m = scan_measures(fs, scan, sigma_r=0.002)
    assert m.explained_tol == pytest.approx(np.mean(expected <= 0.03))
    assert m.explained_sigma == 0.0  # 2 cm is beyond 3 x 2 mm
    assert m.ray_rmse_m == pytest.approx(np.sqrt(np.mean(expected[expected <= 0.03] ** 2)))


def test_noisy_wall_explained_at_three_sigma() -> None:
    scan = wall_scan(noise=0.01, seed=3)
    covered = np.flatnonzero(scan.valid)
    m = scan_measures(FeatureSet([line(3.0, 0.0, covered[0], covered[-1], scan)]), scan, sigma_r=0.01)
    assert m.explained_sigma == pytest.approx(0.997, abs=0.01)  # Gaussian share within 3 sigma
    assert m.ray_rmse_m == pytest.approx(0.01, rel=0.15)


def test_repeatability_finds_the_same_wall_from_a_moved_pose() -> None:
    # the world wall x = 5: from pose a = (0, 0, 0) it is rho 5, alpha 0; from b = (1, 0.5, 0.2) its
    # normal points at -0.2 rad and rho = 5 - 1 = 4
    pose_a, pose_b = (0.0, 0.0, 0.0), (1.0, 0.5, 0.2)
    sa, sb = wall_scan(5.0, 0.0), wall_scan(4.0, -0.2)
    ca, cb = np.flatnonzero(sa.valid), np.flatnonzero(sb.valid)
    fa = FeatureSet([line(5.0, 0.0, ca[0], ca[-1], sa)])
    fb = FeatureSet([line(4.0, -0.2, cb[0], cb[-1], sb)])
    assert repeat_counts(fa, pose_a, fb, pose_b, sb) == (1, 1)
    fb_off = FeatureSet([line(4.0, -0.2 + math.radians(3), cb[0], cb[-1], sb)])  # 3 deg off: not the same
    assert repeat_counts(fa, pose_a, fb_off, pose_b, sb) == (0, 1)
    assert repeat_counts(fa, pose_a, FeatureSet([]), pose_b, sb) == (0, 1)
    # a wrong pose puts the wall where scan b reads nothing: not in view, not counted
    assert repeat_counts(fa, pose_a, fb, (1.0, 0.5, 1.2), sb) == (0, 0)
    cfg = RealDataConfig(repeat_angle_rad=math.radians(5))
    assert repeat_counts(fa, pose_a, fb_off, pose_b, sb, cfg) == (1, 1)
