"""Bad input to the public Python API: every user error is an ``LmsbenchError`` naming the field or
argument, never a raw numpy / Python exception, a silent cast or a lost file (fuzzing of
2026-12-02: Scan, read_log / write_log, extract / extract_many, sim, the Gym env, run_slam)."""

from __future__ import annotations

import dataclasses
import math
import re
from decimal import Decimal
from fractions import Fraction
from typing import Any

import os

import numpy as np
import pytest

from lms200 import LaserGeometry, LmsbenchError, Record, Scan, read_log, write_log
from lms200.errors import InputError, ScanError

GEOM = dict(angle_min=-1.0, angle_increment=0.01, range_min=0.0, range_max=10.0)


# -- Scan ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("ranges", [
    np.array([1 + 1j, 2.0]),                      # was cast to [1, 2] with a ComplexWarning
    np.array([True, False]),                      # was [1 m, 0 m]
    ["1", "2"],                                   # text
    np.array(["2020-01-01"], dtype="datetime64[D]"),  # was 18262 m
    bytearray(b"\x01\x02"),                       # was [1 m, 2 m]: one metre per byte value (bytes were refused)
    memoryview(b"\x01\x02"),                      # the same
])
def test_scan_refuses_ranges_that_are_not_real_numbers(ranges: object) -> None:
    with pytest.raises(ScanError, match="^ranges: must be real numbers"):
        Scan(ranges, **GEOM)  # type: ignore[arg-type]


def test_scan_still_reads_a_memoryview_of_numbers() -> None:
    """A memoryview of float64 (or a buffer cast to them) is numbers, not raw bytes: read as before."""
    assert Scan(memoryview(np.array([1.5, 2.0])), **GEOM).ranges.tolist() == [1.5, 2.0]
    raw = bytearray(np.array([1.5, 2.0]).tobytes())
    assert Scan(memoryview(raw).cast("d"), **GEOM).ranges.tolist() == [1.5, 2.0]
    assert Scan(np.frombuffer(raw, "<f8"), **GEOM).ranges.tolist() == [1.5, 2.0]


@pytest.mark.parametrize("field, value, message", [
    ("ranges", np.ones((3, 3)), "^ranges: must be 1-D"),
    ("ranges", [], "^ranges: must hold at least one beam"),
    ("ranges", [-1.0, 1.0], "^ranges: negative"),
    ("angle_min", np.nan, "^angle_min: must be finite"),
    ("angle_increment", 0.0, "^angle_increment: must be > 0"),
    ("range_min", -1.0, "^range_min: must be >= 0"),
    ("range_max", np.inf, "^range_max: must be finite"),
    ("stamp", np.nan, "^stamp: must be finite"),
    ("stamp", None, "^stamp: must be a number"),
])
def test_scan_errors_are_lmsbench_errors_naming_the_field(field: str, value: object, message: str) -> None:
    kw: dict[str, object] = dict(ranges=np.ones(5), **GEOM)
    kw[field] = value
    with pytest.raises(ScanError, match=message) as info:
        Scan(**kw)  # type: ignore[arg-type]
    assert isinstance(info.value, LmsbenchError) and isinstance(info.value, ValueError)


def test_scan_lms200_names_ranges_for_text() -> None:
    with pytest.raises(ScanError, match="^ranges: must be real numbers"):  # was "could not convert string to float"
        Scan.lms200("abc")  # type: ignore[arg-type]


def test_masked_beams_become_invalid() -> None:
    """A numpy masked array's masked beams are nan (invalid), not their hidden values."""
    scan = Scan(np.ma.array([1.0, 2.0, 3.0], mask=[True, False, False]), **GEOM)
    assert np.isnan(scan.ranges[0]) and scan.ranges[1:].tolist() == [2.0, 3.0]
    assert scan.valid.tolist() == [False, True, True]


# -- read_log / write_log ----------------------------------------------------------------------------
def _records(n: int = 3) -> list[Record]:
    rng = np.random.default_rng(0)
    return [Record(scan=Scan.lms200(np.round(2.0 + rng.uniform(0, 1, 361), 3), stamp=0.1 * i)) for i in range(n)]


@pytest.mark.parametrize("kw, message", [
    (dict(topic=5), "^topic: must be"),
    (dict(geometry="x"), "^geometry: must be"),               # was AttributeError: 'str' object has no attribute 'fov'
    (dict(skip_bad_lines="yes"), "^skip_bad_lines: must be True or False"),  # was accepted as truthy
])
def test_read_log_options_of_the_wrong_type(tmp_path, kw: dict, message: str) -> None:
    path = tmp_path / "a.log"
    assert write_log(path, _records()) == 3
    with pytest.raises(InputError, match=message):
        read_log(path, **kw)


@pytest.mark.parametrize("path", [5, None])
def test_read_log_path_of_the_wrong_type(path: object) -> None:
    with pytest.raises(InputError, match="^path: must be a str or os.PathLike"):
        read_log(path)  # type: ignore[arg-type]


@pytest.mark.parametrize("path, message", [
    ("/dev/zero", "/dev/zero is not a regular file"),  # exists but is no file: refused by name, not read
    ("/no/such.log", "no such log: /no/such.log"),
    ("/tmp", "is a folder but not a ROS 2 bag"),
])
def test_read_log_of_a_device_folder_or_nothing(path: str, message: str) -> None:
    """A LogNotFoundError: an LmsbenchError (was a bare FileNotFoundError) and still a FileNotFoundError."""
    from lms200.errors import LogNotFoundError

    with pytest.raises(LogNotFoundError, match=message) as info:
        read_log(path)
    assert isinstance(info.value, FileNotFoundError)


def test_a_file_of_a_ros2_bag_folder_names_the_folder_to_give(tmp_path, capsys) -> None:
    """Round 7: a bag's metadata.yaml given as the log was "not a CARMEN log: none of its 38 lines ... starts
    with a message name", its .db3 "a binary file, not a CARMEN log, ROS 1 .bag or ROS 2 bag folder" (the
    command line): a bag is read as its folder, which the error now names, in read_log and the command line."""
    from experiments.cli import main

    bag = tmp_path / "run"
    write_log(bag, [Record(scan=Scan(np.full(5, 2.0), **GEOM))] * 2, fmt="bag2")
    for member, what in ((bag / "metadata.yaml", "metadata"), (bag / "run.db3", "storage file")):
        said = (f"{member}: a file of the ROS 2 bag {bag} (its {what}), not a log by itself: a ROS 2 bag is read as its "
                f"folder; give {bag}")
        with pytest.raises(InputError, match=f"^{re.escape(said)}$"):
            read_log(member)
        assert main(["info", str(member)]) == 2
        assert capsys.readouterr().err.splitlines() == [f"lmsbench info: error: {said}"]
    assert sum(1 for _ in read_log(bag)) == 2


def test_a_file_of_a_simulate_folder_names_what_to_give(tmp_path, capsys) -> None:
    """Round 9: a lmsbench simulate folder's groundtruth.tum, world.json or config.yaml given as the log was
    "not a CARMEN log: none of its 37 lines ... starts with a message name", its map.png "a binary file" (the
    command line), with no hint: the error names the folder to give (command line) or its scans.clf (read_log)."""
    from experiments.cli import main

    run = tmp_path / "run"
    run.mkdir()
    write_log(run / "scans.clf", [Record(scan=Scan(np.full(5, 2.0), **GEOM))] * 2)
    files = {"groundtruth.tum": ("# t x y z qx qy qz qw\n0 1 2 0 0 0 0 1\n", "its ground-truth trajectory"),
             "world.json": ('{"walls": []}\n', "its world"), "map.png": ("\x89PNG\r\n\x1a\n\x00", "its map figure")}
    for name, (text, what) in files.items():
        member = run / name
        member.write_text(text, encoding="latin-1")
        said = (f"{member}: a file of the lmsbench simulate output folder {run} ({what}), not a log: the run's scans "
                "are its scans.clf; give ")
        with pytest.raises(InputError, match=f"^{re.escape(said + str(run / 'scans.clf'))}$"):  # old: LogFormatError
            read_log(member)
        assert main(["info", str(member)]) == 2
        assert capsys.readouterr().err.splitlines() == [f"lmsbench info: error: {said}{run}"]
    (run / "scans.clf").unlink()  # no simulate folder: the file is said as what it holds
    with pytest.raises(LmsbenchError, match="not a CARMEN log"):
        list(read_log(run / "groundtruth.tum"))


def test_write_log_with_a_bad_record_keeps_the_existing_file(tmp_path) -> None:
    """Before: a bad item part-way was an AttributeError after the file had been truncated, and the
    5-scan log at the path was left with the scans before the bad item."""
    path = tmp_path / "run.log"
    good = _records(5)
    assert write_log(path, good) == 5
    before = path.read_bytes()
    with pytest.raises(InputError, match=r"^records\[2\]: expected an lms200.Record, got Scan"):
        write_log(path, [*good[:2], good[2].scan, *good[3:]])  # type: ignore[list-item]
    assert path.read_bytes() == before
    back = [r.scan.ranges for r in read_log(path)]
    assert len(back) == 5 and all(np.array_equal(a, g.scan.ranges) for a, g in zip(back, good))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.log"]  # no temporary file left


def test_write_log_writes_a_links_target_keeps_a_files_mode_and_packs_by_the_name(tmp_path) -> None:
    """write_log kept its own temporary-file-and-rename beside write_whole: a symbolic link was
    replaced by a regular file (its target left as it was), where every other whole-file output
    writes the target. One mechanism now; the temporary name keeps ``.gz`` so the log is packed."""
    import gzip

    target = tmp_path / "real.log.gz"
    assert write_log(target, _records(2)) == 2
    os.chmod(target, 0o600)
    link = tmp_path / "latest.log.gz"
    link.symlink_to(target.name)
    assert write_log(link, _records(4)) == 4
    assert link.is_symlink() and os.readlink(link) == target.name  # the link stays a link
    assert os.stat(target).st_mode & 0o777 == 0o600
    assert sum(line.startswith(b"ROBOTLASER1 ") for line in gzip.decompress(target.read_bytes()).splitlines()) == 4  # packed, by the .gz of the name
    assert len(list(read_log(link))) == 4
    assert sorted(q.name for q in tmp_path.iterdir()) == ["latest.log.gz", "real.log.gz"]


def test_write_log_bag_with_a_bad_record_leaves_no_bag(tmp_path) -> None:
    path = tmp_path / "run.bag"
    with pytest.raises(InputError, match=r"^records\[1\]: expected an lms200.Record, got int"):
        write_log(path, [_records(1)[0], 1])  # type: ignore[list-item]
    assert not path.exists()


@pytest.mark.parametrize("name, fmt", [("run.log", "robotlaser1"), ("run.log", "flaser"), ("run.log.gz", "robotlaser1")])
@pytest.mark.parametrize("range_max", [1e308, 20_000.0, 0.05])
def test_write_log_refuses_a_range_max_its_reader_refuses(tmp_path, name: str, fmt: str, range_max: float) -> None:
    """A Scan with range_max 1e308 (or 20 km, or 5 cm) was written as a CARMEN log, exit 0, that
    read_log then refused ('maximum range must be in [0.1, 10000] m'): the writer wrote what its
    reader cannot read back. The earlier log at the path is kept."""
    path = tmp_path / name
    write_log(path, _records(2), fmt=fmt)
    before = path.read_bytes()
    odd = Record(Scan(np.full(5, 0.04), -0.1, 0.05, 0.0, range_max, stamp=2.0))
    with pytest.raises(InputError, match=rf"^records: item 2: range_max {re.escape(f'{range_max:g}')} m is outside \[0\.1, 10000\] m, "
                                         r"which the CARMEN reader refuses \(the log could not be read back\)$"):
        write_log(path, [*_records(2), odd], fmt=fmt)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]
    write_log(path, [Record(Scan(np.full(5, 5000.0), -0.1, 0.05, 0.0, 10_000.0))], fmt=fmt)  # the bound itself
    assert [r.scan.ranges.tolist() for r in read_log(path)] == [[5000.0] * 5]


@pytest.mark.parametrize("ranges, range_max", [(np.full(5, 1e300), 1e308), (np.full(5, 2.0), 1e39),
                                               (np.array([1e39, 1, 1, 1, 1]), 1e38)])
def test_write_log_bag_refuses_numbers_a_laserscan_cannot_hold(tmp_path, ranges: np.ndarray, range_max: float) -> None:
    """A range or range_max beyond float32 was rosbags' raw OverflowError ('float too large to pack
    with f format') after a RuntimeWarning of the float32 cast; no bag is left."""
    path = tmp_path / "run.bag"
    with pytest.raises(InputError, match=r"^records: item 1: a range or range_max beyond 3\.403e\+38 m cannot be stored "
                                         r"in a bag \(a LaserScan's fields are float32\)"):
        write_log(path, [_records(1)[0], Record(Scan(ranges, -0.1, 0.05, 0.0, range_max, stamp=5.0))])
    assert not path.exists()


@pytest.mark.parametrize("path_of, records, fmt, message", [
    (lambda d: d, "good", None, "^path: .* is not a regular file"),          # was IsADirectoryError
    (lambda d: d / "missing" / "x.log", "good", None, "^path: the folder .* does not exist"),  # was FileNotFoundError
    (lambda d: "/dev/full", "good", None, "^path: /dev/full exists and is not a regular file"),  # was OSError ENOSPC
    (lambda d: d / "x.log", None, None, "^records: must be an iterable"),    # was TypeError
    (lambda d: d / "x.log", "good", "xyz", "^fmt: must be"),                  # was a bare ValueError
    (lambda d: d / "x.clf.zst", "good", None, r"^path: x\.clf\.zst names a zstd-compressed file, which write_log does "
                                              r"not write \(a CARMEN log is plain text, or compressed as \.gz, \.bz2 or "
                                              r"\.xz\)$"),  # plain text under a .zst name
    (lambda d: d / "x.log.ZIP", "good", None, r"^path: x\.log\.ZIP names a zip archive"),  # the same
    (lambda d: d / "x.bag", "good", "flaser", r"^path: a CARMEN log \(flaser\) named x\.bag is not read back"),  # written,
    (lambda d: d / "x.bag", "good", "robotlaser1", r"read_log reads a \.bag as a ROS 1 bag"),  # then refused by read_log
])
def test_write_log_bad_paths_and_arguments(tmp_path, path_of, records, fmt, message: str) -> None:
    recs = _records(2) if records == "good" else records
    with pytest.raises(InputError, match=message):
        write_log(path_of(tmp_path), recs, fmt=fmt)


# -- extract / extract_many ---------------------------------------------------------------------------
@pytest.mark.parametrize("scans", [None, 5])
def test_extract_many_of_something_not_iterable(scans: object) -> None:
    from features import extract_many
    from features.errors import ScanTypeError

    with pytest.raises(ScanTypeError, match="^extract_many: expected a sequence of lms200.Scan"):  # was TypeError
        extract_many(scans)  # type: ignore[arg-type]


@pytest.mark.parametrize("call, starts", [
    (lambda a: Scan(np.ones(3), a, 0.01, 0.0, 1.0), "angle_min: must be a number, got array([[1., 1., 1.], [1., 1., 1.]])"),
    (lambda a: __import__("features").extract(Scan.lms200(np.full(361, 3.0)), method=a), "method: must be a method name"),
    (lambda a: __import__("features").extract_many([Scan.lms200(np.full(361, 3.0))], threads=a), "threads: must be"),
    (lambda a: next(iter(read_log("x.clf", topic=a))), "topic: must be a topic name (str) or None, got array([[1., 1., 1.], [1."),
    # its != "auto" was elementwise: "ValueError: The truth value of an array ... is ambiguous"
    (lambda a: __import__("features").extract(Scan.lms200(np.full(361, 3.0)), sigma_r=a), "sigma_r: must be a range noise std"),
])
def test_an_array_given_for_a_scalar_is_an_error_of_one_line(call, starts: str) -> None:
    """Round 7: a 2-D array's repr spans lines, and ~90 messages quote a value by its repr: each was an
    LmsbenchError of two lines (LmsbenchError now makes its message one line)."""
    with pytest.raises(LmsbenchError) as info:
        call(np.ones((2, 3)))
    assert str(info.value).startswith(starts) and "\n" not in str(info.value)


def test_error_messages_stay_one_line_when_named_again_and_keep_keyword_arguments() -> None:
    """Review of round 7: a lone \\r stayed, a trailing break left a blank, a user extractor's
    multi-line error came back on two lines once ``at`` named its scan (``args`` set again), and
    ImportError's ``name=`` of NumbaUnavailableError was a TypeError."""
    from experiments.user_methods import UserMethodFailed
    from lms200.errors import NumbaUnavailableError

    assert [str(LmsbenchError(m)) for m in ("a\rb", "end\n", "a\n \n b", "two  spaces")] == ["a b", "end", "a b", "two  spaces"]
    failed = UserMethodFailed("m:f", "raised ValueError: bad value:\n  line two", Scan.lms200(np.full(361, 3.0)), True)
    assert str(failed.at("office:0", 3)) == "your extractor m:f raised ValueError: bad value: line two on office:0 scan 3"
    assert NumbaUnavailableError("no numba", name="numba").name == "numba"


@pytest.mark.parametrize("method", [["sensor"], 5])
def test_extract_method_that_is_not_a_name(method: object) -> None:
    from features import extract
    from features.errors import ConfigError

    with pytest.raises(ConfigError, match="^method: must be a method name") as info:  # ["sensor"] was "unhashable type"
        extract(Scan.lms200(np.full(361, 3.0)), method=method)  # type: ignore[arg-type]
    assert "sensor" in str(info.value)


@pytest.mark.parametrize("field", ["merge_gap", "bridge_invalid", "corner_max_gap"])
def test_sensor_beam_counts_beyond_any_scan(field: str) -> None:
    """1e300 beams was an OverflowError building the kernels' int64 record; it means the same as
    any count above the scan's beams: the gaps join every run. (min_points=1e300 found no line, exit
    0: it is at most 16,384 beams now, tests/test_baselines.py.)"""
    from features import extract

    rng = np.random.default_rng(3)
    ang = np.deg2rad(np.arange(361) * 0.5 - 90.0)
    ranges = 2.0 / np.maximum(np.cos(ang - 0.2), 0.05) + rng.normal(0, 0.005, 361)  # a wall 2 m away
    scan = Scan.lms200(np.where(ranges < 8.0, ranges, np.inf))
    huge = extract(scan, **{field: 1e300})
    big = extract(scan, **{field: 10**6})  # already more than any scan's beams
    assert repr(list(huge.lines)) == repr(list(big.lines))
    if field == "min_points":
        assert len(huge.lines) == 0 and len(extract(scan).lines) >= 1


# -- sim ----------------------------------------------------------------------------------------------
def test_simulate_records_duration_is_bounded() -> None:
    """duration=1e9 planned a tour for over 30 s and then ran out of memory; now refused at once."""
    from sim import simulate_records
    from experiments import options
    from sim.records import MAX_DURATION_S

    assert MAX_DURATION_S == 3600.0 and options.MAX_DURATION_S == MAX_DURATION_S  # one bound for both
    with pytest.raises(InputError, match=r"^duration: must be a number of seconds in \(0, 3600\]"):
        simulate_records("office", seed=0, duration=1e9)


