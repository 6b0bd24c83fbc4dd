"""ROS bags and TUM files: stamps, poses and errors reproduced by a review (session 32).

Bags are built both with the project's writer (``write_log``) and with the ``rosbags`` library
directly, so the reader is checked on bags it did not write itself.
"""

from __future__ import annotations

import math
import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lms200 import Record, Scan, read_log, write_log
from lms200.bag import BagError
from lms200.errors import InputError, LmsbenchError, LogFormatError, LogNotFoundError


def _scan(t: float, v: float = 1.0) -> Scan:
    """A 5-beam scan stamped ``t``; a stamp outside 0 .. 2^32 s, which Scan refuses, is set in place past its
    check: what the bag writer still refuses for a Scan changed after it was made."""
    if 0.0 <= t <= 2.0**32:
        return Scan(np.full(5, v), -0.1, 0.05, 0.0, 8.0, stamp=t)
    scan = Scan(np.full(5, v), -0.1, 0.05, 0.0, 8.0)
    object.__setattr__(scan, "stamp", t)
    return scan


def _ros2_bag(path: Path, messages: list[tuple], beams: int = 3, range_max: float = 10.0,
             increment: float = 0.01) -> Path:
    """A ROS 2 bag written with rosbags itself: ``messages`` are (topic, bag time s, header stamp s,
    payload) in the order written; payload a range value for /scan (``beams`` of it), (x, y, qx, qy, qz, qw) for a
    pose topic (PoseStamped)."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    LS, H, Time = T["sensor_msgs/msg/LaserScan"], T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    PS, Pose, Pt, Q = (T["geometry_msgs/msg/PoseStamped"], T["geometry_msgs/msg/Pose"], T["geometry_msgs/msg/Point"],
                       T["geometry_msgs/msg/Quaternion"])
    with Writer(path, version=8) as w:
        conns: dict[str, object] = {}
        for topic, bag_t, stamp, payload in messages:
            ns = round(Fraction(stamp) * 10**9)
            header = H(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="x")
            if topic == "/scan":
                kind = "sensor_msgs/msg/LaserScan"
                msg = LS(header=header, angle_min=-1.0, angle_max=-1.0 + (beams - 1) * increment, angle_increment=increment,
                         time_increment=0.0, scan_time=0.0, range_min=0.1, range_max=range_max,
                         ranges=np.full(beams, payload, np.float32),
                         intensities=np.zeros(0, np.float32))
            else:
                kind = "geometry_msgs/msg/PoseStamped"
                x, y, qx, qy, qz, qw = payload
                msg = PS(header=header, pose=Pose(position=Pt(x=x, y=y, z=0.0), orientation=Q(x=qx, y=qy, z=qz, w=qw)))
            if topic not in conns:
                conns[topic] = w.add_connection(topic, kind, typestore=ts)
            w.write(conns[topic], round(Fraction(bag_t) * 10**9), ts.serialize_cdr(msg, kind))
    return path


def _header_stamps(path: Path) -> list[tuple[int, int]]:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([path], default_typestore=get_typestore(Stores.ROS1_NOETIC)) as reader:
        return [(m.header.stamp.sec, m.header.stamp.nanosec)
                for c, _, raw in reader.messages() for m in [reader.deserialize(raw, c.msgtype)]]


# --- stamps -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["s.bag", "s2"])
def test_every_epoch_stamp_round_trips_bit_for_bit(tmp_path: Path, name: str) -> None:
    """round(t * 1e9) in float64 stored 1602566218.7060776 as ...706077696 ns (exact: ...706077576)
    and read back ...7060778; 22 of 300 epoch stamps did not round-trip."""
    rng = np.random.default_rng(2)
    stamps = sorted([1602566218.7060776] + [float(t) for t in rng.uniform(1.6e9, 1.8e9, 300)]
                    + [float(t) for t in rng.uniform(2.0**23, 2.0**31 - 1, 50)])
    write_log(tmp_path / name, [Record(_scan(t)) for t in stamps], fmt="bag" if name.endswith(".bag") else "bag2")
    back = [r.scan.stamp for r in read_log(tmp_path / name)]
    assert back == stamps  # bit for bit
    assert (1602566218, 706077576) in _header_stamps(tmp_path / name)


def test_a_stamp_below_2_to_23_s_reads_back_to_the_nearest_nanosecond(tmp_path: Path) -> None:
    stamps = [0.1, 3.1867706181171185, 1000.0 + 0.026667, 8388607.123456789]
    write_log(tmp_path / "s.bag", [Record(_scan(t)) for t in stamps])
    back = [r.scan.stamp for r in read_log(tmp_path / "s.bag")]
    assert back == [float(Fraction(round(Fraction(t) * 10**9), 10**9)) for t in stamps]
    assert back[:3] == [0.1, 3.186770618, 1000.026667]


# --- what write_log cannot store in a bag -----------------------------------------------------------
@pytest.mark.parametrize("stamp", [-1.5, -1e-10, 2.0**31, 2.0**31 + 0.5, 2.0**32 + 0.5, 1e12])
def test_a_stamp_a_ros2_bag_cannot_hold_is_an_input_error(tmp_path: Path, stamp: float) -> None:
    """-1.5 s and >= 2**31 s raised struct.error from rosbags' serialiser (ROS 2 read -1.5 back)."""
    recs = [Record(_scan(1.0)), Record(_scan(stamp))]
    with pytest.raises(InputError, match=rf"^records: item 1: stamp {re.escape(repr(stamp))} s cannot be stored in a "
                                         r"bag \(a ROS 2 bag holds 0 <= stamp < 2\*\*31 s = 2147483648 s, int32 seconds; "
                                         r"a ROS 1 bag \(\*\.bag\) holds stamps to 2\*\*32 s\)$"):
        write_log(tmp_path / "s2", recs, fmt="bag2")
    assert not (tmp_path / "s2").exists()
    last = np.nextafter(2.0**31, 0)  # the largest stamp a ROS 2 bag holds
    write_log(tmp_path / "s2", [Record(_scan(0.0)), Record(_scan(last))], fmt="bag2")
    assert [r.scan.stamp for r in read_log(tmp_path / "s2")] == [0.0, last]


@pytest.mark.parametrize("stamp", [-1.5, -1e-10, 2.0**32, 2.0**32 + 0.5, 1e12])
def test_a_stamp_a_ros1_bag_cannot_hold_is_an_input_error(tmp_path: Path, stamp: float) -> None:
    recs = [Record(_scan(1.0)), Record(_scan(stamp))]
    with pytest.raises(InputError, match=rf"^records: item 1: stamp {re.escape(repr(stamp))} s cannot be stored in a "
                                         r"bag \(a ROS 1 bag holds 0 <= stamp < 2\*\*32 s = 4294967296 s, uint32 seconds\)$"):
        write_log(tmp_path / "s.bag", recs, fmt="bag")
    assert not (tmp_path / "s.bag").exists()


def test_a_ros1_bag_holds_the_stamps_a_log_reader_takes_up_to_2106(tmp_path: Path) -> None:
    """write_bag refused stamps from 2**31 s (2038-01-19) in a ROS 1 bag too, though its time is uint32
    seconds and a CARMEN log stamped 2038-2106 reads: it could not be converted; and rosbags decodes
    ROS 1 seconds as int32, so such a bag read back negative (refused)."""
    last = np.nextafter(2.0**32, 0)  # the largest stamp a ROS 1 bag holds (2^32 s itself does not fit uint32)
    stamps = [1.0, 2.0**31 - 0.5, 2.0**31, 2.0**31 + 0.25, 3e9, last]
    recs = [Record(_scan(t), odom=(t * 1e-9, 0.0, 0.0), truth=(0.0, 1.0, 0.5)) for t in stamps]
    assert write_log(tmp_path / "s.bag", recs, fmt="bag") == 6
    back = list(read_log(tmp_path / "s.bag"))
    assert [r.scan.stamp for r in back] == stamps
    assert [r.odom for r in back] == [(t * 1e-9, 0.0, 0.0) for t in stamps]  # each scan its own pose, by header stamp
    assert all(r.truth == (0.0, 1.0, pytest.approx(0.5)) for r in back)
    assert (2**31, 0) in [(s % 2**32, n) for s, n in _header_stamps(tmp_path / "s.bag")]


def test_records_of_the_last_stamp_a_ros1_bag_holds_moved_past_it_are_an_input_error(tmp_path: Path) -> None:
    """Bag times move 1 ns past the message before; at the last stamp a ROS 1 bag holds they would
    leave its uint32 seconds (struct.error from rosbags' writer)."""
    last = float(np.nextafter(2.0**32, 0))
    with pytest.raises(InputError, match=r"^records: item \d+: bag time 4294967296000000000 ns \(the stamp, moved 1 ns "
                                         r"past the message before\) cannot be stored in a bag \(a ROS 1 bag holds"):
        write_log(tmp_path / "s.bag", [Record(_scan(last))] * 1000, fmt="bag")


