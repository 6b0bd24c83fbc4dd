"""Valid but unusual CARMEN logs of other writers (a measurement session's variants of the real logs,
rebuilt here as small synthetic fixtures): lines whose hostname is missing, is more than one word,
or whose tail ends at the ipc_timestamp."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lms200 import LogFormatError, read_log

RANGES = "1.00 2.00 3.00"
POSES = "0.5 0.25 0.1 1.5 -2.0 0.3"  # laser pose, then odometry


def _log(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "log.clf"
    path.write_text("\n".join(lines) + "\n")
    return path


# the words after a line's ipc_timestamp, CARMEN's own first
TAILS = {"carmen": "b21 {l}", "no host": "{l}", "ipc only": "", "host only": "b21",
         "host with spaces": "my robot host {l}"}


@pytest.mark.parametrize("tail", list(TAILS))
def test_flaser_lines_read_whatever_follows_their_ipc_timestamp(tmp_path: Path, tail: str) -> None:
    """FLASER lines without a hostname, without hostname and logger_timestamp, or with a hostname of
    three words were refused ("FLASER with 3 beams needs 14 fields, got 13" / 12 / 16): CARMEN's
    readers take the fields in order up to the ipc_timestamp, which is all this reader uses."""
    end = TAILS[tail]
    lines = [f"ODOM 1 2 0.5 0 0 0 {t} {end.format(l=t + 0.04)}".rstrip() for t in (10.0,)]
    lines += [f"FLASER 3 {RANGES} {POSES} {t} {end.format(l=t + 0.04)}".rstrip() for t in (10.0, 10.2)]
    lines += [f"TRUEPOS 7 8 0.25 1.5 -2.0 0.3 10.3 {end.format(l=10.34)}".rstrip(),
              f"FLASER 3 {RANGES} {POSES} 10.4 {end.format(l=10.44)}".rstrip()]
    recs = list(read_log(_log(tmp_path, lines)))
    assert [r.scan.stamp for r in recs] == [10.0, 10.2, 10.4]
    assert np.array_equal(recs[0].scan.ranges, [1.0, 2.0, 3.0])
    assert recs[0].odom == (1.5, -2.0, 0.3) and recs[2].truth == (7.0, 8.0, 0.25)


@pytest.mark.parametrize("tail", list(TAILS))
def test_robotlaser_and_rawlaser_lines_read_whatever_follows_their_ipc_timestamp(tmp_path: Path, tail: str) -> None:
    """The same for ROBOTLASER1 (robot pose as odometry) and RAWLASER1 with ODOM lines (CARMEN 0.7)."""
    end = TAILS[tail]
    head = "0 -0.017453 0.034906 0.017453 30.0 0.001 0 3 " + RANGES + " 0"
    robot = [f"ROBOTLASER1 {head} 0 0 0 1.5 -2.0 0.3 0 0 0 0 0 {t} {end.format(l=t)}".rstrip() for t in (5.0, 5.1)]
    recs = list(read_log(_log(tmp_path, robot)))
    assert [(r.scan.stamp, r.odom) for r in recs] == [(5.0, (1.5, -2.0, 0.3)), (5.1, (1.5, -2.0, 0.3))]
    raw = [f"ODOM 1 2 0.5 0 0 0 5.0 {end.format(l=5.0)}".rstrip(), f"RAWLASER1 {head} 5.0 {end.format(l=5.0)}".rstrip(),
           f"ODOM 3 2 0.5 0 0 0 5.2 {end.format(l=5.2)}".rstrip(), f"RAWLASER1 {head} 5.1 {end.format(l=5.1)}".rstrip(),
           f"ODOM 5 2 0.5 0 0 0 5.4 {end.format(l=5.4)}".rstrip()]
    recs = list(read_log(_log(tmp_path, raw)))
    assert [r.scan.stamp for r in recs] == [5.0, 5.1]
    assert recs[0].odom == (1.0, 2.0, 0.5) and recs[1].odom == pytest.approx((2.0, 2.0, 0.5))
    assert len(recs[0].scan) == 3 and recs[0].scan.range_max == 30.0


@pytest.mark.parametrize(("line", "reason"), [
    # a range lost, a range split in two (a CR in a word), two lines run together: still malformed
    (f"FLASER 3 1.00 2.00 {POSES} 10.0 b21 10.0", "FLASER with 3 beams needs 14 fields, got 13"),
    (f"FLASER 3 1.00 2.00 {POSES} 10.0 10.0", "FLASER with 3 beams needs 14 fields, got 12"),
    (f"FLASER 3 1.00 2.00 3. 00 {POSES} 10.0 b21 10.0", "FLASER with 3 beams needs 14 fields, got 15"),
    (f"FLASER 3 {RANGES} {POSES} 10.0 b21 10.0 FLASER 3", "FLASER with 3 beams needs 14 fields, got 16"),
    ("ODOM 0 0 0 0 0 0 2 h 2 FLASER 3 1 2 3", "ODOM has 15 fields, at most 10"),
    (f"FLASER 3 {RANGES} {POSES} 10.0 b21 x", "logger_timestamp: 'x' is not a number"),
])
def test_lines_that_lost_or_gained_a_word_are_still_malformed(tmp_path: Path, line: str, reason: str) -> None:
    path = _log(tmp_path, [f"FLASER 3 {RANGES} {POSES} 9.0 b21 9.0", line])
    with pytest.raises(LogFormatError, match=rf"log\.clf:2: malformed (FLASER|ODOM) line: .*{reason}"):
        list(read_log(path))


def test_a_line_whose_tail_differs_from_the_first_lines_is_malformed(tmp_path: Path) -> None:
    """In a log whose lines end at "ipc_timestamp logger_timestamp" (no hostname), a line that lost a
    range fits a tail that ends at its ipc_timestamp (its fields shifted by one: the logger_timestamp read
    as the stamp): it is told by its tail, unlike the first line's."""
    path = _log(tmp_path, [f"FLASER 3 {RANGES} {POSES} 9.0 9.01", f"FLASER 3 1.00 2.00 {POSES} 10.0 10.01",
                           f"FLASER 3 {RANGES} {POSES} 11.0 11.01"])
    with pytest.raises(LogFormatError, match=r"log\.clf:2: malformed FLASER line: FLASER with 3 beams needs 13 fields, "
                                             r"got 12: 0 words after its ipc_timestamp, where line 1 has 1 \(a word "
                                             r"lost or gained\?\)"):
        list(read_log(path))
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [9.0, 11.0] and reader.stats.skipped_count == 1


