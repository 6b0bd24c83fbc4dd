"""Logs of scanners other than the LMS200 (Hokuyo shapes: 1081 beams over 270 deg, 683 over 240 deg).

Found by building such logs from the simulator and running every command on them (session 34):
SLAM de-skewed every scan with the LMS200's interlaced mirror timing, whatever its shape.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lms200 import Record, Scan, write_log
from lms200.timing import beam_time_offsets

UTM_STEP_S = 0.025 / 1440  # s between beams of a Hokuyo UTM-30LX (a 1440-step turn in 25 ms)
ROOM = np.array([  # walls (x0, y0, x1, y1), m: a room with two boxes, so no pose looks like another
    (-9, -5, 9, -5), (9, -5, 9, 5), (9, 5, -9, 5), (-9, 5, -9, -5),
    (2, 1, 3, 1), (3, 1, 3, 2.5), (3, 2.5, 2, 2.5), (2, 2.5, 2, 1),
    (-4, -2, -3, -2), (-3, -2, -3, -1.2), (-3, -1.2, -4, -1.2), (-4, -1.2, -4, -2),
], float)


def _cast(origins: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """Exact ranges (m) of rays from (n, 2) origins along (n,) headings to the nearest wall of ROOM."""
    d = np.column_stack((np.cos(headings), np.sin(headings)))[:, None, :]
    a, e = ROOM[None, :, :2], (ROOM[:, 2:] - ROOM[:, :2])[None]
    w = a - origins[:, None, :]
    den = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * e[..., 1] - w[..., 1] * e[..., 0]) / den
        u = (w[..., 0] * d[..., 1] - w[..., 1] * d[..., 0]) / den
    t = np.where((t > 0) & (u >= 0) & (u <= 1) & np.isfinite(t), t, np.inf)
    return t.min(axis=1)


def _pose(t: np.ndarray) -> np.ndarray:
    """(n, 3) a circle of 1.2 m radius about (0, -0.5) at 1 rad/s, heading along it."""
    phi = 1.0 * t
    return np.column_stack((1.2 * np.cos(phi), -0.5 + 1.2 * np.sin(phi), phi + math.pi / 2))


def hokuyo_run(n: int = 1081, res_deg: float = 0.25, scans: int = 60, rate_hz: float = 10.0,
               step_s: float = UTM_STEP_S, noise: float = 0.005) -> list[Record]:
    """A Hokuyo-like run: beams swept in beam order ``step_s`` apart from the moving robot, ``noise`` m
    of range noise, 1 mm steps."""
    rng = np.random.default_rng(0)
    res = math.radians(res_deg)
    start = -(n - 1) / 2 * res
    records = []
    for k in range(scans):
        t0 = k / rate_hz
        poses = _pose(t0 + np.arange(n) * step_s)
        r = _cast(poses[:, :2], poses[:, 2] + start + np.arange(n) * res)
        r = np.round(r + rng.normal(0, noise, n), 3)
        p = tuple(float(v) for v in _pose(np.array([t0]))[0])
        records.append(Record(Scan(r, start, res, 0.0, 30.0, t0), odom=p, truth=p))
    return records


def test_only_lms200_shaped_scans_are_lms200_shaped():
    from lms200.timing import lms200_shaped

    d = math.radians
    for n, res in ((361, 0.5), (360, 0.5), (181, 1.0), (180, 1.0), (721, 0.25), (401, 0.25), (101, 1.0)):
        assert lms200_shaped(n, d(res)), (n, res)
    assert lms200_shaped(361, 0.008727)  # the CSAIL ROBOTLASER1 log's 6-decimal step
    for n, res in ((1081, 0.25), (769, 360 / 1024), (683, 360 / 1024), (726, 360 / 1024), (362, 0.5), (182, 1.0),
                   (360, 1.0), (541, 0.5), (1440, 0.25)):
        assert not lms200_shaped(n, d(res)), (n, res)


def test_deskew_times_follow_the_scan_shape():
    from slam.scanslam import _offsets
    from slam import SlamConfig

    al = SlamConfig().alignment
    lms = Scan.lms200(np.full(361, 3.0))
    np.testing.assert_array_equal(_offsets(lms, al), beam_time_offsets(361, lms.angle_increment))
    assert _offsets(lms, al)[1] == pytest.approx(1 / 75 + 0.5 / 360 / 75)  # the odd beams: the second turn
    hokuyo = hokuyo_run(scans=1)[0].scan
    assert _offsets(hokuyo, al) is None  # was the LMS200's: beam 1 at 13.3 ms, the last at 50 ms
    given = SlamConfig.from_dict({"alignment": {"beam_time_increment": UTM_STEP_S}}).alignment
    times = _offsets(hokuyo, given)
    assert times[1] == pytest.approx(UTM_STEP_S) and times[-1] == pytest.approx(1080 * UTM_STEP_S)


def _wall_scatter(points: np.ndarray) -> float:
    """RMS distance (m) of the points on the far wall x = 9 m of ROOM (world frame) from their own fitted line."""
    pts = points[np.isfinite(points).all(axis=1)]
    c = pts - pts.mean(axis=0)
    return float(np.sqrt(np.linalg.eigvalsh(c.T @ c / len(c))[0]))


def test_deskew_of_a_hokuyo_scan_keeps_a_wall_straight():
    """One noise-free UTM-30LX scan taken while turning at 1 rad/s (1.2 m/s ahead), de-skewed with the
    true twist by ScanSlam.deskew and the times ``_offsets`` gives: the far wall's points stay on a
    line. With the LMS200's interlaced times (the old default) neighbours 13-40 ms apart were moved
    apart by the turn: a zigzag of 34 mm RMS about the wall."""
    from slam import SlamConfig
    from slam.scanslam import ScanSlam, _offsets

    rec = hokuyo_run(scans=1, noise=0.0)[0]
    scan = rec.scan
    x, y, th = rec.truth
    twist = np.array([1.2, 0.0, 1.0])  # the circle's v (m/s, sensor x) and w (rad/s)

    class Moving:
        def velocity(self) -> np.ndarray:
            return twist

    def on_wall(offsets):
        pts = scan.points if offsets is None else ScanSlam.deskew(Moving(), scan.points, offsets)  # type: ignore[arg-type]
        c, s = math.cos(th), math.sin(th)
        world = np.column_stack((x + c * pts[:, 0] - s * pts[:, 1], y + s * pts[:, 0] + c * pts[:, 1]))
        return world[(np.abs(world[:, 0] - 9.0) < 0.5) & (np.abs(world[:, 1]) < 4.0)]  # corners left out

    al = SlamConfig().alignment
    timed = SlamConfig.from_dict({"alignment": {"beam_time_increment": UTM_STEP_S}}).alignment
    assert len(on_wall(None)) == 216
    assert _wall_scatter(on_wall(beam_time_offsets(len(scan), scan.angle_increment))) > 0.03  # the old timing: 34 mm
    assert _offsets(scan, al) is None and _wall_scatter(on_wall(None)) < 0.003  # not de-skewed: 2.2 mm (a slight bend)
    assert _wall_scatter(on_wall(_offsets(scan, timed))) < 0.0005  # the scanner's own timing: 0.3 mm (1 mm steps)


def test_slam_command_says_it_does_not_deskew_a_hokuyo_log(tmp_path, capsys):
    from experiments.cli import main
    from lms200.yamlio import load

    log = tmp_path / "utm.log"
    write_log(log, hokuyo_run(scans=12))
    out = tmp_path / "run"
    assert main(["slam", str(log), "--out", str(out), "--quiet", "--no-paper-baseline"]) == 0
    err = capsys.readouterr().err
    assert (f"{log}: 1081 beams at 0.25 deg over 270 deg, which no LMS200 takes: its beam timing is unknown, "
            "alignment.deskew off") in err
    alignment = load((out / "config.yaml").read_text())["slam"]["alignment"]
    assert alignment["deskew"] is False and alignment["beam_time_increment"] == 0.0  # the config that ran
    out2 = tmp_path / "timed"
    (tmp_path / "timed.yaml").write_text(f"alignment:\n  beam_time_increment: {UTM_STEP_S!r}\n")
    assert main(["slam", str(log), "--out", str(out2), "--quiet", "--no-paper-baseline",
                 "--config", str(tmp_path / "timed.yaml")]) == 0
    assert "no LMS200" not in capsys.readouterr().err
    assert load((out2 / "config.yaml").read_text())["slam"]["alignment"]["deskew"] is True


def test_beam_time_increment_is_bounded(tmp_path):
    from slam import SlamConfig
    from slam.config import SlamConfigError

    with pytest.raises(SlamConfigError, match=r"alignment.beam_time_increment: must be in \[0, 0.01\] s"):
        SlamConfig.from_dict({"alignment": {"beam_time_increment": 1.0}})
    with pytest.raises(SlamConfigError, match=r"alignment.beam_time_increment: must be in \[0, 0.01\] s between beams"):
        SlamConfig.from_dict({"alignment": {"beam_time_increment": -1e-5}})


def test_calibrate_and_sim2real_refuse_a_270_deg_log_in_one_line(tmp_path, capsys):
    """calibrate measured a 1081-beam 270 deg log and wrote a 721-beam 180 deg sensor (``n_beams``
    cut, silently), which sim2real then simulated against the log's 270 deg scans."""
    from experiments.cli import main

    log = tmp_path / "utm.log"
    write_log(log, hokuyo_run(scans=8))
    expected = (f"{log}: its scans hold 1081 beams at 0.25 deg, 270 deg from first to last: the LMS200 model spans "
                "at most 180 deg (721 beams at 0.25 deg); calibrate and sim2real cannot model this scanner")
    assert main(["calibrate", str(log), "--out", str(tmp_path / "sensor.yaml")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"lmsbench calibrate: error: {expected}"]
    assert not (tmp_path / "sensor.yaml").exists()
    assert main(["sim2real", str(log), "--seeds", "0", "--duration", "2", "--out", str(tmp_path / "s2r")]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"lmsbench sim2real: error: {expected}"


def _rawlaser_line(scan: Scan, stamp: float) -> str:
    n, fov = len(scan), (len(scan) - 1) * scan.angle_increment
    ranges = " ".join(f"{r:.2f}" for r in scan.ranges)
    return (f"RAWLASER1 0 {scan.angle_min!r} {fov!r} {scan.angle_increment!r} 81.9 0.01 0 {n} {ranges} "
            f"{n} {' '.join('7' for _ in range(n))} {stamp!r} host {stamp!r}")


def test_rawlaser_scans_take_odometry_interpolated_from_odom_lines(tmp_path):
    """A CARMEN 0.7 log of RAWLASER1 lines (with remissions) and ODOM lines at 20 Hz, each scan's line
    written after the first ODOM line stamped after it (as a logger writes what arrives): the scans
    read as written, each with the pose interpolated at its stamp (linear motion, the heading across
    +-pi the shorter way); none before the first ODOM line or inside a 1 s gap of the odometry.
    Before, every RAWLASER scan read with odom None (info: "odometry no"; slam --odometry refused)."""
    from lms200 import read_log

    def pose(t: float) -> tuple[float, float, float]:
        return (0.5 * t, -0.2 * t, math.remainder(2.5 + 0.8 * t, 2 * math.pi))

    odom_stamps = [0.05 * k for k in range(1, 81) if not 30 <= k < 50]  # 0.05 .. 4.0 s, none in 1.5 .. 2.45 s
    scan_stamps = [0.02 + 0.2 * k for k in range(20)]  # 0.02 .. 3.82 s
    scans = [Scan.lms200(np.round(2.0 + 0.3 * np.sin(np.arange(361) / 40 + k), 2), stamp=t)
             for k, t in enumerate(scan_stamps)]
    lines, pending = [], list(zip(scan_stamps, scans))
    for t in odom_stamps:
        x, y, th = pose(t)
        lines.append(f"ODOM {x!r} {y!r} {th!r} 0.5 0.8 0 {t!r} host {t!r}")
        while pending and pending[0][0] < t:
            lines.append(_rawlaser_line(pending[0][1], pending[0][0]))
            pending.pop(0)
    lines += [_rawlaser_line(sc, t) for t, sc in pending]
    log = tmp_path / "raw.log"
    log.write_text("\n".join(lines) + "\n")
    recs = list(read_log(log))
    assert [r.scan.stamp for r in recs] == scan_stamps
    for rec, sc in zip(recs, scans):
        np.testing.assert_array_equal(rec.scan.ranges, sc.ranges)
    got = {round(r.scan.stamp, 2): r.odom for r in recs}
    assert got[0.02] is None  # before the first ODOM line (0.05 s)
    assert [t for t, p in got.items() if p is None] == [0.02, 1.62, 1.82, 2.02, 2.22, 2.42]  # 1.5 .. 2.45 s: no ODOM
    for t, p in got.items():
        if p is not None:
            np.testing.assert_allclose(p[:2], pose(t)[:2], atol=1e-12)
            assert abs(math.remainder(p[2] - pose(t)[2], 2 * math.pi)) < 1e-12, t
    assert any(abs(p[2]) > 3.0 for p in got.values() if p is not None)  # the heading crossed +-pi in the run


def test_rawlaser_lines_written_late_behind_fast_odometry_still_take_their_pose(tmp_path):
    """ODOM at 100 Hz and each RAWLASER line written 0.1 s after its stamp (10 ODOM lines later):
    every scan read with odom None (a review: the pairing kept the last 8 ODOM lines only). Now the
    ODOM lines of the last ODOM_KEEP_S are kept: each scan takes its interpolated pose."""
    from lms200 import read_log

    def pose(t: float) -> tuple[float, float, float]:
        return (0.3 * t, 0.1 * t, math.remainder(0.4 * t, 2 * math.pi))

    scan_stamps = [0.105 + 0.2 * k for k in range(12)]
    scans = [Scan.lms200(np.full(361, 3.0), stamp=t) for t in scan_stamps]
    lines, pending = [], list(zip(scan_stamps, scans))
    for k in range(1, 301):  # 0.01 .. 3.0 s
        t = 0.01 * k
        x, y, th = pose(t)
        lines.append(f"ODOM {x!r} {y!r} {th!r} 0.3 0.4 0 {t!r} host {t!r}")
        while pending and pending[0][0] + 0.1 <= t:
            lines.append(_rawlaser_line(pending[0][1], pending[0][0]))
            pending.pop(0)
    log = tmp_path / "late.log"
    log.write_text("\n".join(lines) + "\n")
    recs = list(read_log(log))
    assert [r.scan.stamp for r in recs] == scan_stamps
    for rec in recs:
        assert rec.odom is not None, rec.scan.stamp
        np.testing.assert_allclose(rec.odom, pose(rec.scan.stamp), atol=1e-9)


def test_odom_pairing_survives_scan_stamps_far_ahead_of_the_odometry():
    """A scan stamped 10 s after the last ODOM line (two clocks, or one bad stamp) made the next
    ODOM line empty the kept lines and raise IndexError (`lmsbench info: internal error`); the
    lines are kept behind the latest ODOM stamp instead, and the scans read on."""
    from lms200.carmen_odom import OdomPairing
    from lms200.records import Record

    pairing = OdomPairing()
    assert list(pairing.odom(10.0, (0.0, 0.0, 0.0))) == []
    ahead = Record(scan=Scan.lms200(np.full(361, 2.0), stamp=20.0), odom=None, truth=None)
    assert list(pairing.scan(ahead)) == []
    assert list(pairing.odom(11.0, (1.0, 0.0, 0.0))) == []
    near = Record(scan=Scan.lms200(np.full(361, 2.0), stamp=10.5), odom=None, truth=None)
    released = list(pairing.scan(near)) + list(pairing.flush())
    assert [r.scan.stamp for r in released] == [20.0, 10.5]
    assert released[0].odom is None and released[1].odom == pytest.approx((0.5, 0.0, 0.0))


def _bag_with_timing(path, records, time_increment: float):
    """A ROS 2 bag of ``records``' scans written with rosbags itself, each LaserScan giving
    ``time_increment`` (s between beams), as a Hokuyo driver does."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    LS, H, Time = T["sensor_msgs/msg/LaserScan"], T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    with Writer(path, version=8) as w:
        conn = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        for rec in records:
            s = rec.scan
            ns = round(s.stamp * 1e9)
            msg = LS(header=H(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="laser"),
                     angle_min=s.angle_min, angle_max=s.angle_max, angle_increment=s.angle_increment,
                     time_increment=time_increment, scan_time=len(s) * time_increment, range_min=0.02,
                     range_max=s.range_max, ranges=s.ranges.astype(np.float32), intensities=np.zeros(0, np.float32))
            w.write(conn, ns + 1, ts.serialize_cdr(msg, "sensor_msgs/msg/LaserScan"))
    return path


def test_slam_deskews_a_bag_with_the_time_increment_its_scans_give(tmp_path, capsys):
    """A Hokuyo bag's LaserScans say the time between beams (time_increment), which the reader
    dropped: `slam` ran such a bag without de-skew, as for a log of unknown timing. Now a bag whose
    scans all give one time_increment is de-skewed with it, said in one line and in config.yaml;
    lms200's own writer gives 0 (unknown) for scans no LMS200 takes, not the LMS200's mirror timing."""
    from experiments.cli import main
    from lms200 import read_log
    from lms200.yamlio import load

    records = hokuyo_run(scans=12)
    bag = _bag_with_timing(tmp_path / "utm", records, UTM_STEP_S)
    reader = read_log(bag)
    assert len(list(reader)) == 12 and reader.stats.time_increment == pytest.approx(UTM_STEP_S, rel=1e-6)
    out = tmp_path / "run"
    assert main(["slam", str(bag), "--out", str(out), "--quiet", "--no-paper-baseline"]) == 0
    err = capsys.readouterr().err
    assert ("1081 beams at 0.25 deg over 270 deg, which no LMS200 takes: de-skewed with the bag's time_increment, "
            "17.36 us between beams (alignment.beam_time_increment)") in err
    alignment = load((out / "config.yaml").read_text())["slam"]["alignment"]
    assert alignment["deskew"] is True and alignment["beam_time_increment"] == pytest.approx(UTM_STEP_S, rel=1e-6)
    write_log(tmp_path / "ours.bag", records)  # lms200's writer: a scan no LMS200 takes has no known timing
    reader = read_log(tmp_path / "ours.bag")
    assert len(list(reader)) == 12 and reader.stats.time_increment is None  # was the LMS200's 9.26 us
    lms = [Record(Scan.lms200(np.full(361, 3.0), stamp=0.1 * k)) for k in range(3)]
    write_log(tmp_path / "lms.bag", lms)
    reader = read_log(tmp_path / "lms.bag")
    assert len(list(reader)) == 3 and reader.stats.time_increment == pytest.approx(0.5 / 360 / 75, rel=1e-6)
    reader = read_log(_bag_with_timing(tmp_path / "zero", records[:3], 0.0))
    assert len(list(reader)) == 3 and reader.stats.time_increment is None  # 0: unknown


def test_bag_timing_is_one_value_or_none():
    """One timing for the bag: the scans' time_increment where they agree within 5 % (their mean:
    a driver that measures each scan's period, rplidar_ros, gives a slightly different one in every
    scan, which a review found left such a bag without de-skew), else none."""
    from lms200.bag import BagReadStats

    stats = BagReadStats()
    assert stats.time_increment is None
    for _ in range(3):
        stats.see_timing(1.5625e-05, 0.01)
    assert stats.time_increment == 1.5625e-05  # exactly (a review: the mean gave 1.5624999999999143e-05)
    stats = BagReadStats()
    stats.see_timing(1e-5, 0.01)
    stats.see_timing(1.02e-5, 0.01)
    assert stats.time_increment == pytest.approx(1.01e-5, rel=1e-9)  # within 5 %: their mean
    stats.see_timing(2e-5, 0.01)
    assert stats.time_increment is None  # two timings: none trusted
    for bad in (0.0, float("nan")):
        stats = BagReadStats()
        stats.see_timing(1e-5, 0.01)
        stats.see_timing(bad, 0.01)  # unknown in one scan
        assert stats.time_increment is None
    stats = BagReadStats()
    stats.see_timing(1e-5, -0.01)  # swept clockwise: read reversed, its last beam first
    assert stats.time_increment is None
