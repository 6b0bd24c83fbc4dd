"""The Scan type and the SICK special codes."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from lms200 import InputError, Scan, codes_to_ranges, decode_logged_ranges, ranges_to_codes
from lms200.scan import snap_angle


def test_lms200_default_geometry() -> None:
    s = Scan.lms200(np.full(361, 2.0), stamp=3.5)
    assert len(s) == 361
    assert s.angle_min == pytest.approx(-np.pi / 2, abs=1e-15)
    assert s.angle_max == pytest.approx(np.pi / 2, abs=1e-12)
    assert s.angles[180] == pytest.approx(0.0, abs=1e-12)
    assert np.diff(s.angles) == pytest.approx(np.deg2rad(0.5))
    assert s.stamp == 3.5
    # beam 0 looks to the right (-y), beam 180 ahead (+x), beam 360 to the left (+y)
    np.testing.assert_allclose(s.points[[0, 180, 360]], [[0, -2], [2, 0], [0, 2]], atol=1e-12)


def test_points_and_valid_follow_rep117() -> None:
    s = Scan(np.array([1.0, np.inf, np.nan, 0.05, 9.0]), 0.0, 0.1, 0.1, 8.0)
    np.testing.assert_array_equal(s.valid, [True, False, False, False, False])
    assert np.isnan(s.points[1:]).all()
    np.testing.assert_allclose(s.points[0], [1.0, 0.0])


def test_a_zero_range_is_never_valid() -> None:
    """Loggers write 0 for a missing reading: with range_min 0 (CARMEN scans) it is still invalid."""
    s = Scan(np.array([0.0, 1e-9, 1.0, 0.0]), 0.0, 0.1, 0.0, 8.0)
    np.testing.assert_array_equal(s.valid, [False, True, True, False])
    assert np.isnan(s.points[[0, 3]]).all()


def test_scan_is_immutable_and_copies_its_input() -> None:
    r = np.ones(5)
    s = Scan(r, 0.0, 0.1, 0.0, 10.0)
    r[0] = 7.0
    assert s.ranges[0] == 1.0
    with pytest.raises(ValueError):
        s.ranges[0] = 3.0
    with pytest.raises(AttributeError):
        s.angle_min = 1.0  # type: ignore[misc]
    assert s.replace(stamp=2.0).stamp == 2.0 and s.replace(stamp=2.0) != s
    assert Scan(np.ones(5), 0.0, 0.1, 0.0, 10.0) == s



@pytest.mark.parametrize("how", ["pickle", "pickle protocol 0", "deepcopy"])
def test_a_copied_or_unpickled_scan_stays_immutable(how: str) -> None:
    """pickle restores arrays writable: an unpickled Scan (a sweep's worker gets its scans so) could
    be changed in place, and its ranges typed differently in the extractors' compiled calls."""
    s = Scan(np.array([1.0, 2.0, np.inf, np.nan, 3.0]), -0.2, 0.1, 0.0, 10.0, stamp=4.5)
    t = {"pickle": lambda: pickle.loads(pickle.dumps(s)),
         "pickle protocol 0": lambda: pickle.loads(pickle.dumps(s, protocol=0)),
         "deepcopy": lambda: copy.deepcopy(s)}[how]()
    with pytest.raises(ValueError, match="read-only"):
        t.ranges[0] = 3.0
    with pytest.raises(ValueError, match="read-only"):
        t.angles[0] = 3.0
    assert t == s and t.stamp == 4.5 and t.angle_min == -0.2
    np.testing.assert_array_equal(t.angles, s.angles)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        (dict(ranges=np.ones((2, 3))), "ranges"),
        (dict(ranges=np.array([1.0, -0.5])), "ranges"),
        (dict(ranges=np.array([])), "ranges"),
        (dict(ranges=["a", "b"]), "ranges"),
        (dict(angle_increment=0.0), "angle_increment"),
        (dict(angle_increment=-0.01), "angle_increment"),
        (dict(angle_min=np.nan), "angle_min"),
        (dict(range_min=-1.0), "range_min"),
        (dict(range_max=0.0), "range_max"),
        (dict(stamp=np.inf), "stamp"),
    ],
)
def test_inconsistent_fields_raise_naming_the_field(kwargs: dict, field: str) -> None:
    base = dict(ranges=np.ones(3), angle_min=0.0, angle_increment=0.01, range_min=0.0, range_max=8.0)
    base.update(kwargs)
    with pytest.raises(ValueError, match=f"^{field}"):
        Scan(**base)


