"""Values no log holds, which the readers took (a fuzzing round of the CARMEN, bag and TUM readers):
stamps of 1e300 s or below 0, angle steps finer than any rangefinder's, range_max beyond any
rangefinder's, nan in a ROBOTLASER1 line's laser pose and a beam count written ``361.0``. Each is
one line naming the file and line (or message), an ``LmsbenchError``, exit 2 from the CLI."""

from __future__ import annotations

from pathlib import Path

import pytest

from lms200 import LogFormatError, read_log, read_tum, write_tum
from lms200.errors import InputError, LmsbenchError

STAMP_RULE = ("is outside 0 .. 2^32 s (4294967296 s, 2106-02-07), the stamps every log reader and writer takes: a "
              "clock's UNIX time, or seconds since the run's start")


def _robotlaser(t: str = "5", logger: str | None = None, laser_pose: str = "0 0 0", count: str = "3",
                resolution: str = "1.5707963", fov: str = "3.1415926", max_range: str = "80") -> str:
    return (f"ROBOTLASER1 0 -1.5707963 {fov} {resolution} {max_range} 0.01 0 {count} 1 2 3 0 "
            f"{laser_pose} 0 0 0 0 0 0 0 0 {t} h {t if logger is None else logger}\n")


def _flaser(t: str, logger: str | None = None) -> str:
    return f"FLASER 3 1 2 3 0 0 0 0 0 0 {t} h {t if logger is None else logger}\n"


@pytest.mark.parametrize("line, kind, message", [
    (_robotlaser("1e300"), "ROBOTLASER1", f"ipc_timestamp 1e+300 s {STAMP_RULE}"),
    (_robotlaser("6", logger="1e300"), "ROBOTLASER1", f"logger_timestamp 1e+300 s {STAMP_RULE}"),
    (_robotlaser("6", logger="-3"), "ROBOTLASER1", f"logger_timestamp -3.000000 s {STAMP_RULE}"),
    (_robotlaser("6", logger="x"), "ROBOTLASER1", "logger_timestamp: 'x' is not a number"),
    (_robotlaser("-1"), "ROBOTLASER1", f"ipc_timestamp -1.000000 s {STAMP_RULE}"),
    (_robotlaser("4294967296.5"), "ROBOTLASER1", f"ipc_timestamp 4294967296.500000 s {STAMP_RULE}"),
    ("ODOM 0 0 0 0 0 0 1e300 h 6\n", "ODOM", f"ipc_timestamp 1e+300 s {STAMP_RULE}"),
    ("ODOM 0 0 0 0 0 0 6 h nan\n", "ODOM", f"logger_timestamp nan s {STAMP_RULE}"),
    ("TRUEPOS 0 0 0 0 0 0 1e300 h 6\n", "TRUEPOS", f"ipc_timestamp 1e+300 s {STAMP_RULE}"),
])
def test_a_carmen_stamp_outside_0_to_2_32_s_is_a_malformed_line(tmp_path: Path, line: str, kind: str,
                                                                  message: str) -> None:
    # was read: `lmsbench info` said "duration 1e+300 s", "scan rate 1e-300 scans/s", exit 0
    path = tmp_path / "t.log"
    path.write_text(_robotlaser("5") + line)
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == f"{path}:2: malformed {kind} line: {message}"


