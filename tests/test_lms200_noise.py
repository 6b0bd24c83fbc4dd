"""lms200.noise: the range-noise / quantisation estimator against scans of known noise (analytic
lines, and the simulator's office with a moving, interlaced LMS200)."""

from __future__ import annotations

import numpy as np
import pytest

from lms200 import Scan
from lms200.noise import estimate_quantum, estimate_range_noise, interlace_stride, line_residuals

INC = np.deg2rad(0.5)
ANGLES = -np.pi / 2 + np.arange(361) * INC


def line_scan(rho: float, alpha: float, sigma: float, rng: np.random.Generator, quantum: float = 0.0) -> Scan:
    """A scan of the line x cos(alpha) + y sin(alpha) = rho (+inf where the beam misses it)."""
    c = np.cos(ANGLES - alpha)
    with np.errstate(divide="ignore"):
        r = np.where(c > 0.15, rho / c, np.inf)
    r = r + sigma * rng.standard_normal(r.size)
    if quantum:
        r = np.rint(r / quantum) * quantum
    r = np.where(r < 30, r, np.inf)
    return Scan(r, ANGLES[0], INC, 0.0, 81.83)


def line_scans(sigma: float, n: int, seed: int, quantum: float = 0.0) -> list[Scan]:
    rng = np.random.default_rng(seed)
    return [line_scan(rng.uniform(0.8, 5.0), rng.uniform(-1.2, 1.2), sigma, rng, quantum) for _ in range(n)]


def test_residual_is_zero_on_exact_lines_at_any_incidence() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        scan = line_scan(rng.uniform(0.3, 8.0), rng.uniform(-1.4, 1.4), 0.0, rng)
        for stride in (1, 2, 3):
            z, r0, centre = line_residuals(scan.ranges, INC, stride=stride)
            assert z.size > 50
            assert np.abs(z).max() < 1e-9
            assert np.array_equal(r0, scan.ranges[centre])


def test_normalised_residual_has_one_beams_sigma() -> None:
    sigma = 0.01
    z = np.concatenate([line_residuals(s.ranges, INC)[0] for s in line_scans(sigma, 200, seed=1)])
    assert np.std(z) == pytest.approx(sigma, rel=0.03)


@pytest.mark.parametrize("sigma, quantum", [(0.005, 0.0), (0.005, 0.001), (0.005, 0.01), (0.012, 0.01), (0.02, 0.01)])
def test_recovers_sigma_and_quantum_on_lines(sigma: float, quantum: float) -> None:
    est = estimate_range_noise(line_scans(sigma, 100, seed=2, quantum=quantum))
    assert est.quantum_m == quantum
    assert est.sigma_m == pytest.approx(sigma, rel=0.05)
    assert est.resolved and est.n_used > 10_000
    assert 0 < est.sigma_std_m < 0.02 * sigma


def test_standard_error_matches_the_scatter_of_repeats() -> None:
    ests = [estimate_range_noise(line_scans(0.008, 20, seed=s, quantum=0.001)) for s in range(12)]
    spread = np.std([e.sigma_m for e in ests], ddof=1)
    typical = np.median([e.sigma_std_m for e in ests])
    assert 0.5 < typical / spread < 2.0


def test_quantum_detection() -> None:
    rng = np.random.default_rng(3)
    r = rng.uniform(0.2, 40.0, 5000)
    assert estimate_quantum(r) == 0.0
    assert estimate_quantum(np.rint(r * 100) / 100) == 0.01
    assert estimate_quantum(np.rint(r * 1000) / 1000) == 0.001
    assert estimate_quantum((np.rint(r * 1000) / 1000).astype(np.float32)) == 0.001  # bag float32 values
    assert estimate_quantum(np.array([np.inf, np.nan])) == 0.0