def test_simulate_records_rate_above_the_sensors_is_refused() -> None:
    """rate_hz=1e9 silently kept the sensor's 37.5 scans/s; the bound is the sensor's scan rate."""
    from sim import SensorConfig, simulate_records
    from sim.records import check_rate

    with pytest.raises(InputError, match=r"^rate_hz: 1e\+09 scans/s is more than the sensor gives \(37.5 scans/s"):
        simulate_records("office", seed=0, duration=1.0, rate_hz=1e9)
    one_deg = SensorConfig.lms200_1deg()
    check_rate(75.0, one_deg)  # the 1 deg sweep's rate is allowed
    with pytest.raises(InputError, match=r"\(75 scans/s at 1 deg\)"):
        check_rate(76.0, one_deg)
    recs = simulate_records("office", seed=0, duration=1.0, rate_hz=37.5)
    assert len(recs) == len(simulate_records("office", seed=0, duration=1.0))  # every scan, as without a rate


@pytest.mark.parametrize("rate_hz", [1e-320, 5e-324, 1e-300, 1e-4])
def test_a_rate_below_one_scan_an_hour_is_refused(rate_hz: float, tmp_path) -> None:  # noqa: ANN001
    """simulate_records(rate_hz=1e-300) (and a simulate config's or a sweep's rate_hz) ran and kept the
    first scan alone: no run of at most an hour keeps a second one."""
    from sim import simulate_records

    from experiments.slamrun import load_input
    from experiments.sweep.kinds import _check_sensors

    floor = "1/3600 scans/s (one scan an hour, the longest simulated run: a lower rate keeps the first scan alone)"
    with pytest.raises(InputError, match=re.escape(f"rate_hz: {rate_hz:g} scans/s is below the lowest rate kept, {floor}")):
        simulate_records("office", seed=0, duration=1.0, rate_hz=rate_hz)
    with pytest.raises(LmsbenchError, match=re.escape(f"rate_hz: {rate_hz:g} scans/s is below the lowest rate kept")):
        _check_sensors([{"rate_hz": rate_hz}], {}, {})
    log = tmp_path / "two.clf"
    write_log(log, simulate_records("office", seed=0, duration=0.2))
    # slam's load_input reads logs, which may last longer than an hour: no floor, the one scan kept refused after the read
    with pytest.raises(LmsbenchError, match=re.escape(f"{log}: --rate-hz {rate_hz:g} keeps 1 of the 7 scans read")):
        load_input(log, rate_hz=rate_hz)
    assert len(simulate_records("office", seed=0, duration=1.0, rate_hz=1 / 3600)) == 1  # the floor itself runs


def test_slam_on_a_log_of_zero_readings_says_they_are_what_is_invalid(tmp_path) -> None:
    """A log of 0 readings (invalid, as REP-117 gives no return as +inf) was refused as "all +inf or nan"
    (fuzz round): the message named readings the log does not hold."""
    from experiments.slamrun import load_input

    log = tmp_path / "zeros.clf"
    write_log(log, [Record(Scan.lms200(np.zeros(361), stamp=float(t))) for t in range(3)])
    with pytest.raises(LmsbenchError, match=re.escape(f"{log}: none of its 3 scans has a valid beam (every reading "
                                                      "+inf, -inf, nan, 0 or outside the scan's range limits)")):
        load_input(log)


@pytest.mark.parametrize("rate_hz", [1e-320, 5e-324, 1e-300])
def test_a_rate_near_zero_keeps_the_first_scan_as_any_low_rate_does(rate_hz: float) -> None:
    """`simulate --rate-hz 1e-320` (also compare --rate, sim2real --rate-hz, sweeps' rate_hz) was
    "internal error: OverflowError: cannot convert float infinity to integer" (1 / (period * rate)
    is inf), and 5e-324 a ZeroDivisionError; a rate this low keeps the first scan, as 0.001 does."""
    from sim import SensorConfig
    from sim.records import scan_stamps

    sensor = SensorConfig()
    for duration in (0.5, 10.0, 3600.0):
        low = scan_stamps(sensor, duration, rate_hz)
        assert low.tolist() == scan_stamps(sensor, duration, 1e-4).tolist() == [0.0]
    assert len(scan_stamps(sensor, 10.0, 2.0)) == 20 and len(scan_stamps(sensor, 10.0, None)) == 375  # as before


@pytest.mark.parametrize("kw, message", [
    (dict(seed=-1), "^seed: must be a whole number"),
    (dict(clutter="x"), "^clutter: must be a number or None"),   # was "could not convert string to float"
    (dict(name=None), "^name: unknown world None"),
    # fuzz round 10: 100 ran 103 s for 19 panels, 1e6 for hours, 2**70 was numpy's "lam value too large" ValueError
    (dict(glass=2**70), r"^glass: must be a rate in \[0, 2\] \(panels per 10 m of route and clutter level"),
    (dict(glass=2.5), r"^glass: must be a rate in \[0, 2\]"),
])
def test_make_world_errors_are_lmsbench_errors(kw: dict, message: str) -> None:
    from sim import make_world

    args: dict = dict(name="office", seed=0)
    args.update(kw)
    with pytest.raises(InputError, match=message):
        make_world(**args)


BOX = [0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 2.0]  # cx, cy, yaw, hx, hy, z0, z1


@pytest.mark.parametrize("kw, message", [
    (dict(boxes=[["a"] * 7]), r"^boxes: must be a \(k, 7\) array of real numbers \(cx, cy, yaw, hx, hy, z0, z1\), got list$"),
    (dict(boxes=np.array([BOX]) + 1j), r"^boxes: must be a \(k, 7\) array of real numbers"),  # ComplexWarning, imaginary part lost
    (dict(boxes=np.ones((1, 7), bool)), r"^boxes: must be a \(k, 7\) array of real numbers"),  # read as 0 / 1 m
    (dict(boxes=np.ones((2, 6))), r"^boxes: must be a \(k, 7\) array \(cx, .*\), got shape \(2, 6\)$"),  # reshape's ValueError
    (dict(boxes=np.ones(14)), r"^boxes: must be a \(k, 7\) array .* got shape \(14,\)$"),  # read as two garbled boxes
    (dict(boxes=None), r"^boxes: must be a \(k, 7\) array of real numbers .* got NoneType$"),  # reshape's ValueError
    (dict(cylinders=[[0, 0, 1, 0]]), r"^cylinders: must be a \(k, 5\) array \(cx, cy, r, z0, z1\), got shape \(1, 4\)$"),
    (dict(glass="x"), r"^glass: must be a \(k, 4\) array of real numbers"),  # numpy's ValueError
    (dict(scan_height="0.35"), r"^scan_height: must be a finite height >= 0 m, got '0.35'$"),  # math.isfinite's TypeError
    (dict(route_nodes=[[0, 0], [1, 1]], route_edges=[[0.5, 1.7]]), r"^route_edges: must be whole numbers \(route node "
                                                                   r"indices\), got \[\[0.5, 1.7\]\]$"),  # read as 0 - 1
    (dict(route_nodes=[[0, 0]], route_targets=["0"]), r"^route_targets: must be a \(k, 1\) array of real numbers"),
    (dict(route_nodes=[[0, 0]], route_targets=[[0], [1, 2]]), r"^route_targets: must be a \(k, 1\) array of real numbers"),
    (dict(route_nodes=[[0, 0], [1, 1]], route_edges=[[0, 1e300]]), r"^route_edges: must be whole numbers"),  # no cast warning
    (dict(name=5), r"^name: must be text, got int 5$"),  # taken
    (dict(seed=-3), r"^seed: must be a whole number >= 0, got -3$"),  # taken
])
def test_a_world_built_by_hand_names_a_bad_field(kw: dict, message: str) -> None:
    """``sim.World`` built directly (simulate_records takes one): each field read by its shape and
    kind, an InputError naming it (they were read by ``np.asarray(..., dtype=float).reshape(-1, 7)``)."""
    from sim.world import World

    args: dict = dict(name="w", seed=0, boxes=[BOX], cylinders=np.zeros((0, 5)))
    args.update(kw)
    with pytest.raises(InputError, match=message):
        World(**args)


def test_a_world_built_by_hand_keeps_what_it_took() -> None:
    """One box given flat, empty lists, numpy ints and floats: read as before."""
    from sim.world import World

    w = World("w", np.int64(2), np.array(BOX), [], route_nodes=[[0, 0], [1.0, 1]], route_edges=[[0, 1.0]],
              route_targets=np.array([1]), scan_height=np.float32(0.5))
    assert w.boxes.tolist() == [BOX] and w.cylinders.shape == (0, 5) and w.glass.shape == (0, 4)
    assert w.route_edges.tolist() == [[0, 1]] and w.route_edges.dtype == np.int64 and w.route_targets.tolist() == [1]
    assert w.scan_height == 0.5 and len(w.walls) == 4


@pytest.mark.parametrize("action", [
    np.array([np.nan, 0.0]),     # drove the pose to (nan, nan)
    None,                        # the same
    np.array([0.1]),             # broadcast to v = w = 0.1
    0.3,                         # the same
    np.array([0.1, 0.1, 0.1]),   # numpy broadcast error
    np.array([1 + 1j, 0.0]),     # imaginary part dropped
    "ab",
])
def test_gym_step_refuses_actions_that_are_not_two_finite_numbers(action: object) -> None:
    from sim.gym_env import OfficeEnv

    env = OfficeEnv()
    env.reset(seed=0)
    pose = env.pose.copy()
    with pytest.raises(InputError, match=r"^action: must be two finite numbers"):
        env.step(action)  # type: ignore[arg-type]
    assert np.array_equal(env.pose, pose) and env.steps == 0  # the episode is as it was
    obs, *_ = env.step(np.array([0.1, 0.0]))
    assert np.all(np.isfinite(env.pose)) and env.observation_space.contains(obs)


def test_gym_step_before_reset_is_refused() -> None:
    """Fuzz round 10: OfficeEnv().step(...) before reset() stepped from pose (0, 0, 0), with a reward, exit 0."""
    from sim.gym_env import OfficeEnv

    env = OfficeEnv()
    with pytest.raises(InputError, match=r"^step: no episode yet: call reset\(\) first"):
        env.step(np.array([0.1, 0.0]))
    assert env.steps == 0
    env.reset(seed=0)
    assert env.step(np.array([0.1, 0.0]))[4]["progress_m"] >= 0


def test_gym_step_or_reset_after_close_is_refused_and_close_twice_is_fine() -> None:
    """Probe 14: step or reset after close() was PyBullet's TypeError ("'NoneType' object cannot be
    interpreted as an integer"), naming nothing, through gymnasium.make's env too; so was a scan of a
    closed LMS200Sim. Now an InputError saying the environment (or simulator) is closed."""
    import gymnasium

    from sim.gym_env import OfficeEnv

    closed = "the environment is closed (close() was called); make a new one (gymnasium.make or sim.gym_env.OfficeEnv)"
    for env in (OfficeEnv(), gymnasium.make("lmsbench/Office-v0")):
        env.reset(seed=0)
        env.close()
        env.close()  # twice: fine
        with pytest.raises(InputError, match=f"^step: {re.escape(closed)}$"):
            env.step(np.array([0.1, 0.0], dtype=np.float32))
        with pytest.raises(InputError, match=f"^reset: {re.escape(closed)}$"):
            env.reset(seed=1)
    env = OfficeEnv()
    env.sim.close()
    with pytest.raises(InputError, match=r"^LMS200Sim: closed \(close\(\) was called\), so it casts no ray; make a new one$"):
        env.sim.scan_at((0.0, 0.0, 0.0))


@pytest.mark.parametrize("seed", [-1, 1.5, "a"])
def test_gym_reset_seed_must_be_a_whole_number(seed: object) -> None:
    """reset(seed=-1) raised Gymnasium's own error, not an LmsbenchError."""
    from sim.gym_env import OfficeEnv

    with pytest.raises(InputError, match="^seed: must be a whole number >= 0"):
        OfficeEnv().reset(seed=seed)  # type: ignore[arg-type]
    a, b = OfficeEnv(), OfficeEnv()
    assert np.array_equal(a.reset(seed=np.int64(3))[0], b.reset(seed=3)[0])  # numpy ints are seeds too


def test_calibration_of_too_few_scans_says_so_and_prints_no_nan() -> None:
    """A 1-scan log printed '+- nan' for every rate; a log without nan readings printed 'nan +- nan'."""
    from experiments.calibrate import fit_sensor, format_calibration
    from lms200.calibration import calibrate_scans
    from sim import simulate_records

    scans = [r.scan for r in simulate_records("office", seed=0, duration=1.0, rate_hz=4)]
    with pytest.raises(InputError, match="^scans: calibrating needs at least 2 distinct scans"):  # a bare ValueError
        calibrate_scans(scans[:1])
    cal = calibrate_scans([s.replace(ranges=np.where(np.isnan(s.ranges), 5.0, s.ranges)) for s in scans[:3]])
    assert np.isnan(cal.nan_clustering.value)  # no nan reading: nothing to measure
    text = "\n".join(format_calibration(fit_sensor(cal, "office", 2.0)))
    assert "nan clustering         n/a" in text and "nan +-" not in text and "+- nan" not in text


def test_gym_out_of_bounds_action_is_clipped() -> None:
    """Out-of-bounds actions are clipped to the action space (v in [0, v_max], |w| <= w_max)."""
    from sim.gym_env import OfficeEnv

    a, b = OfficeEnv(), OfficeEnv()
    a.reset(seed=0)
    b.reset(seed=0)
    a.step(np.array([100.0, -100.0]))
    b.step(b.action_space.high * np.array([1.0, -1.0], dtype=np.float32))
    assert np.allclose(a.pose, b.pose)


# -- run_slam -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("records, message", [
    (None, "^records: must be an iterable of lms200.Record"),                # was TypeError
    ([Scan.lms200(np.full(361, 3.0))], r"^records\[0\]: expected an lms200.Record, got Scan"),  # was AttributeError
    ([1, 2], r"^records\[0\]: expected an lms200.Record, got int"),
])
@pytest.mark.parametrize("preset", ["default", "paper"])
def test_run_slam_records_of_the_wrong_type(records: object, message: str, preset: str) -> None:
    from slam import SlamConfig, run_slam
    from slam.run import SlamInputError

    with pytest.raises(SlamInputError, match=message):
        run_slam(records, SlamConfig(preset=preset))  # type: ignore[arg-type]


@pytest.mark.parametrize("config", [None, {}])
def test_run_slam_config_of_the_wrong_type(config: object) -> None:
    from slam import run_slam
    from slam.run import SlamInputError

    with pytest.raises(SlamInputError, match="^config: must be a slam.SlamConfig"):  # was AttributeError
        run_slam([Record(scan=Scan.lms200(np.full(361, 3.0)))], config)  # type: ignore[arg-type]


@pytest.mark.parametrize("preset", ["default", "paper"])
@pytest.mark.parametrize("source", ["list", "tuple", "generator"])
def test_run_slam_refuses_records_all_of_one_stamp_as_lmsbench_slam_does(source: str, preset: str, monkeypatch) -> None:
    """run_slam took 10 scans all stamped 3 s and returned a trajectory (the default preset turned and
    moved the robot in zero time, the paper preset predicted no motion), where `lmsbench slam` refuses
    such a log; now the same check and message (slam.run.same_stamp_problem), a list or tuple before
    any work (nothing matched, nothing extracted), a generator at its end. Two stamps, or one scan, still run."""
    import slam.run
    import slam.scanslam
    from slam import SlamConfig, run_slam
    from slam.run import SlamInputError

    scans = [Record(scan=Scan.lms200(np.full(361, 3.0 + 0.01 * k), stamp=3.0)) for k in range(10)]
    made = {"list": list, "tuple": tuple, "generator": lambda s: (r for r in s)}[source]
    worked: list[int] = []
    if source != "generator":
        monkeypatch.setattr(slam.scanslam, "run_scan_slam", lambda *a, **k: worked.append(1))
        monkeypatch.setattr(slam.run, "_observed", lambda *a, **k: worked.append(1) or iter(()))
    message = ("records: all 10 scans read have the same stamp (3.000000 s); SLAM's motion model needs the time "
               "between scans (a log written without a clock?)")
    with pytest.raises(SlamInputError, match=f"^{re.escape(message)}$"):
        run_slam(made(scans), SlamConfig(preset=preset))
    assert worked == []
    with pytest.raises(SlamInputError, match=r"^records: all 4 scans read have the same stamp \(3\.000000 s\)"):
        run_slam(made(scans), SlamConfig(preset=preset), max_scans=4)
    monkeypatch.undo()
    assert len(run_slam(made(scans[:1]), SlamConfig(preset=preset)).trajectory) == 1
    timed = [*scans[:-1], Record(scan=scans[-1].scan.replace(stamp=3.5))]
    assert len(run_slam(made(timed), SlamConfig(preset=preset)).trajectory) == 10


# -- Record -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kw, message", [
    (dict(scan=5), "^scan: must be an lms200.Scan"),                       # write_log: AttributeError
    (dict(odom="abc"), "^odom: must be None or three numbers"),            # write_log: "Unknown format code"
    (dict(truth=(1.0, 2.0)), "^truth: must be None or three numbers"),     # write_log: "not enough values"
    (dict(odom=(np.nan, 0.0, 0.0)), "^odom: must be finite"),               # written, then refused by read_log
    (dict(truth=(np.inf, 0.0, 0.0)), "^truth: must be finite"),
])
def test_record_fields_are_checked(kw: dict, message: str) -> None:
    args: dict = dict(scan=Scan.lms200(np.full(361, 3.0)))
    args.update(kw)
    with pytest.raises(InputError, match=message):
        Record(**args)


def test_record_poses_are_float_tuples() -> None:
    rec = Record(scan=Scan.lms200(np.full(361, 3.0)), odom=np.array([1.0, 2.0, 0.5]), truth=[1, 2, 0])
    assert rec.odom == (1.0, 2.0, 0.5) and type(rec.odom) is tuple and rec.truth == (1.0, 2.0, 0.0)


def test_scan_replace_unknown_field() -> None:
    with pytest.raises(ScanError, match="^foo: not a Scan field"):  # was TypeError from __init__
        Scan.lms200(np.full(361, 3.0)).replace(foo=1)


@pytest.mark.parametrize("kw, message", [
    (dict(control_period=np.nan), r"^control_period: must be a number of seconds in \(0, 10\]"),  # was ScanError "stamp"
    (dict(control_period=-1.0), r"^control_period: must be"),         # time ran backwards
    (dict(max_steps="x"), "^max_steps: must be a whole number"),       # was int() ValueError
    (dict(max_steps=-1), "^max_steps: must be a whole number"),
    (dict(path_length_m=1e9), r"^path_length_m: must be a number of metres in \(0, 1800\]"),  # was a hang
    (dict(path_length_m=-5.0), "^path_length_m: must be"),             # was "route graph joins no two route targets"
    (dict(render_mode="human"), "^render_mode: must be None or 'rgb_array'"),
])
def test_gym_env_arguments(kw: dict, message: str) -> None:
    from sim.gym_env import OfficeEnv

    with pytest.raises(InputError, match=message):
        OfficeEnv(**kw)