def test_a_bag_pose_stamped_outside_the_logs_range_is_a_bag_error(tmp_path: Path) -> None:
    """A pose's header stamp was not checked (a scan's is): /odom stamped -5 s read, silently."""
    msgs = [("/odom", 10, -5.0, (1.0, 2.0, 0.0, 0.0, 0.0, 1.0)), ("/scan", 10, 10.0, 1.0),
            ("/scan", 11, 11.0, 1.0)]
    path = _ros2_bag(tmp_path / "b", msgs)
    with pytest.raises(BagError, match=r"^.*b: topic /odom message 0: cannot read: header stamp -5.000000 s is outside "
                                       r"0 \.\. 2\^32 s \(4294967296 s, 2106-02-07\)"):
        list(read_log(path))
    reader = read_log(path, skip_bad_lines=True)
    assert [(r.scan.stamp, r.odom) for r in reader] == [(10.0, None), (11.0, None)]
    assert reader.stats.skipped_count == 1


@pytest.mark.parametrize("name", ["a.bag", "a2"])
def test_writing_over_an_existing_bag_is_an_input_error_naming_it(tmp_path: Path, name: str) -> None:
    fmt = "bag" if name.endswith(".bag") else "bag2"
    write_log(tmp_path / name, [Record(_scan(1.0))], fmt=fmt)
    with pytest.raises(InputError, match=rf"path: .*{name} exists; a bag is never written over") as info:
        write_log(tmp_path / name, [Record(_scan(2.0))], fmt=fmt)
    assert isinstance(info.value, FileExistsError) and isinstance(info.value, LmsbenchError)
    assert [r.scan.stamp for r in read_log(tmp_path / name)] == [1.0]  # left as it was


@pytest.mark.parametrize("name", ["full.bag", "full2"])
def test_a_full_disk_while_writing_a_bag_is_one_input_error_and_leaves_no_bag(
        tmp_path: Path, name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """ENOSPC from rosbags' writer (a chunk's write) was a raw OSError (a traceback from the command
    line); it is the CARMEN writer's one line now, and the half-written bag is removed."""
    import errno
    import sqlite3

    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import Writer as Writer2

    fmt = "bag" if name.endswith(".bag") else "bag2"

    def full(*args: object, **kwargs: object) -> None:  # as each writer says it on a full tmpfs
        if fmt == "bag":
            raise OSError(errno.ENOSPC, "No space left on device")
        raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(Writer1 if fmt == "bag" else Writer2, "write", full)
    reason = "No space left on device" if fmt == "bag" else "database or disk is full"
    with pytest.raises(InputError, match=rf"^path: cannot write .*{name}: {reason}$") as info:
        write_log(tmp_path / name, [Record(_scan(1.0)), Record(_scan(2.0))], fmt=fmt)
    assert isinstance(info.value, LmsbenchError)
    assert not (tmp_path / name).exists()


# --- quaternions: normalised, a zero one refused ---------------------------------------------------
_POS = (1.0, 2.0)


def _pose_bag(path: Path, xy: tuple[float, float], q: tuple[float, float, float, float]) -> Path:
    """Three scans at 10, 11, 12 s, each with its odometry (x, y, q) just before it, by rosbags."""
    msgs: list[tuple] = []
    for i in range(3):
        msgs += [("/odom", 10 + i, 10 + i, (*xy, *q)), ("/scan", 10 + i, 10 + i, 1.0)]
    return _ros2_bag(path, msgs)


@pytest.mark.parametrize("q, deg", [((0.0, 0.0, 1.0, 1.0), 90.0), ((0.0, 0.0, 3e-200, 3e-200), 90.0),
                                    ((0.0, 0.0, 1e200, -1e200), -90.0), ((0.0, 0.0, 0.0, 2.0), 0.0),
                                    ((0.0, 0.0, -1.5 * math.sqrt(3), 1.5), -120.0)])
def test_a_bag_pose_of_a_non_unit_quaternion_is_normalised(tmp_path: Path, q: tuple, deg: float) -> None:
    """(0, 0, 1, 1) read as 116.57 deg (the unit formula on a quaternion of norm sqrt 2)."""
    out = list(read_log(_pose_bag(tmp_path / "b", _POS, q)))
    assert [r.odom[:2] for r in out] == [_POS] * 3
    assert [math.degrees(r.odom[2]) for r in out] == pytest.approx([deg] * 3, abs=1e-9)


@pytest.mark.parametrize("q", [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, math.nan, 1.0), (0.0, 0.0, math.inf, 1.0)])
def test_a_bag_pose_with_a_zero_or_non_finite_quaternion_is_a_bag_error(tmp_path: Path, q: tuple) -> None:
    """(0, 0, 0, 0) was read as yaw 0."""
    bag = _pose_bag(tmp_path / "b", _POS, q)
    with pytest.raises(BagError, match=rf"b: topic /odom message 0: cannot read: orientation \(x, y, z, w\) = "
                                       rf"\(0\.0, 0\.0, {re.escape(repr(q[2]))}, {re.escape(repr(q[3]))}\) is no rotation"):
        list(read_log(bag))
    reader = read_log(bag, skip_bad_lines=True)
    out = list(reader)
    assert [r.odom for r in out] == [None] * 3 and [r.scan.stamp for r in out] == [10.0, 11.0, 12.0]
    assert [i for i, _ in reader.stats.skipped] == [0, 1, 2]


def test_a_tum_quaternion_is_normalised_and_a_zero_one_is_refused(tmp_path: Path) -> None:
    from lms200 import read_tum

    path = tmp_path / "u.tum"
    path.write_text("0 0 0 0 0 0 1 1\n1 0 0 0 0 0 0.70710678 0.70710678\n2 0 0 0 0 0 -3 3\n3 5 6 0 0 0 0 7\n")
    stamps, poses = read_tum(path)
    assert np.degrees(poses[:, 2]) == pytest.approx([90.0, 90.0, -90.0, 0.0], abs=1e-6)  # was 116.57 deg first
    assert poses[3, :2].tolist() == [5.0, 6.0]
    path.write_text("0 0 0 0 0 0 1 1\n1 0 0 0 0 0 0 0\n")  # was yaw 0
    with pytest.raises(LogFormatError, match=r"u\.tum:2: TUM row's quaternion \(qx qy qz qw\) is zero: '1 0 0 0 0 0 0 0'"):
        read_tum(path)


def test_quaternion_to_yaw_normalises_and_gives_nan_for_no_rotation() -> None:
    from lms200.tum import quaternion_to_yaw

    q = np.array([[0, 0, 1, 1], [0, 0, 0, 0], [0, 0, np.nan, 1], [0, 0, 0, 1], [0, 0, 1, 0]], dtype=float)
    yaw = quaternion_to_yaw(q)
    assert yaw[[0, 3, 4]] == pytest.approx([np.pi / 2, 0.0, np.pi])
    assert np.isnan(yaw[1]) and np.isnan(yaw[2])


# --- TUM: nan poses, missing paths ------------------------------------------------------------------
def test_a_lost_pose_write_tum_writes_reads_back_with_allow_nan(tmp_path: Path) -> None:
    """write_tum wrote nan poses that read_tum refused: now read_tum(path, allow_nan=True) reads them."""
    from lms200 import read_tum, write_tum

    path = tmp_path / "t.tum"
    poses = np.array([[1.0, 2.0, 0.5], [np.nan, 0.0, 0.2], [np.nan, np.nan, np.nan], [3.0, -1.0, -3.0]])
    write_tum(path, [0.0, 1.0, 2.0, 3.0], poses)
    with pytest.raises(LogFormatError, match=r"t\.tum:3: TUM row has a non-finite number: '1\.0 nan 0\.0 "):
        read_tum(path)  # a ground truth must be finite: the default refuses, as slam needs
    stamps, back = read_tum(path, allow_nan=True)
    assert stamps.tolist() == [0.0, 1.0, 2.0, 3.0]
    np.testing.assert_allclose(back, poses, atol=1e-6)  # nan where nan was written (assert_allclose: nan == nan)
    assert np.isnan(back[1, 0]) and back[1, 1:].tolist() == pytest.approx([0.0, 0.2], abs=1e-6)
    path.write_text("nan 0 0 0 0 0 0 1\n")  # a stamp must be finite either way
    with pytest.raises(LogFormatError, match=r"t\.tum:1: TUM row has a non-finite number"):
        read_tum(path, allow_nan=True)
    path.write_text("0 inf 0 0 0 0 0 1\n")
    with pytest.raises(LogFormatError, match=r"t\.tum:1: TUM row has a non-finite number"):
        read_tum(path, allow_nan=True)


