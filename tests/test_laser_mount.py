"""A laser mounted off the robot's centre (or a rear laser, mounted backwards) in CARMEN logs.

CARMEN's robot module places the laser at (robot_frontlaser_offset, _side_offset, _angular_offset) on the
robot, the rear laser before CARMEN 0.7 turned by pi with robot_rearlaser_offset along its own heading, and
ROBOTLASER1 / 2 lines are placed by the same PARAM lines, never by their own laser pose (docs/data.md, "Laser mounting"). The reader gives every record the
laser's poses (odometry, truth, corrected pose), what the scan was taken from. Each test builds a log
whose robot poses are the laser's moved by a known mount, with independent (numpy) geometry, and checks
that it reads with the same laser poses as the log written at the laser's own poses; before, the
robot's poses were read as the laser's (off by the mount: 0.27 m and 17 deg here)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from lms200 import Record, read_log, write_log
from sim import simulate_records

MOUNT = (0.25, -0.1, 0.3)  # x forward m, y left m, theta rad: the laser on the robot
DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "carmen"
INTEL = DATA / "intel-corrected.log.gz"


def _matrix(p) -> np.ndarray:
    c, s = math.cos(p[2]), math.sin(p[2])
    return np.array([[c, -s, p[0]], [s, c, p[1]], [0.0, 0.0, 1.0]])


def _pose(m: np.ndarray) -> tuple[float, float, float]:
    return (float(m[0, 2]), float(m[1, 2]), math.atan2(m[1, 0], m[0, 0]))


def _robot(laser, mount=MOUNT) -> tuple[float, float, float]:
    """The robot's pose that puts a laser mounted at ``mount`` at ``laser``: laser (+) mount^-1."""
    return _pose(_matrix(laser) @ np.linalg.inv(_matrix(mount)))


def _assert_poses(got, want, atol=1e-9) -> None:
    got, want = np.asarray(got, float), np.asarray(want, float)
    np.testing.assert_allclose(got[:, :2], want[:, :2], atol=atol, rtol=0)
    np.testing.assert_allclose(np.angle(np.exp(1j * (got[:, 2] - want[:, 2]))), 0, atol=atol)


@pytest.fixture(scope="module")
def laser_records() -> list[Record]:
    """Simulated scans (a turning tour) with the laser's true pose and a drifting odometry of it."""
    recs = simulate_records("office", seed=0, duration=3.0, rate_hz=5)
    out = []
    for k, r in enumerate(recs):
        x, y, th = r.truth
        out.append(Record(r.scan, odom=(x * 1.02 + 0.01 * k, y * 0.98, th + 0.003 * k), truth=r.truth))
    return out


def _offset_log(tmp_path: Path, recs: list[Record], fmt: str, params: list[str], mount, name: str,
                kind: str = "FLASER") -> Path:
    """``recs`` written at the robot's poses (odometry and truth) for a laser mounted at ``mount``, with
    ``params`` (PARAM name value) after the header; FLASER's first pose and ROBOTLASER's laser pose at the
    laser's odometry pose, as CARMEN's robot module writes them. ``kind`` RLASER: the FLASER lines and
    their geometry PARAM lines renamed to the rear laser's."""
    robot = [Record(r.scan, odom=_robot(r.odom, mount), truth=_robot(r.truth, mount)) for r in recs]
    path = tmp_path / name
    write_log(path, robot, fmt=fmt)
    lines = path.read_text().splitlines()
    laser_odom = iter([r.odom for r in recs if r.odom is not None])
    out = lines[:3] + [f"PARAM {p} lmsbench 0" for p in params]
    for line in lines[3:]:
        words = line.split()
        if words[0] in ("FLASER", "ROBOTLASER1"):
            n = int(words[1]) if words[0] == "FLASER" else int(words[8])
            at = 2 + n if words[0] == "FLASER" else 10 + n  # the laser pose (ROBOTLASER1: after 0 remissions)
            words[at : at + 3] = [repr(v) for v in next(laser_odom)]
            line = " ".join(words)
        if kind == "RLASER":
            line = (line.replace("FLASER", "RLASER").replace("laser_front_laser", "laser_rear_laser")
                    .replace("robot_front_laser_max", "robot_rear_laser_max").replace("lmsbench_front_", "lmsbench_rear_"))
        out.append(line)
    path.write_text("\n".join(out) + "\n")
    return path


def _front_params(mount=MOUNT) -> list[str]:
    return [f"robot_frontlaser_offset {mount[0]!r}", f"robot_frontlaser_side_offset {mount[1]!r}",
            f"robot_frontlaser_angular_offset {mount[2]!r}"]