def test_paper_slam_over_a_long_gap_in_the_stamps() -> None:
    """A 1e9 s gap between two scans was 2e9 prediction steps of the paper preset (a hang); it is
    now at most MAX_PREDICT_STEPS, and the poses before the gap are those of the run without it."""
    import dataclasses

    from sim import simulate_records
    from slam import SlamConfig, run_slam
    from slam.filter import MAX_PREDICT_STEPS

    assert MAX_PREDICT_STEPS == 10_000
    recs = simulate_records("office", seed=0, duration=1.0, rate_hz=10)
    gap = [dataclasses.replace(r, scan=r.scan.replace(stamp=r.scan.stamp + (1e9 if i >= 6 else 0.0)))
           for i, r in enumerate(recs)]
    cfg = SlamConfig(preset="paper")
    with_gap, plain = run_slam(gap, cfg).trajectory, run_slam(recs, cfg).trajectory
    assert with_gap.shape == plain.shape and with_gap[-1, 0] == gap[-1].scan.stamp
    assert np.array_equal(with_gap[:6], plain[:6]) and np.all(np.isfinite(with_gap))


@pytest.mark.parametrize("kw, message", [
    (dict(noise_sigma="x"), "^noise_sigma: must be a number"),
    (dict(units="m"), "^units: must be 'mm' or 'cm'"),
    (dict(resolution=-1.0), r"^resolution: must be in \[0.004363, 0.017453\] rad \(0.25-1 deg, the LMS200's steps\), "
                            r"got -1.0$"),
    # values that were taken and ran: 1e-6 deg (10^8 beams) hung, 1e-300 overflowed (internal error),
    # the others simulated silently meaningless scans
    (dict(n_beams=100_000_000, resolution=1e-8), r"^resolution: must be in \[0.004363, 0.017453\] rad"),
    (dict(resolution=1e-300), r"^resolution: must be in \[0.004363, 0.017453\] rad"),
    # degrees given as radians (a file of the old spelling with the key renamed): refused, with the hint
    (dict(resolution=0.5), r"^resolution: must be in \[0.004363, 0.017453\] rad \(0.25-1 deg, the LMS200's steps\), "
                           r"got 0.5 \(degrees given as radians\?\)$"),
    (dict(resolution=2.0), r"^resolution: must be in .* got 2.0$"),  # not a degree step: no hint
    (dict(n_beams=361, resolution=math.radians(1.0)), r"^n_beams, resolution: field of view 360 deg exceeds 180 deg"),
    (dict(noise_sigma=5.0), r"^noise_sigma: must be in \[0, 0.1\] m"),
    (dict(noise_tail_sigma=1e300), r"^noise_tail_sigma: must be in \[0, 1\] m"),
    (dict(noise_sigma_per_m=-1e300), r"^noise_sigma_per_m: must be within \+-0.05 m per m"),
    (dict(mixed_gap=-1.0), r"^mixed_gap: must be in \[0, 1\] m"),
    # values in cm or mm where metres are meant, taken and simulated (0.44: MIT CSAIL's 4.4 mm in cm;
    # 0.5 mm per m; a 10 cm gap; 30 cm cells): physically implausible, refused naming field and unit
    (dict(noise_sigma=0.44), r"^noise_sigma: must be in \[0, 0.1\] m \(a 1-sigma range error in metres; the "
                             r"datasheet's is 0.005: a value in mm or cm is refused\), got 0.44$"),
    (dict(noise_sigma_per_m=0.5), r"^noise_sigma_per_m: must be within \+-0.05 m per m of range \(metres of noise per "
                                  r"metre; real logs' are below 0.001\), got 0.5$"),
    (dict(mixed_gap=10.0), r"^mixed_gap: must be in \[0, 1\] m \(a depth step in metres; the default is 0.1\), got 10.0$"),
    (dict(mixed_gap=1e300), r"^mixed_gap: must be in \[0, 1\] m"),
    (dict(noise_tail_patch_m=30.0), r"^noise_tail_patch_m: must be 0 \(beam by beam\) or a cell size in \[0.001, 10\] m, "
                                    r"got 30.0$"),
    (dict(dropout_patch_m=1e300), r"^dropout_patch_m: must be 0 \(beam by beam\) or a cell size in \[0.001, 10\] m"),
    (dict(beam_width=1e300), r"^beam_width: must be in \[0, 0.174533\] rad \(0-10 deg\), got 1e\+300$"),
    (dict(beam_width=0.5), r"^beam_width: must be in \[0, 0.174533\] rad \(0-10 deg\), got 0.5 \(degrees given as radians\?\)$"),
    (dict(dropout_prob=0.5, dropout_patch_m=1e-300), r"^dropout_patch_m: must be 0 \(beam by beam\) or a cell size"),
    (dict(noise_tail_patch_m=1e-9), r"^noise_tail_patch_m: must be 0"),
    (dict(noise_sigma=10**400), r"^noise_sigma: must be finite"),  # was numpy's "ufunc 'isfinite' not supported"
])
def test_sensor_config_errors_are_lmsbench_errors(kw: dict, message: str) -> None:
    from sim.sensor import SensorConfig

    with pytest.raises(InputError, match=message):  # were bare ValueErrors
        SensorConfig(**kw)


@pytest.mark.parametrize("value", [0.5, 1e300, float("nan"), -1e-3, float("inf")])
def test_sigma_bearing_is_a_bearing_error_of_radians(value: float) -> None:
    """sigma_bearing took any value >= 0: 1000 rad gave 103 lines, 1e160 none, both silently."""
    from features.errors import ConfigError
    from features.registry import make_config

    with pytest.raises(ConfigError, match=r"^sigma_bearing: must be a number in \[0, 0.1\] rad"):
        make_config("sensor", sigma_bearing=value)
    assert make_config("sensor", sigma_bearing=0.005).sigma_bearing == 0.005