@pytest.mark.parametrize("good_tail, bad", [
    ("b21 {t}", "FLASER 3 1.00 2.00 {p} 9.0 9.01"),  # CARMEN's lines, the first lost a range and its hostname
    ("{t}", "FLASER 3 1.00 2.00 {p} 9.0 9.01"),  # no hostname (ipc, logger), the first lost a range
])
def test_a_damaged_first_line_is_told_by_the_lines_after_it(tmp_path: Path, good_tail: str, bad: str) -> None:
    """A review: the first laser line's tail set the rule alone. A first line that lost a range and its
    hostname read silently with its fields shifted by one (Intel's first FLASER line so damaged: exit 0, its
    last range the laser pose's x, its stamp the logger_timestamp), since CARMEN's tail was taken after any
    first line; and in a log of other tails, a first line that lost a range made every good line after it
    malformed (under skip_bad_lines only the damaged line was kept). The rule is the tail the first lines
    share: the damaged line is malformed, the good ones read, with the ODOM lines among them in log order."""
    lines = [bad.format(p=POSES)] + [f"FLASER 3 {RANGES} {POSES} {t} {good_tail.format(t=t)}".strip()
                                      for t in (10.0, 11.0, 12.0)]
    lines.insert(1, "ODOM 1.5 -2.0 0.3 0 0 0 9.5 b21 9.5")
    path = _log(tmp_path, lines)
    with pytest.raises(LogFormatError, match=r"log\.clf:1: malformed FLASER line: FLASER with 3 beams needs \d+ fields, "
                                             r"got 12: 0 words after its ipc_timestamp, where line 3 has"):
        list(read_log(path))
    reader = read_log(path, skip_bad_lines=True)
    recs = list(reader)
    assert [r.scan.stamp for r in recs] == [10.0, 11.0, 12.0] and [n for n, _ in reader.stats.skipped] == [1]
    assert all(r.scan.ranges.tolist() == [1.0, 2.0, 3.0] for r in recs)
    good = _log(tmp_path, lines[1:])  # the same log without the damaged line: the same records
    assert [(r.scan.stamp, r.odom, r.truth) for r in read_log(good)] == [(r.scan.stamp, r.odom, r.truth) for r in recs]