def test_a_tum_file_reads_back_its_stamps_and_poses_exactly(tmp_path: Path) -> None:
    """write_tum wrote 6 decimals (9 for the quaternion): epoch stamps came back up to 477 ns off,
    x and y up to 0.5 um, the yaw 1.3e-9 rad. Now the shortest decimal of every float64: stamps, x,
    y exact, the yaw that of the quaternion written (within 2 ulp of theta); evo reads it too."""
    from lms200 import read_tum, write_tum
    from lms200.tum import quaternion_to_yaw, yaw_to_quaternion

    rng = np.random.default_rng(0)
    n = 300
    stamps = np.sort(np.concatenate([[1e-7, 3.0000004, 1700000000.1234567], rng.uniform(1.6e9, 1.8e9, n)]))
    poses = np.column_stack([rng.uniform(-50, 50, n + 3), rng.uniform(-1e-3, 1e-3, n + 3), rng.uniform(-np.pi, np.pi, n + 3)])
    poses[:3] = [(-0.0, 1e-300, np.pi), (123456.789012345, -5e-324, -0.0), (0.1, 0.2, 1e-20)]
    path = tmp_path / "exact.tum"
    write_tum(path, stamps, poses)
    back_t, back_p = read_tum(path)
    assert back_t.tobytes() == stamps.tobytes() and back_p[:, :2].tobytes() == poses[:, :2].tobytes()
    assert back_p[:, 2].tobytes() == quaternion_to_yaw(yaw_to_quaternion(poses[:, 2])).tobytes()
    assert np.all(np.abs(back_p[:, 2] - poses[:, 2]) <= 2 * np.spacing(np.abs(poses[:, 2])))
    evo = pytest.importorskip("evo.tools.file_interface")
    traj = evo.read_tum_trajectory_file(str(path))
    assert traj.check()[0] and traj.timestamps.tobytes() == stamps.tobytes()
    assert traj.positions_xyz[:, :2].tobytes() == poses[:, :2].tobytes()


def test_write_tum_refuses_an_infinite_pose_read_tum_could_not_read(tmp_path: Path) -> None:
    from lms200 import write_tum

    with pytest.raises(InputError, match=r"poses: row 1 is infinite \(\[inf, 0\.0, 0\.0\]\); a lost pose is written as nan"):
        write_tum(tmp_path / "t.tum", [0.0, 1.0], [[0.0, 0.0, 0.0], [np.inf, 0.0, 0.0]])
    assert not (tmp_path / "t.tum").exists()


def test_read_tum_of_a_missing_path_or_a_folder_is_log_not_found(tmp_path: Path) -> None:
    """Were a raw FileNotFoundError / IsADirectoryError (read_log says LogNotFoundError)."""
    from lms200 import read_tum

    with pytest.raises(LogNotFoundError, match=r"no such TUM file: .*missing\.tum"):
        read_tum(tmp_path / "missing.tum")
    with pytest.raises(LogNotFoundError, match=r"is a folder, not a TUM file"):
        read_tum(tmp_path)
    with pytest.raises(InputError, match="allow_nan: must be True or False, got str"):
        read_tum(tmp_path / "missing.tum", allow_nan="yes")


def test_write_tum_to_a_folder_a_device_or_a_missing_folder_is_an_input_error(tmp_path: Path) -> None:
    """The wrong-input hunt: write_tum(FOLDER, ...) was a raw IsADirectoryError, and a file in a
    folder that does not exist a raw FileNotFoundError (write_log says InputError for both)."""
    from lms200 import write_tum

    stamps, poses = np.array([0.0]), np.zeros((1, 3))
    with pytest.raises(InputError, match=rf"path: {re.escape(str(tmp_path))} exists and is not a regular file "
                                         r"\(a folder or a device\); name a file to write the trajectory to"):
        write_tum(tmp_path, stamps, poses)
    with pytest.raises(InputError, match=r"path: /dev/null exists and is not a regular file"):
        write_tum("/dev/null", stamps, poses)
    with pytest.raises(InputError, match=rf"path: the folder {re.escape(str(tmp_path / 'gone'))} does not exist"):
        write_tum(tmp_path / "gone" / "t.tum", stamps, poses)


def test_a_ros2_bag_whose_storage_file_is_a_pipe_is_a_bag_error_not_a_hang(tmp_path: Path) -> None:
    """The wrong-input hunt: `lmsbench info BAG` where BAG/BAG.db3 was a named pipe (or linked to
    one) waited in sqlite's open for ever, and SIGTERM did not stop it (sqlite retries the
    interrupted open). A bag's files that are no regular files are refused unread."""
    import os
    import subprocess
    import sys

    bag = tmp_path / "b2"
    write_log(bag, [Record(Scan.lms200(np.full(361, 3.0), stamp=0.1 * k)) for k in range(3)], fmt="bag2")
    (db,) = bag.glob("*.db3")
    db.unlink()
    os.mkfifo(db)
    code = f"from lms200 import read_log\nlist(read_log({str(bag)!r}))"
    try:
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("reading a bag whose storage file is a pipe hung")
    assert done.returncode == 1
    assert done.stderr.strip().splitlines()[-1] == (
        f"lms200.bag.BagError: {db}: not a regular file (a pipe, a device or a socket) in the ROS 2 bag {bag}; a "
        "bag's files must be regular files (give the files themselves)")


# --- a pose that is not finite -------------------------------------------------------------------------
@pytest.mark.parametrize("xy", [(math.nan, 0.0), (0.0, math.inf)])
def test_a_bag_pose_that_is_not_finite_is_a_bag_error_naming_the_message(tmp_path: Path, xy: tuple) -> None:
    """position x = nan raised InputError 'odom: must be finite' (from Record, built outside the try)
    without bag, topic or index, even with skip_bad_lines=True."""
    bag = _pose_bag(tmp_path / "b", xy, (0.0, 0.0, 0.0, 1.0))
    with pytest.raises(BagError, match=rf"b: topic /odom message 0: cannot read: position \(x, y\) = "
                                       rf"\({re.escape(repr(xy[0]))}, {re.escape(repr(xy[1]))}\) is not finite"):
        list(read_log(bag))
    reader = read_log(bag, skip_bad_lines=True)
    out = list(reader)
    assert [r.odom for r in out] == [None] * 3 and [r.scan.stamp for r in out] == [10.0, 11.0, 12.0]
    assert [i for i, _ in reader.stats.skipped] == [0, 1, 2]
    assert "topic /odom message 2: position" in reader.stats.skipped[2][1]


@pytest.mark.parametrize("xy", [(1e300, 0.0), (0.0, -2e9)])
def test_a_bag_pose_beyond_1e9_m_is_a_bag_error_and_is_not_written(tmp_path: Path, xy: tuple) -> None:
    """An odometry or truth pose of 1e300 m was written to a bag and read back (a review), where the CARMEN,
    TUM and relations readers refuse x or y beyond 1e9 m (lms200.carmen.MAX_COORD_M). Both ends refuse it now."""
    bag = _pose_bag(tmp_path / "b", xy, (0.0, 0.0, 0.0, 1.0))
    with pytest.raises(BagError, match=r"b: topic /odom message 0: cannot read: " + re.escape(
            f"pose ({xy[0]:.6g}, {xy[1]:.6g}) m lies beyond +-1e+09 m (damaged, or not metres?)")):
        list(read_log(bag))
    scan = Scan.lms200(np.full(361, 2.0), stamp=1.0)
    for which in ("odom", "truth"):
        with pytest.raises(InputError, match="^" + re.escape(f"records: item 0: {which} pose ({xy[0]:.6g}, {xy[1]:.6g}) "
                                                             "m lies beyond +-1e+09 m (damaged, or not metres?), which the bag reader refuses") + "$"):
            write_log(tmp_path / f"w_{which}.bag", [Record(scan, **{which: (*xy, 0.0)})])
    write_log(tmp_path / "edge.bag", [Record(scan, odom=(1e9, -1e9, 0.0))])
    assert [r.odom for r in read_log(tmp_path / "edge.bag")] == [(1e9, -1e9, 0.0)]


# --- poses by header stamp ------------------------------------------------------------------------------
def _stream_bag(path: Path, scan_hz: float, scan_lag: float, odom_hz: float, odom_lag: float, odom_offset: float = 0.0,
                start: float = 1.0, end: float = 2.0) -> Path:
    """Scans and odometry (x = its own stamp) stamped on their own clocks, each arriving (bag time)
    some lag after its stamp, as a driver and a robot base record them; built with rosbags."""
    msgs = [("/scan", start + k / scan_hz + scan_lag, start + k / scan_hz, 1.0) for k in range(round((end - start) * scan_hz))]
    n_odom = round((end - start + 0.2) * odom_hz)
    msgs += [("/odom", start - 0.1 + odom_offset + j / odom_hz + odom_lag, start - 0.1 + odom_offset + j / odom_hz,
              (start - 0.1 + odom_offset + j / odom_hz, 0.0, 0.0, 0.0, 0.0, 1.0)) for j in range(n_odom)]
    msgs.sort(key=lambda m: m[1])
    return _ros2_bag(path, msgs)


@pytest.mark.parametrize("scan_lag, odom_lag", [(0.002, 0.003), (0.005, 0.001), (0.002, 0.030), (0.0, 0.0)])
def test_a_scan_gets_the_odometry_of_its_own_stamp_whatever_the_arrival_order(tmp_path: Path, scan_lag: float,
                                                                              odom_lag: float) -> None:
    """Scans at 10 Hz arriving 2 ms after their stamp, odometry at 50 Hz arriving 3 ms after: the
    scan at 1.1 s got odometry stamped 1.08 and the first scan None (poses were attached by
    arrival order: a scan was handed out as soon as any later-arriving message showed up)."""
    out = list(read_log(_stream_bag(tmp_path / "b", 10, scan_lag, 50, odom_lag)))
    stamps = [r.scan.stamp for r in out]
    assert len(out) == 10 and stamps[:2] == [1.0, 1.1]
    assert [r.odom[0] for r in out] == pytest.approx(stamps, abs=1e-12)


@pytest.mark.parametrize("offset, expected", [(-0.015, -0.015), (-0.045, -0.045), (0.0, 0.0), (0.005, None),
                                              (-0.06, None), (0.045, None)])