def test_a_flaser_log_with_a_mounting_offset_reads_the_lasers_poses(tmp_path, laser_records):
    path = _offset_log(tmp_path, laser_records, "flaser", _front_params(), MOUNT, "front.log")
    got = list(read_log(path))
    assert len(got) == len(laser_records) == 14
    _assert_poses([r.odom for r in got], [r.odom for r in laser_records])
    _assert_poses([r.truth for r in got], [r.truth for r in laser_records])
    # the robot's pose, which was read as the laser's, lies 0.27 m and 17 deg off it
    off = np.hypot(*(np.array(_robot(laser_records[5].odom)[:2]) - laser_records[5].odom[:2]))
    assert off == pytest.approx(math.hypot(0.25, 0.1), abs=1e-9)
    # the scans themselves read as from the log written at the laser's poses
    plain = tmp_path / "plain.log"
    write_log(plain, laser_records, fmt="flaser")
    assert all(np.array_equal(a.scan.ranges, b.scan.ranges, equal_nan=True) and a.scan.stamp == b.scan.stamp
               for a, b in zip(got, read_log(plain), strict=True))


def test_zero_offset_params_read_bit_for_bit_as_none(tmp_path, laser_records):
    plain = tmp_path / "plain.log"
    write_log(plain, laser_records, fmt="flaser")
    zero = _offset_log(tmp_path, laser_records, "flaser", _front_params((0.0, 0.0, 0.0)), (0.0, 0.0, 0.0), "zero.log")
    assert [(r.odom, r.truth) for r in read_log(zero)] == [(r.odom, r.truth) for r in read_log(plain)]


def test_an_old_carmen_rear_laser_is_turned_by_pi_behind_the_robot(tmp_path, laser_records):
    # CARMEN before 0.7: RLASER's pose = odometry turned by pi, robot_rearlaser_offset along that heading
    mount = (-0.4, 0.0, math.pi)
    path = _offset_log(tmp_path, laser_records, "flaser", ["robot_rearlaser_offset 0.4"], mount, "rear.log",
                       kind="RLASER")
    reader = read_log(path)
    got = list(reader)
    assert reader.stats.laser == "RLASER" and len(got) == 14
    _assert_poses([r.odom for r in got], [r.odom for r in laser_records])
    _assert_poses([r.truth for r in got], [r.truth for r in laser_records])
    # no offset PARAM at all: still turned by pi (the module's rule), on the robot's centre
    bare = _offset_log(tmp_path, laser_records, "flaser", [], (0.0, 0.0, math.pi), "bare.log", kind="RLASER")
    _assert_poses([r.odom for r in read_log(bare)], [r.odom for r in laser_records])


def test_a_carmen_07_rear_laser_takes_its_angular_offset(tmp_path, laser_records):
    mount = (-0.3, 0.05, 3.1415923)  # carmen-std.ini's pioneer: rearlaser_offset -0.23, angular 3.1415923
    params = ["robot_rearlaser_offset -0.3", "robot_rearlaser_side_offset 0.05", "robot_rearlaser_angular_offset 3.1415923"]
    path = _offset_log(tmp_path, laser_records, "flaser", params, mount, "rear07.log", kind="RLASER")
    _assert_poses([r.odom for r in read_log(path)], [r.odom for r in laser_records])


def test_a_robotlaser_log_is_moved_by_its_mounting_params(tmp_path, laser_records):
    path = _offset_log(tmp_path, laser_records, "robotlaser1", _front_params(), MOUNT, "robotlaser.log")
    got = list(read_log(path))
    _assert_poses([r.odom for r in got], [r.odom for r in laser_records])
    _assert_poses([r.truth for r in got], [r.truth for r in laser_records])  # TRUEPOS is the robot's
    # ROBOTLASER2, CARMEN 0.7's rear laser: robot_rearlaser_*, the angular offset holding its pi
    rear = (-0.3, 0.05, 3.1415923)
    params = ["robot_rearlaser_offset -0.3", "robot_rearlaser_side_offset 0.05", "robot_rearlaser_angular_offset 3.1415923"]
    path2 = _offset_log(tmp_path, laser_records, "robotlaser1", params, rear, "robotlaser2.log")
    path2.write_text(path2.read_text().replace("ROBOTLASER1 ", "ROBOTLASER2 "))
    reader = read_log(path2)
    got2 = list(reader)
    assert reader.stats.laser == "ROBOTLASER2" and len(got2) == 14
    _assert_poses([r.odom for r in got2], [r.odom for r in laser_records])


