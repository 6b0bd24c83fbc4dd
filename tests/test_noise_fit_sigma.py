"""``features.noise_estimate.fit_sigma``: the scatter of beams about fitted lines, which the
split / merge tests of split_merge and iepf allow for, against known noise and interlace offsets."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.synthetic import L_ROOM, room_scan
from features.noise_estimate import fit_residuals, fit_sigma, neighbour_sigma
from lms200 import Scan

POSES = [(0.0, 0.0, 0.3), (1.0, -1.0, -0.4), (3.5, -1.5, 1.9)]


def rooms(sigma: float, zigzag: float = 0.0) -> list[Scan]:
    """L-room scans (361 beams, 0.5 deg) with Gaussian noise ``sigma`` and the two interlaced 1 deg
    sweeps offset by ``zigzag`` (m: even beams +zigzag / 2, odd beams -zigzag / 2)."""
    out = []
    for seed in range(4):
        for pose in POSES:
            scan, _ = room_scan(L_ROOM, pose, sigma=sigma, seed=seed)
            offset = np.where(np.arange(scan.ranges.size) % 2 == 0, 0.5, -0.5) * zigzag
            out.append(scan.replace(ranges=scan.ranges + offset))
    return out


def test_exact_walls_have_no_fit_residual() -> None:
    """A straight wall is 1 / r = A cos b + B sin b exactly: its beams' residuals vanish, and only
    runs over a corner carry one."""
    scan, _ = room_scan(L_ROOM, POSES[0], sigma=0.0)
    z = np.abs(fit_residuals(scan))
    assert z.size > 300
    assert np.median(z) < 1e-9
    assert np.count_nonzero(z > 1e-6) <= 6 * 6  # up to 6 windows over each corner and depth step


@pytest.mark.parametrize("sigma", [0.005, 0.025])
def test_fit_sigma_is_the_noise_of_straight_walls(sigma: float) -> None:
    assert fit_sigma(rooms(sigma)) == pytest.approx(sigma, rel=0.08)


def test_interlace_offset_counts_as_about_half_its_size() -> None:
    """Sweeps offset by d = 13 mm over 5 mm noise (MIT CSAIL's neighbour scatter, 12 mm): the beams
    scatter about a line fitted through both sweeps by sqrt(sigma^2 + d^2 / 4) = 8.3 mm RMS;
    fit_sigma reads it within 25 % (the robust scale of a two-peaked scatter reads high), the
    neighbour scatter (a second difference: 0.82 d) about 50 % above it."""
    scans = rooms(0.005, zigzag=0.013)
    truth = float(np.hypot(0.005, 0.013 / 2))
    assert fit_sigma(scans) == pytest.approx(truth, rel=0.25)
    assert neighbour_sigma(scans) > 1.35 * truth > 1.1 * fit_sigma(scans)
    assert fit_sigma(rooms(0.005)) < fit_sigma(scans)


def test_too_few_runs_fall_back() -> None:
    r = np.full(361, np.nan)
    r[::7] = 2.0  # no run of 7 valid beams
    assert fit_sigma(Scan.lms200(r)) == 0.005
    assert fit_residuals(Scan(np.full(5, 2.0), -0.01, 0.005, 0.0, 8.0)).size == 0


def test_readings_beyond_any_rangefinder_overflow_neither_fit_nor_bearing_sigma() -> None:
    """fit_sigma and bearing_sigma of scans of 1e160 m readings (range_max 1e308, which a Scan takes)
    overflowed r^2 (RuntimeWarnings, errors under this suite's filter); readings of 10 km or more are
    not used now: no residual, the fallback (fit_sigma) and 0 (bearing_sigma)."""
    from features.noise_estimate import bearing_sigma

    scans = [Scan(np.full(361, 1e300) * (1 + np.random.default_rng(i).normal(0, 1e-3, 361)), -np.pi / 2, np.pi / 360,
                  0.0, 1e308) for i in range(5)]
    assert fit_residuals(scans[0]).size == 0
    assert fit_sigma(scans, fallback=0.007) == 0.007
    assert bearing_sigma(scans) == 0.0