def test_a_scan_gets_the_latest_odometry_at_or_before_it_within_half_the_scan_period(tmp_path: Path, offset: float,
                                                                                     expected: float | None) -> None:
    """Odometry at 10 Hz stamped ``offset`` from the scans (10 Hz, tolerance 50 ms): the latest at
    or before each scan, if within 50 ms; never one stamped after it."""
    out = list(read_log(_stream_bag(tmp_path / "b", 10, 0.002, 10, 0.003, odom_offset=offset)))
    assert len(out) == 10
    for r in out:
        if expected is None:
            assert r.odom is None
        else:
            assert r.odom[0] == pytest.approx(r.scan.stamp + expected, abs=1e-9)


def test_poses_of_one_stamp_that_come_after_its_scans_go_to_them_in_order(tmp_path: Path) -> None:
    q = (0.0, 0.0, 0.0, 1.0)
    bag = _ros2_bag(tmp_path / "b", [("/scan", 1.0, 1.0, 1.0), ("/scan", 1.0, 1.0, 2.0), ("/odom", 1.001, 1.0, (1.0, 0.0, *q)),
                                     ("/odom", 1.002, 1.0, (2.0, 0.0, *q)), ("/scan", 2.0, 2.0, 3.0),
                                     ("/odom", 2.0, 2.0, (3.0, 0.0, *q)), ("/ground_truth", 2.0, 2.0, (9.0, 0.0, *q))])
    out = list(read_log(bag))
    assert [(r.scan.ranges[0], r.odom and r.odom[0], r.truth and r.truth[0]) for r in out] == [
        (1.0, 1.0, None), (2.0, 2.0, None), (3.0, 3.0, 9.0)]


def _pose_records(stamps: list[float], rng: np.random.Generator) -> list[Record]:
    out = []
    for i, t in enumerate(stamps):
        odom = (float(i), float(rng.normal()), float(rng.uniform(-3, 3))) if rng.random() < 0.6 else None
        truth = (float(-i), float(rng.normal()), float(rng.uniform(-3, 3))) if rng.random() < 0.5 else None
        out.append(Record(_scan(t, float(i + 1)), odom, truth))
    return out


def _poses_of(recs: list[Record]) -> list[tuple]:
    """Stamps to the nanosecond (a bag's resolution: exact from 2^23 s on)."""
    return [(round(Fraction(r.scan.stamp) * 10**9), r.scan.ranges[0], r.odom and r.odom[:2], r.truth and r.truth[:2]) for r in recs]


ROUND_TRIPS = {  # the review's cases (bag_pose.py), then random ones
    # two records at t = 1.0 with odometry 1 and 2 read back 2 and 2
    "repeat": [Record(_scan(1.0, 1), odom=(1, 0, 0)), Record(_scan(1.0, 2), odom=(2, 0, 0)), Record(_scan(2.0, 3), odom=(3, 0, 0))],
    # written with odom=None after a record with the same stamp: read back with odometry 1
    "repeat_none": [Record(_scan(1.0, 1), odom=(1, 0, 0)), Record(_scan(1.0, 2), odom=None), Record(_scan(2.0, 3), odom=(3, 0, 0))],
    # written with odom=None 10 ms after a scan, the median period 100 ms: read back with odometry 1
    "irregular": [Record(_scan(0.0, 1), odom=(1, 0, 0)), Record(_scan(0.01, 2), odom=None)]
    + [Record(_scan(0.1 * k, 3), odom=(k, 0, 0)) for k in range(1, 6)],
    # stamps that go back: written order kept (was bag-time order)
    "backwards": [Record(_scan(2.0, 1), odom=(1, 0, 0)), Record(_scan(1.0, 2), odom=(2, 0, 0)), Record(_scan(3.0, 3), odom=(3, 0, 0))],
    "none_first": [Record(_scan(1.0, 1)), Record(_scan(1.0, 2), odom=(2, 0, 0), truth=(5, 0, 0)), Record(_scan(1.0, 3)),
                   Record(_scan(1.0, 4), truth=(6, 0, 0))],
}


@pytest.mark.parametrize("fmt", ["bag", "bag2"])
@pytest.mark.parametrize("case", [*ROUND_TRIPS, "random_repeats", "random_irregular", "random_epoch"])
def test_records_with_missing_poses_and_repeated_stamps_round_trip_exactly(tmp_path: Path, fmt: str, case: str) -> None:
    rng = np.random.default_rng(len(case))
    if case == "random_repeats":
        recs = _pose_records(sorted(float(t) for t in rng.integers(0, 40, 200) * 0.1), rng)
    elif case == "random_irregular":
        recs = _pose_records(sorted(float(t) for t in rng.uniform(0, 5, 200)), rng)
    elif case == "random_epoch":
        recs = _pose_records([1.7e9 + float(t) for t in np.cumsum(rng.choice([0.0, 0.001, 0.0267, 0.0267, 0.5], 300))], rng)
    else:
        recs = ROUND_TRIPS[case]
    path = tmp_path / ("r.bag" if fmt == "bag" else "r")
    write_log(path, recs, fmt=fmt)
    back = list(read_log(path))
    assert _poses_of(back) == _poses_of(recs)
    for a, b in zip(recs, back):  # yaw through the quaternion, to 1e-12 rad
        for x, y in ((a.odom, b.odom), (a.truth, b.truth)):
            assert x is None or y[2] == pytest.approx(x[2], abs=1e-12)


@pytest.mark.slow
def test_a_bag_whose_scans_share_one_time_is_read_in_bounded_memory(tmp_path: Path) -> None:
    """Scans that all have one bag time were held until the end of the bag: 3,000 scans of 361
    beams with one time peaked 20 MB above distinct times (5,000 written by write_log: 35 MB vs 8 MB).
    1,500 scans, 6 times MAX_HELD, show it as well (10 MB above distinct times before, 1 MB now)."""
    import tracemalloc

    peaks = {}
    n = 1500
    for name, same in (("distinct", False), ("same", True)):
        msgs: list[tuple] = []
        for i in range(n):
            t = 5.0 if same else 5.0 + 0.0267 * i
            msgs += [("/odom", t, t, (float(i), 0.0, 0.0, 0.0, 0.0, 1.0)), ("/scan", t, t, 2.0)]
        _ros2_bag(tmp_path / name, msgs, beams=361)
        tracemalloc.start()
        try:
            out = [(r.odom[0], r.scan.ranges.size) for r in read_log(tmp_path / name)]
            peaks[name] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert out == [(i, 361) for i in range(n)]  # each its own odometry (were all n - 1 with one time)
    assert peaks["same"] < peaks["distinct"] + 4_000_000, peaks
    print(peaks)  # at most MAX_HELD = 256 scans wait (were 3,000)


def test_a_scan_waits_for_its_poses_at_most_the_look_ahead_window_or_max_held() -> None:
    """A pose topic that falls silent holds each scan for LOOKAHEAD_S of bag time, never longer,
    and never more than MAX_HELD scans (a bag of one bag time); poses stamped after a scan are
    never its own."""
    from lms200.bag import LOOKAHEAD_S, MAX_HELD, _PoseMatcher

    m = _PoseMatcher(["/odom"], tolerance_ns=50_000_000)
    m.add_pose("/odom", 0, (0.0, 0.0, 0.0))
    out = []
    for k in range(40):  # 10 Hz scans, odometry silent after the first
        ns = k * 100_000_000
        m.add_scan(ns, _scan(ns * 1e-9), k, ns)
        out += list(m.ready(ns))
        assert len(m.held) <= LOOKAHEAD_S * 10 + 1
    assert [i for i, _, _ in out] == list(range(40 - len(m.held)))
    assert [p["/odom"] for _, _, p in out] == [(0.0, 0.0, 0.0)] + [None] * (len(out) - 1)
    m = _PoseMatcher(["/odom"], tolerance_ns=1000)
    for k in range(3 * MAX_HELD):  # one bag time, one stamp: poses that come after their scans
        m.add_scan(5, _scan(5e-9), k, 5)
        list(m.ready(5))
        assert len(m.held) <= MAX_HELD
    m.add_pose("/odom", 6, (1.0, 0.0, 0.0))  # stamped after every scan: none of theirs
    assert [p["/odom"] for _, _, p in m.ready(None)] == [None] * MAX_HELD


def test_a_scan_arriving_after_a_later_stamped_one_still_gets_its_odometry(tmp_path: Path) -> None:
    """Review 32 (t8.py): scans at 37.5 Hz arriving 60 ms after their stamp, two of them (50 and 51)
    swapped, odometry at 100 Hz arriving 1 ms after its stamp (x = stamp): handing out scan 51
    dropped every pose older than its stamp minus the tolerance, so scan 50 (stamped 2.3333 s),
    coming next, got None instead of the pose stamped 2.33 s."""
    period = Fraction(1, 375) * 10  # 37.5 scans/s
    order = list(range(200))
    order[50], order[51] = 51, 50
    msgs = [("/scan", 1 + k * period + Fraction(6, 100), 1 + i * period, 1.0) for k, i in enumerate(order)]
    msgs += [("/odom", Fraction(j, 100) + Fraction(1, 1000), Fraction(j, 100), (j / 100, 0.0, 0.0, 0.0, 0.0, 1.0))
             for j in range(80, 700)]
    msgs.sort(key=lambda m: m[1])
    out = list(read_log(_ros2_bag(tmp_path / "b", msgs)))
    assert [round(r.scan.stamp, 4) for r in out[49:53]] == [2.3067, 2.36, 2.3333, 2.3867]
    assert [r.odom and r.odom[0] for r in out[49:53]] == [2.3, 2.36, 2.33, 2.38]
    assert [r.odom[0] for r in out] == [math.floor(round(r.scan.stamp * 100, 6)) / 100 for r in out]