def test_a_vasco_robotlaser_log_reads_its_raw_robot_poses_as_odometry(tmp_path, laser_records):
    """CARMEN's scan matcher (vasco-tiny.c: ``l.laser_pose = corrpos``) writes ROBOTLASER1 lines whose laser
    pose is the corrected pose and robot pose the raw odometry: no mounting PARAM, no mounting; before, the
    line's laser pose seen from its robot pose was taken as the mounting and .odom read as the corrected pose."""
    raw = [Record(r.scan, odom=r.odom) for r in laser_records]
    path = tmp_path / "vasco.log"
    write_log(path, raw, fmt="robotlaser1")
    corrected = iter(r.truth for r in laser_records)
    lines = []
    for line in path.read_text().splitlines():
        words = line.split()
        if words[0] == "ROBOTLASER1":
            at = 10 + int(words[8])
            words[at : at + 3] = [repr(v) for v in next(corrected)]  # the laser pose field: vasco's corrpos
            line = " ".join(words)
        lines.append(line)
    path.write_text("\n".join(lines) + "\n")
    reader = read_log(path)
    got = list(reader)
    assert [r.odom for r in got] == [r.odom for r in raw]
    assert got[7].odom != pytest.approx(laser_records[7].truth, abs=0.05)  # not the corrected pose
    assert reader.stats.mount is None and reader.stats.mounted == 0


def test_a_robotlaser_laser_starting_at_the_origin_takes_no_step(tmp_path, laser_records):
    """A laser whose first pose is exactly 0 0 0 is mounted like the others; before, 0 0 0 was taken for a
    converter's placeholder and that scan placed at the robot's pose, 0.27 m and 17 deg from the next."""
    first = laser_records[0].odom
    c, s = math.cos(first[2]), math.sin(first[2])

    def from_first(p):
        dx, dy = p[0] - first[0], p[1] - first[1]
        return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(p[2] - first[2]), math.cos(p[2] - first[2])))

    laser = [Record(r.scan, odom=from_first(r.odom), truth=from_first(r.truth)) for r in laser_records]
    assert laser[0].odom == (0.0, 0.0, 0.0)
    got = list(read_log(_offset_log(tmp_path, laser, "robotlaser1", _front_params(), MOUNT, "origin.log")))
    _assert_poses([r.odom for r in got], [r.odom for r in laser])
    assert math.hypot(got[0].odom[0], got[0].odom[1]) < 1e-9 and abs(got[0].odom[2]) < 1e-9


def test_written_back_the_laser_poses_are_both_flaser_poses_and_read_alike(tmp_path, laser_records):
    got = list(read_log(_offset_log(tmp_path, laser_records, "flaser", _front_params(), MOUNT, "front.log")))
    out = tmp_path / "back.log"
    write_log(out, got, fmt="flaser")
    for line, rec in zip((ln for ln in out.read_text().splitlines() if ln.startswith("FLASER")), got):
        words = line.split()
        n = int(words[1])
        # CARMEN's meaning: x y theta the laser's pose, odom_x odom_y odom_theta the robot's; no mount PARAM
        # is written, so the robot's frame is the laser's and both are the laser's odometry pose
        assert tuple(map(float, words[2 + n : 5 + n])) == rec.odom == tuple(map(float, words[5 + n : 8 + n]))
    assert "offset" not in out.read_text()
    assert [(r.odom, r.truth) for r in read_log(out)] == [(r.odom, r.truth) for r in got]


def test_bad_mount_params_are_malformed_lines(tmp_path, laser_records):
    path = _offset_log(tmp_path, laser_records[:2], "flaser", ["robot_frontlaser_offset nan"], MOUNT, "bad.log")
    with pytest.raises(ValueError, match=r"bad.log:4: .*robot_frontlaser_offset must be a finite number \(m"):
        list(read_log(path))


def test_slam_with_odometry_gives_the_same_run_on_the_offset_log(tmp_path, laser_records):
    from slam import SlamConfig, run_slam
    from slam.config import MotionConfig
    from slam.metrics import ate

    plain = tmp_path / "plain.log"
    write_log(plain, laser_records, fmt="flaser")
    offset = _offset_log(tmp_path, laser_records, "flaser", _front_params(), MOUNT, "front.log")
    config = SlamConfig(motion=MotionConfig(use_odometry=True))
    runs = [run_slam(list(read_log(p)), config) for p in (plain, offset)]
    truth = np.array([(r.scan.stamp, *r.truth) for r in laser_records])
    np.testing.assert_allclose(runs[1].trajectory, runs[0].trajectory, atol=1e-6)
    assert ate(runs[1].trajectory, truth).rmse == pytest.approx(ate(runs[0].trajectory, truth).rmse, abs=1e-6)


