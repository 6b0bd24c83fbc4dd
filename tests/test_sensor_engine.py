"""The one implementation of the sensor method against the independent oracle (``sensor_oracle``):
per-beam signals on simulated worlds, noisy rooms with dropouts, other resolutions and any scan
a Scan accepts; and the engine's handling of degenerate scans."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sensor_oracle
from features import extract
from features.sensor import signals
from lms200 import Scan
from sensor_geometry import room
from test_sensor_props import scans


def assert_signals_match(scan: Scan, k: int) -> int:
    """The engine's signals of ``scan`` equal the oracle's (nan in the same places); returns how
    many beams have a finite AD."""
    got = signals(scan, k=k)
    ref = sensor_oracle.signals(scan.ranges, scan.angles, scan.angle_increment, k, max(scan.range_min, 0.02),
                                scan.range_max)
    for name, key in (("ad", "AD"), ("ad_slope", "ad")):
        np.testing.assert_array_equal(np.isnan(got[name]), np.isnan(ref[key]), err_msg=name)
        np.testing.assert_allclose(got[name], ref[key], rtol=1e-9, atol=1e-9, equal_nan=True, err_msg=name)
    on = np.isfinite(ref["theta"])
    np.testing.assert_array_equal(np.isfinite(got["theta"]), on)
    err = np.angle(np.exp(1j * (got["theta"][on] - ref["theta"][on])))
    assert np.abs(err).max(initial=0.0) < 1e-9
    fin = np.isfinite(ref["psi"])
    np.testing.assert_array_equal(np.isfinite(got["psi"]), fin)
    assert np.abs(np.angle(np.exp(1j * (got["psi"][fin] - ref["psi"][fin])))).max(initial=0.0) < 1e-9
    assert got["ad_line"] == pytest.approx(ref["ad_line"], abs=1e-12)
    return int(np.isfinite(got["ad"]).sum())


@pytest.mark.parametrize("world", ["office", "angles", "pillars"])
def test_signals_on_simulated_worlds(world: str) -> None:
    sim = pytest.importorskip("sim")
    records = sim.simulate_records(world=world, seed=3, duration=20.0, rate_hz=1.0)
    assert sum(assert_signals_match(rec.scan, 3) for rec in records) > 100 * len(records)


@pytest.mark.parametrize("n, increment_deg", [(361, 0.5), (181, 1.0), (401, 0.25), (180, 1.0)])
@pytest.mark.parametrize("k", [1, 3, 10])
def test_signals_on_noisy_rooms_with_dropouts(n: int, increment_deg: float, k: int) -> None:
    rng = np.random.default_rng(n + k)
    for seed in range(5):
        scan = room(seed, n, np.deg2rad(increment_deg))
        ranges = scan.ranges.copy()
        ranges[rng.random(n) < 0.03] = np.nan
        ranges[rng.random(n) < 0.02] = np.inf
        assert_signals_match(scan.replace(ranges=ranges), k)


@settings(max_examples=100, deadline=None)
@given(scans(), st.integers(1, 12))
def test_signals_of_any_scan(scan: Scan, k: int) -> None:
    assert_signals_match(scan, k)


@pytest.mark.parametrize(
    "ranges",
    [
        np.full(361, np.inf),
        np.full(361, np.nan),
        np.zeros(361),
        np.full(361, 1e300),
        np.where(np.arange(361) == 180, 2.0, np.inf),
        np.array([2.0]),
        np.full(7, 2.0),
        np.where(np.arange(361) % 2 == 0, 2.0, np.nan),
        np.full(361, 0.5),
    ],
    ids=["inf", "nan", "zeros", "huge", "one-valid", "one-beam", "seven-beams", "alternating", "circle"],
)
def test_degenerate_inputs_give_no_features(ranges: np.ndarray) -> None:
    got = extract(Scan(ranges, -np.pi / 2, np.deg2rad(0.5), 0.0, 8.183), method="sensor")
    assert got.lines == [] and got.corners == []


def test_wide_circle_pieces_are_chords_within_the_noise() -> None:
    """The sensor at the centre of a round room of radius 2 m: the run that spans it bends, so it
    is split (at the beam farthest from its chord) until its pieces fit lines. A piece of 0.4 m lies
    within 1 cm of its chord (the pillars world's curved wall makes the same point), so the pieces
    are lines within two noise sigmas of every beam they hold, and no corners."""
    scan = Scan(np.full(361, 2.0), -np.pi / 2, np.deg2rad(0.5), 0.0, 8.183)
    got = extract(scan, method="sensor")
    assert got.corners == []
    for line in got.lines:
        beams = np.arange(line.first, line.last + 1)
        predicted = line.rho / np.cos(scan.angles[beams] - line.alpha)
        assert np.abs(scan.ranges[beams] - predicted).max() < 2 * 0.005
        assert line.length < 0.6


def test_medians_and_pairwise_sums_equal_numpys() -> None:
    """The engine's median (quickselect, branchless three-way partitions) and pairwise sums (fixed levels up
    to 1,928 terms, an explicit stack beyond) equal numpy's bit for bit: ties, constant, sorted and
    reversed data, even and odd sizes, sums across the levels' limits."""
    from features.sensor import engine

    rng = np.random.default_rng(12)
    for n in (1, 2, 3, 8, 9, 40, 64, 65, 128, 129, 300, 301, 1000):
        for data in (rng.standard_normal(n), np.round(rng.standard_normal(n), 1), np.full(n, 0.25),
                     np.sort(rng.standard_normal(n)), np.sort(rng.standard_normal(n))[::-1].copy()):
            assert engine.median(data) == np.median(data)
    for n in (1, 2, 7, 64, 361):  # a nan anywhere (the check has no early exit) gives nan, as numpy's does
        for at in {0, n // 2, n - 1}:
            data = rng.standard_normal(n)
            data[at] = np.nan
            assert np.isnan(engine.median(data)) and np.isnan(np.median(data))
            data[at] = np.inf  # infinities are values, not nan
            assert engine.median(data) == np.median(data)
    a = rng.standard_normal(8000) * np.exp(rng.standard_normal(8000) * 4)
    for n in (0, 7, 8, 127, 128, 129, 248, 249, 488, 489, 968, 969, 1928, 1929, 3848, 3849, 7999):
        assert engine.pairwise_sum(a, 1, n) == (np.add.reduce(a[1:1 + n]) if n else 0.0)


def test_log_ranges_within_one_ulp_of_libm() -> None:
    """The engine's vectorised log (Cephes' log.c) of the ranges is within one ulp of numpy's (libm's)
    log on positive normal values of 1e-300 .. 1e300, ranges of 1 mm - 100 m and values next to 1 and
    to powers of two; most are equal bit for bit."""
    from features.sensor import engine

    rng = np.random.default_rng(14)
    x = np.concatenate([rng.uniform(0.001, 100.0, 200_000), 10 ** rng.uniform(-300, 300, 50_000),
                        1.0 + rng.normal(0.0, 1e-6, 20_000), 2.0 ** rng.integers(-1000, 1000, 2_000),
                        np.nextafter(2.0 ** rng.integers(-60, 60, 2_000), 0.0), [1.0, 2.0, 0.5, 0.7071067811865476]])
    got = engine.log_ranges(x)
    ref = np.log(x)
    ulps = np.abs(got - ref) / np.spacing(np.abs(ref) + np.finfo(float).tiny)
    assert ulps.max() <= 1.0
    assert np.mean(got == ref) > 0.9
    assert got[-4] == 0.0 and got[-3] == np.log(2.0)


def test_quantum_step_equals_lms200s() -> None:
    """The engine's quantisation step (a step given up at the first value off its grid that decides
    it) equals lms200.noise.estimate_quantum: every candidate grid and continuous values, with off-grid
    counts either side of the 99 % share (sizes 1-1000), nan and non-positive values among them."""
    from features.sensor import engine
    from lms200.noise import QUANTUM_CANDIDATES_M, estimate_quantum

    rng = np.random.default_rng(13)
    found = set()
    for n in (1, 2, 50, 72, 100, 101, 199, 200, 201, 1000):
        for q in (*QUANTUM_CANDIDATES_M, 0.0):
            for off in sorted({0, 1, 2, n // 100, n // 100 + 1, n // 50}):
                x = rng.uniform(0.05, 30.0, n)
                if q:
                    x = np.rint(x / q) * q
                at = rng.choice(n, min(off, n), replace=False)
                x[at] += 1.3e-4 + rng.uniform(0.0, 1e-3, at.size)
                x[rng.random(n) < 0.05] = np.nan
                if n > 3:
                    x[0] = -1.0
                got = engine.quantum_step(x)
                assert got == estimate_quantum(x)
                found.add(got)
    assert found == {*QUANTUM_CANDIDATES_M, 0.0}  # every outcome occurs


def test_no_extractor_kernel_is_compiled_with_fast_math() -> None:
    """Fast-math (even reassociation alone) lets LLVM group sums by the CPU's vector width, so the
    same scan gave other bits on another machine (109 of 120 MIT CSAIL scans between an AVX-512
    build and a generic x86-64 one); outputs must not depend on the machine."""
    import numba

    import features.baselines.engine as cartesian
    import features.sensor.engine as sensor
    import sim.hits
    import sim.nearest
    import slam.icpkernel

    kernels = [(mod.__name__, name, obj) for mod in (sensor, cartesian, sim.hits, sim.nearest, slam.icpkernel)
               for name, obj in vars(mod).items() if isinstance(obj, numba.core.registry.CPUDispatcher)]
    assert len(kernels) > 40
    fast = [f"{m}.{n}" for m, n, k in kernels if k.targetoptions.get("fastmath")]
    assert fast == []


def first_pass_beams(scan: Scan, cfg) -> int:  # noqa: ANN001
    """Beams of find_lines' first pass on ``scan``: its candidate runs of window centres, each
    grown by k beams at both ends (as find_lines makes its first spans)."""
    from features.sensor import engine  # noqa: PLC0415
    from features.sensor.grid import grid_constants  # noqa: PLC0415

    p = cfg.params
    grid = grid_constants(p.k, scan.angle_increment, p.hough_subdiv)
    sigma = float(cfg.sigma_for(scan.range_max))
    _, sig = engine.signal_block(scan.ranges, scan.angles, p.k, max(scan.range_min, cfg.min_range), scan.range_max, sigma,
                                 grid.two_sin_sum)
    c0, c1 = engine.candidate_runs(sig, p.k, grid.ad_line, sigma, p)
    grown = c1 - c0 + 2 * p.k + 1
    return int(grown[grown >= min(p.min_points, 2 * p.k + 1)].sum())


def test_overlapping_first_pass_spans_fit_the_scratch_blocks() -> None:
    """Centre runs a beam or two apart grow into spans that overlap, so a pass can hold more beams
    than the scan (366 of 361 on an office scan): find_lines sizes its scratch blocks by the first
    pass (sized by the scan's beams, the kernel wrote past a row and changed lines by up to 4 mm;
    fit_spans now refuses a pass larger than its blocks). The lines are those of a single call."""
    sim = pytest.importorskip("sim")
    from features import extract_many, make_config  # noqa: PLC0415

    cfg = make_config("sensor")
    scans = [rec.scan for rec in sim.simulate_records(world="office", seed=0, duration=12.0)][:300]
    over = [s for s in scans if first_pass_beams(s, cfg) > len(s)]
    assert len(over) >= 1, "no office scan whose first-pass spans overlap: the test needs a new source of them"
    for scan, many in zip(over, extract_many(over, "sensor", cfg)):
        one = extract(scan, "sensor", cfg)
        np.testing.assert_array_equal(one.lines.values, many.lines.values)
        assert len(one.lines) >= 3


@pytest.mark.parametrize("angle_min", [0.0, -2 * np.pi])
def test_a_corner_s_beam_is_its_bearing_s_beam_on_a_scan_past_pi(angle_min: float) -> None:
    """A 720-beam 360 deg scan (0.5 deg) of the L room with 5 mm noise, its bearings from 0 to 2 pi
    (or the same from -2 pi to 0): each corner's beam is the beam of its bearing, counted from the
    first beam modulo a full turn. atan2 gives bearings in (-pi, pi], and taken as they were, beam
    indices past pi (angle_min 0) came out negative and those before -pi (angle_min -2 pi) past the
    scan: each clamped onto a line's end, the corner at 264.8 deg read as beam 529, not 530 (and
    from -2 pi, 136 and 354 as 137 and 355)."""
    from experiments.synthetic import L_ROOM, cast

    inc = np.pi / 360
    ranges = cast(L_ROOM, (0.5, 0.5, 1.0), np.arange(720) * inc)[0]
    ranges = ranges + np.random.default_rng(0).normal(0.0, 0.005, ranges.size)
    fs = extract(Scan(ranges, angle_min, inc, 0.0, 8.0), method="sensor")
    assert fs.corners.beams[:, 0].tolist() == [136, 354, 530, 605, 683]
    bearing_beams = np.mod(np.arctan2(fs.corners.y, fs.corners.x), 2 * np.pi) / inc
    np.testing.assert_array_equal(fs.corners.beams[:, 0], np.rint(bearing_beams))


def test_a_corner_bearing_just_before_the_first_beam_stays_at_the_scan_s_start() -> None:
    """The ``corners`` kernel on two lines made to meet at a bearing 0.3 beams before the first beam
    (line 0 over beams 0-2 runs along x = -7.9 mm, nearly radial there; line 1 from beam 4 along
    y = -3 m): the corner's beam is line 0's last (2), the nearest of its bearing's three beams a
    full turn apart (-0.3, -720.3, 719.7). A wrap of every bearing into [angle_min, angle_min + 2 pi)
    read 719.7 and clamped it onto line 1's first beam (4), the other line."""
    from features.sensor.config import SensorMethodConfig
    from features.sensor.engine import S_PSI, corners

    n, inc, angle_min = 361, np.deg2rad(0.5), -np.pi / 2
    b = angle_min - 0.3 * inc  # the corner's bearing
    cx, cy = 3.0 * np.tan(b + np.pi / 2), -3.0  # on y = -3, at bearing b
    # rows: rho, alpha, start x, y, end x, y, cov (4); line 0 ends 0.1 m before the corner, line 1
    # starts at beam 4's hit on y = -3
    start_1 = 3.0 / np.cos(4 * inc)  # the range of beam 4 (2 deg past -90 deg) on y = -3
    lv = np.array([[-cx, np.pi, cx, cy - 1.0, cx, cy + 0.1, 1e-6, 0.0, 0.0, 1e-6],
                   [3.0, -np.pi / 2, start_1 * np.cos(angle_min + 4 * inc), -3.0, 2.0, -3.0, 1e-6, 0.0, 0.0, 1e-6]])
    lb = np.array([[0, 2], [4, 40]], np.int64)
    sig = np.full((11, n), np.nan)
    sig[S_PSI] = np.pi / 2  # the turn shows in psi everywhere
    ranges = np.full(n, 3.0)
    valid = np.ones(n, np.bool_)
    p = SensorMethodConfig(acute_check=False).params
    values, beams = corners(lv, lb, sig, ranges, valid, angle_min, inc, 0.01, p)
    assert len(beams) == 1
    assert values[0, 0] == pytest.approx(cx, abs=1e-12) and values[0, 1] == pytest.approx(cy, abs=1e-12)
    assert values[0, 2] == pytest.approx(np.pi / 2, abs=1e-9)
    assert beams[0].tolist() == [2, 0, 1]