@pytest.mark.parametrize("arrival", ["bulk", "bursts"])
def test_the_pose_tolerance_comes_from_header_stamps_not_bag_times(tmp_path: Path, arrival: str) -> None:
    """Review 32 (t6.py, t7.py): 200 scans stamped at 37.5 Hz, each with odometry stamped 1 ms
    before it (x = its index), bag times 1 us apart (a bulk-converted bag) or scans delivered in
    bursts of 4 0.1 ms apart: the tolerance came from bag times (1 us) while matching compares
    header stamps, so all 200 scans got odom=None; now the tolerance is 13.3 ms and each scan gets
    its odometry."""
    from lms200.bag import pose_tolerance

    period = Fraction(1, 375) * 10
    msgs = []
    for i in range(200):
        stamp = 1 + i * period
        if arrival == "bulk":
            msgs += [("/odom", 1 + Fraction(2 * i, 10**6), stamp - Fraction(1, 1000), (float(i), 0.0, 0.0, 0.0, 0.0, 1.0)),
                     ("/scan", 1 + Fraction(2 * i + 1, 10**6), stamp, 1.0)]
        else:
            msgs += [("/scan", 1 + (i // 4 + 1) * 4 * period + (i % 4) * Fraction(1, 10**4), stamp, 1.0),
                     ("/odom", stamp + Fraction(1, 1000), stamp - Fraction(1, 1000), (float(i), 0.0, 0.0, 0.0, 0.0, 1.0))]
    msgs.sort(key=lambda m: m[1])
    out = list(read_log(_ros2_bag(tmp_path / "b", msgs)))
    assert [r.odom and r.odom[0] for r in out] == [float(i) for i in range(200)]
    assert pose_tolerance(round(r.scan.stamp * 1e9) for r in out) == pytest.approx(0.5 / 37.5, abs=1e-9)


def test_odometry_slower_than_twice_the_scan_rate_leaves_some_scans_without_it(tmp_path: Path) -> None:
    """The documented limit (review 32, t1.py): 300 scans at 37.5 Hz (tolerance 13.3 ms), odometry at
    50 Hz (20 ms apart) 10 ms out of phase: every third scan's latest odometry is 16.7 ms before it,
    beyond the tolerance, so 100 of 300 scans get None."""
    out = list(read_log(_stream_bag(tmp_path / "b", 37.5, 0.002, 50, 0.003, odom_offset=-0.01, end=9.0)))
    assert len(out) == 300
    assert [r.odom is None for r in out] == [k % 3 == 1 for k in range(300)]
    gaps = {round((r.scan.stamp - r.odom[0]) * 1000, 2) for r in out if r.odom is not None}
    assert gaps == {10.0, 3.33}


# --- one decode per scan --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["d.bag", "d2"])
def test_every_scan_is_decoded_once(tmp_path: Path, name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The pose tolerance needs every scan's header stamp before the first scan is matched: a first
    pass decoded every scan for it, and the reading pass decoded it again (2 decodes a scan). The
    stamps now come from the messages' bytes; the records are the same."""
    from rosbags.highlevel import AnyReader

    records = [Record(_scan(1700000000.0 + k / 37.5 + 1e-9 * k), odom=(k, 0.5, 0.1), truth=(k, 0.25, -0.1))
               for k in range(40)]
    path = tmp_path / name
    write_log(path, records, fmt="bag" if name.endswith(".bag") else "bag2")
    decoded: dict[str, int] = {}
    real = AnyReader.deserialize

    def counting(self, raw, typ):  # noqa: ANN001, ANN202
        decoded[typ] = decoded.get(typ, 0) + 1
        return real(self, raw, typ)

    monkeypatch.setattr(AnyReader, "deserialize", counting)
    out = list(read_log(path))
    assert decoded == {"sensor_msgs/msg/LaserScan": 40, "geometry_msgs/msg/PoseStamped": 80}
    assert [r.scan.stamp for r in out] == [r.scan.stamp for r in records]
    assert [(r.odom, r.truth) for r in out] == [(r.odom, r.truth) for r in records]


@pytest.mark.parametrize("store", ["ros1", "cdr_le", "cdr_be"])
def test_a_stamp_read_from_the_bytes_is_the_decoded_messages(store: str) -> None:
    from types import SimpleNamespace

    from rosbags.typesys import Stores, get_typestore

    from lms200.bag import _header_ns, _raw_stamp_reader, _unsigned_ros1_stamp

    ts = get_typestore(Stores.ROS1_NOETIC if store == "ros1" else Stores.ROS2_HUMBLE)
    T = ts.types
    stamp_of = _raw_stamp_reader(SimpleNamespace(is2=store != "ros1", typestore=ts))
    assert stamp_of is not None
    for sec, nanosec in [(0, 0), (1700000000, 123456789), (2**31 - 1, 2**32 - 1), (-2**31, 5), (-1, 999_999_999)]:
        header = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec), frame_id="x",
                                          **({"seq": 7} if store == "ros1" else {}))
        msg = T["sensor_msgs/msg/LaserScan"](header=header, angle_min=-1.0, angle_max=1.0, angle_increment=1.0,
                                             time_increment=0.0, scan_time=0.0, range_min=0.1, range_max=10.0,
                                             ranges=np.ones(3, np.float32), intensities=np.zeros(0, np.float32))
        kind = "sensor_msgs/msg/LaserScan"
        raw = bytes(ts.serialize_ros1(msg, kind) if store == "ros1"
                    else ts.serialize_cdr(msg, kind, little_endian=store == "cdr_le"))
        decoded = ts.deserialize_ros1(raw, kind) if store == "ros1" else ts.deserialize_cdr(raw, kind)
        # ROS 1's seconds are uint32 (rosbags decodes them as int32): -1 there is 2^32 - 1 s
        unsigned = sec % 2**32 if store == "ros1" else sec
        assert stamp_of(raw) == _header_ns(decoded if store != "ros1" else _unsigned_ros1_stamp(decoded)) \
            == unsigned * 10**9 + nanosec
    assert stamp_of(b"\x00\x01\x00") is None  # too short to hold a stamp: left out, as a message that fails to decode


def test_a_bag_laying_out_its_scans_otherwise_has_them_decoded_for_their_stamps() -> None:
    from types import SimpleNamespace

    from rosbags.typesys import Stores, get_typestore

    from lms200.bag import _raw_stamp_reader

    ts = get_typestore(Stores.ROS2_HUMBLE)
    odd = {**ts.fielddefs, "builtin_interfaces/msg/Time": ([], ts.fielddefs["builtin_interfaces/msg/Time"][1][::-1])}
    assert _raw_stamp_reader(SimpleNamespace(is2=True, typestore=SimpleNamespace(fielddefs=odd))) is None
    assert _raw_stamp_reader(SimpleNamespace(is2=False, typestore=ts)) is None  # ROS 2 definitions in a ROS 1 bag


def test_scans_waiting_for_their_poses_are_bounded_by_their_beams(monkeypatch: pytest.MonkeyPatch) -> None:
    """The wrong-input hunt (bounded memory): scans wait for their poses, at most MAX_HELD (256) of
    them whatever their size: 100 scans of 300,000 beams of one bag time (a 120 MB bag written by
    write_log) were all held, 528 MB resident against 76 MB when stamped 1 s apart. Now they are
    held up to MAX_HELD_BEAMS (2^20; here 20,000) too, and handed out in order."""
    from lms200 import bag

    monkeypatch.setattr(bag, "MAX_HELD_BEAMS", 20_000, raising=False)
    m = bag._PoseMatcher(["/odom"], tolerance_ns=1000)
    out = []
    for k in range(30):  # one bag time, one stamp, no pose yet: nothing tells a scan to stop waiting
        m.add_scan(5, Scan(np.full(10_000, 2.0), -np.pi / 2, np.pi / 10_000, 0.0, 30.0, 5e-9), k, 5)
        out += [i for i, _, _ in m.ready(5)]
        assert sum(len(h.scan) for h in m.held) <= 30_000  # old: every scan so far, up to 300,000 beams
    out += [i for i, _, _ in m.ready(None)]
    assert out == list(range(30))


@pytest.mark.parametrize("name", ["s.bag", "s2"])
def test_a_scan_write_bag_refuses_leaves_the_ones_before_it_readable(tmp_path: Path, name: str) -> None:
    """write_bag refusing item 2 left rosbags' writer aborted, the bag unindexed ("Bag is not
    indexed"): `lms200 record` said the scans before it were saved in a file no command could read.
    Found by the session's review. (write_log still removes the file: all or nothing.)"""
    from lms200.bag import write_bag

    recs = [Record(_scan(0.0), odom=(0.0, 0.0, 0.0)), Record(_scan(1.0, 2.0)), Record(_scan(-1.0))]
    with pytest.raises(InputError, match=r"records: item 2: stamp -1.0 s cannot be stored in a bag"):
        write_bag(tmp_path / name, recs)
    got = list(read_log(tmp_path / name))
    assert [r.scan.stamp for r in got] == [0.0, 1.0] and [r.scan.ranges[0] for r in got] == [1.0, 2.0]
    assert got[0].odom == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("name", ["empty.bag", "empty2"])
def test_a_bag_of_no_message_says_it_holds_no_topic(tmp_path: Path, name: str) -> None:
    """The wrong-input hunt: a bag of no message (write_bag of no record; write_log now refuses to
    write one, but other tools make them) was refused as "no any sensor_msgs/LaserScan topic; topics: []"."""
    from lms200.bag import BagError

    from lms200.bag import write_bag

    write_bag(tmp_path / name, [])  # write_log refuses no records; the reader still meets such bags
    with pytest.raises(BagError, match=rf"^{re.escape(str(tmp_path / name))}: no sensor_msgs/LaserScan topic; it holds "
                                       r"no topic \(an empty bag\)$"):
        list(read_log(tmp_path / name))


def test_a_ros2_bag_listing_its_storage_file_twice_is_a_bag_error(tmp_path: Path) -> None:
    """rosbags opened b2.db3 once for each listing in relative_file_paths: 3 scans read as 6,
    the fourth stamped before the third, exit 0 from `lmsbench info`."""
    bag = tmp_path / "b2"
    write_log(bag, [Record(Scan(np.full(5, 1.0), -0.1, 0.05, 0.0, 8.0, stamp=float(k))) for k in range(3)], fmt="bag2")
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    meta.write_text(text.replace("relative_file_paths:\n  - b2.db3\n", "relative_file_paths:\n  - b2.db3\n  - sub/b2.db3\n"))
    with pytest.raises(BagError) as e:
        list(read_log(bag))
    assert str(e.value) == (f"{bag}: its metadata.yaml lists the storage file b2.db3 more than once (relative_file_paths); "
                            "each message would be read once for each listing")
    meta.write_text(text)
    assert [r.scan.stamp for r in read_log(bag)] == [0.0, 1.0, 2.0]


def _unindexed(tmp_path: Path, n: int = 10, cut: int = 0) -> tuple[Path, list]:
    """A bag as a killed recording leaves it: its chunks (one every scan here) and their index data
    records, no index, index_pos 0 in its header; ``cut`` bytes more removed from its end."""
    import struct

    from lms200 import Record, Scan
    from lms200.bag import write_bag

    recs = [Record(Scan.lms200(np.full(361, 1.0 + i / 100), stamp=float(i)), odom=(i / 10, 0.0, 0.0)) for i in range(n)]
    whole = tmp_path / "whole.bag"
    write_bag(whole, recs, flush_s=0.0)
    data = bytearray(whole.read_bytes())
    at = data.index(b"index_pos=") + 10
    index_pos = struct.unpack("<Q", data[at:at + 8])[0]
    data[at:at + 8] = bytes(8)
    out = tmp_path / "killed.bag"
    out.write_bytes(bytes(data[:index_pos - cut]))
    return out, recs


def _read_recovered(out: Path) -> list:
    """The records read from ``_unindexed``'s bag of 10 scans, asserting the one warning of its recovery."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = list(read_log(out))
    assert [str(w.message) for w in caught] == [
        f"{out}: the bag was not closed (a recording killed or cut by a power failure): it has no index; 20 messages "
        "recovered from its 10 whole chunks"]
    return got


def test_an_unindexed_bag_is_recovered_from_its_chunks(tmp_path: Path) -> None:
    """A bag never closed (a killed recording) was refused: "Bag is not indexed, reindex before reading"."""
    out, recs = _unindexed(tmp_path)
    got = _read_recovered(out)
    assert [r.scan.stamp for r in got] == [float(i) for i in range(10)]
    assert [r.odom for r in got] == [r.odom for r in recs]
    assert np.array_equal(got[9].scan.ranges, np.full(361, 1.09, dtype=np.float32).astype(float))


def test_an_unindexed_bag_drops_its_truncated_last_record(tmp_path: Path) -> None:
    """The chunk being written when the recording was cut is dropped; those before it are read."""
    import warnings

    from lms200 import read_log

    out, _ = _unindexed(tmp_path, cut=1000)  # into the last scan's chunk (a scan is 1.5 kB)
    last_chunk = out.read_bytes().rindex(b"compression=none") - 16  # its header length, its op field (4 + 4 bytes)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = list(read_log(out))
    assert [r.scan.stamp for r in got] == [float(i) for i in range(9)]
    assert str(caught[0].message).endswith("18 messages recovered from its 9 whole chunks; a truncated last record "
                                           f"at byte {last_chunk} dropped")


def test_an_unindexed_bag_with_a_damaged_record_names_its_offset(tmp_path: Path) -> None:
    from lms200 import read_log
    from lms200.bag import BagError

    out, _ = _unindexed(tmp_path)
    data = bytearray(out.read_bytes())
    at = data.index(b"op=\x05", 4200)  # the second chunk's op code
    data[at + 3] = 9
    out.write_bytes(bytes(data))
    with pytest.raises(BagError, match=rf"killed\.bag: an unindexed bag \(not closed\) whose record at byte {at - 8} is "
                       r"damaged: op code 9, which no record between"):  # the record's header length, the op field's
        list(read_log(out))


def test_an_unindexed_bag_cut_in_its_header_says_so(tmp_path: Path) -> None:
    from lms200 import read_log
    from lms200.bag import BagError

    out, _ = _unindexed(tmp_path)
    out.write_bytes(out.read_bytes()[:86])
    with pytest.raises(BagError, match=r"killed\.bag: the bag was not closed and ends within its header \(86 bytes: a "
                       r"recording killed before its first messages were written\); no message to recover$"):
        list(read_log(out))


@pytest.mark.parametrize("field", ["header length", "data length"])
def test_an_unindexed_bag_with_a_damaged_length_mid_file_is_damaged_not_truncated(tmp_path: Path, field: str) -> None:
    """A length no record has (0xFFFFFF00) in the second chunk ran past the file's end, so it was taken
    for the truncated last record: the eight chunks after it dropped under a warning (the review)."""
    import struct

    from lms200 import read_log
    from lms200.bag import BagError

    out, _ = _unindexed(tmp_path)
    data = bytearray(out.read_bytes())
    op = data.index(b"op=\x05", 4200)  # the second chunk's op code
    pos = data.rindex(b"compression=none", 0, op) - 16  # the record's header length (4) and the field's (4)
    hlen = struct.unpack("<I", data[pos:pos + 4])[0]
    at = pos if field == "header length" else pos + 4 + hlen
    data[at:at + 4] = struct.pack("<I", 0xFFFFFF00)
    out.write_bytes(bytes(data))
    with pytest.raises(BagError, match=rf"killed\.bag: an unindexed bag \(not closed\) whose record at byte {pos} is "
                       r"damaged: a (header|data length) of 4294967040 bytes"):
        list(read_log(out))


def test_an_unindexed_bag_s_uncompressed_chunk_must_hold_what_it_declares(tmp_path: Path) -> None:
    """An uncompressed chunk's data length differing from its declared size is damage (such a chunk
    of size 100 and 400 MiB of data was read whole, 444 MB of memory, before its records failed)."""
    import struct

    from lms200 import read_log
    from lms200.bag import BagError

    out, _ = _unindexed(tmp_path)
    data = bytearray(out.read_bytes())
    op = data.index(b"op=\x05", 4200)
    pos = data.rindex(b"compression=none", 0, op) - 16
    at = data.index(b"size=", pos) + 5
    declared = struct.unpack("<I", data[at:at + 4])[0]
    data[at:at + 4] = struct.pack("<I", declared - 1)
    out.write_bytes(bytes(data))
    with pytest.raises(BagError, match=rf"whose record at byte {pos} is damaged: an uncompressed chunk of {declared} "
                       rf"bytes that declares {declared - 1}$"):
        list(read_log(out))


def test_an_unindexed_bag_s_damaged_message_record_is_named_by_its_chunk_offset(tmp_path: Path) -> None:
    """A message record whose header was damaged inside a chunk was named by the chunk's byte alone."""
    import struct

    from lms200 import read_log
    from lms200.bag import BagError

    out, _ = _unindexed(tmp_path)
    data = bytearray(out.read_bytes())
    op = data.index(b"op=\x05", 4200)
    pos = data.rindex(b"compression=none", 0, op) - 16
    hlen = struct.unpack("<I", data[pos:pos + 4])[0]
    datapos = pos + 4 + hlen + 4  # the chunk's data: a connection record, then the scan's message record
    msg = data.index(b"op=\x02", datapos) - 8  # that record's header length, its op field's
    data[msg + 4:msg + 8] = struct.pack("<I", 0xFFFF)  # the op field's length, past the record's header
    out.write_bytes(bytes(data))
    with pytest.raises(BagError, match=rf"whose record at byte {pos} is damaged: its record at chunk offset "
                       rf"{msg - datapos}: .* \(a chunk offset counts bytes of the chunk's data, decompressed\)$"):
        list(read_log(out))


