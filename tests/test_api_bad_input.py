"""Bad input to the public Python API: every user error is an ``LmsbenchError`` naming the field or
argument, never a raw numpy / Python exception, a silent cast or a lost file (fuzzing of
2026-12-02: Scan, read_log / write_log, extract / extract_many, sim, the Gym env, run_slam)."""

from __future__ import annotations

import numpy as np
import pytest

from lms200 import LmsbenchError, Record, Scan, read_log, write_log
from lms200.errors import InputError, ScanError

GEOM = dict(angle_min=-1.0, angle_increment=0.01, range_min=0.0, range_max=10.0)


# -- Scan ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("ranges", [
    np.array([1 + 1j, 2.0]),                      # was cast to [1, 2] with a ComplexWarning
    np.array([True, False]),                      # was [1 m, 0 m]
    ["1", "2"],                                   # text
    np.array(["2020-01-01"], dtype="datetime64[D]"),  # was 18262 m
])
def test_scan_refuses_ranges_that_are_not_real_numbers(ranges: object) -> None:
    with pytest.raises(ScanError, match="^ranges: must be real numbers"):
        Scan(ranges, **GEOM)  # type: ignore[arg-type]


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


def test_read_log_of_a_device_is_refused_at_once() -> None:
    """/dev/zero exists but is no file: refused by name, not read (no hang, no memory)."""
    with pytest.raises(FileNotFoundError, match="/dev/zero is not a regular file"):
        read_log("/dev/zero")


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


def test_write_log_bag_with_a_bad_record_leaves_no_bag(tmp_path) -> None:
    path = tmp_path / "run.bag"
    with pytest.raises(InputError, match=r"^records\[1\]: expected an lms200.Record, got int"):
        write_log(path, [_records(1)[0], 1])  # type: ignore[list-item]
    assert not path.exists()


@pytest.mark.parametrize("path_of, records, fmt, message", [
    (lambda d: d, "good", None, "^path: .* is not a regular file"),          # was IsADirectoryError
    (lambda d: d / "missing" / "x.log", "good", None, "^path: the folder .* does not exist"),  # was FileNotFoundError
    (lambda d: "/dev/full", "good", None, "^path: /dev/full exists and is not a regular file"),  # was OSError ENOSPC
    (lambda d: d / "x.log", None, None, "^records: must be an iterable"),    # was TypeError
    (lambda d: d / "x.log", "good", "xyz", "^fmt: must be"),                  # was a bare ValueError
])
def test_write_log_bad_paths_and_arguments(tmp_path, path_of, records, fmt, message: str) -> None:
    recs = _records(2) if records == "good" else records
    with pytest.raises(InputError, match=message):
        write_log(path_of(tmp_path), recs, fmt=fmt)