def test_degrees_given_as_radians_are_refused_and_a_full_turn_is_kept() -> None:
    with pytest.raises(ValueError, match=r"^angle_increment: 361 beams 0.5 rad apart span 180 rad.*degrees given"):
        Scan(np.ones(361), -1.5, 0.5, 0.0, 8.0)  # a SICK sweep written in degrees
    with pytest.raises(ValueError, match=r"^angle_min: .*-90 deg is -1.5708 rad"):
        Scan(np.ones(361), -90.0, np.deg2rad(0.5), 0.0, 8.0)
    full = Scan(np.ones(720), -np.pi, 2 * np.pi / 720, 0.0, 8.0)  # a 360 deg lidar: 719 steps < 2 pi
    assert full.angle_max < np.pi
    Scan(np.ones(721), -np.pi, 2 * np.pi / 720, 0.0, 8.0)  # first and last beam on the same bearing
    inc32 = float(np.float32(2 * np.pi / 360) * np.float32(1 + 1e-7))  # a ROS float32 increment, rounded up
    Scan(np.ones(362), -np.pi, inc32, 0.0, 8.0)  # a driver that repeats the first beam at the end
    with pytest.raises(ValueError, match="^angle_increment: 364 beams"):
        Scan(np.ones(364), -np.pi, inc32, 0.0, 8.0)


def test_lms200_constructor_checks_beam_count() -> None:
    with pytest.raises(ValueError, match="ranges"):
        Scan.lms200(np.ones(180))


def test_sick_codes_map_the_rep117_way() -> None:
    codes = np.array([0, 1234, 8182, 8183, 8186, 8187, 8189, 8190, 8191, 8183 | 0x8000])
    mm = codes_to_ranges(codes, "mm")
    np.testing.assert_allclose(mm[:3], [0.0, 1.234, 8.182])
    assert np.isposinf(mm[3]) and np.isposinf(mm[9])  # flag bits are masked off
    assert np.isnan(mm[4:9]).all()
    cm = codes_to_ranges(codes, "cm")
    np.testing.assert_allclose(cm[:3], [0.0, 12.34, 81.82])
    with pytest.raises(ValueError, match="units"):
        codes_to_ranges(codes, "m")  # type: ignore[arg-type]


def test_sick_codes_inverse() -> None:
    r = np.array([0.0, 1.2344, 8.182, np.inf, np.nan, 9.5])
    np.testing.assert_array_equal(ranges_to_codes(r, "mm"), [0, 1234, 8182, 8183, 8191, 8183])
    np.testing.assert_array_equal(ranges_to_codes(r, "cm"), [0, 123, 818, 8183, 8191, 950])
    back = codes_to_ranges(ranges_to_codes(r[:5], "mm"), "mm")
    np.testing.assert_allclose(back[:3], [0.0, 1.234, 8.182])
    with pytest.raises(ValueError, match="negative"):
        ranges_to_codes(np.array([-1.0]))


def test_logged_special_values() -> None:
    cm = decode_logged_ranges(np.array([81.83, 81.91, 81.86, 1.5, 81.82, 8.19, 8.18]))
    assert np.isposinf(cm[0]) and np.isnan(cm[[1, 2]]).all()
    np.testing.assert_allclose(cm[3:], [1.5, 81.82, 8.19, 8.18])  # 8.19 m is a valid cm reading
    mm = decode_logged_ranges(np.array([8.183, 8.191, 8.19, 1.234, 8.182]))  # mm digits: mm mode
    assert np.isposinf(mm[0]) and np.isnan(mm[[1, 2]]).all()
    np.testing.assert_allclose(mm[3:], [1.234, 8.182])
    forced = decode_logged_ranges(np.array([8.19, 1.5]), units="mm")
    assert np.isnan(forced[0]) and forced[1] == 1.5