def _moved_log(src: Path, dst: Path, mount) -> None:
    """A real log's robot poses (FLASER's odometry pose, ODOM, TRUEPOS) moved so that a laser mounted at
    ``mount`` sits where the log's laser was; FLASER's first pose stays the laser's; mount PARAM lines added."""
    import gzip

    out = [f"PARAM {p} lmsbench 0" for p in _front_params(mount)]
    with gzip.open(src, "rt") as f:
        for line in f:
            words = line.split()
            if words and words[0] == "PARAM" and words[1].startswith("robot_frontlaser"):
                continue
            if words and words[0] in ("FLASER", "ODOM", "TRUEPOS"):
                at = 5 + int(words[1]) if words[0] == "FLASER" else 1
                words[at : at + 3] = [repr(v) for v in _robot(tuple(map(float, words[at : at + 3])), mount)]
                line = " ".join(words) + "\n"
            out.append(line.rstrip("\n"))
    dst.write_text("\n".join(out) + "\n")


@pytest.mark.skipif(not INTEL.exists(), reason=f"needs the Intel log at {INTEL}")
def test_the_intel_log_moved_onto_a_mounted_laser_reads_its_own_laser_poses(tmp_path):
    """A rigid transform of a real corrected log's robot poses: the laser poses (odometry chained from the
    ODOM lines, and the corrected poses) read as from the log itself."""
    _moved_log(INTEL, tmp_path / "intel-moved-corrected.log", MOUNT)
    want = list(read_log(INTEL))
    got = list(read_log(tmp_path / "intel-moved-corrected.log"))
    assert len(got) == len(want) == 910 and all(r.corrected is not None for r in got)
    _assert_poses([r.corrected for r in got], [r.corrected for r in want], atol=1e-8)
    _assert_poses([r.odom for r in got], [r.odom for r in want], atol=1e-8)


def test_info_says_where_the_laser_is_mounted(tmp_path, laser_records, capsys):
    from experiments.cli import main

    path = _offset_log(tmp_path, laser_records, "flaser", _front_params(), MOUNT, "front.log")
    assert main(["info", str(path)]) == 0
    assert ('  laser mount     x 0.250 m, y -0.100 m, 17.19 deg on the robot (14 scans): their poses are the '
            'laser\'s (docs/data.md, "Laser mounting")\n') in capsys.readouterr().out
    plain = tmp_path / "plain.log"
    write_log(plain, laser_records, fmt="flaser")
    assert main(["info", str(plain)]) == 0
    assert "laser mount" not in capsys.readouterr().out


def test_a_mounting_param_line_after_scans_is_told_as_a_change_of_frame(tmp_path, laser_records, capsys):
    """A mounting PARAM line after laser lines applies from its line on: the scans before it are in another
    frame. ReadStats and info say so (the line, the mounting before); before, only the last mount was told."""
    from experiments.cli import main

    path = _offset_log(tmp_path, laser_records, "flaser", _front_params(), MOUNT, "changed.log")
    lines = path.read_text().splitlines()
    at = [i for i, line in enumerate(lines) if line.startswith("FLASER")][5]
    lines[at:at] = ["PARAM robot_frontlaser_offset 0.25 lmsbench 0",  # restated, unchanged: no change
                    "PARAM robot_frontlaser_offset 0.5 lmsbench 0"]
    path.write_text("\n".join(lines) + "\n")
    reader = read_log(path)
    got = list(reader)
    assert len(got) == 14
    stats = reader.stats
    assert (stats.mount_changes, stats.mount_changed_at, stats.mount_before) == (1, at + 2, MOUNT)
    assert stats.mount == (0.5, -0.1, 0.3) and stats.mounted == 14
    _assert_poses([r.odom for r in got[:5]], [r.odom for r in laser_records[:5]])  # the first mount's frame
    assert main(["info", str(path)]) == 0
    assert (f"  laser mount     changed mid-log 1 time, first by the PARAM line {at + 2} (before it x 0.250 m, "
            "y -0.100 m, 17.19 deg): each scan is placed by the mounting of the lines before it\n") in capsys.readouterr().out
    assert main(["info", "--json", str(path)]) == 0
    import json

    assert json.loads(capsys.readouterr().out)["laser_mount_changes"] == {"count": 1, "first_line": at + 2,
                                                                          "before": list(MOUNT)}
    plain = _offset_log(tmp_path, laser_records, "flaser", _front_params(), MOUNT, "steady.log")
    reader = read_log(plain)
    list(reader)
    assert (reader.stats.mount_changes, reader.stats.mount_changed_at, reader.stats.mount_before) == (0, None, None)
