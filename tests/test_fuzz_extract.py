"""Property-based robustness of ``lms200.Scan`` and of ``features.extract`` / ``extract_many`` for
every registered method (the sensor method alone has its own, wider property in test_sensor_props).

Arbitrary range arrays (nan, +-inf, 0, negative, denormals, 1e300, all equal, alternating) on the
supported geometries either make a Scan whose features are well formed (finite rho >= 0, alpha in
(-pi, pi], finite covariances, beam spans inside the scan) or are refused at construction with a
ScanError naming the field; ``extract_many`` equals ``extract`` scan by scan."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from features import FeatureSet, available_methods, extract, extract_many
from features.errors import ConfigError, ScanGeometryError
from lms200 import Scan
from lms200.errors import LmsbenchError, ScanError

SPECIAL = [0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, 2.2e-308, 1e-300, 1e300, 1.7e308, 1e-3, 8.183, 81.83, 2.5, -1.0]
GEOMETRIES = [  # (beams, angle_min, increment, range_max): the LMS200 variants and other scanners
    (361, -np.pi / 2, np.deg2rad(0.5), 8.183),
    (181, -np.pi / 2, np.deg2rad(1.0), 81.83),
    (401, -np.deg2rad(50), np.deg2rad(0.25), 8.183),
    (101, -np.deg2rad(50), np.deg2rad(1.0), 81.83),
    (360, -np.pi, 2 * np.pi / 360, 30.0),
    (7, 0.0, 0.3, 8.183),
]
SETTINGS = dict(max_examples=150, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@st.composite
def range_arrays(draw: st.DrawFn, n: int) -> np.ndarray:
    kind = draw(st.sampled_from(["special", "constant", "alternating", "walls", "walls+special", "floats"]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if kind == "special":
        r = rng.choice(SPECIAL, n)
    elif kind == "constant":
        r = np.full(n, draw(st.sampled_from(SPECIAL)))
    elif kind == "alternating":
        a, b = draw(st.sampled_from(SPECIAL)), draw(st.sampled_from(SPECIAL))
        r = np.where(np.arange(n) % 2 == 0, a, b)
    elif kind == "floats":
        r = np.array(draw(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=n, max_size=n)))
    else:  # piecewise walls with noise, some beams replaced by special values
        r = np.abs(np.repeat(rng.uniform(0.1, 20.0, 1 + n // 30), 30)[:n] + rng.normal(0, 0.01, n))
        if kind == "walls+special":
            hits = rng.random(n) < 0.15
            r[hits] = rng.choice(SPECIAL, int(hits.sum()))
    return np.asarray(r, dtype=np.float64)


@st.composite
def geometries(draw: st.DrawFn) -> tuple:
    """One of GEOMETRIES, or any other a Scan takes: a beam count, a start within +-2 pi, a step
    from 1e-6 rad to a full turn over the beams, range_max from 0.1 m to 1e308 m."""
    if draw(st.booleans()):
        return draw(st.sampled_from(GEOMETRIES))
    n = draw(st.integers(1, 1200))
    inc = draw(st.floats(1e-6, 2 * np.pi / max(n - 1, 1)))
    amin = draw(st.floats(-2 * np.pi, 2 * np.pi))
    rmax = draw(st.sampled_from([0.1, 8.183, 81.83, 1e4, 1e308]))
    return n, amin, inc, rmax


@st.composite
def cases(draw: st.DrawFn) -> tuple[np.ndarray, tuple]:
    geometry = draw(geometries())
    return draw(range_arrays(geometry[0])), geometry


def make_scan(r: np.ndarray, geometry: tuple, stamp: float = 0.0) -> Scan | None:
    """The Scan, or None when the Scan refuses the ranges, which only negative finite ones may cause."""
    n, amin, inc, rmax = geometry
    try:
        return Scan(r, amin, inc, 0.0, rmax, stamp)
    except ScanError as exc:
        assert str(exc).startswith("ranges: negative ranges"), exc
        assert np.any(np.isfinite(r) & (r < 0))
        return None


def check_well_formed(fs: FeatureSet, scan: Scan) -> None:
    assert isinstance(fs, FeatureSet)
    n = len(scan)
    lines = fs.lines
    assert np.isfinite(lines.rho).all() and (lines.rho >= 0).all()
    assert np.all((lines.alpha > -np.pi) & (lines.alpha <= np.pi))
    assert np.isfinite(lines.start).all() and np.isfinite(lines.end).all()
    assert np.isfinite(lines.cov).all() and lines.cov.shape == (len(lines), 2, 2)
    assert np.all((0 <= lines.first) & (lines.first <= lines.last) & (lines.last < n))
    assert np.all(lines.n_points <= lines.last - lines.first + 1)
    for c in fs.corners:
        assert np.isfinite([c.x, c.y]).all() and 0 < c.angle < np.pi
        assert 0 <= c.lines[0] < c.lines[1] < len(lines)
        assert 0 <= c.index < n


def step_too_coarse(method: str, scan: Scan) -> bool:
    """Whether the method's default config cannot segment the scan: a baseline's breakpoint_lambda
    (10 deg) not above the beam step, below 90 deg (``features.registry.step_problem``)."""
    return method != "sensor" and np.deg2rad(10.0) <= scan.angle_increment < np.pi / 2


def check_step_refusal(exc: ConfigError, method: str, scan: Scan) -> None:
    """A ConfigError of extract is the step mismatch, and only for such a scan."""
    assert step_too_coarse(method, scan), exc
    assert str(exc).startswith(f"scan: the beam step {np.rad2deg(scan.angle_increment):.6g} deg is not below "
                               f"{method}'s breakpoint_lambda 10 deg (0.174533 rad): "), exc
    assert "; set breakpoint_lambda above the step, e.g. " in str(exc), exc


def same(a: FeatureSet, b: FeatureSet) -> bool:
    return (np.array_equal(a.lines.values, b.lines.values, equal_nan=True)
            and np.array_equal(a.lines.beams, b.lines.beams)
            and np.array_equal(a.corners.values, b.corners.values, equal_nan=True)
            and len(a.corners) == len(b.corners)
            and all(x.index == y.index and x.lines == y.lines for x, y in zip(a.corners, b.corners)))


@pytest.mark.parametrize("method", available_methods())
@settings(**SETTINGS)
@given(case=cases())
def test_any_ranges_give_well_formed_features_or_a_scan_error(method: str, case) -> None:  # noqa: ANN001
    r, geometry = case
    scan = make_scan(r, geometry)
    if scan is None:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning (overflow, inf * 0) is a defect too
        try:
            fs = extract(scan, method=method)
        except ScanGeometryError as exc:  # what the method cannot take: a step too fine for its grid, a
            # range too large for hough's accumulator; the message names the field or the method
            assert str(exc).startswith(("angle_increment: ", "scan: ", f"{method}: ")), exc
            return
        except ConfigError as exc:  # a baseline's default breakpoint_lambda not above the step: it would find nothing
            check_step_refusal(exc, method, scan)
            return
    assert not step_too_coarse(method, scan)
    check_well_formed(fs, scan)


@pytest.mark.parametrize("method", available_methods())
@settings(**{**SETTINGS, "max_examples": 30})
@given(batch=st.tuples(geometries(), st.integers(1, 4)).flatmap(
    lambda gk: st.tuples(st.just(gk[0]), st.lists(range_arrays(gk[0][0]), min_size=gk[1], max_size=gk[1]))))
def test_extract_many_equals_extract_scan_by_scan(method: str, batch) -> None:  # noqa: ANN001
    geometry, arrays = batch
    scans = [s for i, r in enumerate(arrays) if (s := make_scan(r, geometry, stamp=float(i))) is not None]
    try:
        many = extract_many(scans, method=method)
    except ScanGeometryError as exc:  # the error extract gives on one of the scans
        messages = []
        for s in scans:
            try:
                extract(s, method=method)
            except ScanGeometryError as one:
                messages.append(str(one))
        assert str(exc) in messages
        return
    except ConfigError as exc:  # as extract refuses each of them
        assert scans
        check_step_refusal(exc, method, scans[0])
        return
    assert len(many) == len(scans)
    for s, fs in zip(scans, many):
        one = extract(s, method=method)
        check_well_formed(fs, s)
        assert same(fs, one)


@settings(**{**SETTINGS, "max_examples": 200})
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=0, max_size=40),
       st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True, allow_infinity=True),
       st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True, allow_infinity=True))
def test_a_scan_is_made_or_refused_with_a_scan_error(ranges, amin, inc, rmin, rmax) -> None:  # noqa: ANN001
    try:
        scan = Scan(np.array(ranges, dtype=np.float64), amin, inc, rmin, rmax)
    except LmsbenchError as exc:
        assert isinstance(exc, ScanError) and isinstance(exc, ValueError)
        assert str(exc).split(":")[0] in ("ranges", "angle_min", "angle_increment", "range_min", "range_max", "stamp"), exc
        return
    assert len(scan) == len(ranges) >= 1
    assert np.isfinite([scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max]).all()
    assert scan.angle_increment > 0 and 0 <= scan.range_min < scan.range_max
    v = scan.valid
    assert np.all(np.isfinite(scan.ranges[v])) and np.all(scan.ranges[v] > 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pts = scan.points
    assert np.isfinite(pts[v]).all() and np.isnan(pts[~v]).all()