@pytest.mark.parametrize("text, message", [
    ("noise_sigma: 0.005\nnoise_sigma: 0.5\n", "key 'noise_sigma' given twice (again at line 2)"),  # the 0.5 ran, silently
    ("a: {b: 1, b: 2}\n", "key 'b' given twice"),
    ("a: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),  # was a RecursionError: an internal error
])
def test_yaml_refuses_duplicate_keys_and_deep_nesting(text: str, message: str) -> None:
    import yaml

    from lms200.yamlio import load

    with pytest.raises(yaml.YAMLError, match=re.escape(message)):
        load(text)
    # a merge key may still be overridden, and the values are those written
    assert load("x: &m {a: 1}\ny:\n  <<: *m\n  a: 2\n") == {"x": {"a": 1}, "y": {"a": 2}}


@pytest.mark.parametrize("path, message", [(None, r"^path: must be a str or os.PathLike"),
                                           (123, r"^path: must be a str or os.PathLike"),
                                           (b"sensor.yaml", r"^path: must be"), (".", r"is a folder, not a sensor YAML")])
def test_sensor_from_yaml_names_a_bad_path(path, message: str) -> None:
    """None, 123 or bytes raised Path's TypeError (not an LmsbenchError); a folder said "no such sensor file"."""
    from sim.sensor import SensorConfig

    with pytest.raises(InputError, match=message):
        SensorConfig.from_yaml(path)


def test_calibrate_log_names_the_log_once_and_keeps_the_error_class(tmp_path):
    """calibrate_log puts the log's path before an error about the log, once, keeping its class (an
    InputError stays a ValueError for API callers); an error that is not the log's (an unknown
    world for the fit) does not name it."""
    from experiments.calibrate import calibrate_log

    log = tmp_path / "far.clf"
    write_log(log, [Record(Scan.lms200(np.full(361, 6.0), stamp=0.1 * k)) for k in range(5)])
    with pytest.raises(LmsbenchError, match=r"far\.clf: too few straight runs") as far:
        calibrate_log(log)
    assert str(far.value).count(str(log)) == 1
    with pytest.raises(InputError, match="has no RLASER lines") as topic:
        calibrate_log(log, topic="RLASER")
    assert isinstance(topic.value, ValueError) and str(topic.value).count(str(log)) == 1
    room = tmp_path / "room.clf"
    b = np.deg2rad(np.linspace(-90, 90, 361))
    walls = np.minimum(2.0 / np.maximum(np.abs(np.cos(b)), 1e-9), 3.0 / np.maximum(np.abs(np.sin(b)), 1e-9))
    rng = np.random.default_rng(0)
    write_log(room, [Record(Scan.lms200(walls + 0.005 * rng.standard_normal(361), stamp=0.1 * k)) for k in range(5)])
    with pytest.raises(LmsbenchError, match="unknown world 'moon'") as world:
        calibrate_log(room, world="moon")
    assert str(room) not in str(world.value)


def test_a_sensor_yaml_with_only_its_calibration_section_is_refused(tmp_path):
    """`lmsbench calibrate` writes the sensor's fields and a calibration section; a file left with
    the calibration section alone gave the default sensor, silently."""
    from sim import SensorConfig

    cut = tmp_path / "cut.yaml"
    cut.write_text("calibration:\n  source: real.clf\n  n_scans: 40\n")
    with pytest.raises(InputError, match=r"cut\.yaml: holds a calibration section but no sensor fields"):
        SensorConfig.from_yaml(cut)
    whole = tmp_path / "whole.yaml"
    SensorConfig(noise_sigma=0.007).to_yaml(whole, extra={"calibration": {"source": "real.clf"}})
    assert SensorConfig.from_yaml(whole).noise_sigma == 0.007


def test_a_sensor_yaml_header_naming_an_undecodable_path_is_written_and_read_back(tmp_path):
    """`lmsbench calibrate b<0xff>/s.clf` put the log's path (os.fsdecode: lone surrogates) into the
    YAML's comment header, whose UTF-8 write failed: an internal error after the whole calibration."""
    from sim import SensorConfig

    source = os.fsdecode(b"b\xff/s.clf")
    out = tmp_path / "s.yaml"
    SensorConfig(noise_sigma=0.007).to_yaml(out, header=f"lmsbench calibrate {source}",
                                            extra={"calibration": {"source": source}})
    assert out.read_text(encoding="utf-8").startswith("# lmsbench calibrate b\\udcff/s.clf\n")
    assert SensorConfig.from_yaml(out).noise_sigma == 0.007


def test_a_world_named_by_an_undecodable_file_name_titles_its_map(tmp_path):
    """`simulate --world w<0xff>.json`: a world with no name takes its file's stem, and map.png's title
    (matplotlib) could not hold its lone surrogate: an internal error, the run left unfinished."""
    import dataclasses
    import warnings

    import matplotlib.image

    from experiments.simulation import draw_map
    from sim import make_world

    world = dataclasses.replace(make_world("corridor", seed=0), name=os.fsdecode(b"w\xff"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # no scan drawn: an empty legend
        draw_map(world, [], tmp_path / "map.png")
    assert matplotlib.image.imread(tmp_path / "map.png").shape[2] in (3, 4)


# -- fuzzing of 2026-12-03: the public Python API ------------------------------------------------------
@pytest.mark.parametrize("field", ["angle_min", "angle_increment", "range_min", "range_max", "stamp"])
@pytest.mark.parametrize("value, message", [
    (10**400, "must be finite, got an int beyond float64's range"),  # was OverflowError: int too large to convert to float
    pytest.param(10**5000, "must be finite, got an int beyond float64's range", id="10**5000"),  # printed: ValueError
    (Fraction(10**400), "must be finite, got a Fraction beyond float64's range"),  # "an int" above (was "a int")
    (True, "must be a number, got True"),                       # was 1.0 (rad, m or s), as bool ranges are refused
    ("0.5", "must be a number, got '0.5'"),                     # was 0.5, as text ranges are refused
])
def test_scan_scalar_fields_refuse_huge_ints_bools_and_text(field: str, value: object, message: str) -> None:
    kw: dict[str, object] = dict(ranges=np.ones(5), **GEOM)
    kw[field] = value
    with pytest.raises(ScanError, match=f"^{field}: {re.escape(message)}"):
        Scan(**kw)  # type: ignore[arg-type]
    kw[field] = np.float32(0.5) if field != "range_max" else np.int64(20)  # numpy numbers stay numbers
    assert isinstance(getattr(Scan(**kw), field), float)  # type: ignore[arg-type]


@pytest.mark.parametrize("ranges", [
    np.ma.array([True, False], mask=[False, False]),  # was [1 m, 0 m]
    np.ma.array([1 + 1j, 2.0], mask=[False, True]),   # was cast to [1, nan] with a ComplexWarning
])
def test_masked_ranges_are_checked_like_arrays(ranges: np.ndarray) -> None:
    with pytest.raises(ScanError, match="^ranges: must be real numbers"):
        Scan(ranges, **GEOM)


@pytest.mark.parametrize("ranges, item", [
    (np.array([True, 1.0, 2.0], dtype=object), "bool True at index 0"),       # was [1 m, 1 m, 2 m]
    (np.array([1.0, np.False_, 2.0], dtype=object), "at index 1"),             # was [1 m, 0 m, 2 m]
    ([1.0, 2.0, True], "bool True at index 2"),                                # a list: float64 [1, 2, 1]
    ((1.0, True), "bool True at index 1"),
    (np.array(["1.5", 1.0], dtype=object), "str '1.5' at index 0"),            # was 1.5 m, as text arrays are refused
    (np.ma.array(np.array([1.0, True], dtype=object), mask=[False, False]), "bool True at index 1"),
    ([np.array(True), 1.0], "bool True at index 0"),                           # a 0-d bool array: was 1 m (review)
])
def test_bools_and_text_inside_object_arrays_and_lists_are_refused(ranges: object, item: str) -> None:
    """A bool array was refused, an object array or list holding the same bools was cast to 1.0 / 0.0
    m silently (the fuzzing hunt of 2026-12-03 left it open); refused with the bool array's message."""
    with pytest.raises(ScanError, match=rf"^ranges: must be real numbers \(m\), got .*{re.escape(item)} "
                                        r"\(bool, complex, text and dates are refused\)$"):
        Scan(ranges, **GEOM)  # type: ignore[arg-type]
    from lms200.codes import ranges_to_codes
    with pytest.raises(InputError, match="^ranges: must be real numbers"):  # the code conversions read ranges alike
        ranges_to_codes(ranges)  # type: ignore[arg-type]


@pytest.mark.parametrize("ranges, item", [
    (np.array([1.0, np.complex128(1 + 1j)], dtype=object), "complex128 np.complex128(1+1j) at index 1"),  # was 1 m
    (np.array([np.datetime64("2020-01-01"), 1.0], dtype=object), "datetime64 np.datetime64('2020-01-01') at index 0"),  # 18262 m
    (np.array([np.timedelta64(5, "s"), 1.0], dtype=object), "timedelta64 np.timedelta64(5,'s') at index 0"),  # was 5 m
])
def test_complex_and_dates_inside_object_arrays_are_refused(ranges: np.ndarray, item: str) -> None:
    """A complex or date array was refused by its dtype; an object array holding numpy's complex,
    date or duration items was cast silently (the real part; the count of days or seconds as metres)."""
    with pytest.raises(ScanError, match=rf"^ranges: must be real numbers \(m\), got {re.escape(item)} "
                                        r"\(bool, complex, text and dates are refused\)$"):
        Scan(ranges, **GEOM)


@pytest.mark.parametrize("ranges, index", [([1.0, None, 2.0], 1), (np.array([None, 1.0], dtype=object), 0), (None, 0)])
def test_none_among_ranges_is_refused_not_read_as_nan(ranges: object, index: int) -> None:
    """numpy casts None to nan: Scan([1.0, None, 2.0]) was a scan with an invalid beam and
    decode_logged_ranges(None) array(nan), silently."""
    from lms200 import decode_logged_ranges
    from lms200.codes import ranges_to_codes

    message = rf"^ranges: must be real numbers \(m\), got None at index {index} \(an invalid reading is nan\)$"
    with pytest.raises(ScanError, match=message):
        Scan(ranges, **GEOM)  # type: ignore[arg-type]
    for convert in (decode_logged_ranges, ranges_to_codes):
        with pytest.raises(InputError, match=message):
            convert(ranges)  # type: ignore[arg-type]


@pytest.mark.parametrize("ranges, message", [
    (np.array([Decimal("1e400"), 1.0], dtype=object), "Decimal at index 0 is beyond float64's range"),
    (np.array([1.0, Decimal("-1e400")], dtype=object), "Decimal at index 1 is beyond float64's range"),
    (np.array([np.longdouble("1e4000"), 1.0]), r"a number beyond float64's range \(dtype float128\)"),
])
def test_finite_ranges_beyond_float64_are_refused_not_read_as_no_return(ranges: np.ndarray, message: str) -> None:
    """Decimal("1e400") and a long double's 1e4000 became +inf, REP-117's "no return", silently (the
    CARMEN reader refuses a range of 1e400 as malformed); infinite items keep their REP-117 meaning."""
    with pytest.raises(ScanError, match=rf"^ranges: {message}"):
        Scan(ranges, **GEOM)
    kept = Scan(np.array([Decimal("Infinity"), np.longdouble("inf"), -np.inf, 1.0], dtype=object), **GEOM)
    assert kept.ranges.tolist() == [np.inf, np.inf, -np.inf, 1.0]


@pytest.mark.parametrize("call", [
    lambda: Scan([1.0], angle_min=np.complex128(0.1 + 1j), angle_increment=0.01, range_min=0.0, range_max=8.0),
    lambda: Record(Scan([1.0], **GEOM), odom=(np.complex128(1 + 1j), 0.0, 0.0)),
    lambda: LaserGeometry(range_max=np.complex128(8 + 1j)),
])
def test_numpy_complex_numbers_are_refused_as_scalar_fields(call) -> None:  # noqa: ANN001
    """numpy's complex scalars went through float(): the real part, a ComplexWarning, and the field
    set (angle_min 0.1 rad, odom x 1 m, range_max 8 m); Python's complex was already refused."""
    with pytest.raises(LmsbenchError, match="complex128"):
        call()


def test_object_arrays_and_lists_of_numbers_still_read() -> None:
    from decimal import Decimal
    from fractions import Fraction

    assert Scan(np.array([1, 2.5, Fraction(1, 2), Decimal("3")], dtype=object), **GEOM).ranges.tolist() == [1, 2.5, 0.5, 3]
    assert Scan([1, 2.5, np.float32(0.5), np.int64(3)], **GEOM).ranges.tolist() == [1, 2.5, 0.5, 3]
    assert Scan([np.array(2.0), 1.0], **GEOM).ranges.tolist() == [2, 1]  # a 0-d array of a number
    masked = Scan(np.ma.array(np.array([True, 1.0], dtype=object), mask=[True, False]), **GEOM)  # a masked item is nan
    assert np.isnan(masked.ranges[0]) and masked.ranges[1] == 1.0


def test_scan_of_too_many_beams_is_refused_before_the_copy() -> None:
    """10**10 beams (a broadcast view of one value) was a raw MemoryError (74.5 GiB asked); 10**8
    beams at 0.01 rad copied 800 MB before the span check refused them."""
    import tracemalloc

    huge = np.broadcast_to(np.float64(2.0), (10**10,))
    with pytest.raises(ScanError, match=r"^ranges: 10000000000 beams need 74.5 GiB"):
        Scan(huge, angle_min=-np.pi, angle_increment=2 * np.pi / 10**10, range_min=0.0, range_max=8.0)
    tracemalloc.start()
    try:
        with pytest.raises(ScanError, match="^angle_increment: 100000000 beams"):
            Scan(np.broadcast_to(np.float64(2.0), (10**8,)), **GEOM)
        assert tracemalloc.get_traced_memory()[1] < 1e6  # bytes: no copy of the ranges
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("method, field", [
    ("sensor", "sigma_r"), ("sensor", "min_points"), ("sensor", "hough_subdiv"), ("split_merge", "sigma"),
    ("iepf", "min_length"), ("hough", "rho_step"), ("ransac", "inlier_band"),
])
def test_config_fields_refuse_ints_beyond_float64(method: str, field: str) -> None:
    """10**400 was an OverflowError in the checks (math.isfinite) or, for hough_subdiv, in the
    Log-Hough template's size at the first extract."""
    from features import make_config
    from features.errors import ConfigError

    with pytest.raises(ConfigError, match=f"^{field}: must be"):
        make_config(method, **{field: 10**400})


def test_extract_with_a_config_and_an_unknown_parameter() -> None:
    """extract(scan, config=cfg, nope=1) was dataclasses.replace's TypeError; now the same
    UnknownMethodError as without a config, and a known one still overrides the config."""
    from features import extract, make_config
    from features.registry import UnknownMethodError

    scan = Scan.lms200(np.full(361, 3.0))
    for method in ("sensor", "split_merge"):
        with pytest.raises(UnknownMethodError, match=rf"^unknown parameter\(s\) \['nope'\] for method '{method}'"):
            extract(scan, method=method, config=make_config(method), nope=1)
    cfg = make_config("split_merge", min_points=5)
    assert len(extract(scan, "split_merge", cfg, min_points=10**6).lines) == 0 < len(extract(scan, "split_merge", cfg).lines)


@pytest.mark.parametrize("args, message", [
    (dict(name=5), "^name: must be a non-empty str"),                   # was registered, then unreachable
    (dict(name="sensor"), "^name: 'sensor' is a built-in method"),      # silently replaced the paper's extractor
    (dict(config_type=dict), "^config_type: must be a dataclass type"), # make_config failed later (TypeError)
    (dict(run=None), "^run: must be callable"),                         # extract failed later ('NoneType' ...)
    (dict(backend="gpu"), "^backend: must be one of numba, numpy, python"),
    (dict(thread_safe="yes"), "^thread_safe: must be True or False"),
])
def test_register_checks_its_arguments(args: dict, message: str) -> None:
    import dataclasses

    from features import FeatureSet, extract, register
    from features.errors import ConfigError
    from features.registry import _REGISTRY

    @dataclasses.dataclass(frozen=True)
    class Cfg:
        a: int = 1

    kw: dict = dict(name="fuzz_method", config_type=Cfg, run=lambda scan, cfg: FeatureSet(method="fuzz_method"))
    kw.update(args)
    before = dict(_REGISTRY)
    with pytest.raises(ConfigError, match=message):
        register(**kw)
    assert _REGISTRY == before
    assert extract(Scan.lms200(np.full(361, 3.0))).method == "sensor"


def _feature_set_tuple(scans: Any, cfg: Any) -> tuple:
    """A run_many returning a tuple of FeatureSets, one a scan, not the list it must return."""
    from features import FeatureSet

    return tuple(FeatureSet() for _ in scans)


@pytest.mark.parametrize("run, run_many, call, message", [
    # fuzz round: extract handed on None as the features, and extract_many [] for a batch of two, without a word
    (lambda scan, cfg: None, None, "extract", r"^method 'fuzz_returns': its run returned NoneType, not a features.FeatureSet"),
    (lambda scan, cfg: [], None, "extract_many", r"^method 'fuzz_returns': its run returned list, not a features.FeatureSet"),
    (None, lambda scans, cfg: [], "extract_many", r"^method 'fuzz_returns': its run_many returned 0 items for 2 scans"),
    (None, lambda scans, cfg: [None, None], "extract_many", r"^method 'fuzz_returns': its run_many returned NoneType at item 0 of 2, not a features"),
    # review: split in pieces (threads > 1 here, or > BATCH_CHUNK scans), each piece's return was joined unchecked:
    # None was "TypeError: 'NoneType' object is not iterable", a tuple was taken
    (None, lambda scans, cfg: None, "extract_many threads", r"^method 'fuzz_returns': its run_many returned NoneType for 2 scans"),
    (None, _feature_set_tuple, "extract_many threads", r"^method 'fuzz_returns': its run_many returned tuple for 2 scans"),
    (None, _feature_set_tuple, "extract_many", r"^method 'fuzz_returns': its run_many returned tuple for 2 scans"),
])
def test_a_registered_method_returning_no_feature_sets_is_named(run, run_many, call, message: str) -> None:  # noqa: ANN001
    import dataclasses

    import features
    from features import FeatureSet, register
    from features.errors import ConfigError
    from features.registry import _REGISTRY

    @dataclasses.dataclass(frozen=True)
    class Cfg:
        a: int = 1

    register("fuzz_returns", Cfg, run or (lambda scan, cfg: FeatureSet()), run_many=run_many, thread_safe=True)
    scan = Scan.lms200(np.full(361, 3.0))
    try:
        with pytest.raises(ConfigError, match=message):
            if call == "extract":
                features.extract(scan, method="fuzz_returns")
            else:
                features.extract_many([scan, scan], method="fuzz_returns", threads=2 if call.endswith("threads") else 1)
    finally:
        _REGISTRY.pop("fuzz_returns", None)


def test_register_takes_numpy_bools_for_thread_safe() -> None:
    """thread_safe=np.True_ was refused while every config flag takes numpy bools (review)."""
    import dataclasses

    from features import FeatureSet, register
    from features.registry import _REGISTRY

    @dataclasses.dataclass(frozen=True)
    class Cfg:
        a: int = 1

    try:
        register("fuzz_np_bool", Cfg, lambda scan, cfg: FeatureSet(method="fuzz_np_bool"), thread_safe=np.True_)
        assert _REGISTRY["fuzz_np_bool"].thread_safe is True
    finally:
        _REGISTRY.pop("fuzz_np_bool", None)


# -- scoring ------------------------------------------------------------------------------------------
def _scored_scene():
    from features import extract
    from sim import LMS200Sim, SensorConfig, make_world, visible_truth

    world = make_world("office", seed=0)
    with LMS200Sim(world, SensorConfig(), seed=0) as lidar:
        scan = lidar.scan_at((6.0, 5.0, 0.0))
    return extract(scan), visible_truth(world, (6.0, 5.0, 0.0), SensorConfig()), scan


@pytest.mark.parametrize("kw, message", [
    (dict(angle_tol=np.nan), r"^angle_tol: must be an angle in \(0, 1.5708\] rad"),  # was F1 0.0, silently
    (dict(angle_tol=0.0), "^angle_tol: must be an angle"),                         # the same, and a divide-by-zero warning
    (dict(distance_tol=np.inf), "^distance_tol: must be a finite number > 0 m"),   # matched any line to any face
    (dict(min_overlap=2.0), r"^min_overlap: must be a number in \[0, 1\]"),        # F1 0.0, silently
    (dict(min_truth_beams="10"), "^min_truth_beams: must be an integer >= 0"),     # numpy UFuncTypeError
    (dict(corner_tol=-1.0), "^corner_tol: must be a finite number > 0 m"),
])
def test_score_config_is_checked(kw: dict, message: str) -> None:
    from features.errors import ConfigError
    from features.scoring import ScoreConfig

    with pytest.raises(ConfigError, match=message):
        ScoreConfig(**kw)


def test_score_scan_refuses_what_is_no_feature_set_or_truth() -> None:
    """None, a dict or a Scan were AttributeErrors; a truth with nan faces counted them as missed
    (F1 0.0 instead of 1.0, silently); a segment_beams of another length scored F1 1.0."""
    import dataclasses

    from features.scoring import score_scan

    fs, truth, scan = _scored_scene()
    good = score_scan(fs, truth)
    assert (good.f1, good.tp, good.n_truth, good.n_dont_care) == (1.0, 5, 5, 1) and len(truth.segments) == 6
    bad = [
        (None, truth, None, "^fs: expected a features.FeatureSet, got NoneType"),
        (scan, truth, None, "^fs: expected a features.FeatureSet, got Scan"),
        (fs, None, None, "^truth: must have the fields of sim.VisibleTruth"),
        (fs, {"segments": truth.segments}, None, "^truth: must have the fields"),
        (fs, dataclasses.replace(truth, segments=truth.segments * np.nan), None, "^truth.segments: must be finite"),
        (fs, dataclasses.replace(truth, segments=truth.segments[:, :3]), None, r"^truth.segments: must be \(k, 4\) rows"),
        (fs, dataclasses.replace(truth, segment_beams=truth.segment_beams[:1]), None, r"^truth.segment_beams: must be \(6, 2\)"),
        (fs, truth, {"angle_tol": 0.1}, "^config: must be a features.scoring.ScoreConfig or None"),
    ]
    for f, t, c, message in bad:
        with pytest.raises(InputError, match=message):
            score_scan(f, t, c)  # type: ignore[arg-type]


@pytest.mark.parametrize("sigma", [np.nan, -1.0, 0.0, np.inf, 10**400, "0.01", None, True, 1e308, 1000.001])
def test_explained_fraction_sigma_must_be_a_range_noise(sigma: object) -> None:
    """nan, -1 and 0 returned (0.0, nan) and inf (1.0, inf), silently; 10**400 was an OverflowError
    (review); text and None were TypeErrors; 1e308 (3 sigma overflowed) explained every covered
    beam with an rms of inf (fuzzing, session 32): at most features.baselines.checks.MAX_SIGMA_M."""
    from features.realdata import scan_measures
    from features.scoring import explained_fraction

    fs, _, scan = _scored_scene()
    with pytest.raises(InputError, match=r"^sigma: must be a finite number in \(0, 1000\] m \(the range noise\)"):
        explained_fraction(fs, scan, sigma)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^sigma_r: must be a finite number in \(0, 1000\] m"):
        scan_measures(fs, scan, sigma)  # type: ignore[arg-type]
    frac, rms = explained_fraction(fs, scan, 0.005)
    assert 0.95 < frac <= 1.0 and 0.0 < rms < 0.005
    assert explained_fraction(fs, scan, 1000.0)[0] >= frac  # the bound itself is a range noise


def test_explained_fraction_of_another_scans_features() -> None:
    """The features of a 361-beam scan against a 10-beam scan scored 0.1, silently (their beam spans
    were clipped onto the scan's last beam); a record or None for the scan was an AttributeError."""
    from features.errors import ScanTypeError
    from features.scoring import explained_fraction

    fs, _, scan = _scored_scene()
    short = Scan(np.full(10, 2.0), angle_min=0.0, angle_increment=0.01, range_min=0.0, range_max=8.0)
    with pytest.raises(InputError, match=r"^fs: its lines span beams \d+\.\.\d+, the scan has 10 \(features of another scan\?\)"):
        explained_fraction(fs, short)
    with pytest.raises(ScanTypeError, match=r"^scan: expected an lms200.Scan, got Record \(a log record: pass record.scan\)"):
        explained_fraction(fs, Record(scan))  # type: ignore[arg-type]


def test_the_real_data_and_scoring_helpers_name_a_bad_argument() -> None:
    """features.realdata / features.scoring functions that take scans or lines, given None or
    another type: each was an AttributeError or TypeError from deep inside (ray_residuals(None,
    scan): 'NoneType' object has no attribute 'line_array'; truth_lines(None): ... 'segments';
    scoring.truth_lines(None): 'NoneType' object is not subscriptable); now an InputError or
    ScanTypeError (both LmsbenchErrors) naming the argument."""
    from features.errors import ScanTypeError
    from features.realdata import RealDataConfig, ray_residuals, repeat_counts, scan_measures, truncated_normal_rms
    from features.realdata import truth_lines as exact_lines
    from features.scoring import ScoreConfig, line_compatibility
    from features.scoring import truth_lines as normal_form

    fs, truth, scan = _scored_scene()
    lines = fs.line_array()
    pose = (0.0, 0.0, 0.0)
    bad: list[tuple[Any, str]] = [
        (lambda: ray_residuals(None, scan), "^fs: expected a features.FeatureSet, got NoneType$"),
        (lambda: ray_residuals(lines, None), "^scan: expected an lms200.Scan, got NoneType$"),
        (lambda: ray_residuals(lines[:, :6], scan), r"^fs: a line array must be \(k, 8\) numbers"),   # was a reshape ValueError
        (lambda: ray_residuals(lines + [0, 0, 0, 0, 0, 0, 0, 400], scan), "^fs: its lines span beams"),  # clipped, silently
        (lambda: exact_lines(None), r"^truth: must have the fields of sim.VisibleTruth \(segments, segment_beams\); "
                                    "NoneType lacks segments, segment_beams$"),
        (lambda: exact_lines(dataclasses.replace(truth, segment_beams=truth.segment_beams[:1])),
         r"^truth.segment_beams: must be \(\d+, 2\) to match"),                                      # was a broadcast ValueError
        (lambda: repeat_counts(None, pose, fs, pose, scan), "^fs_a: expected a features.FeatureSet, got NoneType$"),
        (lambda: repeat_counts(fs, pose, None, pose, scan), "^fs_b: expected a features.FeatureSet, got NoneType$"),
        (lambda: repeat_counts(fs, pose, fs, pose, None), "^scan_b: expected an lms200.Scan, got NoneType$"),
        (lambda: repeat_counts(fs, None, fs, pose, scan), r"^pose_a: must be three numbers \(x m, y m, theta rad\), got None$"),
        (lambda: repeat_counts(fs, pose, fs, (0.0, np.nan, 0.0), scan), "^pose_b: must be finite"),
        (lambda: repeat_counts(fs, pose, fs, pose, scan, {"tolerance_m": 1}), "^config: must be a features.realdata.RealDataConfig"),
        (lambda: scan_measures(fs, scan, 0.005, {"tolerance_m": 1}), "^config: must be a features.realdata.RealDataConfig"),
        # RealDataConfig's fields were not checked: -1 explained nothing, "x" was a TypeError in the measures
        (lambda: RealDataConfig(tolerance_m=-1), r"^tolerance_m: must be a finite number > 0 m, got -1$"),
        (lambda: RealDataConfig(n_sigma=np.nan), r"^n_sigma: must be a finite number > 0 range-noise sigmas, got nan$"),
        (lambda: RealDataConfig(repeat_distance_m="x"), r"^repeat_distance_m: must be a finite number > 0 m, got 'x'$"),
        (lambda: RealDataConfig(repeat_angle_rad=90), r"^repeat_angle_rad: must be an angle in \(0, 3.14159\] rad, got 90$"),
        (lambda: RealDataConfig(repeat_angle_rad=True), r"^repeat_angle_rad: must be an angle in \(0, 3.14159\] rad, got True$"),
        (lambda: scan_measures(None, scan, 0.005), "^fs: expected a features.FeatureSet, got NoneType$"),
        (lambda: truncated_normal_rms(None, 0.03), "^sigma, tolerance: must be finite numbers > 0 m, got None and 0.03$"),  # TypeError
        (lambda: truncated_normal_rms(np.inf, 0.03), "^sigma, tolerance: must be finite numbers > 0 m"),  # ZeroDivisionError
        (lambda: truncated_normal_rms(0.01, np.inf), "^sigma, tolerance: must be finite numbers > 0 m"),  # was nan, silently
        (lambda: normal_form(None), r"^segments: must be a \(k, 4\) array of real numbers \(x1, y1, x2, y2 m\), got NoneType$"),
        (lambda: normal_form(truth.segments[:, :2]), r"^segments: must be a \(k, 4\) array \(x1, y1, x2, y2 m\), got shape \(\d+, 2\)$"),
        (lambda: line_compatibility(None, truth.segments, ScoreConfig()), r"^lines: must be a \(k, >= 6\) array of real numbers \(rho m, alpha rad, x0, y0, x1, y1 m\), got NoneType$"),
        (lambda: line_compatibility(lines, None, ScoreConfig()), r"^seg: must be a \(k, 4\) array of real numbers"),
        (lambda: line_compatibility(lines, lines, ScoreConfig()), r"^seg: must be a \(k, 4\) array \(x1, y1, x2, y2 m\), got shape \(\d+, 8\)$"),  # 0 pairs, silently
        (lambda: normal_form(np.zeros((2, 8))), r"^segments: must be a \(k, 4\) array \(x1, y1, x2, y2 m\), got shape \(2, 8\)$"),  # read x0..y1 from line rows
        (lambda: line_compatibility(lines[:, :3], truth.segments, ScoreConfig()), r"^lines: must be a \(k, >= 6\) array \(rho m, alpha rad, x0, y0, x1, y1 m\), got shape \(\d+, 3\)$"),
        (lambda: line_compatibility(lines, truth.segments, None), "^cfg: must be a features.scoring.ScoreConfig, got NoneType$"),
    ]
    from features.scoring import CheckedTruth, check_truth, score_scan

    checked = check_truth(truth)
    nan_face = checked.segments.copy()
    nan_face[0] = np.nan
    bad += [  # a CheckedTruth built by hand is checked as check_truth checks (score_scan trusts it): the nan
        # face scored recall 1.0 silently, None fields were a TypeError
        (lambda: CheckedTruth(nan_face, checked.segment_beams, checked.corners, checked.corner_beams), "^truth.segments: must be finite"),
        (lambda: CheckedTruth(None, None, None, None), "^truth"),
    ]
    hand_built = CheckedTruth(truth.segments, truth.segment_beams, truth.corners, truth.corner_beams)
    scores = [dataclasses.asdict(score_scan(fs, t)) for t in (hand_built, checked, truth)]
    for name, value in scores[0].items():
        for other in scores[1:]:
            np.testing.assert_array_equal(value, other[name], err_msg=name)
    from features.errors import ConfigError

    for call, message in bad:
        with pytest.raises((InputError, ScanTypeError, ConfigError), match=message) as info:
            call()
        assert isinstance(info.value, LmsbenchError)
    # the good calls give what they gave
    assert ray_residuals(fs, scan).tolist() == ray_residuals(lines, scan).tolist()
    assert repeat_counts(fs, pose, fs, pose, scan, RealDataConfig()) == (len(fs.lines), len(fs.lines))
    assert exact_lines(truth).shape == (len(truth.segments), 8)


# -- CARMEN logs ---------------------------------------------------------------------------------------
def test_a_short_file_of_binary_junk_is_not_a_log(tmp_path) -> None:
    """5,000 random bytes (43 'lines') read as a log of no scans, silently: the 10,000-line rule only
    refused longer files; and a lone capital letter ('M') counted as a message name."""
    from lms200.errors import LogFormatError

    junk = tmp_path / "junk.clf"
    junk.write_bytes(np.random.default_rng(0).integers(0, 256, 5000, dtype=np.uint8).tobytes())
    for skip in (False, True):
        with pytest.raises(LogFormatError, match=r"junk\.clf: not a CARMEN log: none of its \d+ lines"):
            list(read_log(junk, skip_bad_lines=skip))
    (tmp_path / "empty.clf").write_text("# a log with no message yet\n\n")
    # a log of no laser line gives no scan: refused, not read as a run of none (lms200 review, empty logs)
    with pytest.raises(LogFormatError, match=r"empty\.clf: holds only blank or comment lines \(2\): no laser lines"):
        list(read_log(tmp_path / "empty.clf"))
    log = tmp_path / "a.log"
    write_log(log, _records(2))
    assert len(list(read_log(log))) == 2


def test_an_overlong_last_line_is_malformed(tmp_path) -> None:
    """A line over 1 MiB with no newline after it (the end of a file) was dropped silently; one
    followed by a newline was already refused."""
    import gzip

    from lms200.errors import LogFormatError

    log = tmp_path / "a.clf.gz"
    good = tmp_path / "good.log"
    write_log(good, _records(2))
    log.write_bytes(gzip.compress(good.read_bytes() + b"FLASER 361 " + b"2.0 " * 300_000))
    with pytest.raises(LogFormatError, match=r"a\.clf\.gz:\d+: malformed overlong line: longer than 1048576 characters"):
        list(read_log(log))
    reader = read_log(log, skip_bad_lines=True)
    assert len(list(reader)) == 2 and len(reader.stats.skipped) == 1


def test_write_log_flaser_of_a_scan_not_centred_is_an_input_error(tmp_path) -> None:
    """Was a bare ValueError (not an LmsbenchError); the log at the path is kept."""
    path = tmp_path / "run.log"
    write_log(path, _records(2))
    before = path.read_bytes()
    odd = Record(Scan(np.array([1.0, 2.0, 3.0]), angle_min=0.3, angle_increment=0.123, range_min=0.0, range_max=8.0))
    with pytest.raises(InputError, match=r"^records: FLASER cannot carry a 3-beam scan"):
        write_log(path, [odd], fmt="flaser")
    assert path.read_bytes() == before


def test_write_log_flaser_of_one_beam_is_refused_not_written_unreadable(tmp_path) -> None:
    """A one-beam scan centred ahead (angle_min 0) was written as FLASER with ``PARAM
    laser_front_laser_fov -0`` (its field of view, (n - 1) x res, is 0), which read_log refused
    ("laser_front_laser_fov must be a finite number > 0"): now refused when written, the log at the
    path kept; ROBOTLASER1 carries it and reads it back."""
    path = tmp_path / "run.log"
    write_log(path, _records(2))
    before = path.read_bytes()
    one = Record(Scan(np.array([2.0]), angle_min=0.0, angle_increment=np.pi / 360, range_min=0.0, range_max=8.0))
    with pytest.raises(InputError, match=r"^records: FLASER cannot carry a scan of one beam .*use fmt='robotlaser1'$"):
        write_log(path, [one], fmt="flaser")
    assert path.read_bytes() == before
    write_log(tmp_path / "one.log", [one])
    assert [r.scan for r in read_log(tmp_path / "one.log")] == [one.scan]


# -- LMS200 codes and telegrams --------------------------------------------------------------------------
@pytest.mark.parametrize("codes", [
    np.array([np.nan]),        # was 0 m (a RuntimeWarning from the cast)
    np.array([-1, 5]),         # was [nan, 5 mm]
    np.array([1.5]),           # was 1 mm
    np.array([2**40]),         # was 0 m (masked to 13 bits)
    np.array([True]),          # was 1 mm
    "abc",                     # was int()'s ValueError
])
def test_codes_to_ranges_takes_raw_16_bit_values_only(codes: object) -> None:
    from lms200 import codes_to_ranges

    with pytest.raises(InputError, match=r"^codes: must be raw LMS200 values \(whole numbers 0..65535\)"):
        codes_to_ranges(codes)  # type: ignore[arg-type]
    assert codes_to_ranges(np.array([3000.0, 8183, 8191]), "mm").tolist()[:2] == [3.0, np.inf]  # whole floats are codes


@pytest.mark.parametrize("codes, got", [
    (np.array([-1, 5]), "got values from -1 to 5"),
    (np.array([1.5, np.inf]), "got values from 1.5 to 1.5 and nan / inf"),
    (np.array([np.nan]), "got only nan / inf"),
])
def test_codes_error_names_the_values_as_numbers(codes: np.ndarray, got: str) -> None:
    """The message printed numpy 2's reprs ("got values from np.int64(-1) to np.int64(5)"; nan alone
    "from np.float64(nan) to np.float64(nan) and nan / inf"), found trying docs/data.md's codes."""
    from lms200 import codes_to_ranges

    with pytest.raises(InputError) as info:
        codes_to_ranges(codes)
    assert str(info.value).endswith(got) and "np." not in str(info.value)


@pytest.mark.parametrize("call, message", [
    (lambda: __import__("lms200").codes_to_ranges(np.array([1]), "m"), "^units: must be 'mm' or 'cm', got 'm'"),  # a bare ValueError
    (lambda: __import__("lms200").ranges_to_codes(np.array([-1.0])), "^ranges: negative ranges have no LMS200 code"),
    (lambda: __import__("lms200").ranges_to_codes(np.array([1j])), "^ranges: must be real numbers"),  # was code 0, a ComplexWarning
    (lambda: __import__("lms200").decode_logged_ranges(np.array([1 + 1j])), "^ranges: must be real numbers"),
])
def test_code_conversions_are_input_errors(call, message: str) -> None:
    with pytest.raises(InputError, match=message):
        call()


@pytest.mark.parametrize("payload", ["abc", None, [0xB0, 1, 0x40, 0, 0], 5])
def test_decode_scan_of_something_not_bytes(payload: object) -> None:
    """Text, None, a list or an int were TypeErrors from len() or frombuffer."""
    from lms200.protocol import decode_scan

    with pytest.raises(InputError, match="^payload: must be bytes"):
        decode_scan(payload)  # type: ignore[arg-type]


def test_decode_scan_of_a_uint8_array_is_its_bytes() -> None:
    """np.frombuffer(payload, np.uint8) was an OverflowError (its count word 1023 out of bounds for uint8)."""
    from lms200.protocol import decode_scan, encode_scan

    scan = Scan.lms200(np.round(np.linspace(1.0, 3.0, 361), 3))
    payload = encode_scan(scan)
    back = decode_scan(np.frombuffer(payload, np.uint8))
    assert back == decode_scan(payload) and np.allclose(back.ranges, scan.ranges, atol=0.0005)  # mm codes


@pytest.mark.parametrize("call, message", [
    (lambda p: p.encode_scan(Scan.lms200(np.full(361, 3.0)), "mm", 300), "^status: must be a byte 0..255"),  # "bytes must be in range(0, 256)"
    (lambda p: p.encode_measurement(np.ones(3, np.uint16), "m"), "^units: must be 'mm' or 'cm'"),  # KeyError
    (lambda p: p.encode_measurement("abc", "mm"), "^codes: must be raw LMS200 values"),
    (lambda p: p.build_frame("abc"), "^payload: must be bytes"),                  # "string argument without an encoding"
    (lambda p: p.build_frame(b"\x00" * 70000), "^payload: at most 812 bytes"),    # a bare ValueError
    (lambda p: p.crc16("abc"), "^data: must be bytes"),                           # "unsupported operand type(s)"
])
def test_telegram_builders_raise_input_errors(call, message: str) -> None:
    from lms200 import protocol

    with pytest.raises(InputError, match=message):
        call(protocol)


@pytest.mark.parametrize("data", [None, "abc", 5])
def test_frame_parser_feed_of_something_not_bytes(data: object) -> None:
    """None was taken as no bytes, silently; text was 'can't concat str to bytearray'."""
    from lms200.framing import FrameParser
    from lms200.protocol import build_frame, encode_scan

    parser = FrameParser()
    with pytest.raises(InputError, match="^data: must be the bytes received"):
        parser.feed(data)  # type: ignore[arg-type]
    frame = build_frame(encode_scan(Scan.lms200(np.full(361, 3.0))), address=0x80)
    assert len(parser.frames(frame)) == 1 and parser.pending == 0


# -- sim ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("pose", [(np.nan, 5.0, 0.0), (6.0, 5.0, np.inf), (6.0, 5.0), (6.0, 5.0, 0.0, 1.0), "abc", None])
def test_simulator_poses_must_be_three_finite_numbers(pose: object) -> None:
    """A nan pose scanned every beam as +inf and saw no face (an empty VisibleTruth), silently; two
    or four numbers, text or None were unpacking errors."""
    from sim import LMS200Sim, SensorConfig, make_world, visible_truth

    world = make_world("office", seed=0)
    with LMS200Sim(world, SensorConfig(), seed=0) as lidar:
        with pytest.raises(InputError, match=r"^pose: must be 3 finite numbers \(x m, y m, theta rad\)"):
            lidar.scan_at(pose)  # type: ignore[arg-type]
        with pytest.raises(InputError, match=r"^twist: must be 2 finite numbers"):
            lidar.scan_at((6.0, 5.0, 0.0), twist=(np.nan, 0.0))  # was nan beam poses: every beam +inf
        with pytest.raises(InputError, match=r"^beam_poses: must be \(361, 3\)"):
            lidar.scan_from_beam_poses(np.zeros((3, 3)))  # was numpy's broadcast error
        scan = lidar.scan_at(np.array([6.0, 5.0, 0.0]))
    with pytest.raises(InputError, match=r"^pose: must be 3 finite numbers"):
        visible_truth(world, pose)  # type: ignore[arg-type]
    assert np.count_nonzero(scan.valid) > 300 and len(visible_truth(world, (6.0, 5.0, 0.0)).segments) >= 3


@pytest.mark.parametrize("call, message", [
    (lambda sim: sim.LMS200Sim(None), "^world: must be a sim.World, got NoneType"),                 # AttributeError
    (lambda sim: sim.LMS200Sim(sim.make_world("office", 0), {}), "^sensor: must be a sim.SensorConfig or None"),
    (lambda sim: sim.LMS200Sim(sim.make_world("office", 0), seed=-1), "^seed: must be a whole number >= 0"),  # numpy's ValueError
    (lambda sim: sim.visible_truth(None, (0.0, 0.0, 0.0)), "^world: must be a sim.World"),
    (lambda sim: sim.robot_tour(sim.make_world("office", 0), seed=0, duration=1e9), r"^duration: must be a number of seconds in \(0, 3600\]"),  # 400 MB and > 60 s
    (lambda sim: sim.robot_tour(sim.make_world("office", 0), seed=0, duration=-1.0), "^duration: must be"),  # a tour, silently
    (lambda sim: sim.robot_tour(sim.make_world("office", 0), seed=-1), "^seed: must be a whole number"),
    (lambda sim: sim.simulate_records("office", seed=0, duration=1.0, sensor={}), "^sensor: must be a sim.SensorConfig"),  # AttributeError
    (lambda sim: sim.simulate_records("office", seed=0, duration=1.0, odometry={}), "^odometry: must be a sim.OdometryConfig"),  # taken as none
    (lambda sim: sim.simulate_records("office", seed=0, duration=1.0, limits={}), "^limits: must be a sim.RobotLimits"),
    (lambda sim: sim.simulate_records("office", seed=0, duration=1.0, progress=5), "^progress: must be None or callable"),
    (lambda sim: sim.simulate_records("office", seed=0, duration=1e-3), r"^duration: 0.001 s is shorter than one scan"),  # [], silently
    (lambda sim: sim.simulate_records("office", seed=0, duration=1.0, rate_hz=10**400), "^rate_hz: must be a finite number"),  # OverflowError
    (lambda sim: sim.make_world("office", 0, scale=10**400), "^scale: must be finite"),            # numpy TypeError
    (lambda sim: sim.make_world("office", 0, clutter=10**400), "^clutter: must be finite"),        # OverflowError
    (lambda sim: sim.make_world("office", 0, scale=10**5000), "^scale: must be finite, got an int beyond"),  # its message: ValueError
    (lambda sim: sim.simulate_records("office", seed=0, duration=1.0, rate_hz=10**5000), "^rate_hz: must be a finite number"),
])
def test_sim_arguments(call, message: str) -> None:
    import sim

    with pytest.raises(InputError, match=message):
        call(sim)


def test_simulate_records_takes_numpy_numbers() -> None:
    """duration=np.float32(0.5) / np.int64(1) and rate_hz=np.float32(5) were refused (np.float64 taken)."""
    from sim import simulate_records

    plain = simulate_records("office", seed=0, duration=1.0, rate_hz=5.0)
    same = simulate_records("office", seed=0, duration=np.int64(1), rate_hz=np.float32(5.0))
    assert len(plain) == len(same) == 5 and all(a.scan == b.scan for a, b in zip(plain, same))


def test_ransac_window_beyond_int64() -> None:
    """window=2**70 was numpy's 'high is out of bounds for int64' at the first extract; a window past
    the scan's beams reaches every beam, as 2**62 does."""
    from features import extract

    rng = np.random.default_rng(3)
    ang = np.deg2rad(np.arange(361) * 0.5 - 90.0)
    room = np.minimum(2.0 / np.maximum(np.abs(np.cos(ang)), 1e-9), 3.0 / np.maximum(np.abs(np.sin(ang)), 1e-9))
    scan = Scan.lms200(np.where(room < 8.0, room + rng.normal(0, 0.005, 361), np.inf))
    huge, cap = extract(scan, "ransac", window=2**70), extract(scan, "ransac", window=2**62)
    assert len(huge.lines) == 3 and repr(list(huge.lines)) == repr(list(cap.lines))


@pytest.mark.parametrize("obj, hint", [(None, ""), (np.full(361, 3.0), " (build one with"),
                                       (Record(Scan.lms200(np.full(361, 3.0))), " (a log record: pass record.scan)")])
def test_signals_of_something_not_a_scan(obj: object, hint: str) -> None:
    """Was an AttributeError ('... has no attribute angle_increment')."""
    from features.errors import ScanTypeError
    from features.sensor import signals

    with pytest.raises(ScanTypeError, match=f"^signals: expected an lms200.Scan, got {type(obj).__name__}{re.escape(hint)}"):
        signals(obj)  # type: ignore[arg-type]


@pytest.mark.parametrize("section, field", [("motion", "sigma_accel"), ("alignment", "max_iterations"),
                                            ("observations", "min_line_points")])
def test_slam_config_numbers_beyond_float64(section: str, field: str) -> None:
    """10**400 in any numeric field of a SLAM config section was an OverflowError (99 fields)."""
    from slam import SlamConfig
    from slam.config import SlamConfigError

    for huge in (10**400, 10**5000):  # 10**5000: its message printed the int, a ValueError (4,300 digits)
        with pytest.raises(SlamConfigError, match=f"{field}: must be finite, got an int beyond float64's range"):
            SlamConfig(**{section: {field: huge}})
    assert SlamConfig(**{section: {field: 3}}) is not None


@pytest.mark.parametrize("field", ["sigma_r", "sigma_r_cm"])
def test_sensor_range_noise_is_capped_like_the_baselines(field: str) -> None:
    """sigma_r=1e300 built a config whose thresholds found no line on any scan, silently (review of
    the API hunt); the baselines' sigma was already capped at MAX_SIGMA_M."""
    from features import extract, make_config
    from features.baselines.checks import MAX_SIGMA_M
    from features.errors import ConfigError

    with pytest.raises(ConfigError, match=rf"^{field}: must be a range noise std in \[1e-06, 1000\] m, or 'auto', got 1e\+300"):
        make_config("sensor", **{field: 1e300})
    cfg = make_config("sensor", **{field: MAX_SIGMA_M})  # the cap itself is taken
    assert getattr(cfg, field) == MAX_SIGMA_M
    for text in ("AUTO", "0.01"):  # "must be a finite number > 0 m, got 'AUTO'": no word of the one text taken
        with pytest.raises(ConfigError, match=rf"^{field}: must be a range noise std in \[1e-06, 1000\] m, or 'auto', "
                                              rf"got '{text}'$"):
            make_config("sensor", **{field: text})
    assert extract(Scan.lms200(np.full(361, 3.0)), "sensor").method == "sensor"


# -- SLAM config: the extractor ------------------------------------------------------------------------
@pytest.mark.parametrize("kw, message", [
    (dict(extractor="nope"), r"^extractor: unknown extraction method 'nope'; registered methods \(features.registry\): "
                             r"sensor, split_merge, iepf, hough, ransac"),   # was taken; failed when the run started
    (dict(extractor="Sensor"), "^extractor: unknown extraction method 'Sensor'"),
    (dict(extractor_params={"bogus": 1}), r"^extractor_params: unknown parameter\(s\) \['bogus'\] for method 'sensor'"),
    (dict(extractor="hough", extractor_params={"k": 3}), r"^extractor_params: unknown parameter\(s\) \['k'\] for method 'hough'"),
    (dict(extractor_params={"k": -3}), r"^extractor_params.k: must be an integer >= 1"),
    (dict(extractor="split_merge", extractor_params={"split_threshold": "x"}), "^extractor_params.split_threshold: must be"),
    (dict(preset=np.array(["default", "paper"])), r"^preset: must be one of \['default', 'paper'\], got array"),  # fuzz round 10:
    (dict(preset=["default"]), r"^preset: must be one of"),  # numpy's "truth value of an array ... is ambiguous"
])
def test_slam_config_checks_its_extractor_when_built(kw: dict, message: str) -> None:
    from slam import SlamConfig, SlamConfigError

    with pytest.raises(SlamConfigError, match=message) as info:
        SlamConfig(**kw)
    assert isinstance(info.value, LmsbenchError) and isinstance(info.value, ValueError)
    with pytest.raises(SlamConfigError, match=message):  # the YAML path (`lmsbench slam --config FILE`)
        SlamConfig.from_dict(kw)


def test_slam_config_takes_registered_extractors_and_their_params() -> None:
    from features import register
    from features.registry import _REGISTRY
    from slam import SlamConfig

    assert SlamConfig(extractor="ransac", extractor_params={"hypotheses": 32}).extractor_params == {"hypotheses": 32}

    @dataclasses.dataclass(frozen=True)
    class MyConfig:
        gain: float = 1.0

    register("test_slam_mine", MyConfig, lambda scan, cfg: None)  # type: ignore[arg-type, return-value]
    try:
        assert SlamConfig(extractor="test_slam_mine", extractor_params={"gain": 2.0}).extractor == "test_slam_mine"
    finally:
        _REGISTRY.pop("test_slam_mine", None)


# -- SLAM config: ranges a run needs (fuzzing of 2026-12-04: each value built, then run on a 3 s office run) --
@pytest.mark.parametrize("section, field", [("alignment", "sigma_point"), ("motion", "sigma_lateral"),
                                            ("observations", "sigma_rho"), ("observations", "sigma_alpha_obs"),
                                            ("observations", "sigma_corner"), ("prealign", "sigma_xy"),
                                            ("prealign", "sigma_phi"), ("prealign", "scan_velocity_sigma")])
@pytest.mark.parametrize("value", [1e300, 1e-300])
def test_slam_noise_stds_are_bounded_when_built(section: str, field: str, value: float) -> None:
    """1e300 was taken and the run failed with OverflowError (its square); 1e-300 (its inverse
    square) likewise, or gtsam's indeterminate system for loop_closure.prior_sigma."""
    from slam import SlamConfig, SlamConfigError

    with pytest.raises(SlamConfigError, match=rf"^{section}.{field}: must be in \[1e-06, 1000\] .*\(a std whose square "
                                              rf"and inverse square stay finite\), got {re.escape(f'{value:g}')}"):
        SlamConfig(**{section: {field: value}})
    for ok in (1e-6, 1e3):  # the bounds are taken (and run: tests of the fuzzing, not repeated here)
        assert getattr(getattr(SlamConfig(**{section: {field: ok}}), section), field) == ok


def _slam_field(where: str, value: float) -> dict:
    section, name = where.split(".")
    return {section: {name: value}}


def test_every_slam_number_has_one_stated_interval() -> None:
    """Every numeric field of a SlamConfig section has its interval (slam.config.FIELD_RANGES, or its
    own rule for the search window's): a value just outside either end is refused naming the field
    and the same interval, a negative one too (motion.sigma_accel -1 said '>= 0' while 0 said
    '(0, 1000]'), and both ends are taken. alignment.stride 1e12 or damping 1e300 ran a whole run
    that matched no step, exit 0 with a warning; sigma_accel 1e-300 was taken."""
    import dataclasses
    import typing

    from slam import SlamConfig, SlamConfigError
    from slam.config import FIELD_RANGES, OWN_RULE, SECTIONS, field_range_text

    numeric = {f"{name}.{f.name}" for name, cls in SECTIONS.items() for f in dataclasses.fields(cls)
               if typing.get_type_hints(cls)[f.name] in (int, float) and not f.name.endswith("_probability")}
    assert numeric == set(FIELD_RANGES) | OWN_RULE
    assert field_range_text("motion.sigma_accel") == ("must be in [0.001, 1000] m/s^2 (the prediction's std and its "
                                                      "inverse square stay finite)")
    assert field_range_text("alignment.normal_agreement") == "must be in (0, pi] rad (pi: no normal check)"
    for where, (lo, hi, _, lo_open, _) in FIELD_RANGES.items():
        section, name = where.split(".")
        for bad in {lo if lo_open else lo - max(abs(lo) * 0.5, 0.5), hi + max(hi * 0.5, 1), -1.0, 1e300}:
            if bad == -1.0 and lo <= -1.0:
                continue
            if isinstance(getattr(SECTIONS[section](), name), int) and bad != 1e300:
                bad = float(math.floor(bad)) if bad < lo else float(math.ceil(bad))
            with pytest.raises(SlamConfigError, match="^" + re.escape(f"{where}: {field_range_text(where)}, got ")):
                SlamConfig(**_slam_field(where, bad))
        for ok in ((hi,) if lo_open else (lo, hi)):
            values = _slam_field(where, ok)
            if section == "landmarks":  # confirm_hits at most tentative_window + 1 (below)
                values["landmarks"] = {"confirm_hits": 1, "tentative_window": 1000} | values["landmarks"]
            assert getattr(getattr(SlamConfig(**values), section), name) == ok
    # the search window's own rule (OWN_RULE): -1, 0 and 1e300 get the same interval; no
    # empty "()" (fit_margin -1 said "must be in [0, 1] (), got -1.0"; search_step -1 "must be > 0" and
    # 1e300 "must be in [0.1, 10] m (...)"; search_candidates 1e300 was echoed with its 301 digits)
    for where in sorted(OWN_RULE):
        section, name = where.split(".")
        messages = set()
        for bad in (-1.0, 0.0, 1e300):
            if bad == 0.0 and name in ("fit_margin", "ambiguity_sigmas", "voxel", "correlation_length"):  # 0 is taken: no margin, off
                assert getattr(getattr(SlamConfig(**_slam_field(where, 0)), section), name) == 0
                continue
            if isinstance(getattr(SECTIONS[section](), name), int) and bad != 1e300:
                bad = int(bad)
            with pytest.raises(SlamConfigError) as info:
                SlamConfig(**_slam_field(where, bad))
            text = str(info.value)
            assert text.startswith(f"{where}: must be ") and "()" not in text and len(text) < 200, text
            messages.add(text.split(" (")[0].rsplit(", got ", 1)[0])  # the reason names the side
        assert len(messages) == 1, messages
    with pytest.raises(SlamConfigError) as info:
        SlamConfig(alignment={"fit_margin": -1})
    assert str(info.value) == "alignment.fit_margin: must be in [0, 1] (a fit is a share of points), got -1.0"
    with pytest.raises(SlamConfigError) as info:
        SlamConfig(alignment={"search_candidates": 1e300})
    assert str(info.value) == ("alignment.search_candidates: must be in [1, 32] (each is refined by the ICP on every "
                               "searched step), got 1e+300")
    with pytest.raises(SlamConfigError, match=r"^landmarks.confirm_hits: must be at most tentative_window \+ 1 \(7, "):
        SlamConfig(landmarks={"confirm_hits": 8})  # no landmark could ever be confirmed: an empty map
    assert SlamConfig(landmarks={"confirm_hits": 1000, "tentative_window": 999}).landmarks.confirm_hits == 1000


def test_slam_stride_is_bounded_by_the_scans_beams() -> None:
    """alignment.stride was at most 30 whatever the scanner, though scans of up to 16,384 beams are
    taken (features.baselines.checks.MAX_BEAMS), where 60-150 keeps as many points as 3 on an LMS200.
    The config takes up to MAX_BEAMS; the run refuses, at its first scan and before any matching, a
    stride that keeps fewer than the 13 points the matcher needs, naming the largest that works."""
    from types import SimpleNamespace

    from features.baselines.checks import MAX_BEAMS
    from sim import simulate_records
    from slam import SlamConfig, SlamConfigError, run_slam
    from slam.run import SlamInputError, check_first_scan

    assert SlamConfig(alignment={"stride": 150}).alignment.stride == 150
    assert SlamConfig(alignment={"stride": MAX_BEAMS}).alignment.stride == 16384
    with pytest.raises(SlamConfigError, match=re.escape("alignment.stride: must be in [1, 16384] beams (the most beams "
                                                        "of a scan the extractors take), got 16385")):
        SlamConfig(alignment={"stride": MAX_BEAMS + 1})

    def scans(beams: int) -> SimpleNamespace:  # a first scan
        return SimpleNamespace(ranges=np.ones(beams), angle_increment=0.001)

    check_first_scan(scans(16384), SlamConfig(alignment={"stride": 150}))  # 110 points
    check_first_scan(scans(16384), SlamConfig(alignment={"stride": 1365}))  # 13 points
    with pytest.raises(SlamInputError) as info:
        check_first_scan(scans(16384), SlamConfig(alignment={"stride": 1366}))
    assert str(info.value) == ("alignment.stride: 1,366 keeps 12 of the first scan's 16,384 beams, fewer than the 13 "
                               "points the scan matcher needs; at most 1,365 for these scans")
    # too short at any stride: the stride is not why (min_line_points, 8 by default, is above 5 beams: its own refusal)
    check_first_scan(scans(5), SlamConfig(observations={"min_line_points": 5}))
    with pytest.raises(SlamInputError, match=r"^alignment.stride: 3 keeps 5 of the first scan's 13 beams, fewer than "
                                             r"the 13 points the scan matcher needs; at most 1 for these scans$"):
        check_first_scan(scans(13), SlamConfig())
    records = simulate_records("office", seed=0, duration=1.0, rate_hz=5)  # 361-beam scans
    with pytest.raises(SlamInputError, match=r"^alignment.stride: 31 keeps 12 of the first scan's 361 beams, .* "
                                             r"at most 30 for these scans$"):
        run_slam(records, SlamConfig(alignment={"stride": 31}))
    assert run_slam(records, SlamConfig(alignment={"stride": 30})).trajectory.shape[0] == len(records)


def test_slam_turn_rate_bound_allows_any_turn_at_any_scan_rate() -> None:
    """alignment / prealign.max_turn_rate were capped at 100 rad/s, "beyond 100 the whole turn is
    searched at any rate": false, the turn allowed is max_turn_rate * dt, 1.33 rad at 75 scans/s.
    The cap is 1e4 rad/s (any heading at 100 scans/s) with that reason."""
    from slam import SlamConfig, SlamConfigError

    for section in ("alignment", "prealign"):
        assert getattr(SlamConfig(**{section: {"max_turn_rate": 1000.0}}), section).max_turn_rate == 1000.0
        assert getattr(SlamConfig(**{section: {"max_turn_rate": 1e4}}), section).max_turn_rate == 1e4
        for bad in (0, 1e5):
            with pytest.raises(SlamConfigError) as info:
                SlamConfig(**{section: {"max_turn_rate": bad}})
            assert str(info.value) == (f"{section}.max_turn_rate: must be in [0.01, 10000] rad/s (the turn allowed "
                                       f"between scans is it times their interval: 1e4 allows any heading at 100 "
                                       f"scans/s), got {bad!r}")
    assert 1e4 / 100 > 2 * math.pi  # 100 scans/s: every heading within the bound


def test_slam_probabilities_have_one_interval() -> None:
    """Every ``*_probability`` field is one open interval (0, 1) whichever side: -1 said "must be >=
    0" while 0 and 2 said "a probability, must be in (0, 1)"."""
    import dataclasses

    from slam import SlamConfig, SlamConfigError
    from slam.config import SECTIONS

    fields = [(name, f.name) for name, cls in SECTIONS.items() for f in dataclasses.fields(cls)
              if f.name.endswith("_probability")]
    assert len(fields) == 7
    for section, name in fields:
        for bad in (-1, 0, 1, 2, 1e300):
            with pytest.raises(SlamConfigError) as info:
                SlamConfig(**{section: {name: bad}})
            assert str(info.value) == f"{section}.{name}: a probability, must be in (0, 1), got {bad!r}"


def test_slam_lists_are_bounded_and_echoed_short() -> None:
    """alignment.heading_hypotheses of 200,000 offsets were taken (each retry scores every one), and
    a motion.odom_noise of 200,000 numbers was refused with all of them echoed, a 1 MB line."""
    from slam import SlamConfig, SlamConfigError

    with pytest.raises(SlamConfigError, match=r"^alignment.heading_hypotheses: at most 360 offsets \(one a degree of a "
                                              r"whole turn; each is scored on every retry\), got 200,000$"):
        SlamConfig(alignment={"heading_hypotheses": [0.1] * 200_000})
    assert len(SlamConfig(alignment={"heading_hypotheses": [0.1] * 360}).alignment.heading_hypotheses) == 360
    with pytest.raises(SlamConfigError) as info:
        SlamConfig(motion={"odom_noise": [0.1] * 200_000})
    assert str(info.value) == ("motion.odom_noise: must be 3 numbers (x, y, theta), got 200,000: "
                               "[0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1,....1, 0.1] (1000000 characters)")
    with pytest.raises(SlamConfigError) as info:
        SlamConfig(motion={"odom_noise": [-0.1] * 1000})
    assert str(info.value).startswith("motion.odom_noise: must be factors in [0, 10] (m/m, rad/rad, rad/m), "
                                      "got [-0.1, ") and len(str(info.value)) < 200
    # one interval for -1 as for 1e300 (-1 said "must hold numbers >= 0", 1e300 "factors of at most 10")
    for bad in (-1, 11, 1e300):
        with pytest.raises(SlamConfigError) as info:
            SlamConfig(motion={"odom_noise": [0.1, bad, 0.1]})
        assert str(info.value) == (f"motion.odom_noise: must be factors in [0, 10] (m/m, rad/rad, rad/m), "
                                   f"got [0.1, {bad!r}, 0.1]")
    assert SlamConfig(motion={"odom_noise": [0, 10, 10]}).motion.odom_noise == (0.0, 10.0, 10.0)


def test_slam_prior_sigma_and_icp_iterations_are_bounded_when_built() -> None:
    """loop_closure.prior_sigma=1e-300 ran into gtsam's 'Indeterminate linear system'; alignment.
    max_iterations / fine_iterations = 1e300 failed in numba's typing of the compiled ICP."""
    from slam import SlamConfig, SlamConfigError

    with pytest.raises(SlamConfigError, match=r"^loop_closure.prior_sigma: must be in \[1e-06, 1\] m and rad"):
        SlamConfig(loop_closure={"prior_sigma": 1e-300})
    for field in ("max_iterations", "fine_iterations"):
        with pytest.raises(SlamConfigError, match=rf"^alignment.{field}: must be in \[[01], 1000\] Gauss-Newton steps, got 1e\+300"):
            SlamConfig(alignment={field: 1e300})
        assert getattr(SlamConfig(alignment={field: 1000}).alignment, field) == 1000


def test_robot_limits_and_odometry_config_check_their_fields() -> None:
    """RobotLimits and OdometryConfig took any value (v_max=1e300 made robot_tour plan for ever);
    their numbers are now finite and bounded, and the defaults are as before."""
    from sim.records import OdometryConfig
    from sim.robot import RobotLimits

    assert RobotLimits() == RobotLimits(0.5, 0.5, 1.0, 2.0, 0.25, (0.5, 2.0))
    assert RobotLimits(v_max=2).v_max == 2.0 and RobotLimits(pause_s=[0, 0]).pause_s == (0.0, 0.0)
    with pytest.raises(InputError, match=r"^w_max: must be a finite number in \[0\.01, 20\] rad/s, got inf"):
        RobotLimits(w_max=float("inf"))
    with pytest.raises(InputError, match=r"^radius: must be a finite number in \[0, 2\] m, got an int beyond"):
        RobotLimits(radius=10**400)
    with pytest.raises(InputError, match=r"^alpha3: must be a finite number in \[0, 10\], got True"):
        OdometryConfig(alpha3=True)


@pytest.mark.parametrize("field, unit", [("v_max", "m/s"), ("a_max", "m/s^2"), ("w_max", "rad/s"), ("alpha_max", "rad/s^2")])
def test_robot_limits_near_zero_are_refused_and_the_lowest_runs_without_overflow_warnings(field: str, unit: str) -> None:
    """A limit of 1e-300 (then within RobotLimits' bounds, > 0) gave phases of ~1e300 s: a robot that
    never left its first pose, exit 0 (and, before that was fixed, a RuntimeWarning of overflow per
    call). Such a limit is refused now, naming the field, the value and the range: the lowest is
    0.01, with which the robot moves, slowly, and every pose is finite."""
    from sim import simulate_records
    from sim.robot import RobotLimits

    hi = RobotLimits.BOUNDS[field][1]
    with pytest.raises(InputError, match=rf"^{field}: must be a finite number in \[0\.01, {hi:g}\] {re.escape(unit)}, got 1e-300$"):
        RobotLimits(**{field: 1e-300})
    records = simulate_records("office", seed=0, duration=20.0, rate_hz=0.2, limits=RobotLimits(**{field: 0.01}))
    truth = np.array([r.truth for r in records])
    assert len(records) == 5 and np.isfinite(truth).all()
    moved = np.hypot(*(truth[:, :2] - truth[0, :2]).T).max() + np.abs(np.diff(truth[:, 2])).max()
    assert 0.0 < moved < 10.0


# --- TUM trajectories, found by fuzzing the Python API (session 32) ---------------------------------
def _tum_path(tmp_path):
    return tmp_path / "t.tum"


@pytest.mark.parametrize("stamps_of, poses_of, message", [
    # a whole (t, x, y, theta) trajectory of 3k rows passed as poses was written as 4k garbled rows
    (lambda tr: tr[:, 0], lambda tr: tr, r"poses: must be a \(k, 3\) array \(x m, y m, theta rad\), got shape \(6, 4\)"),
    (lambda tr: tr[::-1, 0], lambda tr: tr[:, 1:], r"stamps: must not decrease \(stamp 1: 4\.0 s after 5\.0 s\)"),
    (lambda tr: np.r_[np.nan, tr[1:, 0]], lambda tr: tr[:, 1:], r"stamps: must be finite \(s\); row 0 is not"),
    (lambda tr: "abc", lambda tr: tr[:, 1:], r"stamps: must be a \(k, 1\) array of real numbers \(s\), got str"),
    (lambda tr: tr[:3, 0], lambda tr: tr[:, 1:], r"stamps: 3 stamps for 6 poses"),
    (lambda tr: tr[:, 0], lambda tr: None, r"poses: must be a \(k, 3\) array of real numbers .*got NoneType"),
    (lambda tr: tr[:, 0], lambda tr: tr[:, 1:] + 1j, r"poses: must be a \(k, 3\) array of real numbers"),  # imaginary part dropped
])
def test_write_tum_refuses_what_read_tum_would_not_read_back(tmp_path, stamps_of, poses_of, message: str) -> None:
    from lms200 import write_tum

    traj = np.column_stack((np.arange(6.0), np.ones(6), np.zeros(6), np.full(6, 0.5)))
    with pytest.raises(InputError, match=message):
        write_tum(_tum_path(tmp_path), stamps_of(traj), poses_of(traj))
    assert not _tum_path(tmp_path).exists()


def test_tum_paths_of_the_wrong_type_are_named(tmp_path) -> None:
    from lms200 import read_tum, write_tum

    with pytest.raises(InputError, match="path: must be a str or os.PathLike, got float"):
        write_tum(3.5, [0.0], [[0.0, 0.0, 0.0]])  # a TypeError; an int path was written as a file descriptor
    with pytest.raises(InputError, match="path: must be a str or os.PathLike, got NoneType"):
        read_tum(None)
    write_tum(tmp_path / "ok.tum", [0.0, 1.0], [[0.0, 0.0, 0.1], [np.nan, 0.0, 0.2]])  # a lost run's nan pose: written
    assert "nan" in (tmp_path / "ok.tum").read_text().splitlines()[2]


# --- noise estimators and calibration, found by fuzzing the Python API (session 32) ----------------
def _noise_scan() -> Scan:
    rng = np.random.default_rng(0)
    return Scan.lms200(3.0 / np.cos(np.linspace(-1.0, 1.0, 361)).clip(0.3) + rng.normal(0, 0.005, 361))


@pytest.mark.parametrize("name", ["estimate_range_noise", "neighbour_sigma", "fit_sigma", "bearing_sigma",
                                  "calibrate_scans"])
@pytest.mark.parametrize("scans, message", [
    (None, r"scans: must be an lms200.Scan or an iterable of Scans or records, got NoneType"),  # "not iterable"
    (3.0, r"scans: must be an lms200.Scan or an iterable of Scans or records, got float"),
    ("log.clf", r"scans: must be an lms200.Scan or an iterable of Scans or records, got str"),  # AttributeError
    ([np.full(361, 3.0)], r"scans\[0\]: must be an lms200.Scan or a record with .scan, got ndarray"),  # AttributeError
])
def test_noise_estimators_name_what_is_no_scan(name: str, scans: object, message: str) -> None:
    from features import noise_estimate
    from lms200 import calibration, noise

    fn = getattr(noise, name, None) or getattr(noise_estimate, name, None) or getattr(calibration, name)
    with pytest.raises(InputError, match=message):
        fn(scans)


@pytest.mark.parametrize("call, error, message", [
    (lambda ne, s: ne.scan_sigma(None), "ScanTypeError", r"scan_sigma: expected an lms200.Scan, got NoneType"),
    (lambda ne, s: ne.fit_residuals("scan"), "ScanTypeError", r"fit_residuals: expected an lms200.Scan, got str"),
    # window 0, -1 or True was numpy's LinAlgError, 2.5 an IndexError, None a TypeError
    (lambda ne, s: ne.fit_sigma(s, window=0), "ConfigError", r"window: must be an integer >= 3 and <= 16384, got 0"),
    (lambda ne, s: ne.fit_sigma(s, window=True), "ConfigError", r"window: must be an integer >= 3 .*got True"),
    (lambda ne, s: ne.bearing_sigma([s], window=2.5), "ConfigError", r"window: must be an integer >= 3 .*got 2\.5"),
    (lambda ne, s: ne.fit_residuals(s, window=8), "ConfigError", r"window: must be odd .*got 8"),
    # a nan fallback came back as the noise of a scan with too few triples
    (lambda ne, s: ne.neighbour_sigma([s], fallback=float("nan")), "ConfigError", r"fallback: must be a finite number > 0 m, got nan"),
    (lambda ne, s: ne.scan_sigma(s, fallback=None), "ConfigError", r"fallback: must be a finite number > 0 m, got None"),
    (lambda ne, s: ne.fit_sigma([], fallback="0.005"), "ConfigError", r"fallback: must be a finite number > 0 m, got '0.005'"),
])
def test_noise_estimate_arguments_are_named(call, error: str, message: str) -> None:
    from features import noise_estimate

    with pytest.raises(LmsbenchError, match=message) as info:
        call(noise_estimate, _noise_scan())
    assert type(info.value).__name__ == error


def test_noise_estimators_still_take_scans_and_records() -> None:
    from features import noise_estimate
    from lms200.noise import estimate_range_noise

    s = _noise_scan()
    records = [Record(s), Record(s.replace(stamp=1.0))]
    assert noise_estimate.fit_sigma(records) == noise_estimate.fit_sigma([s, s.replace(stamp=1.0)])
    assert 0.003 < noise_estimate.fit_sigma(s) < 0.008
    assert 0.003 < estimate_range_noise(iter(records)).sigma_m < 0.008


# --- LMS200Sim.cast, found by fuzzing the Python API (session 32) ------------------------------------
@pytest.mark.parametrize("origins, headings, message", [
    (np.full((3, 2), np.nan), np.zeros(3), r"^origins: must be finite \(x m, y m\); row 0 is not"),  # every range +inf, silently
    (np.zeros((3, 3)), np.zeros(3), r"^origins: must be a \(k, 2\) array \(x m, y m\), got shape \(3, 3\)"),  # first 2 columns, silently
    (np.zeros(2), np.zeros(1), r"^origins: must be a \(k, 2\) array .*got shape \(2,\)"),  # IndexError
    ("ab", np.zeros(1), r"^origins: must be a \(k, 2\) array of real numbers .*got str"),  # numpy's ValueError
    (np.zeros((3, 2)), np.zeros(2), r"^headings: 2 headings for 3 origins"),  # numpy's broadcast error
    (np.zeros((3, 2)), [0.0, np.inf, 0.0], r"^headings: must be finite \(rad\); row 1 is not"),
])
def test_cast_names_bad_rays(origins, headings, message: str) -> None:
    import sim

    lidar = sim.LMS200Sim(sim.make_world("office", 0))
    try:
        with pytest.raises(InputError, match=message):
            lidar.cast(origins, headings)
    finally:
        lidar.close()


def test_cast_of_more_rays_than_bullets_batch_is_split() -> None:
    """16,384 rays in one rayTestBatch returned no hits (a ValueError in the caster), more raised
    pybullet's 'Number of rays exceed the maximum batch size'; now cast splits them, same ranges."""
    import sim
    from sim.lidar import _RAY_BATCH

    lidar = sim.LMS200Sim(sim.make_world("office", 0))
    try:
        n = _RAY_BATCH + 1001
        origins = np.tile([[2.0, 2.0]], (n, 1))
        headings = np.linspace(-3.0, 3.0, n)
        ranges = lidar.cast(origins, headings)
        assert ranges.shape == (n,) and np.isfinite(ranges).mean() > 0.9
        assert np.array_equal(ranges[-1000:], lidar.cast(origins[-1000:], headings[-1000:]))
    finally:
        lidar.close()


# --- hand-built FeatureSets, found by fuzzing the Python API (session 32) ----------------------------
def _wall_features() -> tuple[Scan, Any]:
    from features import extract

    angles = -np.pi / 2 + np.arange(361) * np.deg2rad(0.5)
    with np.errstate(divide="ignore"):
        scan = Scan.lms200(np.where(np.abs(angles) < 1.0, 3.0 / np.cos(angles), np.inf))
    return scan, extract(scan).lines[0]


@pytest.mark.parametrize("change, message", [
    # each scored a nan ray RMSE / explained fraction, silently: checked inside a FeatureSet, now when built
    ({"rho": float("nan")}, r"^Line.rho: must be a finite number >= 0 m \(the line's distance from the origin\), got nan$"),
    ({"rho": -3.0}, r"^Line.rho: must be a finite number >= 0 m .*got -3.0$"),
    ({"end": (float("inf"), 0.0)}, r"^Line.end: must be two finite numbers \(x, y m\), got \(inf, 0.0\)$"),
    ({"first": 200, "last": 100}, r"^Line.first, Line.last: must be whole beam indices with 0 <= first <= last, got 200, 100$"),
    ({"first": 2.5}, r"^Line.first, Line.last: must be whole beam indices .*got 2.5, "),  # truncated to 2
    ({"rho": "abc"}, r"^Line.rho: must be a finite number"),  # numpy's ValueError
    ({"start": (1.0, 2.0, 3.0)}, r"^Line.start: must be two finite numbers"),  # a broadcast error
    ({"first": 10**30, "last": 10**30}, r"^Line.first, Line.last: must be whole beam indices"),  # an OverflowError
    # taken before (2026-12-07): outside (-pi, pi], a support beyond the line's beams, covariances of no distribution
    ({"alpha": 4.0}, r"^Line.alpha: must be a finite angle in \(-pi, pi\] rad \(the line's normal; wrap it\), got 4.0$"),
    ({"alpha": float("inf")}, r"^Line.alpha: must be a finite angle"),
    ({"n_points": -1}, r"^Line.n_points: must be a whole number in \[0, \d+\] \(the beams \d+..\d+ that support the line; 0: not known\), got -1$"),
    ({"n_points": 10_000}, r"^Line.n_points: must be a whole number in \[0, "),
    ({"cov": np.eye(3)}, r"^Line.cov: must be a 2x2 array, not one of shape \(3, 3\) \(the covariance of rho, alpha\), got array\(\[\[1"),
    ({"cov": np.array([[1.0, 0.5], [0.0, 1.0]])}, r"^Line.cov: must be symmetric"),
    ({"cov": np.array([[1.0, 2.0], [2.0, 1.0]])}, r"^Line.cov: must be positive semi-definite"),  # a correlation of 2
    ({"cov": np.array([[-1.0, 0.0], [0.0, 1.0]])}, r"^Line.cov: must be positive semi-definite"),
    ({"cov": np.array([[1.0, np.nan], [np.nan, 1.0]])}, r"^Line.cov: must be finite \(or all nan: not known\)"),
    ({"cov": "abc"}, r"^Line.cov: must be a 2x2 array of numbers"),
])
def test_hand_built_lines_are_checked_when_built(change: dict, message: str) -> None:
    _, line = _wall_features()
    with pytest.raises(InputError, match=message):
        dataclasses.replace(line, **change)


@pytest.mark.parametrize("change", [
    {"start": np.array([[0.0], [1.0]])}, {"rho": "x" * 5000}, {"cov": np.arange(1600.0).reshape(40, 40)},
    {"cov": -np.eye(2) * np.arange(1, 3)}, {"alpha": np.full((3, 3), 9.0)}, {"first": np.array([[1], [2]])},
])
def test_line_and_corner_messages_quote_values_on_one_short_line(change: dict) -> None:
    """A review: the values were quoted by their repr, a 2-D array a line a row and a 5,000-character
    text whole (the cov's patched with .replace, 336 characters of runs of spaces for a 40x40 array)."""
    from features import Corner

    _, line = _wall_features()
    for build in (lambda: dataclasses.replace(line, **change),
                  lambda: Corner(**{"x": 1.0, "y": 0.5, "angle": 1.5, "index": 10, "lines": (0, 1),
                                    **{k: v for k, v in (("x", next(iter(change.values()))),)}})):
        with pytest.raises(InputError) as err:
            build()
        text = str(err.value)
        assert "\n" not in text and "  " not in text and len(text) < 250, text


def test_hand_built_records_take_float32_pi_fractions_and_0d_arrays() -> None:
    """A review: float32's pi (8.7e-8 above pi) as alpha, a Fraction and a 0-d array as a number
    were refused when built; main took them (lms200.finite.is_number records the Fraction regression)."""
    from fractions import Fraction

    from features import Corner, FeatureSet, Line

    lines = [Line(Fraction(1, 2), np.float32(np.pi), (np.array(1.0), Fraction(1, 4)), (1.0, 1.0), 10, 20, n_points=3),
             Line(np.array(0.5), -np.float32(np.pi), (1.0, 0.0), (1.0, 1.0), 10, 20)]
    fs = FeatureSet(lines, [Corner(np.array(1.0), Fraction(1, 2), Fraction(3, 2), 10, (0, 1))])
    assert fs.lines.values[:, :4].tolist() == [[0.5, float(np.float32(np.pi)), 1.0, 0.25],
                                               [0.5, -float(np.float32(np.pi)), 1.0, 0.0]]
    assert fs.corners.values.tolist() == [[1.0, 0.5, 1.5]]
    with pytest.raises(InputError, match=r"^Line.alpha: "):  # still refused: beyond float32's rounding
        Line(0.5, np.pi + 1e-5, (1.0, 0.0), (1.0, 1.0), 10, 20)


def test_hand_built_lines_within_their_meanings_are_taken() -> None:
    """The meanings' edges: rho 0 (and -1e-12 of rounding), alpha pi and -pi (atan2's for y = -0.0),
    n_points 0 (not known) or every beam, the default all-nan covariance, a singular one."""
    from features import FeatureSet, Line

    for rho, alpha, n, cov in ((0.0, np.pi, 0, np.full((2, 2), np.nan)), (-1e-12, -np.pi, 11, np.zeros((2, 2))),
                               (2.0, 0.0, 5, [[1e-4, 1e-5], [1e-5, 1e-6]])):
        line = Line(rho, alpha, (0.0, -1.0), (0.0, 1.0), 50, 60, cov=cov, n_points=n)
        assert FeatureSet([line]).lines.beams.tolist() == [[50, 60, n]]
    assert Line(1.0, 0.0, np.array([1.0, 0.0]), [1.0, 1.0], np.int64(3), 4.0).n_points == 0


@pytest.mark.parametrize("change, message", [
    # a Line that skipped its construction's check (set through object.__setattr__) is still checked in a FeatureSet
    ({"rho": float("nan")}, r"^lines: line 0: its values must be finite"),
    ({"rho": -3.0}, r"^lines: line 0: rho must be >= 0 m \(rho, alpha, x0, y0, x1, y1, first, last = -3, "),
    ({"first": 200, "last": 100}, r"^lines: line 0: its beams must be whole numbers with 0 <= first <= last"),
    ({"first": 2.5}, r"^lines\[0\].first: must be a whole number \(a beam index or count\), got 2.5"),
    ({"start": (1.0, 2.0, 3.0)}, r"^lines: each Line must hold numbers"),
])
def test_feature_sets_of_hand_built_lines_are_checked(change: dict, message: str) -> None:
    from features import FeatureSet

    _, line = _wall_features()
    line = dataclasses.replace(line)
    for field_name, value in change.items():
        object.__setattr__(line, field_name, value)
    with pytest.raises(InputError, match=message):
        FeatureSet([line])


def _from_arrays(**change: Any) -> Any:
    from features import Lines

    arrays = dict(rho=[1.0], alpha=[0.0], start=[[1.0, -1.0]], end=[[1.0, 1.0]], cov=[np.eye(2) * 1e-4], first=[10],
                  last=[49], n_points=[40])
    return Lines.from_arrays(**{**arrays, **change})


@pytest.mark.parametrize("make, message", [
    # a FeatureSet of ready Lines / Corners (a user's extractor's) was taken unchecked: nan scores, silently
    (lambda: _from_arrays(rho=[np.nan]), r"^lines: line 0: its values must be finite \(rho, alpha, x0, y0, x1, y1, first, last = nan, "),
    (lambda: _from_arrays(rho=[-2.0]), r"^lines: line 0: rho must be >= 0 m"),
    (lambda: _from_arrays(first=[60]), r"^lines: line 0: its beams must be whole numbers with 0 <= first <= last"),
    (lambda: _from_arrays(n_points=[41]), r"^lines: line 0: n_points must be in \[0, last - first \+ 1\] \(first, last, n_points = \[10, 49, 41\]"),
    (lambda: _from_arrays(cov=[[[1.0, np.nan], [np.nan, 1.0]]]), r"^lines: line 0: its cov must be finite or all nan \(not known\)"),
    (lambda: __import__("features").Lines(np.zeros((2, 3)), np.zeros((2, 3), np.int64)),
     r"^lines: its values must be a \(k, 10\) float64 array and its beams a \(k, 3\) integer array, got \(2, 3\) and \(2, 3\)$"),
    (lambda: _from_arrays(alpha=[0.0, 1.0]), r"^Lines.from_arrays: alpha has 2 items for 1 line \(rho's\); "),  # numpy's ValueError
    (lambda: _from_arrays(start=[[1.0, -1.0, 0.0]]), r"^Lines.from_arrays: rho, alpha \(L,\), .* must be numbers of these shapes, one a line "
                                                      r"\(could not broadcast"),
    # a review: a length-1 array broadcast to every line, and a beam 2.7 was cut to 2, silently
    (lambda: _from_arrays(rho=[1.0, 2.0], alpha=[0.0, 0.0], start=[[1.0, -1.0]] * 2, end=[[1.0, 1.0]] * 2, first=[10, 10],
                          last=[49, 49], n_points=[40, 40]), r"^Lines.from_arrays: cov has 1 item for 2 lines \(rho's\); "),
    (lambda: _from_arrays(n_points=[2.7]), r"^Lines.from_arrays: n_points must be whole numbers \(beam indices, counts\), got 2.7 at line 0$"),
    (lambda: _from_arrays(first=np.array([np.nan])), r"^Lines.from_arrays: first must be whole numbers .*got nan at line 0$"),
    (lambda: __import__("features").Corners(np.array([[1.0, 1.0, 0.0]]), np.zeros((1, 3), np.int64)),
     r"^corners: corner 0: x, y must be finite, angle in \(0, pi\) rad, its beam and lines >= 0 \(x, y, angle = \[1.0, 1.0, 0.0\]"),
    (lambda: __import__("features").Corners(np.array([[np.nan, 1.0, 1.5]]), np.zeros((1, 3), np.int64)), r"^corners: corner 0: "),
])
def test_feature_sets_of_ready_arrays_are_checked(make: Any, message: str) -> None:
    # by check_feature_set, which extract / extract_many / compare run on a user's method's result
    # (outside compare's timed span: test_user_method_errors), not by FeatureSet() itself
    from features import Corners, FeatureSet, Lines
    from features.types import check_feature_set

    with pytest.raises(InputError, match=message):
        made = make()
        check_feature_set(FeatureSet(made) if isinstance(made, Lines) else FeatureSet([], made))
    fs = FeatureSet(_from_arrays(), Corners(np.array([[1.0, 1.0, 1.5]]), np.array([[49, 0, 1]])), "mine")
    assert fs.lines.beams.tolist() == [[10, 49, 40]] and len(fs.corners) == 1
    assert len(FeatureSet(_from_arrays(cov=[np.full((2, 2), np.nan)], n_points=[0])).lines) == 1  # cov, support not known
    empty = _from_arrays(**{k: [] for k in ("rho", "alpha", "start", "end", "cov", "first", "last", "n_points")})
    assert empty == Lines.empty() and len(FeatureSet(empty).lines) == 0  # refused (reshape of 0 lines) before the review
    assert _from_arrays(first=[10.0], last=np.array([49.0])).beams.tolist() == [[10, 49, 40]]  # whole floats are beams


@pytest.mark.parametrize("lines, message", [
    (None, r"^lines: must be a features.Lines or a sequence of features.Line, got NoneType"),  # "not iterable"
    ("abc", r"^lines: must be a features.Lines or a sequence of features.Line, got str"),    # AttributeError
    ([3.0], r"^lines\[0\]: must be a features.Line, got float"),
])
def test_feature_set_of_something_not_lines(lines: object, message: str) -> None:
    from features import FeatureSet

    with pytest.raises(InputError, match=message):
        FeatureSet(lines)


def test_line_arrays_given_to_the_real_data_measures_are_checked() -> None:
    """The (k, 8) array path of scan_measures / ray_residuals: a negative rho or first > last gave
    nan measures, silently; a FeatureSet of valid lines measures as before."""
    from features import FeatureSet, realdata

    scan, line = _wall_features()
    rows = FeatureSet([line]).line_array()
    m = realdata.scan_measures(rows, scan, 0.005)
    assert m.n_lines == 1 and m.explained_tol == pytest.approx(1.0) and np.isfinite(m.ray_rmse_m)
    bad = rows.copy()
    bad[0, 0] = -bad[0, 0]
    with pytest.raises(InputError, match=r"^fs: line 0: rho must be >= 0 m"):
        realdata.scan_measures(bad, scan, 0.005)
    bad = rows.copy()
    bad[0, 6], bad[0, 7] = bad[0, 7], bad[0, 6]
    with pytest.raises(InputError, match=r"^fs: line 0: its beams must be whole numbers with 0 <= first <= last"):
        realdata.ray_residuals(bad, scan)


@pytest.mark.parametrize("reader", ["read_tum", "read_relations"])
@pytest.mark.parametrize("path, message", [
    ("/dev/zero", r"^/dev/zero: a .* must be a regular file, not a device or pipe"),  # read until memory ran out
    (".", r"^\. is a folder, not a "),                                                # IsADirectoryError
    ("no/such.file", r"^no such .*: no/such.file"),
])
def test_tum_and_relations_readers_refuse_what_is_no_file_unread(reader: str, path: str, message: str) -> None:
    from lms200 import read_tum
    from lms200.errors import LogNotFoundError
    from slam.metrics import read_relations

    fn = {"read_tum": read_tum, "read_relations": read_relations}[reader]
    with pytest.raises(LogNotFoundError, match=message):
        fn(path)


@pytest.mark.parametrize("call, message", [
    # a float or text seed was numpy's TypeError ("SeedSequence expects int"), -1 its ValueError
    (lambda s: __import__("lms200.noise").noise.estimate_range_noise(s, seed=2.5), r"^seed: must be a whole number >= 0, got 2.5"),
    (lambda s: __import__("lms200.noise").noise.estimate_range_noise(s, seed=-1), r"^seed: must be a whole number >= 0, got -1"),
    (lambda s: __import__("lms200.calibration").calibration.calibrate_scans([s, s], seed="0"), r"^seed: must be a whole number >= 0, got '0'"),
    # None was "'>' not supported between instances of 'NoneType' and 'float'"
    (lambda s: __import__("lms200.noise").noise.estimate_range_noise(s, min_range=None), r"^min_range: must be a number >= 0 .*got None"),
    (lambda s: __import__("lms200.noise").noise.estimate_range_noise(s, max_range=float("nan")), r"^max_range: must be a number >= 0 .*got nan"),
])
def test_noise_and_calibration_seeds_and_bands_are_checked(call, message: str) -> None:
    with pytest.raises(InputError, match=message):
        call(_noise_scan())


@pytest.mark.parametrize("corners, message", [
    ([1.0], r"^corners\[0\]: must be a features.Corner, got float"),  # AttributeError: no attribute 'x'
    ("abc", r"^corners: must be a features.Corners or a sequence of features.Corner, got str"),
    # a Corner that skipped its construction's check (set through object.__setattr__) is still checked in a FeatureSet
    ("corner:x=nan", r"^corners\[0\]: x, y and angle must be finite numbers, got nan"),  # a nan corner, scored as a miss
    ("corner:x=text", r"^corners\[0\]: x, y and angle must be finite numbers, got 'a'"),  # numpy's ValueError
    ("corner:index=2.5", r"^corners\[0\]: index and lines must be whole numbers .*got 2.5, \(0, 1\)"),  # truncated to 2
])
def test_feature_set_corners_are_checked(corners: object, message: str) -> None:
    from features import Corner, FeatureSet

    if isinstance(corners, str) and corners.startswith("corner:"):
        field, value = corners[7:].split("=")
        corner = Corner(x=1.0, y=0.5, angle=1.5, index=10, lines=(0, 1))
        object.__setattr__(corner, field, {"nan": float("nan"), "text": "a", "2.5": 2.5}[value])
        corners = [corner]
    with pytest.raises(InputError, match=message):
        FeatureSet(corners=corners)
    assert len(FeatureSet(corners=[Corner(1.0, 0.5, 1.5, 10, (0, 1))]).corners) == 1


@pytest.mark.parametrize("change, message", [
    # taken when built before (2026-12-07); the first three only inside a FeatureSet
    (dict(x=float("nan")), r"^Corner.x: must be a finite number \(m\), got nan$"),
    (dict(y="a"), r"^Corner.y: must be a finite number \(m\), got 'a'$"),
    (dict(index=2.5), r"^Corner.index: must be a whole beam index >= 0, got 2.5$"),
    (dict(index=-1), r"^Corner.index: must be a whole beam index >= 0, got -1$"),
    (dict(angle=0.0), r"^Corner.angle: must be in \(0, pi\) rad \(the angle between its two lines\), got 0.0$"),
    (dict(angle=4.0), r"^Corner.angle: must be in \(0, pi\) rad"),
    (dict(angle=float("nan")), r"^Corner.angle: must be in \(0, pi\) rad"),
    (dict(lines=(1, 1)), r"^Corner.lines: must be two different whole line indices >= 0, got \(1, 1\)$"),
    (dict(lines=(-1, 0)), r"^Corner.lines: must be two different whole line indices >= 0, got \(-1, 0\)$"),
    (dict(lines=(0, 1, 2)), r"^Corner.lines: must be two different"),
    (dict(lines="01"), r"^Corner.lines: must be two different"),
    (dict(lines=5), r"^Corner.lines: must be two different"),
])
def test_hand_built_corners_are_checked_when_built(change: dict, message: str) -> None:
    from features import Corner

    good = dict(x=1.0, y=0.5, angle=1.5, index=10, lines=(0, 1))
    with pytest.raises(InputError, match=message):
        Corner(**{**good, **change})
    assert Corner(**{**good, "lines": np.array([2, 1]), "index": 0.0}).index == 0.0


def test_review_of_the_hunt_valid_inputs_it_had_refused(tmp_path) -> None:
    """A review of this hunt's checks found valid inputs they refused: a Corner whose lines are a list
    (a user extractor's; it stopped a whole `lmsbench compare`), a FeatureSet from a generator, beams
    held as whole floats (49.0), rho -1e-12 of a line through the origin, empty lists given to the
    metrics and write_tum, a lost run's nan map lines (map_error raised)."""
    from features.types import Corner, FeatureSet, Line
    from lms200 import write_tum
    from slam.metrics import map_error

    line = Line(rho=1.0, alpha=0.0, start=(1.0, -1.0), end=(1.0, 1.0), first=10, last=49.0, cov=np.eye(2) * 1e-4,
                n_points=40)
    origin = Line(rho=-1e-12, alpha=0.0, start=(0.0, -1.0), end=(0.0, 1.0), first=50, last=60, cov=np.eye(2) * 1e-4,
                  n_points=11)
    fs = FeatureSet((x for x in [line, origin]), [Corner(1.0, 1.0, 1.5, 49, [0, 1]), Corner(0.0, 1.0, 1.5, 50, np.array([0, 1]))])
    assert fs.lines.beams.tolist() == [[10, 49, 40], [50, 60, 11]]
    assert fs.corners.beams.tolist() == [[49, 0, 1], [50, 0, 1]]
    walls = np.array([[0.0, 0.0, 5.0, 0.0], [5.0, 0.0, 5.0, 5.0]])
    assert map_error([], walls).n_lines == 0
    lost = map_error(np.array([[0.1, 0.0, 4.9, 0.0], [np.nan, 0.0, 1.0, 1.0]]), walls)
    assert (lost.n_lines, lost.matched) == (2, 1)
    with pytest.raises(InputError, match=r"^poses: none to write \(a TUM file of no pose is refused by read_tum"):
        write_tum(tmp_path / "none.tum", [], [])  # an empty list is no shape error (it wrote a file read_tum refuses)
    assert not (tmp_path / "none.tum").exists()


@pytest.mark.parametrize("value, message", [
    (dict(drift="chain"), r"^loop_closure.drift: must be 'marginals' or 'joint', got 'chain'$"),
    (dict(drift_inflation=0.5), r"^loop_closure.drift_inflation: must be in \[1, 1e\+06\] \(a factor on the drift the closure gate allows\), got 0.5$"),
    (dict(drift_inflation=float("nan")), r"^loop_closure.drift_inflation: must be finite, got nan$"),
    (dict(search="both"), r"^loop_closure.search: must be 'nearest' or 'window', got 'both'$"),
    (dict(search=5), r"^loop_closure.search: must be a string, got 5$"),
    (dict(window_theta=3.1416), r"^loop_closure.window_theta: must be in \[0.01, pi\] rad, got 3.1416$"),
])
def test_slam_config_checks_the_closure_drift_gate_and_search(value: dict, message: str) -> None:
    from slam import SlamConfig, SlamConfigError

    with pytest.raises(SlamConfigError, match=message):
        SlamConfig.from_dict({"loop_closure": value})
    assert SlamConfig.from_dict({"loop_closure": {"drift": "joint", "drift_inflation": 10}}).loop_closure.drift == "joint"
    assert SlamConfig.from_dict({"loop_closure": {"search": "window", "window_theta": np.pi}}).loop_closure.search == "window"


def test_masked_items_are_nan_wherever_numbers_are_read() -> None:
    """Fuzz round 10: np.asarray dropped a masked array's mask and read its hidden data, silently, everywhere but a
    Scan's ranges: a Record's odometry [1, --, 0.5] was (1.0, 0.0, 0.5), a masked code, bearing or action its data.
    One helper (lms200.codes.unmasked) reads the masked items as nan: refused where a number is needed."""
    from lms200 import Record, codes_to_ranges
    from lms200.codes import unmasked
    from sim.gym_env import _action

    scan = Scan(np.ma.array([1.0, 2.0, 3.0], mask=[False, True, False]), **GEOM)
    assert np.array_equal(scan.ranges, [1.0, np.nan, 3.0], equal_nan=True)  # the rule Scan had, kept
    with pytest.raises(InputError, match=r"^odom: must be finite \(x m, y m, theta rad\), got array\(\[1\. , nan, 0\.5\]\)$"):
        Record(scan, odom=np.ma.array([1.0, 2.0, 0.5], mask=[False, True, False]))
    with pytest.raises(InputError, match=r"^codes: must be raw LMS200 values .* and nan / inf$"):
        codes_to_ranges(np.ma.array([100, 8183, 200], mask=[False, False, True]), "mm")
    with pytest.raises(InputError, match=r"^bearings: must be finite numbers"):
        scan.beam_of(np.ma.array([0.1, 0.2], mask=[False, True]))
    with pytest.raises(InputError, match=r"^action: must be two finite numbers"):
        _action(np.ma.array([1.0, 0.5], mask=[True, False]))
    from features.types import Lines
    from slam import Observations

    with pytest.raises(InputError, match=r"^observations.line_cov: must be \(1, 2, 2\) finite covariances"):
        Observations(lines=[[1.0, 0.1]], line_ends=[[0.0, 0.0, 1.0, 1.0]],
                     line_cov=np.ma.array(np.eye(2)[None] * 0.01, mask=[[[True, False], [False, False]]]))
    with pytest.raises(InputError, match=r"^Lines.from_arrays: first must be whole numbers"):
        Lines.from_arrays([1.0], [0.1], [[0.0, 1.0]], [[1.0, 1.0]], np.full((1, 2, 2), np.nan),
                          np.ma.array([3], mask=[True]), [5], [3])
    from features.types import Line
    from lms200.codes import real_rows

    row = real_rows(np.ma.array([[0.0, 1.0, 2.0, 0.5]], mask=[[False, False, True, False]]), "traj", 4, "t, x, y, theta",
                    finite=False)  # trajectory rows, relations, Observations' lines, ... (review of round 10)
    assert np.array_equal(row, [[0.0, 1.0, np.nan, 0.5]], equal_nan=True)
    with pytest.raises(InputError, match=r"^Line.cov: must be finite \(or all nan: not known\)"):
        Line(1.0, 0.0, (1.0, 0.0), (1.0, 1.0), 0, 5, np.ma.array(np.eye(2) * 1e-4, mask=[[True, False], [False, False]]), 6)
    if np.finfo(np.longdouble).maxexp > 1024:  # a long double wider than float64 (x86-64 Linux; not Windows, ARM macOS)
        huge = np.array([1, 0, 0], dtype=np.longdouble) * np.longdouble(10) ** 4000  # beyond float64
        with pytest.raises(InputError, match=r"^odom: must be finite .*dtype=float128\)$"):  # as unmasked, no warning
            Record(scan, odom=np.ma.array(huge))
    assert Record(scan, odom=np.ma.array([1.0, 2.0, 0.5])).odom == (1.0, 2.0, 0.5)  # nothing masked: its values
    assert unmasked(np.ma.array([True], mask=[True])).dtype == bool  # another dtype: for the caller's refusal


def _array_names() -> list:
    import dataclasses

    from experiments.compare import log_source
    from experiments.sim2real import sim2real
    from features import FeatureSet, register
    from lms200 import Record, write_log
    from sim import SensorConfig

    @dataclasses.dataclass(frozen=True)
    class Cfg:
        a: int = 1

    names = np.array(["numpy", "x"])
    return [
        (lambda tmp: write_log(tmp / "a.clf", [Record(Scan.lms200(np.full(361, 3.0)))], fmt=names), "^fmt: must be"),
        (lambda tmp: SensorConfig(units=names), "^units: must be 'mm' or 'cm'"),
        (lambda tmp: register("fuzz_array_backend", Cfg, lambda scan, cfg: FeatureSet(), backend=names), "^backend: must be"),
        (lambda tmp: log_source(tmp / "none.clf", poses=names), "^poses: must be one of"),
        (lambda tmp: sim2real(tmp / "none.clf", world=names), "^world: unknown world"),
    ]


@pytest.mark.parametrize("case", range(5))
def test_a_name_given_as_an_array_is_refused_naming_the_argument(tmp_path, case: int) -> None:
    """Fuzz round 10: `value in NAMES` of a numpy array compares item by item: numpy's "truth value of an array with
    more than one element is ambiguous" ValueError, not the argument's own refusal (lms200.finite.is_one_of)."""
    from lms200 import LmsbenchError

    call, message = _array_names()[case]
    with pytest.raises(LmsbenchError, match=message):
        call(tmp_path)


@pytest.mark.parametrize("kw, message", [
    (dict(sigma=True), r"^sigma: must be a range noise std in \[0.0001, 1000\] m, or 'auto', got True$"),  # was 1 m
    (dict(sigma=np.array([0.01, 0.02])), r"^sigma: must be a range noise std"),  # numpy's "truth value ... ambiguous"
    (dict(matches={}), r"^matches: must be a list .* got dict$"),  # 'dict' object has no attribute 'append', at the end
])
def test_compare_arguments_are_checked_before_any_source_is_read(kw: dict, message: str) -> None:
    """Fuzz round 10; a source that would fail if it were read shows that nothing was."""
    from experiments.compare import Source, compare
    from lms200 import LmsbenchError

    def never() -> object:
        raise AssertionError("a source was read")

    class Unread:  # records that fail when iterated: the checks come before the first scan
        def __iter__(self) -> object:
            raise AssertionError("a source's records were read")

    src = Source("never", "sim", 0, Unread(), estimate_sigma=never)  # type: ignore[arg-type]
    with pytest.raises(LmsbenchError, match=message):
        compare([src], ["split_merge"], **kw)


def test_summarise_names_a_table_that_is_not_compares() -> None:
    """Fuzz round 10: summarise([1, 2]) was an AttributeError ('list' object has no attribute 'groupby'), a table of
    other columns a KeyError naming one of them."""
    import pandas as pd

    from experiments.compare import summarise

    with pytest.raises(InputError, match=r"^table: must be compare\(\)'s table \(a pandas DataFrame\), got list$"):
        summarise([1, 2])  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^table: lacks compare\(\)'s column\(s\) kind, seed, n_lines, .*microseconds"):
        summarise(pd.DataFrame({"source": ["s"], "method": ["m"]}))


def test_slam_observations_beyond_every_logs_bounds_or_singular_against_the_map_are_named() -> None:
    """Fuzz round 10: Observations built by hand took coordinates of 1e300 m and covariances of 1e300 (the filter
    overflowed under numpy's RuntimeWarnings), and variances of 1e-300 m^2 against a map made uncertain by 1000 s
    gaps left the EKF's innovation covariance singular: numpy's raw LinAlgError 'Singular matrix'."""
    from slam import Observations, SlamConfig, run_observations
    from slam.run import SlamInputError

    with pytest.raises(InputError, match=r"^observations.points: row 0 holds 1e\+300 m, beyond 1e\+09 m"):
        Observations(points=[[1e300, 0.0]])
    with pytest.raises(InputError, match=r"^observations.line_cov: row 0 holds 1e\+300 m\^2 / rad\^2, beyond 1e\+18"):
        Observations(lines=[[1.0, 0.0]], line_cov=[np.eye(2) * 1e300], line_ends=[[1.0, -1.0, 1.0, 1.0]])

    def obs(lines: list, variance: float) -> Observations:
        rows = np.array(lines, float).reshape(-1, 6)
        return Observations(lines=rows[:, :2], line_ends=rows[:, 2:], line_cov=np.repeat(np.eye(2)[None] * variance, len(rows), 0))

    steps = [(0.1, obs([[9.438e-12, 2.145876, 3.556e-10, 5.665e-10, -4.504e-10, -4.714e-10]], 1e-300)),
             (1000.1, obs([], 1.0)),
             (2000.1, obs([[0.291398, 3.102188, 0.018406, 0.588280, -0.736400, 0.118196]], 1e4)),
             (2000.1, obs([[5.960e-10, -2.270278, 8.654e-10, 5.407e-10, 3.424e-11, -9.987e-10],
                           [5.783e-10, 1.692669, -6.271e-10, 1.482e-10, -5.428e-10, -1.175e-10]], 1e-300)),
             (2000.1, obs([], 1.0)), (2000.2, obs([], 1.0)), (2000.2, obs([], 1.0)),
             (2000.200000001, obs([[3.485e-10, 1.862456, -7.181e-10, 1.452e-10, -2.890e-10, 5.384e-10],
                                   [4.956e-10, -2.123189, 1.157e-10, -6.262e-10, 7.585e-10, -7.808e-10]], 1e-300))]
    with pytest.raises(SlamInputError, match=r"^scan 7: the filter's innovation covariance is singular in float64"):
        run_observations([t for t, _ in steps], [o for _, o in steps], SlamConfig(preset="paper"))


def test_slam_overflow_to_inf_is_said_without_numpys_warnings() -> None:
    """Fuzz round 10 (pytest turns RuntimeWarnings into errors): a squared Mahalanobis distance beyond float64 (a
    variance of 1e-300) is inf, and a scan point of 1e200 m is beyond the matcher's max_range, both as before, without
    'overflow encountered' warnings (the default preset warned at every scan of 1e200 m ranges)."""
    from slam.association import mahalanobis2
    from slam.config import AlignmentConfig
    from slam.scanslam import ScanPoints

    assert mahalanobis2(np.array([0.0, 1e5]), np.diag([1.0, 1e-300])) == np.inf
    points = ScanPoints.from_points(np.array([[1e200, 0.0], [1.0, 2.0]]), AlignmentConfig())
    assert points.valid.tolist() == [[1.0, 2.0]]


@pytest.mark.parametrize("call", [lambda: read_log(""), lambda: read_log("  "), lambda: write_log("", [])],
                         ids=["read_log", "read_log blank", "write_log"])
def test_an_empty_path_is_refused_as_empty_not_read_as_the_current_folder(call) -> None:
    """``read_log("")`` (an unset ``$LOG``) said ". is a folder but not a ROS 2 bag (no metadata.yaml)":
    pathlib reads "" as the current folder (probe 13)."""
    with pytest.raises(InputError, match=r"^path: empty \('\s*'\); give a file or folder name$"):
        call()


def test_ctrl_c_inside_a_compiled_extraction_is_a_keyboard_interrupt() -> None:
    """Probe 14: Ctrl-C during extract_many (Jupyter's interrupt too) came out, more than half the time, as
    "SystemError: <built-in method extract_batch ...> returned a result with an exception set" over five
    chained tracebacks: Python's handler raised the KeyboardInterrupt inside numba's _numba_unpickle, which
    the compiled call runs to box its results. features.jit.FixedTypeCall raises that KeyboardInterrupt
    itself; any other SystemError is as it was."""
    from features.jit import FixedTypeCall

    def interrupted_entry(*args: object) -> object:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("<function _numba_unpickle> returned a result with an exception set") from exc

    call = FixedTypeCall(None)  # type: ignore[arg-type]
    call.entry = interrupted_entry
    with pytest.raises(KeyboardInterrupt) as info:
        call(1.0)
    assert info.value.__suppress_context__
    call.entry = lambda *args: (_ for _ in ()).throw(SystemError("another"))
    with pytest.raises(SystemError, match="^another$"):
        call(1.0)


def test_a_genuine_system_error_of_a_compiled_call_keeps_its_cause_and_context() -> None:
    """A review: FixedTypeCall raised every SystemError ``from None``, a genuine one too (not over a
    KeyboardInterrupt), stripping the cause and context that say where it came from."""
    from features.jit import FixedTypeCall

    def failing_entry(*args: object) -> object:
        try:
            raise ValueError("the reason")
        except ValueError as exc:
            raise SystemError("<built-in method extract_batch> returned NULL without setting an exception") from exc

    def failing_while_handling(*args: object) -> object:
        try:
            raise ValueError("the context")
        except ValueError:
            raise SystemError("error return without exception set")  # noqa: B904 - the implicit context

    call = FixedTypeCall(None)  # type: ignore[arg-type]
    call.entry = failing_entry
    with pytest.raises(SystemError, match="returned NULL") as info:
        call(1.0)
    assert isinstance(info.value.__cause__, ValueError) and str(info.value.__cause__) == "the reason"
    call.entry = failing_while_handling
    with pytest.raises(SystemError, match="^error return without exception set$") as info:
        call(1.0)
    assert info.value.__cause__ is None and not info.value.__suppress_context__
    assert isinstance(info.value.__context__, ValueError) and str(info.value.__context__) == "the context"
