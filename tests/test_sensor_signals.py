"""The paper's per-beam signals on exact geometry: AD (eq. 4), slope (eq. 6-7 corrected), psi, and
their noise std against Monte-Carlo."""

from __future__ import annotations

import numpy as np
import pytest
from sensor_geometry import cast, line_scan, polygon

from features.sensor import signals

RESOLUTIONS = [  # (n beams, increment deg): LMS200 0.5 deg, Intel logs 1 deg, 0.25 deg
    (361, 0.5),
    (180, 1.0),
    (401, 0.25),
]


@pytest.mark.parametrize("n,inc_deg", RESOLUTIONS)
@pytest.mark.parametrize("k", [1, 3, 5, 10])
@pytest.mark.parametrize("rho,alpha", [(2.0, 0.3), (0.7, -1.1), (5.5, 0.0), (3.0, 1.35), (1.5, -2.2)])
def test_ad_is_the_line_invariant(n: int, inc_deg: float, k: int, rho: float, alpha: float) -> None:
    inc = np.deg2rad(inc_deg)
    amin = -inc * (n - 1) / 2
    scan = line_scan(rho, alpha, n=n, angle_min=amin, increment=inc, range_max=80.0)
    s = signals(scan, k=k)
    expected = 1 + 2 * sum(np.cos(j * inc) for j in range(1, k + 1))
    on = np.isfinite(s["ad"])
    assert on.sum() >= 10
    np.testing.assert_allclose(s["ad"][on], expected, rtol=0, atol=1e-9)
    assert s["ad_line"] == pytest.approx(expected, abs=1e-12)
    # the slope estimate recovers the true normal angle without noise
    err = np.angle(np.exp(1j * (s["theta"][on] - alpha)))
    assert np.abs(err).max() < 1e-9
    # psi = theta_i - theta_{i+k} vanishes along a line
    psi = s["psi"][np.isfinite(s["psi"])]
    assert psi.size > 0 and np.abs(psi).max() < 1e-9


def test_windows_touching_invalid_beams_are_nan() -> None:
    scan = line_scan(2.0, 0.2)
    r = scan.ranges.copy()
    r[100] = np.nan
    r[200] = np.inf
    s = signals(scan.replace(ranges=r), k=5)
    for bad in (100, 200):
        assert np.isnan(s["ad"][bad - 5 : bad + 6]).all()
    assert np.isfinite(s["ad"][106:195]).all()
    assert np.isnan(s["ad"][:5]).all() and np.isnan(s["ad"][-5:]).all()
    assert not s["valid"][100] and not s["valid"][200]


def test_psi_shows_the_turn_at_a_corner() -> None:
    # right-angle corner at (3, 0) seen from the origin: walls y = x - 3 ... use two segments
    scan = cast(polygon([(3.0, -3.0), (3.0, 0.5), (-1.0, 0.5)])[:2])
    s = signals(scan, k=5)
    psi = s["psi"][np.isfinite(s["psi"])]
    assert np.abs(psi).max() == pytest.approx(np.pi / 2, abs=0.35)
    theta = s["theta"]
    assert np.nanmin(np.abs(np.angle(np.exp(1j * (theta - 0.0))))) < 1e-9  # on the x = 3 wall
    assert np.nanmin(np.abs(np.angle(np.exp(1j * (theta - np.pi / 2))))) < 1e-9  # on y = 0.5


def test_noise_std_matches_monte_carlo() -> None:
    """AD_sigma and theta_sigma (first-order propagation of sigma_r) against 2000 noisy draws."""
    sigma = 0.005
    clean = line_scan(2.5, 0.4)
    rng = np.random.default_rng(7)
    beams = np.array([60, 180, 300])
    draws_ad, draws_theta = [], []
    for _ in range(2000):
        r = clean.ranges + sigma * rng.standard_normal(clean.ranges.size)
        s = signals(clean.replace(ranges=r), k=5, sigma_r=sigma)
        draws_ad.append(s["ad"][beams])
        draws_theta.append(s["theta"][beams])
    ref = signals(clean, k=5, sigma_r=sigma)
    np.testing.assert_allclose(np.std(draws_ad, axis=0), ref["ad_sigma"][beams], rtol=0.08)
    np.testing.assert_allclose(np.std(draws_theta, axis=0), ref["theta_sigma"][beams], rtol=0.08)