def test_snap_angle() -> None:
    assert snap_angle(0.008727) == np.deg2rad(0.5)
    assert snap_angle(-1.570796) == -np.pi / 2
    assert snap_angle(0.0123) == 0.0123  # not near the 0.05 deg grid: unchanged


def test_snap_angle_never_snaps_a_nonzero_angle_onto_0(tmp_path) -> None:
    """0 rad is exact in 6-decimal text and in float32, so neither rounding explains a nonzero angle
    near it: snap_angle(1e-9) was 0.0, and a ROBOTLASER1 scan of 361 beams 1e-9 rad apart, written by
    write_log, was refused by read_log ("angle_increment: must be > 0, got 0.0"); an angle_min of
    3e-7 rad read back as 0."""
    from lms200 import Record, read_log, write_log

    assert snap_angle(1e-9) == 1e-9 and snap_angle(-3e-7) == -3e-7 and snap_angle(0.0) == 0.0
    assert snap_angle(-0.0) == 0.0 and snap_angle(0.000873) == np.deg2rad(0.05)  # the grid's next step still snaps
    # (a step under laser_geometry.MIN_RESOLUTION_RAD, 1e-5 rad, is refused by the reader and so by write_log now)
    scans = [Scan(np.full(361, 2.0), 3e-7, 1e-5, 0.0, 8.0), Scan(np.full(3, 2.0), -1e-7, 2e-5, 0.0, 8.0)]
    for k, scan in enumerate(scans):
        write_log(tmp_path / f"{k}.clf", [Record(scan)])
        assert [r.scan for r in read_log(tmp_path / f"{k}.clf")] == [scan]
    with pytest.raises(InputError, match=r"^records: item 0: angle_increment 1e-09 rad is finer than 1e-05 rad"):
        write_log(tmp_path / "fine.clf", [Record(Scan(np.full(361, 2.0), 3e-7, 1e-9, 0.0, 8.0))])


def test_decoding_a_huge_logged_range_keeps_it_without_a_warning():
    """1e308 m divided by the 1 cm unit overflows to inf: no special code, the value is kept, and
    numpy's overflow warning is not printed to the user (pytest turns RuntimeWarnings into errors)."""
    out = decode_logged_ranges(np.array([1e308, 81.83, 1.5]), units="cm")
    assert out[0] == 1e308 and np.isposinf(out[1]) and out[2] == 1.5


def test_minus_inf_is_taken_with_its_rep117_meaning() -> None:
    """-inf is REP-117's "an object too close to measure": a Scan keeps it and no beam with it is
    valid (it was refused, whole scans of a ROS sensor with it lost); finite negative ranges are
    still refused. On the LMS200 wire it is "not valid" (8191): the device has no code for it."""
    s = Scan(np.array([1.0, -np.inf, 2.0, np.inf, np.nan]), 0.0, 0.01, 0.0, 8.0)
    assert np.isneginf(s.ranges[1])
    np.testing.assert_array_equal(s.valid, [True, False, True, False, False])
    with pytest.raises(ValueError, match="^ranges: negative ranges are not allowed"):
        Scan(np.array([1.0, -1.0, 2.0]), 0.0, 0.01, 0.0, 8.0)
    np.testing.assert_array_equal(ranges_to_codes(np.array([1.0, -np.inf, np.nan, np.inf]), "mm"), [1000, 8191, 8191, 8183])


