"""CARMEN and ROS-bag logs: the real logs of ../shared/data, round trips, malformed lines."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from lms200 import LogFormatError, Record, Scan, read_log, write_log
from lms200.bag import BagError

pytestmark = []


def _records(n: int = 5, units: str = "mm", beams: int = 361, seed: int = 0) -> list[Record]:
    """Scans at the sensor's unit, with +inf / nan beams, odometry and truth on some records."""
    rng = np.random.default_rng(seed)
    unit = 0.001 if units == "mm" else 0.01
    range_max = 8.183 if units == "mm" else 81.83
    out = []
    for i in range(n):
        r = np.round(rng.uniform(0.2, 7.9, beams) / unit) * unit
        r[rng.integers(0, beams, 5)] = np.inf
        r[rng.integers(0, beams, 3)] = np.nan
        if beams == 361:
            scan = Scan.lms200(r, stamp=1000.0 + 0.026667 * i, range_max=range_max)
        else:
            scan = Scan(r, -np.deg2rad(50), np.deg2rad(0.25), 0.0, range_max, 5.0 + i)
        odom = (float(i), 0.5 * i, -0.1 * i) if i % 2 == 0 else None
        truth = (0.1 * i, -0.2 * i, 3.0) if i != 1 else None
        out.append(Record(scan, odom, truth))
    return out


def _assert_same(a: list[Record], b: list[Record], atol: float = 1e-9, poses: bool = True) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert len(x.scan) == len(y.scan)
        np.testing.assert_allclose(y.scan.ranges, x.scan.ranges, atol=atol, rtol=0)  # inf/nan positions equal too
        assert y.scan.angle_min == x.scan.angle_min and y.scan.angle_increment == x.scan.angle_increment
        assert y.scan.stamp == pytest.approx(x.scan.stamp, abs=1e-6)
        if poses:
            for p, q in ((x.truth, y.truth), (x.odom, y.odom)):
                assert (p is None) == (q is None)
                if p is not None:
                    np.testing.assert_allclose(q, p, atol=1e-6)


# --- real logs -----------------------------------------------------------------------------------
@pytest.mark.shared_data
def test_mit_csail_flaser(shared_data: Path) -> None:
    recs = list(read_log(shared_data / "mit-csail.clf.gz"))
    assert len(recs) == 1988
    s = recs[0].scan
    assert len(s) == 361 and s.angle_min == -np.pi / 2 and s.angle_increment == np.deg2rad(0.5)
    assert s.stamp == 1134864629.895182
    assert recs[0].odom == (576.536523, 0.106594, -2.255213) and recs[0].truth is None
    np.testing.assert_allclose(s.ranges[:4], [1.40, 1.39, 1.39, 1.39])
    assert np.isnan(s.ranges[24])  # 81.91 = SICK 8191, not valid
    assert recs[-1].scan.stamp - s.stamp == pytest.approx(424.0, abs=0.5)
    stamps = np.array([r.scan.stamp for r in recs])
    rel = np.loadtxt(shared_data / "mit-csail.relations", usecols=(0, 1)).ravel()
    gap = np.abs(rel[:, None] - stamps[None, :]).min(axis=1)
    assert gap.max() < 1e-5  # every relation timestamp is a scan stamp (printed to 5 or 6 decimals)


@pytest.mark.shared_data
def test_csail_robotlaser1(shared_data: Path) -> None:
    recs = list(read_log(shared_data / "csail-robotlaser1.log.gz"))
    assert len(recs) == 686
    s = recs[0].scan
    assert s.angle_min == -np.pi / 2 and s.angle_increment == np.deg2rad(0.5) and s.range_max == 80.0
    assert s.stamp == 1134864642.914187
    with gzip.open(shared_data / "csail-robotlaser1.log.gz", "rt") as f:
        raw = np.array(f.readline().split()[9:370], dtype=float)
    np.testing.assert_array_equal(np.isnan(s.ranges), raw == 81.91)
    np.testing.assert_array_equal(s.ranges[raw < 80], raw[raw < 80])
    assert recs[1].odom == (0.319678, 0.110037, 0.994330)