def test_poses_written_after_the_look_ahead_window_are_said(tmp_path: Path) -> None:
    """Found by fuzzing: a bag whose poses were written after every scan (a ground truth added to a
    bag afterwards, its topics written one after the other) read its 20 scans without their
    odometry, silently ('odometry yes' in info): a scan waits LOOKAHEAD_S of bag time for its poses.
    The loss is bounded as before, and now said in one warning naming the topic and the count."""
    from lms200.errors import LmsbenchWarning

    q = (0.0, 0.0, 0.0, 1.0)
    scans = [("/scan", 1.0 + 0.1 * k, 1.0 + 0.1 * k, 1.0) for k in range(20)]
    odom = [("/odom", 10.0 + 0.01 * k, 1.0 + 0.1 * k, (float(k), 0.0, *q)) for k in range(20)]
    with pytest.warns(LmsbenchWarning) as caught:
        out = list(read_log(_ros2_bag(tmp_path / "late", scans + odom)))
    assert [r.odom for r in out] == [None] * 20  # as before: the look-ahead is bounded
    assert [str(w.message) for w in caught] == [
        f"{tmp_path / 'late'}: poses came more than 1 s of bag time after the scans they are stamped for (20 on /odom): "
        "those scans were read without them (the bag's topics written one after the other, or a pose topic recorded "
        "late); write the bag in header-stamp order"]
    import warnings

    with warnings.catch_warnings():  # in time (written 0.5 s late): no warning, every scan its odometry
        warnings.simplefilter("error")
        assert [r.odom[0] for r in read_log(_ros2_bag(tmp_path / "in_time", sorted(
            scans + [(t, b - 9.0 + 0.5, s, p) for t, b, s, p in odom], key=lambda m: m[1])))] == [float(k) for k in range(20)]