def test_a_flaser_stamp_of_1e300_s_is_refused_by_info_in_one_line(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    from experiments.cli import main

    path = tmp_path / "t.log"
    path.write_text(_flaser("5") + _flaser("1e300"))
    assert main(["info", str(path)]) == 2
    assert capsys.readouterr().err.strip() == (
        f"lmsbench info: error: {path}:2: malformed FLASER line: ipc_timestamp 1e+300 s {STAMP_RULE} "
        "(--skip-bad-lines skips malformed lines, each reported)")


def test_stamps_at_the_bounds_read(tmp_path: Path) -> None:
    path = tmp_path / "t.log"
    path.write_text("ODOM 0 0 0 0 0 0 0 h 0\n" + _robotlaser("0") + _robotlaser("4294967296", logger="0"))
    assert [r.scan.stamp for r in read_log(path)] == [0.0, 4294967296.0]


@pytest.mark.parametrize("stamp, shown", [("1e300", "1e+300"), ("-0.5", "-0.500000"), ("inf", None)])
def test_a_tum_time_outside_0_to_2_32_s_is_refused_naming_its_line(tmp_path: Path, stamp: str, shown: str | None) -> None:
    path = tmp_path / "t.tum"
    path.write_text(f"1 0 0 0 0 0 0 1\n{stamp} 0 0 0 0 0 0 1\n")
    with pytest.raises(LogFormatError) as err:
        read_tum(path)
    if shown is None:  # refused before, as non-finite
        assert str(err.value).startswith(f"{path}:2: TUM row has a non-finite number")
    else:
        assert str(err.value) == f"{path}:2: TUM time {shown} s {STAMP_RULE}"


def test_write_tum_refuses_a_stamp_read_tum_refuses(tmp_path: Path) -> None:
    with pytest.raises(InputError) as err:
        write_tum(tmp_path / "t.tum", [1.0, 1e300], [[0.0, 0.0, 0.0]] * 2)
    assert str(err.value) == "stamps: stamp 1 (1e+300 s) is outside 0 .. 2^32 s, which read_tum refuses (lms200.records.MAX_STAMP_S)"
    assert not (tmp_path / "t.tum").exists()


def test_a_relations_time_outside_0_to_2_32_s_is_refused_naming_its_line(tmp_path: Path) -> None:
    from slam.metrics import read_relations

    path = tmp_path / "r.relations"
    path.write_text("1 2 0 0 0 0 0 0\n3 1e300 0 0 0 0 0 0\n")
    with pytest.raises(LmsbenchError) as err:
        read_relations(path)
    assert str(err.value) == f"{path}:2: relation row's t2 1e+300 s {STAMP_RULE}"


# -- bags: the CARMEN reader's and the overrides' bounds --------------------------------------------
RANGE_HINT = "give the sensor's maximum range instead: --laser-range-max M (read_log(..., geometry=LaserGeometry(range_max=M)))"


@pytest.mark.parametrize("kw, message", [
    (dict(increment=1e-30), "angle_increment is 1e-30 rad (5.72958e-29 deg), finer than any rangefinder's step "
                            "(at least 1e-05 rad, 0.00057 deg)"),
    (dict(increment=9e-6), "angle_increment is 9e-06 rad (0.000515662 deg), finer than any rangefinder's step "
                           "(at least 1e-05 rad, 0.00057 deg)"),
    (dict(range_max=1e30), f"range_max is 1e+30 m, outside [0.1, 10000] m, which no laser rangefinder's maximum range "
                           f"lies outside; {RANGE_HINT}"),
    (dict(range_max=10001.0), f"range_max is 10001 m, outside [0.1, 10000] m, which no laser rangefinder's maximum "
                              f"range lies outside; {RANGE_HINT}"),
])
def test_a_bag_scan_of_an_impossible_step_or_range_max_is_a_bag_error(tmp_path: Path, capsys, kw: dict,  # noqa: ANN001
                                                                       message: str) -> None:
    # were read: `lmsbench info` showed a resolution of 5.73e-29 deg, or scans of range_max 1e30 m
    from experiments.cli import main
    from lms200.bag import BagError
    from test_bags import _ros2_bag

    bag = _ros2_bag(tmp_path / "b", [("/scan", 1.0, 1.0, 2.0), ("/scan", 1.1, 1.1, 2.0)], **kw)
    with pytest.raises(BagError) as err:
        list(read_log(bag))
    assert str(err.value) == f"{bag}: topic /scan message 0: cannot read: {message}"
    assert main(["info", str(bag)]) == 2
    assert capsys.readouterr().err.strip() == f"lmsbench info: error: {bag}: topic /scan message 0: cannot read: {message}"


def test_a_bag_at_the_bounds_reads_and_an_override_replaces_its_range_max(tmp_path: Path) -> None:
    from lms200.laser_geometry import LaserGeometry
    from test_bags import _ros2_bag

    bag = _ros2_bag(tmp_path / "b", [("/scan", 1.0, 1.0, 2.0)], range_max=10000.0, increment=1e-5)
    (scan,) = [r.scan for r in read_log(bag)]
    assert scan.range_max == 10000.0 and scan.angle_increment == pytest.approx(1e-5, rel=1e-7)
    far = _ros2_bag(tmp_path / "far", [("/scan", 1.0, 1.0, 2.0)], range_max=1e30)
    assert [r.scan.range_max for r in read_log(far, geometry=LaserGeometry(range_max=8.0))] == [8.0]


def test_a_bag_scan_stamped_before_0_is_a_bag_error(tmp_path: Path) -> None:
    from lms200.bag import BagError
    from test_bags import _ros2_bag

    bag = _ros2_bag(tmp_path / "b", [("/scan", 1.0, -5.0, 2.0)])
    with pytest.raises(BagError) as err:
        list(read_log(bag))
    assert str(err.value) == f"{bag}: topic /scan message 0: cannot read: header stamp -5.000000 s {STAMP_RULE}"


@pytest.mark.parametrize("fmt", ["robotlaser1", "flaser", "bag"])
def test_write_log_refuses_a_step_range_max_or_stamp_its_reader_refuses(tmp_path: Path, fmt: str) -> None:
    import numpy as np

    from lms200 import Record, Scan, write_log

    good = Scan(np.full(3, 2.0), -0.05, 0.05, 0.0, 8.0, stamp=1.0)  # centred, as FLASER needs
    bad = {"angle_increment": Scan(np.full(3, 2.0), -1e-7, 1e-7, 0.0, 8.0, stamp=1.0),
           "range_max": Scan(np.full(3, 2.0), -0.05, 0.05, 0.0, 2e4, stamp=1.0)}
    if fmt != "bag":  # Scan refuses the stamp itself now; set in place past its check, the writer still refuses it
        bad["stamp"] = good.replace()
        object.__setattr__(bad["stamp"], "stamp", 1e300)
    for field, scan in bad.items():
        path = tmp_path / (f"{field}-{fmt}" + (".clf" if fmt != "bag" else ""))
        kw = {} if fmt == "bag" else {"fmt": fmt}
        with pytest.raises(InputError, match=rf"^records: item 1: {field} "):
            write_log(path, [Record(good), Record(scan)], **kw)


@pytest.mark.parametrize("resolution, fov", [("0.0000001", "0.0000003"), ("0.000009", "0.000027")])
def test_a_robotlaser_step_finer_than_1e_5_rad_is_a_malformed_line(tmp_path: Path, resolution: str, fov: str) -> None:
    # was read ("resolution 5.73e-06 deg" in info), though --laser-resolution-deg refuses a step under 1e-5 rad
    path = tmp_path / "t.log"
    path.write_text(_robotlaser("5") + _robotlaser("6", resolution=resolution, fov=fov))
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == (f"{path}:2: malformed ROBOTLASER1 line: angular resolution must be at least 1e-05 rad "
                              f"(0.00057 deg; finer than any rangefinder's step), got {resolution}")
    path.write_text(_robotlaser("5", resolution="0.00001", fov="0.00003"))
    assert [r.scan.angle_increment for r in read_log(path)] == [1e-5]


# -- ROBOTLASER1 / FLASER fields that are not read ---------------------------------------------------
@pytest.mark.parametrize("line, message", [
    (_robotlaser("6", laser_pose="nan 0 0"), "ROBOTLASER1 laser pose is not finite"),
    (_robotlaser("6", laser_pose="0 0 inf"), "ROBOTLASER1 laser pose is not finite"),
    ("ROBOTLASER1 0 -1.5707963 3.1415926 1.5707963 80 0.01 0 3 1 2 3 0 0 0 0 0 0 0 nan 0 0 0 0 6 h 6\n",
     "ROBOTLASER1 speeds, safety distances or turn axis are not finite"),
    ("ROBOTLASER1 0 -1.5707963 3.1415926 1.5707963 80 0.01 0 3 1 2 3 0 0 0 0 0 nan 0 0 0 0 0 0 6 h 6\n",
     "ROBOTLASER1 robot pose is not finite"),
    ("FLASER 3 1 2 3 nan inf 0 0 0 0 6 h 6\n", "FLASER laser pose is not finite"),
])
def test_a_non_finite_laser_pose_is_a_malformed_line(tmp_path: Path, line: str, message: str) -> None:
    # the laser pose was read as nan / inf without a word (the robot pose and odometry were refused)
    path = tmp_path / "t.log"
    path.write_text((_flaser("1") if line.startswith("FLASER") else _robotlaser("1")) + line)
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == f"{path}:2: malformed {line.split()[0]} line: {message}"


@pytest.mark.parametrize("line, word", [
    (_robotlaser("6", count="3.0"), "3.0"),
    (_robotlaser("6", count="+3"), "+3"),
    ("ROBOTLASER1 0 -1.5707963 3.1415926 1.5707963 80 0.01 0 3 1 2 3 0.0 0 0 0 0 0 0 0 0 0 0 0 6 h 6\n", "0.0"),
    ("FLASER 3.0 1 2 3 0 0 0 0 0 0 6 h 6\n", "3.0"),
    ("FLASER 3e0 1 2 3 0 0 0 0 0 0 6 h 6\n", "3e0"),
])
def test_a_count_not_written_in_digits_is_a_malformed_line(tmp_path: Path, line: str, word: str) -> None:
    # '361.0' was read as 361 beams (CARMEN's atoi reads '3.61e2' as 3: only digits mean one count to both)
    kind = line.split()[0]
    path = tmp_path / "t.log"
    path.write_text((_flaser("1") if kind == "FLASER" else _robotlaser("1")) + line)
    what = "remission count" if word == "0.0" else "beam count"
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == f"{path}:2: malformed {kind} line: {what} must be a non-negative integer written in digits, got {word!r}"
