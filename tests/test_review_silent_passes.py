"""Silent passes and unhelpful messages found by a review (session of the fix helper): each test
fails on the code before its fix."""

from __future__ import annotations

import bz2
import gzip
import re
from pathlib import Path

import numpy as np
import pytest

from lms200 import read_log
from lms200.errors import LmsbenchWarning, LogFormatError


# -- 1. a log of no laser line ----------------------------------------------------------------------
@pytest.mark.parametrize("name, data, reason", [
    ("empty.clf", b"", r"an empty file \(0 bytes\): no laser lines"),
    ("empty.clf.gz", gzip.compress(b"", mtime=0), r"its gzip data decompresses to nothing: an empty log, no laser lines"),
    ("empty.clf.bz2", bz2.compress(b""), r"its bzip2 data decompresses to nothing"),
    ("quiet.clf", b"# header\n\n   \n# more\n", r"holds only blank or comment lines \(4\): no laser lines"),
    ("odom.clf", b"ODOM 0 0 0 0 0 0 1 h 1\nODOM 0 0 0 0 0 0 2 h 2\nPARAM x 1\n",
     r"holds no laser lines \(FLASER, .*\), only other messages: ODOM \(2\), PARAM \(1\)"),
], ids=["empty", "gzip-of-nothing", "bzip2-of-nothing", "comments", "odom-only"])  # the same ids on every xdist worker
@pytest.mark.parametrize("skip", [False, True])
def test_a_log_of_no_laser_line_is_refused_naming_the_file(tmp_path: Path, name: str, data: bytes, reason: str,
                                                          skip: bool) -> None:
    """A zero-byte log, a gzip of nothing, a file of comments read as no records, silently."""
    (tmp_path / name).write_bytes(data)
    # a whole-file problem names the file alone: it said "FILE:1: ...", a line not at fault
    with pytest.raises(LogFormatError, match=rf"^{re.escape(str(tmp_path / name))}: {reason}") as info:
        list(read_log(tmp_path / name, skip_bad_lines=skip))
    assert info.value.line_no is None


@pytest.mark.parametrize("command", [["info"], ["compare", "--out", "{out}"], ["slam", "--out", "{out}"]],
                         ids=["info", "compare", "slam"])
def test_the_commands_name_a_log_of_no_laser_line_without_a_line(tmp_path: Path, capsys, command: list[str]) -> None:
    """`lmsbench info odo.log` said "odo.log:1: holds no laser lines ...": line 1 is not at fault."""
    from experiments.cli import main

    log = tmp_path / "odo.log"
    log.write_bytes(b"ODOM 0 0 0 0 0 0 1 h 1\n")
    argv = [command[0], str(log), *(a.format(out=tmp_path / "out") for a in command[1:])]
    assert main(argv) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"lmsbench {command[0]}: error: {log}: holds no laser lines (FLASER, RLASER, ROBOTLASER1 / 2, RAWLASER1 .. 4), "
        "only other messages: ODOM (1)"]


def test_a_log_of_junk_skipped_under_skip_bad_lines_says_what_it_skipped(tmp_path: Path) -> None:
    """Lines skipped are the reader's word (stats.skipped): no error for the lack of a laser line then."""
    (tmp_path / "bad.clf").write_text("FLASER 3 1 2\n")
    reader = read_log(tmp_path / "bad.clf", skip_bad_lines=True)
    assert list(reader) == [] and reader.stats.skipped_count == 1


# -- 6. numbers near 1e308 in messages -------------------------------------------------------------
def test_fixed_writes_huge_numbers_with_an_exponent_and_others_as_before() -> None:
    from lms200.finite import fixed

    assert fixed(1700000000.1234567) == "1700000000.123457" == f"{1700000000.1234567:.6f}"
    assert fixed(2.5, 1) == "2.5" and fixed(float("nan")) == "nan" and fixed(float("-inf"), 3) == "-inf"
    assert fixed(1e308) == "1e+308" and fixed(-1.5e300, 3) == "-1.5e+300"


def test_fixed_writes_a_tiny_number_in_significant_digits_not_as_zero() -> None:
    """A value not 0 that the decimals show as 0 (an angle increment of 1e-290 rad: "0.0000 deg")
    is written in significant digits; 0 and values the decimals show stay as they were."""
    from lms200.finite import fixed

    assert fixed(5.729577951308232e-289, 4) == "5.73e-289" and fixed(-1e-7) == "-1e-07" and fixed(4e-5, 4) == "4e-05"
    assert fixed(0.0, 4) == "0.0000" and fixed(5e-5, 4) == "0.0001" and fixed(0.5, 4) == "0.5000" and fixed(0.04, 1) == "0.04"