@pytest.mark.shared_data
@pytest.mark.parametrize(("name", "count"), [("intel-corrected.log.gz", 910), ("aces-corrected.log.gz", 440)])
def test_intel_and_aces(shared_data: Path, name: str, count: int) -> None:
    reader = read_log(shared_data / name)
    recs = list(reader)
    assert len(recs) == count
    s = recs[0].scan
    assert len(s) == 180 and s.angle_increment == np.deg2rad(1.0)
    assert s.angle_max == pytest.approx(np.deg2rad(89.0))
    assert reader.stats.messages["FLASER"] == count and reader.stats.messages["ODOM"] > count
    if name.startswith("intel"):
        assert recs[0].scan.stamp == 32.9068
        assert recs[0].odom == (0.600266, -0.0320327, -0.354665)
        inf_fraction = np.mean([np.isposinf(r.scan.ranges).mean() for r in recs])
        assert 0.02 < inf_fraction < 0.03  # 81.83 = SICK 8183, beyond maximum range


# --- round trips -----------------------------------------------------------------------------------
@pytest.mark.parametrize("units", ["mm", "cm"])
@pytest.mark.parametrize("name", ["run.clf", "run.clf.gz"])
def test_carmen_robotlaser1_round_trip(tmp_path: Path, units: str, name: str) -> None:
    recs = _records(units=units)
    assert write_log(tmp_path / name, recs) == len(recs)
    _assert_same(recs, list(read_log(tmp_path / name)))


def test_carmen_round_trip_401_beams(tmp_path: Path) -> None:
    recs = _records(beams=401)
    write_log(tmp_path / "narrow.clf", recs)
    _assert_same(recs, list(read_log(tmp_path / "narrow.clf")))


def test_carmen_flaser_round_trip(tmp_path: Path) -> None:
    recs = _records(units="cm")
    write_log(tmp_path / "run.log", recs, fmt="flaser")
    back = list(read_log(tmp_path / "run.log"))
    # FLASER carries one pose pair: odometry round-trips; records without odometry read back (0, 0, 0)
    _assert_same(recs, back, poses=False)
    assert [r.odom for r in back] == [r.odom for r in recs]  # None round-trips as PARAM lmsbench_odometry
    centred = [Record(Scan(np.ones(100), -1.0, 0.02, 0.0, 8.183))]  # even count: -1.0 .. +1.0 - 0.02 rad
    write_log(tmp_path / "centred.log", centred, fmt="flaser")  # PARAM lines carry any centred geometry
    _assert_same(centred, list(read_log(tmp_path / "centred.log")), poses=False)
    odd = Record(Scan(np.ones(100), -1.0, 0.01, 0.0, 8.183))  # not centred ahead: FLASER has no start angle
    with pytest.raises(ValueError, match="robotlaser1"):
        write_log(tmp_path / "bad.log", [odd], fmt="flaser")


@pytest.mark.parametrize("fmt", ["robotlaser1", "flaser"])
def test_carmen_round_trip_keeps_range_min(tmp_path: Path, fmt: str) -> None:
    """No CARMEN laser line has a range_min field: written by write_log and read back, a scan's
    range_min was 0.0 whatever it had been (0.05 m), so beams nearer than it became valid. A PARAM
    lmsbench_range_min line now carries it, written only where it changes (not for range_min 0)."""
    ranges = np.array([0.03, 0.5, 1.0, 2.0, 3.0])  # beam 0 lies below 0.05 m: not valid
    recs = [Record(Scan(ranges, -0.02, 0.01, rmin, 8.183, stamp=1.0 + i)) for i, rmin in enumerate((0.05, 0.05, 0.0, 0.1))]
    write_log(tmp_path / "r.clf", recs, fmt=fmt)
    back = list(read_log(tmp_path / "r.clf"))
    assert [r.scan.range_min for r in back] == [0.05, 0.05, 0.0, 0.1]  # was [0.0, 0.0, 0.0, 0.0]
    assert [r.scan.valid.tolist() for r in back] == [r.scan.valid.tolist() for r in recs]
    assert (tmp_path / "r.clf").read_text().count("PARAM lmsbench_range_min") == 3  # 0.05, 0.0, 0.1
    write_log(tmp_path / "zero.clf", _records(n=2), fmt=fmt)  # range_min 0: no such line, the log as before
    assert "lmsbench_range_min" not in (tmp_path / "zero.clf").read_text()


