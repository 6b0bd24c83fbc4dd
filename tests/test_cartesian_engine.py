"""The compiled split_merge and iepf against an independent oracle: every line is the
total-least-squares fit (by eigen-decomposition of the scatter matrix) of the valid points of its
beams, with the covariance of that fit, its endpoints the projections of its end points, and
every corner the intersection of its two lines; on simulated worlds, noisy rooms with dropouts,
other resolutions and degenerate scans."""

from __future__ import annotations

import numpy as np
import pytest

from features import FeatureSet, extract
from lms200 import Scan
from sensor_geometry import cast, room

METHODS = ("split_merge", "iepf")
SIGMA = 0.005  # the methods' default sigma (m)


def tls_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(rho >= 0, alpha, 2x2 covariance) of the total-least-squares line through the points."""
    mx, my = x.mean(), y.mean()
    scatter = np.cov(np.vstack((x - mx, y - my)), bias=True) * x.size
    values, vectors = np.linalg.eigh(scatter)
    nx, ny = vectors[:, 0]  # normal: the direction of least scatter
    rho = mx * nx + my * ny
    if rho < 0:
        nx, ny, rho = -nx, -ny, -rho
    alpha = np.arctan2(ny, nx)
    t = -mx * np.sin(alpha) + my * np.cos(alpha)
    var_a = SIGMA**2 / values[1]
    cov = np.array([[SIGMA**2 / x.size + t * t * var_a, t * var_a], [t * var_a, var_a]])
    return rho, alpha, cov


def check(scan: Scan, **params) -> int:
    """Both methods on ``scan`` against the oracle; returns the number of lines checked."""
    found = 0
    valid = scan.valid
    with np.errstate(invalid="ignore"):
        x, y = scan.ranges * np.cos(scan.angles), scan.ranges * np.sin(scan.angles)
    for method in METHODS:
        fs: FeatureSet = extract(scan, method=method, **params)
        for line in fs.lines:
            beams = np.flatnonzero(valid[line.first : line.last + 1]) + line.first
            assert beams.size == line.n_points and valid[line.first] and valid[line.last]
            rho, alpha, cov = tls_fit(x[beams], y[beams])
            assert line.rho == pytest.approx(rho, abs=1e-9)
            assert abs(np.angle(np.exp(1j * (line.alpha - alpha)))) < 1e-8
            assert -np.pi < line.alpha <= np.pi
            np.testing.assert_allclose(line.cov, cov, rtol=1e-6, atol=1e-14)
            for (px, py), j in ((line.start, line.first), (line.end, line.last)):
                off = x[j] * np.cos(line.alpha) + y[j] * np.sin(line.alpha) - line.rho
                np.testing.assert_allclose((px, py), (x[j] - off * np.cos(line.alpha), y[j] - off * np.sin(line.alpha)),
                                           atol=1e-9)
            found += 1
        for c in fs.corners:
            a, b = (fs.lines[i] for i in c.lines)
            assert c.lines[1] == c.lines[0] + 1 and c.index == a.last
            for line in (a, b):
                assert c.x * np.cos(line.alpha) + c.y * np.sin(line.alpha) == pytest.approx(line.rho, abs=1e-9)
            assert 0 < c.angle < np.pi
    return found


@pytest.mark.parametrize("world", ["office", "angles", "pillars"])
def test_simulated_worlds(world: str) -> None:
    sim = pytest.importorskip("sim")
    records = sim.simulate_records(world=world, seed=4, duration=30.0, rate_hz=1.0)
    assert sum(check(rec.scan) for rec in records) >= 2 * len(records)


@pytest.mark.parametrize("n, increment_deg", [(361, 0.5), (181, 1.0), (401, 0.25)], ids=["361", "181", "401"])
def test_noisy_rooms_at_every_resolution(n: int, increment_deg: float) -> None:
    assert sum(check(room(seed, n, np.deg2rad(increment_deg))) for seed in range(10)) > 20


def test_dropouts_and_other_configs() -> None:
    configs = [{}, {"runs_z": 3.0}, {"merge_rms": 0.0}, {"max_skip": 1, "min_points": 4}, {"split_threshold": 0.01}]
    rng = np.random.default_rng(11)
    for seed in range(6):
        scan = room(200 + seed)
        ranges = scan.ranges.copy()
        ranges[rng.random(ranges.size) < 0.03] = np.nan
        ranges[rng.random(ranges.size) < 0.02] = np.inf
        for params in configs:
            check(scan.replace(ranges=ranges), **params)


def test_a_cluster_longer_than_the_scan_half() -> None:
    """One straight wall over all 401 beams, and a circle (a split to the bottom)."""
    wall = cast([(2.0, -50.0, 2.0, 50.0)], n=401, angle_min=-np.deg2rad(50), increment=np.deg2rad(0.25), sigma=0.003)
    assert check(wall) == 2
    check(cast(circles=[(3.0, 0.0, 1.5)], sigma=0.002))


@pytest.mark.parametrize(
    "ranges",
    [np.full(361, np.inf), np.full(361, np.nan), np.zeros(361), np.full(361, 1e300),
     np.where(np.arange(361) == 180, 2.0, np.inf), np.array([2.0]), np.full(3, 2.0),
     np.where(np.arange(361) % 2 == 0, 2.0, np.nan)],
    ids=["inf", "nan", "zeros", "huge", "one-valid", "one-beam", "three-beams", "alternating"],
)
def test_degenerate_inputs(ranges: np.ndarray) -> None:
    check(Scan(ranges, -np.pi / 2, np.deg2rad(0.5), 0.0, 8.183))


@pytest.mark.parametrize(
    "beams, value, lines_per_method",
    [([180], np.inf, 2), ([150, 151], np.inf, 2), ([120, 240], np.inf, 3),
     ([180], np.nan, 1), ([150, 151], np.nan, 1), ([120, 240], np.nan, 1)],
)
def test_no_return_beams_break_and_invalid_beams_are_bridged(beams: list, value: float, lines_per_method: int) -> None:
    """A cluster is cut at a +inf beam; up to max_skip - 1 nan beams are stepped over."""
    wall = cast([(2.0, -3.0, 2.0, 3.0)], sigma=0.002, seed=5)
    ranges = wall.ranges.copy()
    ranges[beams] = value
    assert check(wall.replace(ranges=ranges)) == len(METHODS) * lines_per_method


def test_merged_rms_within_its_slack_of_fit_range() -> None:
    """The merge pass's cheap residual (eigenvalue formula) stays within its stated bound of
    fit_range's on noisy, rounded and far-off segments, so every merge decision is fit_range's."""
    from features.baselines import engine

    rng = np.random.default_rng(1)
    worst = 0.0
    for trial in range(300):
        n = 120
        t = np.linspace(0.0, rng.uniform(0.1, 5.0), n)
        a = rng.uniform(-np.pi, np.pi)
        off = rng.uniform(-1.0, 1.0, 2) * 10 ** rng.uniform(0, 6)
        x = off[0] + t * np.cos(a) + rng.normal(0, 10 ** rng.uniform(-9, -1), n)
        y = off[1] + t * np.sin(a) + rng.normal(0, 10 ** rng.uniform(-9, -1), n)
        if trial % 2:
            x, y = np.round(x, 3), np.round(y, 3)
        sums = [np.concatenate([[0.0], np.cumsum(v)]) for v in (x, y, x * x, y * y, x * y)]
        for _ in range(5):
            s = int(rng.integers(0, n - 3))
            e = int(rng.integers(s + 2, n))
            approx, slack = engine.merged_rms(*sums, s, e)
            exact = engine.exact_rms(*sums, s, e)
            worst = max(worst, abs(approx - exact) / slack)
    assert worst < 0.01


def test_length_at_least_decides_as_hypot() -> None:
    """The segment length test (sqrt of the squares, hypot only near the limit or outside the
    normal range of squares) decides as the compiled ``math.hypot(dx, dy) >= limit`` it replaced
    (libm's hypot; Python's own math.hypot rounds differently in the last ulp) on lengths at the
    limit to the last ulp, tiny, huge, zero and nan lengths and limits."""
    import math

    from features.baselines import engine
    from lms200.numba_required import numba

    hypot_reaches = numba.njit(lambda dx, dy, limit: math.hypot(dx, dy) >= limit)

    rng = np.random.default_rng(7)
    cases = []
    for _ in range(3000):
        limit = float(10 ** rng.uniform(-3, 3))
        a = rng.uniform(0, 2 * np.pi)
        length = limit * float(1 + rng.choice([0.0, 1e-16, -1e-16, 3e-16, -3e-16, 1e-13, -1e-13, 1e-9]))
        cases.append((length * math.cos(a), length * math.sin(a), limit))
    cases += [(0.0, 0.0, 0.0), (0.0, 0.0, 1e-300), (1e-200, 0.0, 1e-300), (1e-200, 1e-200, 1.5e-200),
              (1e200, 1e200, 1e200), (1e300, 1e300, np.inf), (np.inf, 0.0, 1.0), (np.nan, 1.0, 1.0),
              (1.0, 1.0, np.nan), (3.0, 4.0, 5.0), (3.0, 4.0, 5.000000000000001), (3.0, 4.0, -1.0)]
    got = [engine.length_at_least(dx, dy, lim) for dx, dy, lim in cases]
    want = [hypot_reaches(dx, dy, lim) for dx, dy, lim in cases]
    assert got == want
    assert 0 < sum(want) < len(want)  # both outcomes met