def test_readings_beyond_range_max_leave_the_quantum_and_warn_of_nothing() -> None:
    """A stray reading of 1e308 (beyond range_max: out of limits) entered the quantum's sample, and
    1e308 / 1 mm overflowed: `lmsbench compare LOG` printed numpy's RuntimeWarning (two lines) on
    stderr. Such readings are no measurement: the estimate is that of the log without them."""
    import warnings

    clean = line_scans(0.008, 40, seed=4, quantum=0.01)
    stray = [s.replace(ranges=np.where(np.arange(len(s)) % 5 == 0, 1e308, s.ranges)) for s in clean]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = estimate_range_noise(stray)
        assert estimate_quantum(np.array([1e308, 0.5, 1.25, 2.0, 3.75] * 30)) == 0.0  # 1e308 is off every grid
    assert got.quantum_m == 0.01 == estimate_range_noise(clean).quantum_m


def test_interlace_stride() -> None:
    assert interlace_stride(np.deg2rad(1.0)) == 1
    assert interlace_stride(np.deg2rad(0.5)) == 2
    assert interlace_stride(np.deg2rad(0.25)) == 4


def test_too_few_triples_and_single_scan() -> None:
    empty = estimate_range_noise(Scan(np.full(5, np.nan), 0.0, INC, 0.0, 8.0))
    assert np.isnan(empty.sigma_m) and empty.n_used == 0 and not empty.resolved
    one = estimate_range_noise(line_scan(2.0, 0.3, 0.01, np.random.default_rng(4), 0.001))
    assert one.sigma_m == pytest.approx(0.01, rel=0.2) and np.isfinite(one.sigma_std_m)


@pytest.mark.parametrize("units, sigma", [("mm", 0.005), ("mm", 0.01), ("cm", 0.01), ("cm", 0.02)])
def test_recovers_the_simulators_noise_in_the_office(units: str, sigma: float) -> None:
    """A moving robot, interlaced 0.5 deg scans, mixed pixels, dropouts, furniture and pillars:
    the estimate stays within 10 % of the simulated sigma."""
    from sim import SensorConfig, simulate_records

    sensor = SensorConfig(units=units, noise_sigma=sigma)
    records = simulate_records("office", seed=5, duration=20.0, sensor=sensor, rate_hz=2.0)
    est = estimate_range_noise(records)
    assert est.quantum_m == sensor.unit_m
    assert est.sigma_m == pytest.approx(sigma, rel=0.10)
    # beams of neighbouring mirror turns are shifted by the motion: taking them as one line
    # would read the motion as noise
    adjacent = np.concatenate([line_residuals(r.scan.ranges, r.scan.angle_increment, stride=1)[0] for r in records])
    same_turn = np.concatenate([line_residuals(r.scan.ranges, r.scan.angle_increment)[0] for r in records])
    assert np.median(np.abs(adjacent)) > np.median(np.abs(same_turn))


def test_readings_beyond_any_rangefinder_are_not_used_and_overflow_nothing() -> None:
    """A Scan takes range_max up to 1e308: readings of 1e160 m and more overflowed the triples'
    products (r- r+, a RuntimeWarning, an error under this suite's filter) and those of 1e100 m the
    float32 the residuals are kept in. Readings of 10 km or more are not used now: no triple, sigma
    nan; the same scans at 2 m give the noise as before."""
    from lms200 import Scan
    from lms200.noise import MAX_USED_RANGE_M, estimate_range_noise

    assert MAX_USED_RANGE_M == 10_000.0
    inc = np.pi / 360
    for scale in (1e300, 1e160, 1e100):
        scans = [Scan(np.full(361, scale) * (1 + np.random.default_rng(i).normal(0, 1e-3, 361)), -np.pi / 2, inc, 0.0, 1e308)
                 for i in range(5)]
        noise = estimate_range_noise(scans)
        assert noise.n_used == 0 and np.isnan(noise.sigma_m)
    scans = [Scan(2.0 * (1 + np.random.default_rng(i).normal(0, 1e-3, 361)), -np.pi / 2, inc, 0.0, 1e308) for i in range(5)]
    assert estimate_range_noise(scans).sigma_m == pytest.approx(0.00196, abs=2e-5)
