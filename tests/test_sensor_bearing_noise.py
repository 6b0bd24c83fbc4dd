"""Bearing noise (``sigma_bearing``): on interlaced 0.5 deg scans whose two 1 deg sweeps are
offset in bearing, a beam's range error grows as d tan(incidence) on oblique walls. Scored against
the exact walls of an independent ray caster (``sensor_geometry``): the estimate
``features.noise_estimate.bearing_sigma`` reads the offset, and with it the sensor method finds
walls that the range noise alone rejects."""

from __future__ import annotations

import numpy as np
import pytest

from features import extract
from features.noise_estimate import bearing_sigma, fit_residuals_and_slopes, neighbour_sigma
from lms200 import Scan
from tests.sensor_geometry import cast, polygon

D = np.deg2rad(0.5)
#: a room with six walls, the sensor near one corner: most walls seen obliquely
OFFICE = polygon([(-0.5, -1.5), (3.0, -1.5), (3.0, -0.8), (5.5, -0.8), (5.5, 2.0), (1.0, 2.0), (1.0, 1.0),
                  (-0.5, 1.0)])


def interlaced(segments: np.ndarray, offset: float, sigma: float, seed: int) -> Scan:
    """361 beams at 0.5 deg as two 1 deg sweeps, the odd one's bearings off by ``offset`` (rad),
    Gaussian range noise ``sigma`` (m), rounded to 1 cm (SICK cm codes, range_max 80 m)."""
    even = cast(segments, n=181, angle_min=-np.pi / 2, increment=2 * D, range_max=80.0)
    odd = cast(segments, n=180, angle_min=-np.pi / 2 + D + offset, increment=2 * D, range_max=80.0)
    r = np.empty(361)
    r[0::2], r[1::2] = even.ranges, odd.ranges
    finite = np.isfinite(r)
    r[finite] = np.round(r[finite] + sigma * np.random.default_rng(seed).standard_normal(int(finite.sum())), 2)
    return Scan(r, -np.pi / 2, D, 0.0, 80.0)


def walls() -> np.ndarray:
    """(6, 2) rho (m), alpha (rad) of the office's walls."""
    out = []
    for x1, y1, x2, y2 in OFFICE:
        alpha = np.arctan2(x2 - x1, -(y2 - y1))
        rho = x1 * np.cos(alpha) + y1 * np.sin(alpha)
        out.append((abs(rho), np.angle(np.exp(1j * (alpha + (np.pi if rho < 0 else 0.0))))))
    return np.array(out)


def walls_found(scan: Scan, **params: float) -> int:
    """How many of the office's walls an extracted segment lies on: both its end points within 5 cm
    of the wall's line and its direction within 5 deg (``features.scoring``'s tolerances; rho
    itself moves by a segment's distance times its angle error); six of the eight are in view."""
    lines = extract(scan, method="sensor", **params).line_array()
    rho, alpha = walls().T
    c, s = np.cos(alpha)[:, None], np.sin(alpha)[:, None]
    ends = [np.abs(lines[None, :, 2 + 2 * e] * c + lines[None, :, 3 + 2 * e] * s - rho[:, None]) for e in (0, 1)]
    d_alpha = np.abs(np.angle(np.exp(1j * (alpha[:, None] - lines[None, :, 1]))))
    on = (ends[0] <= 0.05) & (ends[1] <= 0.05) & (d_alpha <= np.deg2rad(5.0))
    return int(np.count_nonzero(on.any(axis=1)))


@pytest.mark.parametrize("offset", [0.008, 0.012])
def test_bearing_sigma_reads_the_sweeps_offset(offset: float) -> None:
    """Sweeps off by +-offset / 2 about the nominal bearings: a bearing noise of about offset / 2
    (it reads 1.15-1.2x: a 7-beam fit takes an alternating error as a little more than its size);
    exact bearings read under 1 mrad."""
    scans = [interlaced(OFFICE, offset, 0.005, seed) for seed in range(12)]
    assert 0.9 * offset / 2 <= bearing_sigma(scans) <= 1.5 * offset / 2
    assert bearing_sigma([interlaced(OFFICE, 0.0, 0.005, seed) for seed in range(12)]) < 0.001


def test_oblique_walls_are_found_with_the_bearing_noise() -> None:
    """12 mm between the sweeps' bearings (MIT CSAIL's log reads 5.2 mrad of bearing noise): with
    the estimated bearing noise all six walls are found in every scan; with the range noise
    alone (sigma_bearing 0, the method before it) the oblique ones fail the chi^2 test in most
    scans. Exact bearings: the same six walls either way."""
    scans = [interlaced(OFFICE, 0.012, 0.005, seed) for seed in range(12)]
    noise = dict(sigma_r_cm=neighbour_sigma(scans))
    found = [walls_found(s, sigma_bearing=bearing_sigma(scans), **noise) for s in scans]
    without = [walls_found(s, sigma_bearing=0.0, **noise) for s in scans]
    assert min(found) == 6, found
    assert np.mean(without) <= 5.0, without
    exact = [interlaced(OFFICE, 0.0, 0.005, seed) for seed in range(4)]
    noise = dict(sigma_r_cm=neighbour_sigma(exact))
    assert [walls_found(s, sigma_bearing=bearing_sigma(exact), **noise) for s in exact] == [6] * 4


#: a hall with alcoves: walls at 1-12 m, seen head-on and obliquely in several range bands
HALL = polygon([(-1.0, -1.2), (4.0, -1.2), (4.0, -2.5), (6.0, -2.5), (6.0, -1.2), (12.0, -1.2), (12.0, 1.5),
                (7.0, 1.5), (7.0, 3.0), (3.0, 3.0), (3.0, 1.5), (-1.0, 1.5)])


def test_bearing_sigma_samples_the_whole_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """A run whose first quarter has exact bearings (the robot standing still) and the rest sweeps
    12 mrad apart (turning), read within a memory bound of 13 scans' residuals: the estimate comes
    from scans spread over the whole run (every 4th), so it reads what the unbounded run reads and
    about the offset / 2 (6 mrad). Reading only the first 13 scans (the estimator before) gave 2.0
    mrad against 6.7 unbounded."""
    import lms200.noise

    run = [interlaced(HALL, 0.0, 0.005, seed) for seed in range(12)]
    run += [interlaced(HALL, 0.012, 0.005, seed) for seed in range(12, 48)]
    whole = bearing_sigma(run)
    monkeypatch.setattr(lms200.noise, "MAX_TRIPLES", 13 * fit_residuals_and_slopes(run[0])[0].size)
    bounded = bearing_sigma(run)
    assert abs(bounded - whole) <= 0.2 * whole, (bounded, whole)
    assert 0.8 * 0.006 <= bounded <= 1.2 * 0.006, bounded


def test_bearing_sigma_is_the_same_on_parts_of_a_run() -> None:
    """Sweeps 8 mrad apart in the hall: each half and each quarter of a 24-scan run reads the
    whole run's estimate within 20 % (0.9-1.5x offset / 2)."""
    run = [interlaced(HALL, 0.008, 0.005, seed) for seed in range(24)]
    whole = bearing_sigma(run)
    assert 0.9 * 0.004 <= whole <= 1.5 * 0.004, whole
    for part in (run[:12], run[12:], run[:6], run[6:12], run[12:18], run[18:]):
        assert abs(bearing_sigma(part) - whole) <= 0.2 * whole, (bearing_sigma(part), whole)
