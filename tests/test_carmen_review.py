"""Defects a read-only review (session 32) reproduced in the CARMEN reader / writer, the Scan angle
snapping and the Record / LaserGeometry argument checks; each test failed on the code before its fix."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lms200 import LaserGeometry, Record, Scan, read_log, write_log
from lms200.errors import InputError, LogFormatError


def _scan() -> Scan:
    return Scan(np.ones(3), -0.1, 0.05, 0.0, 8.0)


@pytest.mark.parametrize("pose, message", [
    ((10**400, 0, 0), "odom: must be finite, got an int beyond float64's range"),
    ("123", "odom: must be None or three numbers (x m, y m, theta rad), got str '123'"),
    ((True, False, True), "odom: must be None or three numbers (x m, y m, theta rad), got bool True among them"),
    ((1.0, 2.0), "odom: must be None or three numbers (x m, y m, theta rad), got 2 items"),
])
def test_record_pose_refused_with_input_error_naming_the_field(pose, message):
    # was: raw OverflowError; "123" read as (1.0, 2.0, 3.0); (True, False, True) as (1.0, 0.0, 1.0)
    with pytest.raises(InputError) as err:
        Record(_scan(), odom=pose)
    assert str(err.value) == message
    with pytest.raises(InputError, match="^truth: "):
        Record(_scan(), truth=pose)
    assert Record(_scan(), odom=(np.float64(1), 2, np.int64(3))).odom == (1.0, 2.0, 3.0)


@pytest.mark.parametrize("kw, message", [
    (dict(fov=-1), r"fov: must be > 0, got -1 rad \(-57.2958 deg\)"),
    (dict(range_max=10**400), "range_max: must be finite, got an int beyond float64's range"),
    (dict(fov="3"), "fov: must be a number, got str '3'"),
    (dict(resolution=True), "resolution: must be a number, got bool True"),
])
def test_laser_geometry_refused_with_input_error_naming_the_field(kw, message):
    # was: plain ValueError, raw OverflowError; "3" and True accepted as 3 rad and 1 rad
    with pytest.raises(InputError, match=f"^{message}$"):
        LaserGeometry(**kw)


def _write(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


def _robotlaser(max_range: str = "80", ranges: str = "1 2 3", count: str = "3") -> str:
    return (f"ROBOTLASER1 0 -1.5707963 3.1415926 1.5707963 {max_range} 0.01 0 {count} {ranges} 0 "
            "0 0 0 0 0 0 0 0 0 0 0 5 h 5\n")


@pytest.mark.parametrize("max_range", ["1e-300", "-5", "0", "0.05"])
def test_robotlaser_impossible_max_range_is_a_malformed_line(tmp_path, max_range):
    # was: 1e-300 became range_max (every reading invalid, silently); -5 and 0 became 81.83 m
    path = _write(tmp_path, "rl.log", "# x\n" + _robotlaser("80") + _robotlaser(max_range))
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == (f"{path}:3: malformed ROBOTLASER1 line: maximum range must be in [0.1, 10000] m, "
                              f"got {max_range}")
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.range_max for r in reader] == [80.0]
    assert reader.stats.skipped == [(3, f"ROBOTLASER1: maximum range must be in [0.1, 10000] m, got {max_range}")]


def _flaser(ranges: str = "1.00 2.00 3.00", count: str | None = None, stamp: str = "12.5") -> str:
    n = count if count is not None else str(len(ranges.split()))
    return f"FLASER {n} {ranges} 0 0 0 0 0 0 {stamp} host {stamp}\n"


@pytest.mark.parametrize("line, reason", [
    (_flaser("1_000 2.00 3.00"), "FLASER ranges: '1_000' is not a number (no '_' in a CARMEN number)"),
    (_flaser("1e400 2.00 3.00"), "FLASER ranges: '1e400' is beyond float64's range"),
    (_flaser("-1e400 2.00 3.00"), "FLASER ranges: '-1e400' is beyond float64's range"),
    (_flaser(stamp="1e400"), "FLASER poses and timestamp: '1e400' is beyond float64's range"),
    ("FLASER 3_0 " + " ".join(["1.00"] * 30) + " 0 0 0 0 0 0 1 h 1\n", "beam count '3_0' is not a number"),
])
def test_overflowing_numbers_and_underscores_are_malformed(tmp_path, line, reason):
    # was: 1e400 read as +inf, -1e400 as -inf, 1_000 as 1000 m and a beam count 3_0 as 30 (Python's float())
    path = _write(tmp_path, "u.log", _flaser() + line)
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == f"{path}:2: malformed FLASER line: {reason}"
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == 1 and reader.stats.skipped == [(2, f"FLASER: {reason}")]


def test_inf_written_as_a_word_keeps_its_meaning(tmp_path):
    path = _write(tmp_path, "w.log", _flaser("Infinity -inf 3.00"))
    assert np.array_equal(next(iter(read_log(path))).scan.ranges, [np.inf, -np.inf, 3.0])


def test_bad_param_line_is_blamed_not_every_laser_line(tmp_path):
    # was: "c.log:3: malformed FLASER line: fov ..." for every FLASER line; skip_bad_lines dropped every scan
    path = _write(tmp_path, "p.log", "# x\nPARAM laser_front_laser_fov 720 h 0\n" + _flaser() + _flaser())
    reason = "laser_front_laser_fov 720: fov: must be at most 2 pi rad (360 deg), got 12.5664 rad (720 deg)"
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == f"{path}:2: malformed PARAM line: {reason}"
    reader = read_log(path, skip_bad_lines=True)
    scans = [r.scan for r in reader]
    assert reader.stats.skipped == [(2, f"PARAM: {reason}")]
    assert len(scans) == 2 and scans[0].angle_increment == pytest.approx(math.pi / 2)  # the convention: 3 beams, 180 deg


def test_robotlaser_placeholder_max_range_is_no_error_under_an_override(tmp_path):
    # was: a converter's 0 was a malformed line even with --laser-range-max given, which replaces it
    from lms200 import LaserGeometry
    path = _write(tmp_path, "rl0.log", _robotlaser("0"))
    assert [r.scan.range_max for r in read_log(path, geometry=LaserGeometry(range_max=30.0))] == [30.0]


def test_a_truepos_stamped_with_the_scan_before_is_not_the_next_scans(tmp_path):
    # was: FLASER 1.0, TRUEPOS 1.0, FLASER 1.1 gave the second scan the pose of the first's time
    text = _flaser(stamp="1.0") + "TRUEPOS 9 9 9 0 0 0 1.0 h 1.0\n" + _flaser(stamp="1.1")
    text += "TRUEPOS 8 8 8 0 0 0 1.15 h 1.15\n" + _flaser(stamp="1.2")
    assert [r.truth for r in read_log(_write(tmp_path, "tp.log", text))] == [None, None, (8.0, 8.0, 8.0)]


def test_snap_angle_keeps_angles_genuinely_off_the_grid():
    from lms200.scan import snap_angle
    half = math.radians(0.5)
    # was: 2 pi / 719 (RPLIDAR style, 720 beams) snapped to 0.5 deg; 0.5 deg + 1.5e-5 rad too
    assert snap_angle(2 * math.pi / 719) == 2 * math.pi / 719
    assert snap_angle(half + 1.5e-5) == half + 1.5e-5
    # what 6 decimals or float32 explain is still snapped (the CSAIL ROBOTLASER1 log writes 0.008727, -1.570796)
    assert snap_angle(0.008727) == half and snap_angle(-1.570796) == -math.pi / 2
    assert snap_angle(float(np.float32(math.radians(0.25)))) == math.radians(0.25)
    # 6 decimals of 0.1 and 0.05 deg (0.001745, 0.000873): snapped however many beams (a 0.1-beam drift rule
    # kept 0.001745 over 1801 beams, the last beam at 89.966 deg instead of 90)
    assert snap_angle(0.001745) == math.radians(0.1) and snap_angle(0.000873) == math.radians(0.05)


def test_robotlaser_six_decimal_fine_resolution_snaps_onto_the_grid(tmp_path):
    n = 1801
    line = ("ROBOTLASER1 0 -1.570796 3.141593 0.001745 80.000000 0.010000 0 " + str(n) + " "
            + " ".join(["2.00"] * n) + " 0 " + "0 " * 11 + "1.0 h 1.0\n")
    path = tmp_path / "fine.log"
    path.write_text(line)
    scan = next(iter(read_log(path))).scan
    assert scan.angle_increment == math.radians(0.1) and scan.angle_max == pytest.approx(math.pi / 2, abs=1e-12)


def test_robotlaser_720_beams_at_2pi_over_719_keeps_its_last_bearing(tmp_path):
    res = 2 * math.pi / 719
    line = (f"ROBOTLASER1 0 {-math.pi!r} {2 * math.pi!r} {res!r} 12 0.001 0 720 " + " ".join(["1.0"] * 720)
            + " 0 0 0 0 0 0 0 0 0 0 0 0 5 h 5\n")
    scan = next(iter(read_log(_write(tmp_path, "rp.log", line)))).scan
    assert scan.angle_increment == res  # was exactly 0.5 deg
    assert math.degrees(scan.angle_max) == pytest.approx(180.0, abs=1e-9)  # was 179.50


@pytest.mark.parametrize("fmt", ["robotlaser1", "flaser"])
def test_valid_readings_near_the_special_codes_stay_valid(tmp_path, fmt):
    path = tmp_path / "v.log"
    # mm mode at the Scan.lms200 default range_max 8.183: 8.183 and 8.1826 read back +inf; then as
    # 8.182 (a unit off); now with the digits they need (8.183 is the code itself: half a unit below)
    mm = Scan(np.array([8.183, 8.1826, 8.1824, np.inf, np.nan, 3.0]), -0.05, 0.02, 0.0, 8.183)
    write_log(path, [Record(mm)], fmt=fmt)
    back = next(iter(read_log(path))).scan
    assert back.ranges[:3].tolist() == [8.1825, 8.1826, 8.182] and back.ranges[5] == 3.0
    assert np.isposinf(back.ranges[3]) and np.isnan(back.ranges[4])
    assert back.valid.tolist() == mm.valid.tolist() == [True, True, True, False, False, True]
    # cm mode, range_max 100: 81.83 / 81.86 / 81.90 / 81.91 read back +inf / nan
    cm = Scan(np.array([81.83, 81.86, 81.90, 81.91, 81.82, 81.95]), -0.05, 0.02, 0.0, 100.0)
    write_log(path, [Record(cm)], fmt=fmt)
    back = next(iter(read_log(path))).scan
    assert back.ranges.tolist() == [81.825, 81.855, 81.895, 81.905, 81.82, 81.95]
    assert back.valid.all()
    # not valid (beyond this scan's range_max): written as it is, and still not valid
    far = Scan(np.array([8.183, 2.0, 8.19]), -0.05, 0.05, 0.0, 8.0)
    write_log(path, [Record(far)], fmt=fmt)
    assert not next(iter(read_log(path))).scan.valid[[0, 2]].any()


def test_truth_is_the_last_truepos_before_the_scan_within_its_gap(tmp_path):
    text = ("TRUEPOS 9 9 9 0 0 0 1 h 1\n" + _flaser("1.00 bad 3.00", stamp="1") + _flaser(stamp="2")
            + "TRUEPOS 7 7 7 0 0 0 100 h 100\n" + "ODOM 0 0 0 0 0 0 150 h 150\n" * 3 + _flaser(stamp="500")
            + "TRUEPOS 6 6 6 0 0 0 600 h 600\nRLASER 3 1 2 3 0 0 0 0 0 0 600 h 600\n" + _flaser(stamp="600")
            + "TRUEPOS 5 5 5 0 0 0 700 h 700\nPARAM laser_front_laser_fov 180 h 0\n# a comment\n" + _flaser(stamp="700")
            + "TRUEPOS 4 4 4 0 0 0 800.0 h 800\nODOM 0 0 0 0 0 0 800.02 h 800\n" + _flaser(stamp="800.05")
            + "TRUEPOS 3 3 3 0 0 0 900 h 900\n" + _flaser(stamp="900.6"))
    reader = read_log(_write(tmp_path, "t.log", text), skip_bad_lines=True, topic="FLASER")
    # was: (2.0, (9, 9, 9)) across a skipped malformed line of the kind read, (500.0, (7, 7, 7)) across ODOM
    # lines 400 s later; a TRUEPOS, ODOM, FLASER cycle (CARMEN's simulator) and another laser kind keep it
    assert [(r.scan.stamp, r.truth) for r in reader] == [(2.0, None), (500.0, None), (600.0, (6.0, 6.0, 6.0)),
                                                        (700.0, (5.0, 5.0, 5.0)), (800.05, (4.0, 4.0, 4.0)),
                                                        (900.6, None)]
    assert reader.stats.skipped == [(2, "FLASER: FLASER ranges: 'bad' is not a number")]


def test_writer_puts_truepos_directly_before_its_laser_line(tmp_path):
    path = tmp_path / "w.log"
    recs = [Record(Scan(np.ones(3), -0.1, 0.1, 0.0, 8.0, stamp=t), odom=(t, 0.0, 0.0), truth=truth)
            for t, truth in ((1.0, (1.0, 2.0, 3.0)), (2.0, None), (3.0, (4.0, 5.0, 6.0)))]
    write_log(path, recs, fmt="flaser")
    lines = [ln.split()[0] for ln in path.read_text().splitlines() if not ln.startswith("#")]
    assert [lines[i + 1] for i, k in enumerate(lines) if k == "TRUEPOS"] == ["FLASER", "FLASER"]
    assert [r.truth for r in read_log(path)] == [(1.0, 2.0, 3.0), None, (4.0, 5.0, 6.0)]


@pytest.mark.parametrize("fmt", ["robotlaser1", "flaser"])
def test_round_trip_is_exact(tmp_path, fmt):
    path = tmp_path / "rt.log"
    scans = [Scan(np.full(1024, 2.0), -math.pi, 2 * math.pi / 1024, 0.0, 30.0, stamp=1700000000.1234567),
             Scan(np.full(5, 2.0), -0.1, 0.05, 1e-5, 30.0, stamp=3.0000004),
             Scan(np.full(361, 2.0), -math.pi / 2, math.pi / 360, 0.0, 30.0, stamp=3.5)]
    if fmt == "flaser":  # FLASER carries scans centred ahead only
        scans[0] = scans[0].replace(angle_min=-(1023 / 2) * scans[0].angle_increment)
    recs = [Record(s, odom=(1.23456789, -2.0, 1e-7), truth=(0.1234567891, 3.0000004, -3.5)) for s in scans]
    write_log(path, recs, fmt=fmt)
    text = path.read_text()
    assert "e-" not in text and "e+" not in text  # plain decimals, as CARMEN tools read them
    back = list(read_log(path))
    # was: stamps 238 ns off (3.0000004 as 3.0), poses to 6 decimals, ROBOTLASER1 1024 beams' last one
    # 7.9e-5 rad off, FLASER angle_min -0.1 as -0.10000000000000002
    for a, b in zip(recs, back):
        assert b.scan == a.scan and b.odom == a.odom and b.truth == a.truth
    assert back[1].scan.angle_min == -0.1 and back[0].scan.stamp == 1700000000.1234567


def test_flaser_exact_geometry_params_yield_to_an_override(tmp_path):
    path = tmp_path / "o.log"
    write_log(path, [Record(Scan(np.full(5, 2.0), -0.1, 0.05, 0.0, 8.0))], fmt="flaser")
    assert "PARAM lmsbench_front_laser_angle_min -0.1 " in path.read_text()
    scan = next(iter(read_log(path, geometry=LaserGeometry(fov=math.radians(4.0), resolution=math.radians(1.0))))).scan
    assert scan.angle_increment == math.radians(1.0) and scan.angle_min == pytest.approx(-math.radians(2.0))


def test_junk_lines_are_bad_lines_and_message_kinds_are_bounded(tmp_path):
    from lms200.carmen import MAX_MESSAGE_KINDS
    # unknown but valid messages (NEFF in Intel / ACES; NMEA, SYNC, other CARMEN messages) are skipped, counted
    valid = "".join(f"{k} 1 2 3\n" for k in ("NEFF", "NMEA", "SYNC", "GPSNMEA", "BASE_VELOCITY"))
    reader = read_log(_write(tmp_path, "k.log", _flaser() + valid + _flaser()))
    assert len(list(reader)) == 2 and reader.stats.skipped == []
    assert reader.stats.messages == {"FLASER": 2, "NEFF": 1, "NMEA": 1, "SYNC": 1, "GPSNMEA": 1, "BASE_VELOCITY": 1}
    # a line that starts with no message name: was counted as a "kind" (1,000,000 junk lines peaked at 88 MB;
    # 30 MB of random bytes after Intel gave 207k kinds and no skipped line)
    junk = _flaser() + "".join(f"W{i:x}q 1 2 3\n" for i in range(5)) + "\x00\x93garbage\n" + _flaser()
    path = _write(tmp_path, "j.log", junk)
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == (f"{path}:2: malformed message line: it starts with 'W0q', which is no CARMEN message "
                              "name (FLASER, ODOM, PARAM, ...: capitals, digits and '_'); junk or a damaged line")
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == 2 and [at for at, _ in reader.stats.skipped] == [2, 3, 4, 5, 6, 7]
    assert reader.stats.messages == {"FLASER": 2}
    # message names are counted one by one up to MAX_MESSAGE_KINDS kinds, the rest as "other"
    many = _flaser() + "".join(f"KIND{i} 1\n" for i in range(200)) + "ODOM 0 0 0 0 0 0 1 h 1\n" + _flaser()
    reader = read_log(_write(tmp_path, "m.log", many))
    assert len(list(reader)) == 2
    messages = reader.stats.messages
    assert len(messages) == MAX_MESSAGE_KINDS + 2 and messages["other"] == 200 - (MAX_MESSAGE_KINDS - 1)
    assert messages["ODOM"] == 1 and messages["FLASER"] == 2


def test_a_pass_ends_after_max_junk_lines_under_skip_bad_lines(tmp_path, monkeypatch):
    import lms200.carmen as carmen
    monkeypatch.setattr(carmen, "MAX_JUNK_LINES", 5)
    # was (with junk counted as kinds, then skipped one by one): 1,000,000 junk lines peaked at 289 MB
    path = _write(tmp_path, "j.log", _flaser() + "".join(f"w{i} 1\n" for i in range(3)) + "NEFF 1\n" + _flaser()
                  + "".join(f"w{i} 1\n" for i in range(100)) + _flaser())
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == 2  # the third FLASER lies beyond the sixth junk line (line 9)
    assert len(reader.stats.skipped) == 5 + 1 and reader.stats.skipped[-1][0] == 9
    assert reader.stats.stopped == ("line 9: more than 5 lines that start with no CARMEN message name: junk from "
                                    "here on, not read")