@pytest.mark.parametrize("value", ["-0.1", "nan", "inf", "abc"])
def test_a_bad_range_min_param_names_file_and_line(tmp_path: Path, value: str) -> None:
    path = tmp_path / "bad.log"
    path.write_text(f"{GOOD}\nPARAM lmsbench_range_min {value} host 0\n{GOOD}\n")
    with pytest.raises(LogFormatError, match=r"bad\.log:2: malformed PARAM line: .*lmsbench_range_min"):
        list(read_log(path))


@pytest.mark.parametrize("fmt,name", [("bag", "run.bag"), ("bag2", "run_ros2")])
def test_bag_round_trip(tmp_path: Path, fmt: str, name: str) -> None:
    recs = _records()
    assert write_log(tmp_path / name, recs, fmt=fmt) == len(recs)
    back = list(read_log(tmp_path / name))
    # LaserScan stores float32: ranges to float32 precision; angles snap back onto the 0.05 deg grid
    _assert_same(recs, back, atol=1e-6, poses=False)
    for x, y in zip(recs, back):  # each scan's own poses; None stays None (not the previous pose)
        for written, read in ((x.truth, y.truth), (x.odom, y.odom)):
            if written is None:
                assert read is None
            else:
                np.testing.assert_allclose(read, written, atol=1e-9)
    assert recs[1].odom is None and back[1].odom is None  # was the previous scan's odometry
    assert recs[1].truth is None and back[1].truth is None


@pytest.mark.parametrize("beams,increment_deg,range_max,turns,unit", [
    (361, 0.5, 8.183, 2, 0.001), (181, 1.0, 81.83, 1, 0.01), (401, 0.25, 8.183, 4, 0.001)])
def test_written_laserscans_carry_the_lms200_timing_and_range_min(tmp_path: Path, beams: int, increment_deg: float,
                                                                   range_max: float, turns: int, unit: float) -> None:
    """time_increment = the mirror's time per beam step (75 rev/s), scan_time = 1/75 s per interlaced turn,
    range_min = one code unit; read back with rosbags itself, not our reader."""
    from rosbags.rosbag1 import Reader
    from rosbags.typesys import Stores, get_typestore

    inc = np.deg2rad(increment_deg)
    scan = Scan(np.full(beams, 2.0), -(beams - 1) / 2 * inc, inc, 0.0, range_max, stamp=1.0)
    write_log(tmp_path / "t.bag", [Record(scan)])
    ts = get_typestore(Stores.ROS1_NOETIC)
    with Reader(tmp_path / "t.bag") as reader:
        (conn, _, raw), = list(reader.messages())
        msg = ts.deserialize_ros1(raw, conn.msgtype)
    assert msg.time_increment == pytest.approx((1 / 75) * increment_deg / 360, rel=1e-6)  # 0.5 deg: 18.5 us
    assert msg.scan_time == pytest.approx(turns / 75, rel=1e-6)
    assert msg.range_min == pytest.approx(unit)
    assert len(msg.ranges) == beams


def test_bag_pose_tolerance_is_half_the_median_scan_period() -> None:
    from lms200.bag import STAMP_EPS_S, pose_tolerance

    ns = [1_000_000_000 + 26_666_667 * i for i in range(10)] + [1_500_000_000]  # 37.5 Hz and one stray
    assert pose_tolerance(ns) == pytest.approx(0.5 * 0.026666667, abs=1e-9)
    assert pose_tolerance([5]) == pose_tolerance([]) == STAMP_EPS_S


def test_bag_errors(tmp_path: Path) -> None:
    write_log(tmp_path / "a.bag", _records(n=1))
    with pytest.raises(FileExistsError):
        write_log(tmp_path / "a.bag", _records(n=1))
    with pytest.raises(BagError, match="no topic '/laser'"):
        list(read_log(tmp_path / "a.bag", topic="/laser"))
    (tmp_path / "junk.bag").write_bytes(b"#ROSBAG V2.0\n garbage")
    with pytest.raises(BagError, match="junk.bag"):
        list(read_log(tmp_path / "junk.bag"))


