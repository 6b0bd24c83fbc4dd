"""What a pass over a CARMEN log keeps about bad lines stays bounded on any input: the first
``MAX_SKIPPED_KEPT`` skipped lines with their reasons (all counted), reasons cut, and the
ROBOTLASER geometries remembered (1,000,000 bad lines of one kind, each kept, peaked at 190-264 MB
traced, 221-299 MB resident; 1,000,000 distinct geometries at 407 MB resident)."""

from __future__ import annotations

import io

import pytest

from experiments.logargs import report_skipped
from lms200 import read_log
from lms200.carmen import MAX_GEOMETRIES
from lms200.errors import LogFormatError
from lms200.records import MAX_REASON_CHARS, MAX_SKIPPED_KEPT

GOOD = "FLASER 3 1.00 2.00 3.00 0 0 0 0 0 0 {t} h {t}\n"
BAD = [  # one of each kind of malformed line a FLASER log can hold, each with its reason
    ("FLASER 3 1.00 x{i} 3.00 0 0 0 0 0 0 1 h 1\n", "FLASER: FLASER ranges: 'x{i}' is not a number"),
    ("FLASER inf 1.00 {i}\n", "FLASER: beam count must be a non-negative integer written in digits, got 'inf'"),
    ("ODOM 0 0 1e400 0 0 0 {i} h {i}\n", "ODOM: ODOM: '1e400' is beyond float64's range"),
    ("TRUEPOS nan 0 0 0 0 0 {i} h {i}\n", "TRUEPOS: TRUEPOS pose is not finite"),
    ("PARAM robot_front_laser_max -{i} h 0\n", "PARAM: robot_front_laser_max must be a finite number > 0, got '-{i}'"),
]


def test_a_pass_keeps_the_first_skipped_lines_and_counts_them_all(tmp_path) -> None:
    # was: every skipped line kept with its reason: 1,000,000 bad lines of one kind peaked at 190-264 MB
    n = 2 * MAX_SKIPPED_KEPT + 7
    path = tmp_path / "bad.log"
    path.write_text(GOOD.format(t=0.5) + "".join(BAD[i % len(BAD)][0].format(i=i) for i in range(n)) + GOOD.format(t=1.5))
    reader = read_log(path, skip_bad_lines=True)
    assert [r.scan.stamp for r in reader] == [0.5, 1.5]
    stats = reader.stats
    assert stats.skipped_count == n and len(stats.skipped) == MAX_SKIPPED_KEPT and stats.stopped is None
    assert stats.skipped == [(i + 2, BAD[i % len(BAD)][1].format(i=i)) for i in range(MAX_SKIPPED_KEPT)]
    out = io.StringIO()
    assert report_skipped(reader, out) == n
    assert out.getvalue().splitlines()[0] == f"{path}: skipped {n} bad lines"
    assert out.getvalue().splitlines()[-1] == f"  ... and {n - 3} more"


def test_a_kept_reason_is_cut_and_the_error_is_whole(tmp_path) -> None:
    word = "y" * 10_000
    path = tmp_path / "long.log"
    path.write_text(GOOD.format(t=0.5) + f"FLASER 3 1.00 {word} 3.00 0 0 0 0 0 0 1 h 1\n")
    reason = f"FLASER ranges: '{word}' is not a number"
    with pytest.raises(LogFormatError) as err:
        list(read_log(path))
    assert str(err.value) == f"{path}:2: malformed FLASER line: {reason}"
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == 1
    kept = f"FLASER: {reason}"
    assert reader.stats.skipped == [(2, f"{kept[:MAX_REASON_CHARS]}... ({len(kept)} characters)")]


def _robotlaser(start: str, n: int, t: int) -> str:
    # fov 3.1415926 at resolution 1.5707963 holds 2 steps: 3 beams (n - 1 steps) or 2 (n steps)
    return (f"ROBOTLASER1 0 {start} 3.1415926 1.5707963 80 0.01 0 {n} {' '.join(['1.00'] * n)} 0 "
            f"0 0 0 0 0 0 0 0 0 0 0 {t} h {t}\n")


def test_the_robotlaser_geometries_a_pass_remembers_are_bounded(tmp_path) -> None:
    # was: every declared geometry remembered: 1,000,000 lines of distinct start angles, 407 MB resident
    starts = [f"-1.{k:07d}" for k in range(MAX_GEOMETRIES + 20)]
    lines = [_robotlaser(s, 3, k) for k, s in enumerate(starts)]
    lines += [_robotlaser(starts[0], 2, 1000), _robotlaser(starts[MAX_GEOMETRIES - 1], 2, 1001),
              _robotlaser(starts[MAX_GEOMETRIES + 5], 2, 1002)]
    path = tmp_path / "geometries.log"
    path.write_text("".join(lines))
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == len(starts) + 1  # the geometry met after the first MAX_GEOMETRIES is not held to a count
    assert reader.stats.skipped == [
        (len(starts) + 1 + k, f"ROBOTLASER1: carries 2 beams, but line {first} with the same start angle, field of view "
                              "and resolution carries 3") for k, first in enumerate([1, MAX_GEOMETRIES])]


def test_pose_less_scans_waiting_for_odometry_are_bounded_by_their_beams(tmp_path, monkeypatch) -> None:
    """The wrong-input hunt (bounded memory): RAWLASER scans wait for the ODOM line after them, at
    most 256 of them whatever their size: 256 scans of one stamp of 314,000 beams each (the longest
    line the reader takes) were held, 1.33 GB resident for a 188 MB log (74 MB when stamped 1 s
    apart). Now they are held up to 2^20 beams too (lms200.carmen_odom.MAX_PENDING_BEAMS; here 20,000
    for a small file): the same records, in order, with a peak a fraction of the log's."""
    import math
    import tracemalloc

    from lms200 import carmen_odom

    n = 10_000
    fov = math.pi
    line = f"RAWLASER1 0 {-fov / 2:.6f} {fov:.6f} {fov / n:.9f} 80.0 0.01 0 {n} " + "1.00 " * n + "0 5.0 host 5.0\n"
    path = tmp_path / "raw.log"
    path.write_text(line * 60)
    monkeypatch.setattr(carmen_odom, "MAX_PENDING_BEAMS", 2 * n, raising=False)
    tracemalloc.start()
    count = 0
    for rec in read_log(path):
        count += 1
        assert rec.odom is None and len(rec.scan) == n
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert count == 60
    assert peak < 60 * n * 8  # 4.8 MB, the 60 scans' ranges; now 3.0 MB, old: 11.8 MB (every scan held)