def test_two_lines_of_differing_tails_take_the_firsts(tmp_path: Path) -> None:
    """A log of two laser lines whose tails differ (nothing shared to tell the rule by) keeps the first's, as
    before the rule was taken from the first lines shared; three that all differ, the first's too."""
    path = _log(tmp_path, [f"FLASER 3 {RANGES} {POSES} 9.0 9.01", f"FLASER 3 {RANGES} {POSES} 10.0"])
    with pytest.raises(LogFormatError, match=r"log\.clf:2: .* 0 words after its ipc_timestamp, where line 1 has 1 "):
        list(read_log(path))
    path = _log(tmp_path, [f"FLASER 3 {RANGES} {POSES} 9.0 9.01", f"FLASER 3 {RANGES} {POSES} 10.0",
                           f"FLASER 3 {RANGES} {POSES} 11.0 a b 11.01", f"FLASER 3 {RANGES} {POSES} 12.0 12.01"])
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [9.0, 12.0] and [n for n, _ in reader.stats.skipped] == [2, 3]


# --- readings at the declared maximum range --------------------------------------------------------
def _hokuyo_line(t: float, ranges: list[str]) -> str:
    """A ROBOTLASER1 line of a Hokuyo UTM-30LX-like laser (270 deg at 0.25 deg written to 6 decimals, max range
    30 m, mm accuracy): ``len(ranges)`` beams from -135 deg."""
    n = len(ranges)
    return (f"ROBOTLASER1 0 -2.356194 {(n - 1) * 0.004363:.6f} 0.004363 30.000000 0.001000 0 {n} {' '.join(ranges)} 0 "
            f"0 0 0 1 2 0.5 0 0 0 0 0 {t} hokuyo {t}")


def test_a_reading_at_the_lines_declared_maximum_range_is_no_return(tmp_path: Path) -> None:
    """CARMEN loggers write a beam with no return as the laser's maximum range: a Hokuyo log's open sectors at
    30.000 m were read as valid readings on an arc at 30 m, which the extractors fitted lines to (a 1081-beam
    log: 17.0 lines a scan against 13.0 with the same beams written above 30 m). Above it, a reading stays out
    of limits (invalid); below it, valid."""
    ranges = ["2.500"] * 1077 + ["30.000", "30", "30.5", "29.999"]
    recs = list(read_log(_log(tmp_path, [_hokuyo_line(1.2e9, ranges)])))
    scan = recs[0].scan
    assert (len(scan), scan.range_max, scan.stamp) == (1081, 30.0, 1.2e9)
    assert scan.angle_min == pytest.approx(np.radians(-135), abs=1e-12)
    assert scan.angle_max == pytest.approx(np.radians(135), abs=1e-12)
    assert scan.ranges[-4:-2].tolist() == [np.inf, np.inf] and scan.ranges[-2:].tolist() == [30.5, 29.999]
    assert scan.valid[-4:].tolist() == [False, False, False, True] and scan.valid[:-4].all()


def test_a_flaser_reading_at_the_param_maximum_range_is_no_return_and_the_writer_keeps_a_valid_one(
        tmp_path: Path) -> None:
    """FLASER's maximum range is the log's PARAM robot_front_laser_max (Freiburg's 80.99 m); the writer, which
    declares the scan's range_max, writes a valid reading at exactly range_max so that it reads back valid."""
    from lms200 import Record, Scan, write_log

    path = _log(tmp_path, ["PARAM robot_front_laser_max 80.99 nohost 0",
                           f"FLASER 4 1.00 80.99 81.00 81.83 {POSES} 10.0 b21 10.0"])
    scan = list(read_log(path))[0].scan
    assert scan.range_max == 80.99 and scan.ranges.tolist() == [1.0, np.inf, 81.0, np.inf]
    assert scan.valid.tolist() == [True, False, False, False]
    for fmt in ("robotlaser1", "flaser"):
        written = Scan(np.array([1.0, 30.0, np.inf, 12.0]), -0.1, 0.05, 0.0, 30.0, stamp=3.0)
        out = tmp_path / f"w-{fmt}.log"
        write_log(out, [Record(written)], fmt=fmt)
        back = list(read_log(out))[0].scan
        assert back.valid.tolist() == [True, True, False, True], fmt
        assert back.ranges[1] == pytest.approx(30.0, abs=0.005) and back.ranges[2] == np.inf