def test_write_bag_flush_s_writes_the_first_scan_at_once_and_on_a_tick(tmp_path: Path) -> None:
    """With ``flush_s`` the first chunk went out only after a scan ``flush_s`` after the bag was
    opened: a recording killed in its first second (and one whose device sent its scans within it,
    then went silent) was a file of the bag's header alone. Now the first scan is written out at
    once, and a None (a tick: no record) writes out the scans held once they are due."""
    import shutil
    import time
    import warnings

    from lms200.bag import write_bag

    out = tmp_path / "rec.bag"
    on_disk: list[int] = []

    def seen() -> int:  # the scans a reader recovers from the file as it is now (as if the writer were killed)
        copy = tmp_path / "copy.bag"
        shutil.copyfile(out, copy)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return sum(1 for _ in read_log(copy))
        except BagError:  # the header alone
            return 0
        finally:
            copy.unlink()

    def records():  # noqa: ANN202
        yield Record(Scan.lms200(np.full(361, 1.0), stamp=0.0))
        on_disk.append(seen())  # the first scan: at once
        yield Record(Scan.lms200(np.full(361, 2.0), stamp=1.0))
        yield None  # a tick 0.3 s before the second scan is due: still held
        on_disk.append(seen())
        time.sleep(0.35)
        yield None  # due now: written out without a next scan
        on_disk.append(seen())
        yield None  # nothing held: nothing written
        on_disk.append(seen())

    assert write_bag(out, records(), flush_s=0.3) == 2
    assert on_disk == [1, 1, 2, 2]
    assert [r.scan.stamp for r in read_log(out)] == [0.0, 1.0]