# --- malformed input -------------------------------------------------------------------------------
GOOD = "FLASER 180 " + " ".join(["1.0"] * 179 + ["81.83"]) + " 0 0 0 0 0 0 12.5 host 12.5"
R180 = " ".join(["1.5"] * 178)


@pytest.mark.parametrize(
    ("bad", "reason"),
    [
        (f"FLASER 180 {R180} 0 0 0 0 0 0 12.5 host 12.5", "needs 191 fields"),
        (f"FLASER 180 {R180} 1.0 abc 0 0 0 0 0 0 12.5 host 12.5", "'abc' is not a number"),
        (f"FLASER 180 {R180} 1.0 -2.0 0 0 0 0 0 0 12.5 host 12.5", "negative"),
        ("FLASER inf 1 1 1 1 1 1 1 0 0 0 0 0 0 12.5 host 12.5", "non-negative integer written in digits, got 'inf'"),
        ("FLASER 7.5 1 1 1 1 1 1 1 0 0 0 0 0 0 12.5 host 12.5", "non-negative integer written in digits"),
        ("FLASER -7 1 1 1 1 1 1 1 0 0 0 0 0 0 12.5 host 12.5", "non-negative integer written in digits"),
        ("FLASER nan 1 1 1 1 1 1 1 0 0 0 0 0 0 12.5 host 12.5", "non-negative integer written in digits"),
        ("FLASER 1e300 1 1 1 1 1 1 1 0 0 0 0 0 0 12.5 host 12.5", "written in digits, got '1e300'"),
        ("TRUEPOS 1 2", "needs x y theta"),
        ("ODOM 1 2 3", "ODOM needs"),
    ],
)
def test_malformed_line_names_file_and_line(tmp_path: Path, bad: str, reason: str) -> None:
    path = tmp_path / "bad.log"
    path.write_text(f"# comment\n{GOOD}\n\n{bad}\n{GOOD}\n")
    with pytest.raises(LogFormatError, match=rf"bad\.log:4: .*{reason}") as info:
        list(read_log(path))
    assert info.value.line_no == 4
    reader = read_log(path, skip_bad_lines=True)
    recs = list(reader)
    assert len(recs) == 2 and [n for n, _ in reader.stats.skipped] == [4]
    assert np.isposinf(recs[0].scan.ranges[179]) and recs[0].scan.ranges[0] == 1.0


def test_truncated_gzip_names_the_file(tmp_path: Path) -> None:
    data = gzip.compress(("\n".join([GOOD] * 2000) + "\n").encode())
    path = tmp_path / "cut.log.gz"
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(LogFormatError, match=r"cut\.log\.gz:\d+: cannot read on"):
        list(read_log(path))


def test_missing_and_unknown(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="no such log"):
        read_log(tmp_path / "nope.clf")
    path = tmp_path / "x.log"
    path.write_text("NEFF 3\nSYNC 1 2\nRAWLASER1 whatever\n" + GOOD + "\n")
    reader = read_log(path)
    assert len(list(reader)) == 1 and reader.stats.messages["NEFF"] == 1


@pytest.mark.parametrize("name", ["src.clf", "src.log.gz", "src.bag", "src2"])
def test_an_error_of_the_records_themselves_is_raised_as_it_is_not_as_a_failed_write(tmp_path: Path, name: str) -> None:
    """A source that fails while read (a reader's missing file: FileNotFoundError) was said as
    "path: cannot write OUT: No such file or directory", blaming the output; its own exception is
    raised now, and nothing is left at the output."""
    def source():  # noqa: ANN202
        yield Record(Scan(np.full(5, 1.0), -0.1, 0.05, 0.0, 8.0, stamp=1.0))
        raise FileNotFoundError(2, "No such file or directory", "the-input.clf")

    with pytest.raises(FileNotFoundError) as info:
        write_log(tmp_path / name, source(), fmt="bag2" if name == "src2" else None)
    assert info.value.filename == "the-input.clf"
    assert list(tmp_path.iterdir()) == []