def test_the_lines_held_until_the_tail_is_told_are_bounded(tmp_path: Path, monkeypatch) -> None:
    """The third review: the laser lines held until their tail is told were at most 3, but the ODOM lines read
    among them were held without a bound (one FLASER line and 500,000 ODOM lines: 130 MB more). Beyond
    _Tails.HELD_EVENTS held lines the tail is taken from the laser lines held, the first's, as at a pass's end."""
    from lms200 import carmen

    odom = [f"ODOM 1.5 -2.0 0.3 0 0 0 {9 + k / 100:.2f} b21 {9 + k / 100:.2f}" for k in range(1, 21)]
    lines = [f"FLASER 3 {RANGES} {POSES} 9.0 9.01"] + odom + [f"FLASER 3 {RANGES} {POSES} {t} b21 {t}" for t in (10.0, 11.0)]
    path = _log(tmp_path, lines)
    reader = read_log(path, skip_bad_lines=True)  # the two lines after share CARMEN's tail: the first is malformed
    assert [r.scan.stamp for r in reader] == [10.0, 11.0] and [n for n, _ in reader.stats.skipped] == [1]
    monkeypatch.setattr(carmen._Tails, "HELD_EVENTS", 10)
    reader = read_log(path, skip_bad_lines=True)  # 10 held: the first line's tail, told alone
    assert [r.scan.stamp for r in reader] == [9.0] and [n for n, _ in reader.stats.skipped] == [22, 23]


def test_a_reading_at_a_declared_maximum_off_the_unit_grid_is_no_return(tmp_path: Path) -> None:
    """A maximum range off the grid of the line's unit (4.095 m in a cm log) is written by CARMEN rounded, with
    %.2f as "4.09" (or "4.10" at the tie): "4.09" was read as a valid reading 5 mm short of the maximum, where
    the logger meant no return. The grid words within half a unit of the maximum (both, at a tie) and the
    maximum itself are no return; a reading a unit below is valid; the writer keeps a valid reading at such a
    maximum valid (it writes it off the grid)."""
    from lms200 import Record, Scan, write_log

    path = _log(tmp_path, ["PARAM robot_front_laser_max 4.095 nohost 0",
                           f"FLASER 5 1.00 4.09 4.10 4.08 4.095 {POSES} 10.0 b21 10.0"])
    scan = list(read_log(path))[0].scan
    assert scan.range_max == 4.095 and scan.ranges.tolist() == [1.0, np.inf, np.inf, 4.08, np.inf]
    assert scan.valid.tolist() == [True, False, False, True, False]
    head = "0 -0.034906 0.069812 0.017453 4.093000 0.010000 0 5"  # 4.093 m: rounds to 4.09 only
    path = _log(tmp_path, [f"ROBOTLASER1 {head} 1.00 4.09 4.10 4.08 4.093 0 0 0 0 1 2 0.5 0 0 0 0 0 10.0 b21 10.0"])
    scan = list(read_log(path))[0].scan
    assert scan.ranges.tolist() == [1.0, np.inf, 4.1, 4.08, np.inf] and scan.valid.tolist() == [True, False, False, True, False]
    written = Scan(np.array([1.0, 30.0, 30.005, np.inf, 29.99]), -0.1, 0.05, 0.0, 30.005, stamp=3.0)  # cm: 30.005 off the grid
    out = tmp_path / "w.log"
    write_log(out, [Record(written)], fmt="robotlaser1")
    back = list(read_log(out))[0].scan
    assert back.valid.tolist() == [True, True, True, False, True]
    assert back.ranges[1] == pytest.approx(30.0, abs=0.005) and back.ranges[2] == pytest.approx(30.005, abs=0.005)