def test_an_unindexed_bag_is_told_by_its_header_not_by_rosbags_words(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A bag never closed was told by the text of rosbags' refusal ("Bag is not indexed, reindex
    before reading"): a rosbags that words it otherwise (here: "Bag has no index") made a killed
    recording "cannot open as a ROS bag: AnyReaderError: Bag has no index.". It is told by its header's
    index_pos 0 now, and recovered as before."""
    from rosbags.rosbag1 import reader as r1

    opened = r1.Reader.open

    def reworded(self) -> None:  # noqa: ANN001
        try:
            opened(self)
        except r1.ReaderError as exc:
            raise r1.ReaderError(str(exc).replace("Bag is not indexed, reindex before reading.", "Bag has no index.")) from None

    monkeypatch.setattr(r1.Reader, "open", reworded)
    out, recs = _unindexed(tmp_path)
    got = _read_recovered(out)
    assert [r.scan.stamp for r in got] == [float(i) for i in range(10)]
    # an indexed bag still goes through rosbags' own open (its refusals as they were)
    whole = tmp_path / "whole.bag"
    assert [r.scan.stamp for r in read_log(whole)] == [float(i) for i in range(10)]
    data = bytearray(whole.read_bytes())
    data[:13] = b"#ROSBAG V1.2\n"
    whole.write_bytes(bytes(data))
    with pytest.raises(BagError, match=r"whole\.bag: cannot open as a ROS bag: AnyReaderError: Bag version 102 is not supported\.$"):
        list(read_log(whole))


@pytest.mark.parametrize("content, held", [
    ("", "an empty file (0 bytes)"),
    ("# timestamp x y z qx qy qz qw\n", "holds only blank or comment lines (1)"),
    ("# t x y z qx qy qz qw\n\n   \n# end\n", "holds only blank or comment lines (4)"),
])
def test_a_tum_file_of_no_pose_is_refused_naming_it(tmp_path: Path, content: str, held: str) -> None:
    """An empty TUM file, or one of comments only (a cut or emptied trajectory), read as no poses,
    silently, where an empty CARMEN log is refused ("FILE: an empty file (0 bytes): no laser lines")."""
    from lms200 import read_tum

    path = tmp_path / "gt.tum"
    path.write_text(content)
    with pytest.raises(LogFormatError) as info:
        read_tum(path)
    assert str(info.value) == (f"{path}: no poses: {held}; a TUM file holds a row t x y z qx qy qz qw per pose (a cut or "
                               "emptied file?)")
    path.write_text(content + "1.0 2.0 3.0 0 0 0 0 1\n")  # one pose: read
    stamps, poses = read_tum(path)
    assert stamps.tolist() == [1.0] and poses.tolist() == [[2.0, 3.0, 0.0]]


def test_write_bag_refuses_an_angle_increment_that_float32_makes_0(tmp_path: Path) -> None:
    """A Scan 1e-290 rad apart was written to a bag as 0 (a LaserScan's fields are float32), a bag
    its reader refuses ("angle_increment: must be > 0, got 0.0", of a value never given): refused
    when written, naming the item and the value; the scans before it are kept."""
    from lms200.bag import write_bag

    recs = [Record(_scan(0.0)), Record(Scan(np.full(5, 1.0), -0.1, 1e-290, 0.0, 8.0, stamp=1.0))]
    with pytest.raises(InputError, match=r"^records: item 1: angle_increment 1e-290 rad cannot be stored in a bag "
                                         r"\(a LaserScan's fields are float32, in which it is 0\)$"):
        write_bag(tmp_path / "s.bag", recs)
    assert [r.scan.stamp for r in read_log(tmp_path / "s.bag")] == [0.0]


def test_a_reading_beyond_a_limit_stays_beyond_it_in_the_bags_float32(tmp_path: Path) -> None:
    """REP-117: a reading above range_max (below range_min) is out of range, and a bag's reader compares
    in the message's float32. write_bag rounded each field to its nearest float32, which put a reading
    just above range_max onto it (8.18300005 m under 8.183 m: both 8.1829996 m) and one just below
    range_min onto that: both read back valid. They are now written as the next float32 beyond."""
    ranges = np.array([1.0, 8.183, 8.18300005, 0.01 - 1e-10, 0.01, 9.0])
    scan = Scan(ranges, -math.pi / 2, math.radians(0.5), 0.01, 8.183, stamp=1.0)
    assert scan.valid.tolist() == [True, True, False, False, True, False]
    write_log(tmp_path / "edge.bag", [Record(scan)], fmt="bag")
    got = next(iter(read_log(tmp_path / "edge.bag"))).scan
    assert got.valid.tolist() == [True, True, False, False, True, False]  # old: [True] * 5 + [False]
    f32 = np.float32
    assert got.range_max == float(f32(8.183)) and got.range_min == float(f32(0.01))
    assert got.ranges.tolist() == [1.0, float(f32(8.183)), float(np.nextafter(f32(8.183), f32(np.inf))),
                                   float(np.nextafter(f32(0.01), f32(0))), float(f32(0.01)), 9.0]


def test_a_bags_angles_are_snapped_only_as_far_as_float32_explains(tmp_path: Path) -> None:
    """A bag's angle_min or angle_increment is float32; it was snapped onto the 0.05 deg grid with the
    allowance of 6-decimal text (5e-7 rad + 1e-6 of the value), so an angle_min 2e-6 rad off the grid
    (17 float32 steps at 90 deg: a calibrated mount) read as -90 deg. Now only an angle whose float32
    is the grid angle's, or one float32 step from it, is snapped."""
    from lms200.scan import snap_float32_angle

    grid = -math.pi / 2
    step = abs(float(np.spacing(np.float32(grid))))  # 1.19e-7 rad
    f32 = lambda a: float(np.float32(a))  # noqa: E731 - the message's value
    assert snap_float32_angle(f32(grid)) == grid
    assert snap_float32_angle(f32(grid) + step) == grid and snap_float32_angle(f32(grid) - step) == grid
    assert snap_float32_angle(f32(grid) + 2 * step) == f32(grid) + 2 * step
    assert snap_float32_angle(f32(grid + 2e-6)) == f32(grid + 2e-6)  # old: -pi/2
    assert snap_float32_angle(f32(math.radians(0.5))) == math.radians(0.5)
    for k, (angle_min, expected) in enumerate([(grid, grid), (grid + 2e-6, f32(grid + 2e-6)),
                                               (grid + 3e-7, f32(grid + 3e-7)), (grid + 5e-8, grid)]):
        path = tmp_path / f"a{k}.bag"
        write_log(path, [Record(Scan(np.full(361, 2.0), angle_min, math.radians(0.5), 0.0, 8.183, stamp=1.0))], fmt="bag")
        got = next(iter(read_log(path))).scan
        assert (got.angle_min, got.angle_increment) == (expected, math.radians(0.5)), angle_min


def test_a_range_max_override_is_compared_in_the_bags_float32(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A review: --laser-range-max M on a bag compared its float32 readings in float64, so a reading
    stored as float32(M), above M for about half of all M (81.83 m -> 81.83000183), read invalid: `lmsbench info
    bag --laser-range-max 81.83` said "invalid 100.00 %" of readings written as 81.83 m. It is at the
    limit, valid, as a reading equal to the bag's own (float32) range_max is; the next float32 above stays beyond."""
    from experiments.cli import main
    from lms200.laser_geometry import LaserGeometry

    f32 = np.float32
    above = float(np.nextafter(f32(81.83), f32(np.inf)))
    bag = _ros2_bag(tmp_path / "b", [("/scan", 1.0, 1.0, 81.83), ("/scan", 1.1, 1.1, above)], range_max=math.inf)
    at, beyond = (r.scan for r in read_log(bag, geometry=LaserGeometry(range_max=81.83)))
    assert at.range_max == 81.83 and at.valid.tolist() == [True] * 3  # old: [False] * 3
    assert at.ranges.tolist() == [81.83] * 3
    assert beyond.valid.tolist() == [False] * 3 and beyond.ranges.tolist() == [above] * 3
    assert main(["info", str(bag), "--laser-range-max", "81.83"]) == 0
    assert "  invalid         50.00 % of readings" in capsys.readouterr().out  # old: 100.00 %
    # a limit whose float32 is below it: float32(8.183) is 8.1829996 m, valid either way
    bag = _ros2_bag(tmp_path / "c", [("/scan", 1.0, 1.0, 8.183)], range_max=math.inf)
    (scan,) = (r.scan for r in read_log(bag, geometry=LaserGeometry(range_max=8.183)))
    assert scan.valid.tolist() == [True] * 3 and scan.ranges.tolist() == [float(f32(8.183))] * 3


def test_a_bag_rosbags_cannot_open_is_one_line(tmp_path: Path) -> None:
    """rosbags' own errors span lines (PyYAML's on a ROS 2 bag's metadata.yaml quotes the text under a
    caret; a message definition it cannot parse is quoted whole), and read_log's BagError quoted them
    as they were: a multi-line error from the API (fuzzing read_log with damaged bags, 2026-12-07)."""
    bag = tmp_path / "b2"
    write_log(bag, [Record(_scan(float(k))) for k in range(2)], fmt="bag2")
    meta = bag / "metadata.yaml"
    lines = meta.read_text().split("\n")
    lines[3] += ": x: y"  # "mapping values are not allowed here"
    meta.write_text("\n".join(lines))
    with pytest.raises(BagError) as e:
        list(read_log(bag))
    assert "\n" not in str(e.value) and len(str(e.value)) < 500, str(e.value)
    assert re.match(rf"^{re.escape(str(bag))}: cannot open as a ROS bag: AnyReaderError: .*mapping values are not allowed "
                    r"here in \"<unicode string>\", line 4", str(e.value)), str(e.value)
    spaced = tmp_path / "two  spaces.bag"  # a review: every run of whitespace was collapsed, a path with two spaces misquoted
    assert str(BagError(f"{spaced}: cannot open\n   ^ here")) == f"{spaced}: cannot open ^ here"


@pytest.mark.parametrize("name, fmt", [("empty.clf", None), ("empty.clf.gz", None), ("empty.bag", None),
                                       ("empty2", "bag2")])
def test_write_log_of_no_record_writes_nothing(tmp_path: Path, name: str, fmt: str | None) -> None:
    """Defect: write_log(path, []) wrote a CARMEN log of comments (or a bag of no message) that
    read_log refused; now the pair agrees: no record is an InputError and an older log is kept."""
    path = tmp_path / name
    with pytest.raises(InputError, match=rf"^records: none to write to {re.escape(str(path))}: read_log refuses"):
        write_log(path, iter([]), fmt=fmt)
    assert not path.exists() and list(tmp_path.iterdir()) == []
    if fmt is None and not name.endswith(".bag"):
        write_log(path, [Record(_scan(1.0))])
        with pytest.raises(InputError):
            write_log(path, [])
        assert [r.scan.stamp for r in read_log(path)] == [1.0]


def test_write_log_checks_its_path_before_it_takes_a_record(tmp_path: Path) -> None:
    """Review: write_log took the first record (to refuse no record) before its path checks, so a
    path it refuses left a live source one record short. The path and fmt are checked first."""
    rec = Record(_scan(1.0))
    for name, fmt in (("x.clf.zip", None), ("x.clf", "bag"), ("x.bag", "bag2")):
        source = iter([rec])
        with pytest.raises(InputError, match=r"^path: "):
            write_log(tmp_path / name, source, fmt=fmt)
        assert next(source) is rec
    (tmp_path / "folder").mkdir()
    source = iter([rec])
    with pytest.raises(InputError, match=r"^path: .* exists and is not a regular file"):
        write_log(tmp_path / "folder", source)
    assert next(source) is rec


def test_a_killed_writers_temporary_file_is_removed_by_the_next_write(tmp_path: Path) -> None:
    """Defect: a SIGKILL between write_whole's write and rename left .NAME.PID.tmp for ever; the
    next write of that path removes one whose PID this host gives, no process here has, and that is
    older than STALE_TEMPORARY_S (10 min). Kept: a fresh one of a dead PID and one of a PID beyond
    pid_max (a live writer's on another host, NFS, or in a container), a live writer's, another
    suffix's or name's, and a user's .NAME.notes.tmp."""
    import itertools
    import os
    import time

    from lms200.logs import STALE_TEMPORARY_S, pid_max, process_alive

    dead_pid, other_dead_pid = itertools.islice((p for p in range(pid_max() - 1, 1, -1) if not process_alive(p)), 2)
    path = tmp_path / "x.clf.gz"
    dead = tmp_path / f".x.clf.gz.{dead_pid}.tmp.gz"
    fresh = tmp_path / f".x.clf.gz.{other_dead_pid}.tmp.gz"
    old_kept = [tmp_path / f".x.clf.gz.{os.getppid()}.tmp.gz",  # a live writer's
                tmp_path / ".x.clf.gz.9876543210.tmp.gz",  # 10 digits: beyond any pid_max, another host's
                tmp_path / ".x.clf.gz.notes.tmp.gz", tmp_path / f".x.clf.gz.{dead_pid}.tmp",
                tmp_path / f".y.clf.gz.{dead_pid}.tmp.gz"]
    long_ago = time.time() - STALE_TEMPORARY_S - 60
    for p in (dead, fresh, *old_kept):
        p.write_text("cut")
        if p is not fresh:
            os.utime(p, (long_ago, long_ago))
    write_log(path, [Record(_scan(1.0))])
    assert not dead.exists() and fresh.exists() and all(p.exists() for p in old_kept)
    assert [r.scan.stamp for r in read_log(path)] == [1.0]


def test_a_signalling_nan_reads_and_writes_as_nan_without_a_warning(tmp_path: Path) -> None:
    """Fuzzing (a byte of a ROS 2 bag changed): a float32 signalling nan (0x7f800001, a driver's raw
    bits) among the ranges made numpy's cast warn, "RuntimeWarning: invalid value encountered in
    cast", two lines on stderr for each such scan of `lmsbench info`, exit 0; a float64 one warned in
    write_log alike. Both are a nan: an invalid reading (REP-117)."""
    import struct
    import warnings

    ranges = np.full(5, 2.0)
    ranges[2] = np.frombuffer(struct.pack("<Q", 0x7FF0000000000001), np.float64)[0]
    for name in ("s.bag", "s2"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            write_log(tmp_path / name, [Record(Scan(ranges, -0.1, 0.05, 0.0, 8.0, stamp=1.0))],
                      fmt=None if name.endswith(".bag") else "bag2")
    data = (tmp_path / "s.bag").read_bytes()
    quiet = struct.pack("<f", np.float32(np.nan))
    assert data.count(quiet) == 1
    (tmp_path / "s.bag").write_bytes(data.replace(quiet, struct.pack("<I", 0x7F800001)))
    for name in ("s.bag", "s2"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            got = [r.scan.ranges for r in read_log(tmp_path / name)]
        assert len(got) == 1 and np.isnan(got[0][2]) and np.array_equal(np.delete(got[0], 2), np.full(4, 2.0))