def test_minus_inf_beams_extract_as_nan_beams() -> None:
    """Every method gives for a -inf beam what it gives for an invalid (nan) one: a wall 2 m ahead
    (x = 2) with a run of beams too close in its middle."""
    from features import available_methods, extract  # noqa: PLC0415

    angles = -np.pi / 2 + np.arange(361) * np.deg2rad(0.5)
    ranges = np.where(np.abs(angles) < 1.2, 2.0 / np.cos(angles), np.inf)
    ranges[170:176] = -np.inf
    close = Scan(ranges, -np.pi / 2, np.deg2rad(0.5), 0.0, 8.0)
    invalid = Scan(np.where(np.isneginf(ranges), np.nan, ranges), -np.pi / 2, np.deg2rad(0.5), 0.0, 8.0)
    for method in available_methods():
        a, b = extract(close, method), extract(invalid, method)
        assert len(a.lines) >= 1, method
        np.testing.assert_array_equal(a.lines.values, b.lines.values, err_msg=method)
        np.testing.assert_array_equal(a.lines.beams, b.lines.beams, err_msg=method)


def test_scans_of_one_geometry_share_their_read_only_bearings() -> None:
    """Every scan held its own copy of its bearings (2.9 kB a 361-beam scan, half of what a run's
    records take: simulate_records of 3,600 s held 390 MB of identical bearings). Now the scans of one
    geometry share one read-only array; other geometries have their own, and the values are as before."""
    import tracemalloc

    ranges = np.full(361, 2.0)
    first = Scan.lms200(ranges)
    tracemalloc.start()
    scans = [Scan.lms200(ranges, stamp=float(t)) for t in range(1000)]
    held, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert all(s.angles is first.angles for s in scans) and not first.angles.flags.writeable
    assert held < 1000 * 3500  # each scan's ranges (2.9 kB) and its object; its bearings were 2.9 kB more
    np.testing.assert_array_equal(first.angles, -np.pi / 2 + np.arange(361) * np.deg2rad(0.5))
    other = Scan(ranges, -np.pi / 2, np.deg2rad(0.5), 0.0, 8.183, 0.0)  # the same geometry given by hand
    assert other.angles is first.angles
    moved = Scan(ranges, -np.pi / 2 + 1e-12, np.deg2rad(0.5), 0.0, 8.183)
    assert moved.angles is not first.angles and moved.angles[0] == -np.pi / 2 + 1e-12


@pytest.mark.parametrize("bearings", [np.nan, [0.1, np.inf], "abc", None])
def test_beam_of_refuses_bearings_that_are_no_finite_numbers(bearings: object) -> None:
    """nan gave beam -2**63 (and numpy's RuntimeWarning of the cast), text numpy's ValueError
    (fuzzing the Python API, 2026-12-07)."""
    scan = Scan.lms200(np.ones(361))
    with pytest.raises(InputError, match=r"^bearings: must be finite numbers \(rad\), got "):
        scan.beam_of(bearings)
    assert scan.beam_of(np.array([-np.pi / 2, 0.0, np.pi / 2])).tolist() == [0, 180, 360]


def test_a_float32_signalling_nan_in_ranges_is_a_nan_without_a_warning() -> None:
    """Review: a float32 signalling nan (0x7f800001, a driver's raw bits) among a Scan's ranges made
    numpy's float64 cast warn "RuntimeWarning: invalid value encountered in cast" (the bag readers
    ignored it, Scan did not); it is a nan, an invalid reading (REP-117), silently, masked or not."""
    import warnings

    raw = np.array([2.0, 2.0, 3.0], np.float32)
    raw.view(np.uint32)[1] = 0x7F800001
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        plain = Scan(raw, -np.pi / 2, np.pi / 2, 0.0, 8.0)
        masked = Scan(np.ma.array(raw, mask=[True, False, False]), -np.pi / 2, np.pi / 2, 0.0, 8.0)
    assert plain.ranges.dtype == np.float64 and np.isnan(plain.ranges[1]) and plain.ranges[[0, 2]].tolist() == [2.0, 3.0]
    assert np.isnan(masked.ranges[:2]).all() and masked.ranges[2] == 3.0