def test_a_pass_ended_by_an_error_takes_the_tail_the_held_lines_tell(tmp_path: Path) -> None:
    """A pass ended by an error while laser lines were held took the first line's tail: in a log of lines
    ending "ipc_timestamp logger_timestamp", a first line that lost a range (0 words after its ipc_timestamp)
    was given with its fields shifted ([1, 2, 0.5] at 9.01) and the good line after it dropped. Two lines of
    differing tails tell no rule (neither is CARMEN's): both are left out; lines that all end alike, or one
    ending as CARMEN writes, are taken as the pass would have taken them."""
    bad = f"FLASER 3 1.00 2.00 {POSES} 9.0 9.01"
    path = _log(tmp_path, [bad, f"FLASER 3 {RANGES} {POSES} 10.0 10.01", "ODOM x"])
    reader = read_log(path)
    got = []
    with pytest.raises(LogFormatError, match=r"log\.clf:3: malformed ODOM line: ODOM needs x y theta tv rv accel"):
        got.extend(r.scan.stamp for r in reader)
    assert got == []
    path = _log(tmp_path, [f"FLASER 3 {RANGES} {POSES} 9.0 9.01", f"FLASER 3 {RANGES} {POSES} 10.0 10.01", "ODOM x"])
    got = []
    with pytest.raises(LogFormatError, match=r"log\.clf:3: "):
        got.extend(r.scan.stamp for r in read_log(path))
    assert got == [9.0, 10.0]
    path = _log(tmp_path, [bad, f"FLASER 3 {RANGES} {POSES} 10.0 b21 10.01", "ODOM x"])  # the second CARMEN's
    got = []
    with pytest.raises(LogFormatError, match=r"log\.clf:3: "):
        got.extend(r.scan.stamp for r in read_log(path))
    assert got == [10.0]


def test_lines_skipped_among_held_lines_are_reported_in_log_order(tmp_path: Path, monkeypatch) -> None:
    """A line skipped while laser lines were held was recorded at once, a held line found malformed later
    when the lines were released: skipped [3, 1]. Both are recorded in log order, and so are junk lines up to
    the one that ends the pass as junk."""
    from lms200 import carmen

    path = _log(tmp_path, [f"FLASER 3 1.00 2.00 {POSES} 9.0 9.01", f"FLASER 3 {RANGES} {POSES} 10.0 10.01", "ODOM x",
                           f"FLASER 3 {RANGES} {POSES} 11.0 11.01", "ODOM y"])
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [10.0, 11.0]
    assert [n for n, _ in reader.stats.skipped] == [1, 3, 5] and reader.stats.skipped_count == 3
    assert reader.stats.skipped[0][1].startswith("FLASER: FLASER with 3 beams needs 13 fields, got 12")
    monkeypatch.setattr(carmen, "MAX_JUNK_LINES", 3)
    path = _log(tmp_path, [f"FLASER 3 1.00 2.00 {POSES} 9.0 9.01", f"FLASER 3 {RANGES} {POSES} 10.0 b21 10.01"]
                + ["junk"] * 5)
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [10.0] and [n for n, _ in reader.stats.skipped] == [1, 3, 4, 5, 6]
    assert reader.stats.stopped is not None and reader.stats.stopped.startswith("line 6: more than 3 lines")


def test_a_held_line_found_malformed_leaves_no_trace(tmp_path: Path) -> None:
    """A held line later found malformed still set the last scan's stamp: a first line that lost a range and
    its hostname reads its logger_timestamp (9.7) as its stamp, and the TRUEPOS at 9.6 before the next scan
    (10.0) was taken as stale, that scan's truth lost. The log reads as it does without the damaged line. A
    ROBOTLASER1 line found malformed by its tail no longer sets its geometry's beam count either (the next
    line of that geometry, one beam more, was refused as "line 3 ... carries 4")."""
    lines = [f"FLASER 3 1.00 2.00 {POSES} 9.0 9.7", "TRUEPOS 7 8 0.25 1.5 -2.0 0.3 9.6 b21 9.6",
             f"FLASER 3 {RANGES} {POSES} 10.0 b21 10.0", f"FLASER 3 {RANGES} {POSES} 11.0 b21 11.0"]
    reader = read_log(_log(tmp_path, lines), skip_bad_lines=True)
    recs = [(r.scan.stamp, r.truth) for r in reader]
    assert recs == [(10.0, (7.0, 8.0, 0.25)), (11.0, None)] and [n for n, _ in reader.stats.skipped] == [1]
    assert recs == [(r.scan.stamp, r.truth) for r in read_log(_log(tmp_path, lines[1:]))]

    def robot(t: float, start: str, n: int, end: str) -> str:  # fov 4 steps: 4 or 5 beams
        return (f"ROBOTLASER1 0 {start} 0.069812 0.017453 30.0 0.001 0 {n} {' '.join(['2.0'] * n)} 0 "
                f"0 0 0 1 2 0.5 0 0 0 0 0 {t} {end}")

    lines = [robot(1.0, "-0.034906", 5, "b21 1.0"), robot(2.0, "-0.034906", 5, "b21 2.0"),
             robot(3.0, "-0.052360", 4, "3.0"), robot(4.0, "-0.052360", 5, "b21 4.0")]
    reader = read_log(_log(tmp_path, lines), skip_bad_lines=True)
    assert [(r.scan.stamp, len(r.scan)) for r in reader] == [(1.0, 5), (2.0, 5), (4.0, 5)]
    assert [n for n, _ in reader.stats.skipped] == [3]