def test_calibrate_and_info_show_a_tiny_resolution_as_it_is(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    """A CARMEN log declaring an angular resolution of 1e-290 rad: calibrate said "angular resolution
    0.0000 deg: the LMS200 model has 0.25, 0.5 or 1 deg" and info "resolution 0.000 deg", a value the
    log does not hold."""
    import numpy as np

    from experiments.cli import main
    from lms200 import Record, Scan, write_log

    log = tmp_path / "tiny.clf"
    write_log(log, [Record(Scan(np.full(361, 2.0), -0.1, 0.5 * np.pi / 180, 0.0, 8.0, stamp=0.2 * i)) for i in range(20)])
    lines = log.read_text().splitlines(keepends=True)
    for k, line in enumerate(lines):  # the geometry of 361 beams 1e-290 rad apart, as written by hand
        if line.startswith("ROBOTLASER1 "):
            words = line.split(" ")
            words[3:5] = ["3.6e-288", "1e-290"]
            lines[k] = " ".join(words)
    log.write_text("".join(lines))
    # the reader refuses the line now (a step under laser_geometry.MIN_RESOLUTION_RAD, 1e-5 rad): both commands did not
    # show it as 0 but took it (calibrate said "angular resolution 5.73e-289 deg: the LMS200 model has ...", info exit 0)
    first = 1 + next(k for k, line in enumerate(lines) if line.startswith("ROBOTLASER1 "))
    for command in (["calibrate", str(log), "--out", str(tmp_path / "s.yaml")], ["info", str(log)]):
        assert main(command) == 2
        assert capsys.readouterr().err == (
            f"lmsbench {command[0]}: error: {log}:{first}: malformed ROBOTLASER1 line: angular resolution must be at "
            "least 1e-05 rad (0.00057 deg; finer than any rangefinder's step), got 1e-290 (--skip-bad-lines skips "
            "malformed lines, each reported)\n")


def test_a_tum_stamp_near_1e308_is_quoted_compactly(tmp_path: Path) -> None:
    """'TUM stamps go backwards (1.000000 s after 1000000000000000010979063629440455417404923096773118...'"""
    from lms200 import read_tum

    (tmp_path / "t.tum").write_text("1e308 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n")
    with pytest.raises(LogFormatError) as info:
        read_tum(tmp_path / "t.tum")
    # refused at its own line now (lms200.records.MAX_STAMP_S), still quoted compactly
    assert str(info.value) == (f"{tmp_path / 't.tum'}:1: TUM time 1e+308 s is outside 0 .. 2^32 s (4294967296 s, "
                               "2106-02-07), the stamps every log reader and writer takes: a clock's UNIX time, or "
                               "seconds since the run's start")


def _flaser_log(path: Path, stamps: list[str]) -> Path:
    ranges = " ".join(["2.0"] * 181)
    path.write_text("".join(f"FLASER 181 {ranges} 0 0 0 0 0 0 {t} h {t}\n" for t in stamps))
    return path


def test_slam_and_info_quote_a_stamp_near_1e308_compactly(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Both said "time goes backwards ... after 1e+308 s" / "duration 1e+308 s"; now the stamp is
    refused at its line (lms200.records.MAX_STAMP_S), still quoted compactly."""
    from experiments.cli import main

    log = _flaser_log(tmp_path / "big.log", ["1e308", "1", "2"])
    for command in (["slam", str(log), "--out", str(tmp_path / "s")], ["info", str(log)]):
        assert main(command) == 2
        err = capsys.readouterr().err.strip()
        assert err == (f"lmsbench {command[0]}: error: {log}:1: malformed FLASER line: ipc_timestamp 1e+308 s is "
                       "outside 0 .. 2^32 s (4294967296 s, 2106-02-07), the stamps every log reader and writer takes: "
                       "a clock's UNIX time, or seconds since the run's start (--skip-bad-lines skips malformed lines, "
                       "each reported)")


def test_a_robotlaser_header_of_1e300_steps_is_quoted_compactly(tmp_path: Path) -> None:
    """'which holds 10000000000000000525047602552044202487...0.0 steps' (301 digits); and its resolution
    of 1e-290 rad was 'at 0.0000 deg'."""
    log = tmp_path / "rl.log"
    log.write_text("ROBOTLASER1 0 -1 1e10 1e-290 80 0.01 0 3 2 2 2 0 0 0 0 0 0 0 0 0 0 0 0 1 h 1\n")
    with pytest.raises(LogFormatError, match=r"rl\.log:1: malformed ROBOTLASER1 line: declares a field of view of "
                                             r"572957795130\.823 deg at 5\.73e-289 deg, which holds 1e\+300 steps, but "
                                             r"carries 3 beams \(fov must be n or n - 1 steps\)$"):
        list(read_log(log))


# -- 4. a bag's LaserScan range_max of inf ------------------------------------------------------------
def test_a_bag_scan_of_range_max_inf_says_how_to_override_it_and_the_override_reads_it(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Was "range_max: must be finite, got inf", and --laser-range-max was refused for bags ("no geometry override")."""
    import math

    from experiments.cli import main
    from lms200.bag import BagError
    from lms200.laser_geometry import LaserGeometry
    from test_bags import _ros2_bag

    bag = _ros2_bag(tmp_path / "b", [("/scan", 1.0, 1.0, 2.0), ("/scan", 1.1, 1.1, 20.0)], range_max=math.inf)
    hint = ("give the sensor's maximum range instead: --laser-range-max M "
            "(read_log(..., geometry=LaserGeometry(range_max=M)))")
    with pytest.raises(BagError) as info:
        list(read_log(bag))
    assert str(info.value) == (f"{bag}: topic /scan message 0: cannot read: range_max is inf (no limit, as some "
                               f"drivers write), which no scan takes (a reading's validity is judged against it); {hint}")
    scans = [r.scan for r in read_log(bag, geometry=LaserGeometry(range_max=8.0))]
    assert [s.range_max for s in scans] == [8.0, 8.0] and [int(s.valid.sum()) for s in scans] == [3, 0]
    assert main(["info", str(bag), "--laser-range-max", "8"]) == 0
    assert "  scans           2\n" in capsys.readouterr().out
    with pytest.raises(BagError, match=r"the range_max override \(0\.1 m, --laser-range-max\) is not above the "
                                       r"scan's range_min \(0\.1 m\); give a larger one"):
        list(read_log(bag, geometry=LaserGeometry(range_max=0.1)))
    with pytest.raises(BagError, match=r"the override of resolution \(--laser-\*-deg\) applies to CARMEN FLASER / "
                                       r"RLASER lines only"):
        read_log(bag, geometry=LaserGeometry(resolution=0.01, range_max=8.0))


# -- 5. calibrate_scans of copies of one scan ----------------------------------------------------------
def test_calibrating_copies_of_one_scan_says_they_are_copies(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """50 copies of one scan said "got 1", as if one scan had been given."""
    import numpy as np

    from experiments.cli import main
    from lms200 import Scan
    from lms200.calibration import calibrate_scans
    from lms200.errors import InputError

    scan = Scan(np.linspace(1.0, 5.0, 181), -np.pi / 2, np.pi / 180, 0.0, 81.83, 1.0)
    with pytest.raises(InputError) as info:
        calibrate_scans([scan] * 50)
    assert str(info.value) == ("scans: calibrating needs at least 2 distinct scans (standard errors are a bootstrap "
                               "over scans), got 50 scans but only 1 distinct: 49 repeat the scan before them (same "
                               "stamp, geometry and readings), which is no second sample")
    with pytest.raises(InputError, match=r"at least 2 distinct scans \(standard errors are a bootstrap over scans\), "
                                         r"got 1$"):
        calibrate_scans([scan])
    ranges = " ".join(f"{r:.2f}" for r in np.linspace(1.0, 5.0, 181))
    log = tmp_path / "dup.log"
    log.write_text(f"FLASER 181 {ranges} 0 0 0 0 0 0 1 h 1\n" * 50)
    assert main(["calibrate", str(log), "--out", str(tmp_path / "s.yaml")]) == 2
    assert "got 50 scans but only 1 distinct: 49 repeat the scan before them" in capsys.readouterr().err


# -- 3. a TUM pose with roll or pitch ---------------------------------------------------------------
def _quaternion(roll_deg: float, pitch_deg: float, yaw_deg: float) -> tuple[float, float, float, float]:
    """(qx, qy, qz, qw) of the rotation Rz(yaw) Ry(pitch) Rx(roll)."""
    import math

    cr, sr = math.cos(math.radians(roll_deg) / 2), math.sin(math.radians(roll_deg) / 2)
    cp, sp = math.cos(math.radians(pitch_deg) / 2), math.sin(math.radians(pitch_deg) / 2)
    cy, sy = math.cos(math.radians(yaw_deg) / 2), math.sin(math.radians(yaw_deg) / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def _tum(path: Path, tilts: list[tuple[float, float]]) -> Path:
    path.write_text("".join(f"{i} {i} 0 0 {' '.join(map(repr, _quaternion(r, p, 30.0)))}\n"
                            for i, (r, p) in enumerate(tilts)))
    return path


def test_a_tum_pose_tilted_beyond_30_deg_is_refused_naming_the_line(tmp_path: Path) -> None:
    """A camera-frame trajectory (z forward: 90 deg from upright) gave a yaw, silently."""
    from lms200 import read_tum

    tum = _tum(tmp_path / "cam.tum", [(0, 0), (0, 0), (-90, 0)])
    with pytest.raises(LogFormatError, match=r"cam\.tum:3: TUM row's rotation is tilted 90\.0 deg from upright \(roll "
                                             r"or pitch; at most 30 deg\): its z axis is not up"):
        read_tum(tum)
    with pytest.raises(LogFormatError, match=r"cam\.tum:2: TUM row's rotation is tilted 31\.0 deg"):
        read_tum(_tum(tmp_path / "cam.tum", [(0, 0), (0, 31)]))


def test_a_tum_pose_tilted_a_little_is_read_as_its_heading_with_one_warning(tmp_path: Path) -> None:
    import warnings

    from lms200 import read_tum
    from lms200.errors import LmsbenchWarning

    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        stamps, poses = read_tum(_tum(tmp_path / "t.tum", [(0, 0), (2, 1), (10, 0), (0, -12), (4, 3)]))
    assert poses[:, 2] == pytest.approx([0.5235987755982988] * 5, abs=1e-12)  # 30 deg: the heading, tilted or not
    assert [(w.category, str(w.message)) for w in said] == [(LmsbenchWarning, (
        f"{tmp_path / 't.tum'}: 2 of its 5 poses are tilted by more than 5 deg (roll or pitch; up to 12.0 deg, line 4): "
        "read as the heading of their x axis and the projection of their position onto the plane"))]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a planar file, and one tilted by under 5 deg, read without a word
        read_tum(_tum(tmp_path / "u.tum", [(0, 0), (2, 1), (-4.9, 0)]))


# -- 2. ROBOTLASER1 angles near the 0.05 deg grid ------------------------------------------------------
@pytest.mark.parametrize("angle_min, increment", [
    (-1.5707963267948966 + 3e-7, 0.008726646259971648),  # off the grid by 3e-7 rad: read back on it
    (-1.5707963267948966, 0.008726646259971648 + 2e-7),  # an increment 2e-7 rad off: 7.2e-5 rad at the last beam
    (-1.570796, 0.008727),  # as a CARMEN logger's 6 decimals give them
    (-1.5707963705062866, 0.008726646192371845),  # float32
])
def test_robotlaser1_angles_round_trip_exactly(tmp_path: Path, angle_min: float, increment: float) -> None:
    """The writer wrote them exactly, but the reader snapped them onto the grid, as it does a logger's 6 decimals."""
    import numpy as np

    from lms200 import Record, Scan, write_log

    scan = Scan(np.linspace(1.0, 5.0, 361), angle_min, increment, 0.0, 80.0, 1.0)
    write_log(tmp_path / "a.log", [Record(scan=scan)] * 2)
    back = [r.scan for r in read_log(tmp_path / "a.log")]
    assert [(s.angle_min, s.angle_increment) for s in back] == [(angle_min, increment)] * 2
    assert (tmp_path / "a.log").read_text().count("PARAM lmsbench_robotlaser_angles exact lmsbench 0\n") == 1


def test_a_log_of_grid_angles_is_written_as_before_and_a_logger_s_6_decimals_still_snap(tmp_path: Path) -> None:
    import math

    import numpy as np

    from lms200 import Record, Scan, write_log

    scan = Scan(np.linspace(1.0, 5.0, 361), -math.pi / 2, math.radians(0.5), 0.0, 80.0, 1.0)
    write_log(tmp_path / "a.log", [Record(scan=scan)])
    text = (tmp_path / "a.log").read_text()
    assert "robotlaser_angles" not in text and " -1.5707963267948966 3.141592653589793 0.008726646259971648 " in text
    ranges = " ".join(["2.00"] * 361)
    tail = "0 0 0 0 0 0 0 0 0 0 0 1 h 1"
    (tmp_path / "b.log").write_text(f"ROBOTLASER1 0 -1.570796 3.150447 0.008727 80 0.01 0 361 {ranges} 0 {tail}\n"
                                    "PARAM lmsbench_robotlaser_angles grid\n"
                                    f"ROBOTLASER1 0 -1.570796 3.150447 0.008727 80 0.01 0 361 {ranges} 0 {tail}\n"
                                    "PARAM lmsbench_robotlaser_angles maybe\n")
    assert [(s.scan.angle_min, s.scan.angle_increment) for s in read_log(tmp_path / "b.log", skip_bad_lines=True)] \
        == [(-math.pi / 2, math.radians(0.5))] * 2
    with pytest.raises(LogFormatError, match=r"b\.log:4: malformed PARAM line: lmsbench_robotlaser_angles must be "
                                             r"exact or grid, got 'maybe'"):
        list(read_log(tmp_path / "b.log"))


# -- 7. a sweep cell reads its sensor file once -----------------------------------------------------
def test_a_sweep_cell_computes_with_the_bytes_its_key_names(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The cell read the sensor file twice (its digest, then its content): an edit between the reads,
    put back before the cell finished, had the cell compute with the edit and the row stored under
    the key of the file as it was (the runner's check after the cell read the old content again)."""
    import pandas as pd

    from experiments.sweep import SweepSpec, kinds, run_sweep
    from sim import SensorConfig

    monkeypatch.chdir(tmp_path)
    sensor = tmp_path / "sensor.yaml"
    SensorConfig(noise_sigma=0.005).to_yaml(sensor)
    before = sensor.read_bytes()
    SensorConfig(noise_sigma=0.03).to_yaml(sensor)
    edit = sensor.read_bytes()
    sensor.write_bytes(before)
    real = SensorConfig.from_yaml.__func__

    def edited_while_read(cls, p, data=None):  # noqa: ANN001, ANN202 - the file is the edit while the cell parses it
        sensor.write_bytes(edit)
        try:
            return real(cls, p, *([] if data is None else [data]))
        finally:
            sensor.write_bytes(before)

    seen: list[float] = []
    monkeypatch.setattr(kinds, "compare", lambda sources, methods, params, sigma: seen.append(sigma) or pd.DataFrame())
    monkeypatch.setattr(kinds, "summarise", lambda table, reference: pd.DataFrame({"f1": [1.0]}))
    spec = SweepSpec.from_dict({"name": "sf", "kind": "extract",
                                "fixed": {"duration": 0.5, "rate_hz": 2.0, "sensor_file": "sensor.yaml"}})
    kinds._run.cache_clear()
    monkeypatch.setattr(SensorConfig, "from_yaml", classmethod(edited_while_read))
    result = run_sweep(spec, tmp_path / "out", "inprocess", progress=False)
    assert seen == [0.005] and (result.computed, len(result.table)) == (1, 1)  # the content of its key


def test_a_sweep_cell_that_read_an_edit_put_back_before_it_finished_is_not_stored(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The runner judged a cell by the file as it was when the cell finished: an edit the cell read,
    put back since, passed, and its row was stored under the key of the content it did not read."""
    import experiments.sweep.runner as runner
    from experiments.sweep import SweepSpec, run_sweep
    from lms200.errors import LmsbenchWarning
    from sim import SensorConfig

    monkeypatch.chdir(tmp_path)
    sensor = tmp_path / "sensor.yaml"
    SensorConfig(noise_sigma=0.03).to_yaml(sensor)
    edit = sensor.read_bytes()
    SensorConfig(noise_sigma=0.005).to_yaml(sensor)
    before = sensor.read_bytes()
    real = runner.run_cell

    def edited_while_running(kind, params, fn=None):  # noqa: ANN001, ANN202
        sensor.write_bytes(edit)
        try:
            return real(kind, params, fn)
        finally:
            sensor.write_bytes(before)

    monkeypatch.setattr(runner, "run_cell", edited_while_running)
    spec = SweepSpec.from_dict({"name": "sf", "kind": "extract",
                                "fixed": {"duration": 0.5, "rate_hz": 2.0, "sensor_file": "sensor.yaml"}})
    with pytest.warns(LmsbenchWarning, match=r"^sensor.yaml changed while the sweep ran: 1 cell that finished after "
                                             r"the change was not stored"):
        result = run_sweep(spec, tmp_path / "out", "inprocess", progress=False)
    assert (result.total, result.computed) == (1, 0) and result.table.empty


# -- more silent passes: an ODOM / TRUEPOS line with more fields than its message has ------------------
def test_a_laser_line_run_into_an_odom_line_is_a_malformed_line_not_a_lost_scan(tmp_path: Path) -> None:
    """A lost line break ran a FLASER line into the ODOM line before it: the ODOM line's extra words
    were ignored and the scan lost without a word (found by fuzzing damaged logs)."""
    ranges = " ".join(["2.00"] * 181)
    log = tmp_path / "a.log"
    log.write_text(f"ODOM 0 0 0 0 0 0 1 h 1\nFLASER 181 {ranges} 0 0 0 0 0 0 1.5 h 1.5\n"
                   f"ODOM 0 0 0 0 0 0 2 h 2 FLASER 181 {ranges} 0 0 0 0 0 0 2.5 h 2.5\n"
                   f"TRUEPOS 0 0 0 0 0 0 3 h 3 x\nFLASER 181 {ranges} 0 0 0 0 0 0 3 h 3\n")
    with pytest.raises(LogFormatError, match=r"a\.log:3: malformed ODOM line: ODOM has 202 fields, at most 10 \(ODOM "
                                             r"and 6 numbers, ipc_timestamp, hostname, logger_timestamp\): two lines "
                                             r"run together \(a lost line break\)\?"):
        list(read_log(log))
    reader = read_log(log, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [1.5, 3.0]
    assert [at for at, _ in reader.stats.skipped] == [3, 4] and "TRUEPOS has 11 fields" in reader.stats.skipped[1][1]
    log.write_text(f"ODOM 0 0 0 0 0 0 1 h 1\nODOM 0 0 0 0 0 0 1\nFLASER 181 {ranges} 0 0 0 0 0 0 1.5 h 1.5\n")
    assert len(list(read_log(log))) == 1  # 8 to 10 words read as before


def test_a_bag_pose_tilted_beyond_30_deg_is_a_bag_error_as_in_a_tum_file(tmp_path: Path) -> None:
    """A /odom pose in a frame whose z is not up gave its yaw, silently (read_tum refuses it)."""
    import math

    from lms200.bag import BagError
    from test_bags import _POS, _pose_bag

    bag = _pose_bag(tmp_path / "b", _POS, _quaternion(-90.0, 0.0, -90.0))
    with pytest.raises(BagError, match=r"b: topic /odom message 0: cannot read: orientation \(x, y, z, w\) = .* is "
                                       r"tilted 90\.0 deg from upright \(roll or pitch; at most 30 deg\)"):
        list(read_log(bag))
    tilted = [r.odom[2] for r in read_log(_pose_bag(tmp_path / "c", _POS, _quaternion(10.0, -5.0, 40.0)))]
    assert tilted == pytest.approx([math.radians(40.0)] * 3, abs=1e-12)  # a little tilt: its heading, as before


def test_a_bag_whose_laserscan_topic_holds_no_message_is_a_bag_error(tmp_path: Path) -> None:
    """A bag with a /scan connection but no scan on it read as no records, silently."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    from lms200.bag import BagError
    from test_bags import _ros2_bag

    ts = get_typestore(Stores.ROS2_HUMBLE)
    with Writer(tmp_path / "e", version=8) as w:
        w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts)
    for skip in (False, True):
        with pytest.raises(BagError, match=r"e: its LaserScan topic /scan holds no message: no scan \(a recording "
                                           r"stopped before its first scan\?\)$"):
            list(read_log(tmp_path / "e", skip_bad_lines=skip))
    bag = _ros2_bag(tmp_path / "s", [("/scan", 1.0, 1.0, 2.0)])
    assert len(list(read_log(bag))) == 1


def test_a_relation_of_large_roll_or_pitch_is_refused_naming_its_line(tmp_path: Path) -> None:
    """A relation's z, roll and pitch were dropped: a 3-D motion was scored as its x, y and yaw, silently."""
    from slam.metrics import read_relations

    rel = tmp_path / "r.relations"
    rel.write_text("1 2 0.3 0.0 0 0 0 0.2\n2 3 0.3 0.0 0.1 0.05 -0.1 0.2\n3 4 0.3 0.0 0 0 0.6 0.2\n")
    with pytest.raises(LogFormatError, match=r"r\.relations:3: relation row's roll and pitch tilt it by more than 30 "
                                             r"deg, or are not near 0: not a planar motion, whose x, y and yaw could be scored: "
                                             r"'3 4 0\.3 0\.0 0 0 0\.6 0\.2'"):
        read_relations(rel)
    # roll and pitch of 25 deg each tilt it by 34.8 deg, as read_tum measures a quaternion's tilt (the first
    # version of this check took the larger of the two, and passed it)
    from lms200.tum import tilt_deg, tilt_of_roll_pitch_deg

    for roll, pitch, yaw in ((0.4363, 0.4363, 0.2), (0.3, -0.5, 1.0), (-1.2, 0.1, -2.5)):  # z-y-x Euler -> quaternion
        cr, sr, cp, sp, cy, sy = (f(a / 2) for a in (roll, pitch, yaw) for f in (np.cos, np.sin))
        q = np.array([sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
                      cr * cp * cy + sr * sp * sy])
        assert tilt_of_roll_pitch_deg(roll, pitch) == pytest.approx(tilt_deg(q), abs=1e-9)
    assert tilt_of_roll_pitch_deg(0.4363, 0.4363) == pytest.approx(34.77, abs=0.01)
    rel.write_text("1 2 0.3 0.0 0 0.4363 0.4363 0.2\n")
    with pytest.raises(LogFormatError, match=r"r\.relations:1: relation row's roll and pitch tilt it"):
        read_relations(rel)
    # roll and pitch of pi tilt it by 0 but turn it by pi: its yaw 0.5 is a heading of 0.5 + pi (the review)
    rel.write_text("0 1 1.0 0 0 3.14159265 3.14159265 0.5\n")
    with pytest.raises(LogFormatError, match=r"r\.relations:1: relation row's roll and pitch tilt it by more than 30 "
                                             r"deg, or are not near 0: not a planar motion"):
        read_relations(rel)
    rel.write_text("1 2 0.3 0.0 0 0 0 0.2\n2 3 0.3 0.0 0.1 0.05 -0.1 0.2\n")
    with pytest.warns(LmsbenchWarning, match=r"1 of its 2 relations leaves the plane"):  # a little: read, and said
        assert read_relations(rel).tolist() == [[1, 2, 0.3, 0, 0.2], [2, 3, 0.3, 0, 0.2]]


def test_a_relation_whose_z_climbs_off_the_plane_is_refused_or_said(tmp_path: Path, shared_data: Path) -> None:
    """A relation's z was not read: a row of z = 5 m over 0.3 m of x, y motion was scored on its x and y,
    silently. Its climb, atan2(|z|, hypot(x, y)), is held to the tilt bounds: refused beyond 30 deg naming
    file and line, said once from 5 deg (as read_tum says tilted poses); a z within 1 cm is read as 0.
    MIT CSAIL's relations (every z, roll and pitch 0) read without a word."""
    import math
    import warnings

    from slam.metrics import read_relations

    rel = tmp_path / "r.relations"
    rel.write_text("1 2 0.3 0.0 0 0 0 0.2\n2 3 0.3 0.0 5 0 0 0.2\n")
    climb = math.degrees(math.atan(5 / 0.3))
    with pytest.raises(LogFormatError, match=re.escape(f"r.relations:2: relation row's z 5 m climbs {climb:.1f} deg over "
                                                       "its x, y motion of 0.3 m (at most 30 deg where z is beyond "
                                                       "0.1 m): not a planar motion")):
        read_relations(rel)  # old: read, scored on x = 0.3, y = 0
    # 0.1 m over 0.3 m climbs 18.4 deg (line 2), a roll of 0.17 rad tilts 9.7 deg (line 4): said once; 0.05 m over
    # 1 m climbs 2.9 deg, and 5 mm over no x, y motion is within the floor (text rounding, not a climb); a turn on
    # the spot with z = 2 cm climbs 90 deg but hides at most 2 cm: said, not refused (it refused the file; review)
    rel.write_text("1 2 0.3 0 0 0 0 0.2\n2 3 0.3 0 0.1 0 0 0.2\n3 4 1 0 0.05 0 0 0\n4 5 0.3 0 0 0.17 0 0.1\n"
                   "5 6 0 0 0.005 0 0 0.3\n6 7 0 0 0.02 0 0 0.5\n")
    with pytest.warns(LmsbenchWarning) as said:
        assert read_relations(rel)[:, 2].tolist() == [0.3, 0.3, 1.0, 0.3, 0.0, 0.0]
    assert [str(w.message) for w in said] == [
        f"{rel}: 3 of its 6 relations leave the plane by more than 5 deg (roll / pitch tilt, or a z beyond 0.01 m "
        "climbing over the x, y motion; up to 90.0 deg, line 6): scored on their x, y and yaw"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_relations(shared_data / "mit-csail.relations").shape == (1172, 5)


def test_a_misspelt_lmsbench_param_is_a_malformed_line(tmp_path: Path) -> None:
    """`PARAM lmsbench_range_unit mm` was passed over: the scan's unit inferred instead (cm here: range_max
    81.83 m where the log meant mm mode's 8.183 m, its readings of 20 m taken as valid)."""
    ranges = " ".join(["20.00"] * 181)
    log = tmp_path / "a.log"
    log.write_text(f"PARAM lmsbench_range_unit mm h 0\nFLASER 181 {ranges} 0 0 0 0 0 0 1 h 1\n")
    with pytest.raises(LogFormatError, match=r"a\.log:1: malformed PARAM line: 'lmsbench_range_unit' is no lmsbench "
                                             r"PARAM: 'lmsbench_range_units' misspelt\? "
                                             r"\(known: lmsbench_front_laser_angle_increment, .*, "
                                             r"lmsbench_range_units, lmsbench_rear_laser_angle_increment, "
                                             r"lmsbench_rear_laser_angle_min, lmsbench_robotlaser_angles\)$"):
        list(read_log(log))
    log.write_text(f"PARAM lmsbench_range_units mm h 0\nPARAM other_thing 1 h 0\nFLASER 181 {ranges} 0 0 0 0 0 0 1 h 1\n")
    assert [(r.scan.range_max, int(r.scan.valid.sum())) for r in read_log(log)] == [(8.183, 0)]  # as before


@pytest.mark.parametrize("name", ["lmsbench_writer_version", "lmsbench_odometry_frame", "lmsbench_range_min_m"])
def test_an_lmsbench_param_near_no_known_name_is_passed_over_with_a_warning(tmp_path: Path, name: str) -> None:
    """A name near none of the known ones (a lab's own), or one that extends a known one (a later
    version's), is no misspelling: a log refused for it lost every scan (the review: `PARAM
    lmsbench_writer_version 0.2.0`; compared whole, the shared prefix made `lmsbench_odometry_frame` a
    misspelt `lmsbench_odometry`); it is read as other programs' PARAM lines are, with a warning naming it."""
    ranges = " ".join(["2.00"] * 181)
    log = tmp_path / "a.log"
    log.write_text(f"PARAM {name} 0.2.0 h 0\nFLASER 181 {ranges} 0 0 0 0 0 0 1 h 1\n")
    with pytest.warns(LmsbenchWarning, match=rf"PARAM {name}: no lmsbench PARAM this version reads"):
        records = list(read_log(log))
    assert [int(r.scan.valid.sum()) for r in records] == [181]


@pytest.mark.parametrize("name, known", [("lmsbench_unit", "lmsbench_range_units"),
                                         ("lmsbench_odometri", "lmsbench_odometry"),
                                         ("lmsbench_robotlaser_angle", "lmsbench_robotlaser_angles")])
def test_an_lmsbench_param_misspelt_by_more_than_a_letter_is_still_malformed(tmp_path: Path, name: str,
                                                                            known: str) -> None:
    """`lmsbench_unit mm` shares a word only lmsbench_range_units has: refused naming it (whole names
    compared, it was only warned of, the unit inferred)."""
    log = tmp_path / "a.log"
    log.write_text(f"PARAM {name} mm h 0\nFLASER 181 {' '.join(['20.00'] * 181)} 0 0 0 0 0 0 1 h 1\n")
    with pytest.raises(LogFormatError, match=rf"a\.log:1: malformed PARAM line: '{name}' is no lmsbench PARAM: "
                                             rf"'{known}' misspelt\?"):
        list(read_log(log))


@pytest.mark.parametrize("hostname", ["my host", "", "tab\there", "nl\n", "höst", 7])
def test_write_carmen_refuses_a_hostname_that_is_not_one_field(tmp_path: Path, hostname: object) -> None:
    """`write_carmen(..., hostname="my host")` wrote a log of lines one field too long, none of which
    read back (the review); an empty or non-ASCII one was written as well."""
    from lms200 import Scan
    from lms200.carmen import write_carmen
    from lms200.errors import InputError
    from lms200.records import Record

    records = [Record(Scan(np.full(181, 2.0), -np.pi / 2, np.pi / 180, 0.0, 8.0, stamp=1.0))]
    with pytest.raises(InputError, match=r"^hostname: must be one word of printable ASCII"):
        write_carmen(tmp_path / "a.log", records, hostname=hostname)  # type: ignore[arg-type]
    assert not (tmp_path / "a.log").exists()
    write_carmen(tmp_path / "b.log", records, hostname="robot-7")
    assert [r.scan.stamp for r in read_log(tmp_path / "b.log")] == [1.0]