def test_a_log_of_this_projects_writer_reads_the_grid_words_near_its_maximum_as_valid(tmp_path: Path) -> None:
    """This project's writer marks its logs with PARAM lmsbench_range_units, writes the exact maximum and no return
    as a SICK code, never a rounded maximum. Its older versions wrote a valid reading near a maximum just off the
    grid as the grid word: a ROS float32 range_max (6.3 stored as 6.300000190734863) in mm, 30.005 m in cm. Those
    words were read as no return by the grid rule ([1.0, inf, inf], main read [1.0, 6.3, 6.3]); such a log reads
    them as valid readings, and the exact maximum alone as no return. The lines are the older writer's own."""
    rl = "0.0 0.0 0.0 0.0 0.0 0.0 0.000000 0.000000 0.000000 0.000000 0.000000 3.0 lmsbench 3.0"
    path = _log(tmp_path, ["PARAM lmsbench_range_units mm lmsbench 0", "PARAM lmsbench_odometry absent lmsbench 0",
                           f"ROBOTLASER1 0 -0.1 0.15000000000000002 0.05 6.300000190734863 0.001 0 4 1.000 6.300 6.300 "
                           f"6.300000190734863 0 {rl}"])
    scan = list(read_log(path))[0].scan
    assert scan.ranges.tolist() == [1.0, 6.3, 6.3, np.inf] and scan.valid.tolist() == [True, True, True, False]
    path = _log(tmp_path, ["PARAM lmsbench_range_units cm lmsbench 0", "PARAM lmsbench_odometry absent lmsbench 0",
                           f"ROBOTLASER1 0 -0.1 0.15000000000000002 0.05 30.005 0.01 0 4 1.00 30.00 30.00 81.83 0 {rl}"])
    scan = list(read_log(path))[0].scan
    assert scan.ranges.tolist() == [1.0, 30.0, 30.0, np.inf] and scan.valid.tolist() == [True, True, True, False]
    path = _log(tmp_path, ["PARAM lmsbench_range_units cm lmsbench 0", "PARAM robot_front_laser_max 4.095 nohost 0",
                           f"FLASER 4 1.00 4.09 4.10 4.095 {POSES} 10.0 b21 10.0"])  # FLASER too
    scan = list(read_log(path))[0].scan
    assert scan.ranges.tolist() == [1.0, 4.09, 4.1, np.inf] and scan.valid.tolist() == [True, True, False, False]


def test_held_lines_whose_ending_a_pass_ended_by_an_error_cannot_tell_are_listed_as_skipped(tmp_path: Path,
                                                                                           monkeypatch) -> None:
    """A review: with skip_bad_lines, a pass ended by an error (here a run of blank lines) while laser lines of
    differing endings (neither CARMEN's) were held left them out without a word: stats.skipped held the ODOM line
    between them alone ([2]). They are listed, in log order, with why."""
    from lms200 import carmen

    monkeypatch.setattr(carmen, "MAX_BLANK_RUN", 3)
    path = _log(tmp_path, [f"FLASER 3 {RANGES} {POSES} 9.0 9.01", "ODOM x", f"FLASER 3 {RANGES} {POSES} 10.0 a b c 10.01"]
                + [""] * 5)
    reader = read_log(path, skip_bad_lines=True)
    got: list[float] = []
    with pytest.raises(LogFormatError, match=r"log\.clf:4: more than 3 blank or comment lines in a row"):
        got.extend(r.scan.stamp for r in reader)
    why = ("FLASER: the pass ended by an error before the laser lines' ending could be told (the held lines have 1, 4 "
           "words after their ipc_timestamp, none shared, none as CARMEN writes); not read")
    assert got == [] and reader.stats.skipped == [(1, why), (2, "ODOM: ODOM needs x y theta tv rv accel timestamp"),
                                                  (3, why)]
    assert reader.stats.skipped_count == 3
