"""Property-based robustness of the CARMEN reader (``read_log`` and its line parser).

Random edits of valid FLASER / ROBOTLASER1 / RAWLASER1 / ODOM / TRUEPOS / PARAM lines (tokens
dropped, duplicated or replaced by nan, inf, -1, 1e308, 1e400, a count of 10**12, non-ASCII, NUL;
lines truncated, joined, ended by CRLF, a lone CR inserted) either read or raise a LogFormatError naming the file and
a line; never another exception, a hang, or memory beyond the file's lines. With
``skip_bad_lines``, no laser line left alone is lost: each is read as it was written."""

from __future__ import annotations

import bz2
import gzip
import lzma
import os
import tempfile

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lms200 import LogFormatError, read_log
from lms200.errors import LmsbenchError

SETTINGS = dict(deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
REPLACEMENTS = ["nan", "NaN", "inf", "-inf", "+Infinity", "-1", "-0", "0", "1e308", "-1e308", "1e400", "5e-324",
                "1000000000000", "9" * 40, "1_0", "0x10", "", "\x00", "caf\u00e9", "\u00ff\u00fe", "\ufeff1",
                "FLASER", "#", "1e-320", "3.000000000000000000001"]


def rng_ranges(rng: np.random.Generator, n: int, units: str) -> list[str]:
    decimals = 3 if units == "mm" else 2
    values = rng.uniform(0.1, 8.0, n)
    return [f"{v:.{decimals}f}" for v in values]


def flaser_log(rng: np.random.Generator, scans: int) -> list[str]:
    n = 181
    lines = ["# a FLASER log", "PARAM lmsbench_range_units cm lmsbench 0", "PARAM laser_front_laser_resolution 1 lmsbench 0",
             "PARAM laser_front_laser_fov 180 lmsbench 0", "PARAM robot_front_laser_max 81.83 lmsbench 0"]
    for i in range(scans):
        t = 10.0 + 0.1 * i
        lines.append(f"ODOM {0.1 * i:.3f} 0 0 0 0 0 {t - 0.05:.3f} host {t - 0.05:.3f}")
        lines.append(f"TRUEPOS {0.1 * i:.3f} 0 0 {0.1 * i:.3f} 0 0 {t:.3f} host {t:.3f}")
        lines.append(f"FLASER {n} {' '.join(rng_ranges(rng, n, 'cm'))} {0.1 * i:.3f} 0 0 {0.1 * i:.3f} 0 0 {t:.3f} host {t:.3f}")
    return lines


def robotlaser_log(rng: np.random.Generator, scans: int) -> list[str]:
    n = 361
    lines = ["PARAM lmsbench_range_units mm lmsbench 0", "PARAM lmsbench_range_min 0.01 lmsbench 0"]
    for i in range(scans):
        t = 20.0 + 0.1 * i
        lines.append(f"ODOM {0.1 * i:.3f} 0 0 0 0 0 {t - 0.05:.3f} host {t - 0.05:.3f}")
        lines.append(f"ROBOTLASER1 0 -1.570796 3.141593 0.008727 8.183 0.001 0 {n} {' '.join(rng_ranges(rng, n, 'mm'))} 0 "
                     f"0 0 0 {0.1 * i:.3f} 0 0 0 0 0 0 0 {t:.3f} host {t:.3f}")
    return lines


def rawlaser_log(rng: np.random.Generator, scans: int) -> list[str]:
    n = 181
    lines = ["PARAM lmsbench_range_units cm lmsbench 0"]
    for i in range(scans):
        t = 30.0 + 0.1 * i
        lines.append(f"ODOM {0.1 * i:.3f} 0 0 0 0 0 {t - 0.05:.3f} host {t - 0.05:.3f}")
        lines.append(f"RAWLASER1 0 -1.570796 3.141593 0.017453 81.83 0.01 0 {n} {' '.join(rng_ranges(rng, n, 'cm'))} 0 "
                     f"{t:.3f} host {t:.3f}")
    lines.append(f"ODOM 1 0 0 0 0 0 {30.0 + 0.1 * scans:.3f} host 0")
    return lines


LOGS = {"FLASER": flaser_log, "ROBOTLASER1": robotlaser_log, "RAWLASER1": rawlaser_log}


@st.composite
def edit(draw: st.DrawFn, line: str) -> bytes:
    """One line damaged, as bytes (its newline included)."""
    words = line.split(" ")
    kind = draw(st.sampled_from(["drop", "duplicate", "replace", "replace", "truncate", "crlf", "nul", "cr", "bytes", "join"]))
    if kind in ("drop", "duplicate", "replace"):
        # a word among the first 10 or the last 15 (counts, headers, poses, stamps) as often as a range
        i = draw(st.integers(0, len(words) - 1) | st.integers(0, min(9, len(words) - 1))
                 | st.integers(max(0, len(words) - 15), len(words) - 1))
        if kind == "drop":
            del words[i]
        elif kind == "duplicate":
            words.insert(i, words[i])
        else:
            words[i] = draw(st.sampled_from(REPLACEMENTS))
        return (" ".join(words) + "\n").encode("utf-8")
    data = line.encode()
    if kind == "truncate":
        return data[: draw(st.integers(0, len(data)))] + b"\n"
    if kind == "crlf":
        return data + b"\r\n"
    if kind == "join":  # the newline lost: the next line goes on this one
        return data + b" "
    i = draw(st.integers(0, len(data)))
    insert = {"nul": b"\x00", "cr": b"\r"}.get(kind) or draw(st.binary(min_size=1, max_size=6))
    return data[:i] + insert + data[i:] + b"\n"


@st.composite
def damaged_logs(draw: st.DrawFn) -> tuple[str, list[str], bytes, set[int], list[int]]:
    """(laser kind, the log's lines, the damaged file, the damaged lines' numbers in the log, and
    the number in the file of the line each line of the log starts on: a lost or an inserted
    newline moves them)."""
    kind = draw(st.sampled_from(sorted(LOGS)))
    lines = LOGS[kind](np.random.default_rng(draw(st.integers(0, 2**32 - 1))), draw(st.integers(1, 4)))
    chosen = draw(st.sets(st.integers(0, len(lines) - 1), min_size=1, max_size=3))
    out = [draw(edit(line)) if i in chosen else (line + "\n").encode() for i, line in enumerate(lines)]
    where = list(1 + np.cumsum([0] + [part.count(b"\n") for part in out]))
    return kind, lines, b"".join(out), {i + 1 for i in chosen}, where


COMPRESS = {"gzip": lambda b: gzip.compress(b, mtime=0), "bzip2": bz2.compress, "xz": lzma.compress}


@st.composite
def damaged_archives(draw: st.DrawFn) -> bytes:
    """A valid log compressed (gzip, bzip2, xz), then its compressed bytes cut short or hit."""
    kind = draw(st.sampled_from(sorted(LOGS)))
    lines = LOGS[kind](np.random.default_rng(draw(st.integers(0, 2**32 - 1))), draw(st.integers(1, 4)))
    packed = bytearray(COMPRESS[draw(st.sampled_from(sorted(COMPRESS)))]("".join(line + "\n" for line in lines).encode()))
    if draw(st.booleans()):
        return bytes(packed[: draw(st.integers(0, len(packed) - 1))])
    for i in draw(st.sets(st.integers(0, len(packed) - 1), min_size=1, max_size=3)):
        packed[i] ^= draw(st.integers(1, 255))
    return bytes(packed)


def read(data: bytes, skip: bool) -> tuple[list, LmsbenchError | None, str]:
    fd, path = tempfile.mkstemp(suffix=".log")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        reader = read_log(path, skip_bad_lines=skip)
        recs: list = []
        try:
            for rec in reader:
                recs.append(rec)
        except LmsbenchError as exc:
            return recs, exc, path
        return recs, None, path
    finally:
        os.unlink(path)


@settings(max_examples=150, **SETTINGS)
@given(damaged_logs())
def test_a_damaged_log_reads_or_names_the_file_and_a_damaged_line(case) -> None:  # noqa: ANN001
    kind, lines, data, edited, where = case
    recs, exc, path = read(data, skip=False)
    if exc is not None and data.startswith(MAGIC):  # bytes inserted at the start made it look compressed or packed
        assert isinstance(exc, LogFormatError) and exc.line_no in (None, 1), repr(exc)
        return
    if exc is not None and "holds no laser lines" in str(exc):  # the damage took every laser line (a lost
        assert not recs and exc.line_no is None  # newline merged it into an ODOM line): no scan, said as such
        return
    if exc is not None and isinstance(exc, LogFormatError) and exc.line_no is None:  # the whole file (no line)
        assert str(exc).startswith(f"{path}: not a CARMEN log"), repr(exc)
        return
    if exc is not None:
        assert isinstance(exc, LogFormatError), repr(exc)
        assert exc.path == path and str(exc).startswith(f"{path}:{exc.line_no}: ")
        # the line blamed is a damaged one (or the next, which a damaged line that lost its newline
        # took on), or one after a damaged PARAM line (whose value spoils later lines)
        blamed = {n for e in edited for n in range(where[e - 1], where[e] + 1)}
        params = [where[e - 1] for e in edited if lines[e - 1].startswith("PARAM")]
        assert exc.line_no in blamed or (params and min(params) < exc.line_no < where[-1]), (exc.line_no, edited, str(exc))
    for rec in recs:
        assert len(rec.scan) in (181, 361)


MAGIC = (b"\x1f\x8b", b"BZh", b"\xfd7zXZ\x00", b"PK\x03\x04")  # gzip, bzip2, xz, zip (told by these, not by names)


def laser_lines(kind: str, lines: list[str]) -> list[int]:
    return [i + 1 for i, line in enumerate(lines) if line.startswith(kind + " ")]


@settings(max_examples=150, **SETTINGS)
@given(damaged_logs())
def test_skipping_bad_lines_loses_no_laser_line_left_alone(case) -> None:  # noqa: ANN001
    kind, lines, data, edited, _ = case
    clean = "".join(line + "\n" for line in lines).encode()
    want, exc, _ = read(clean, skip=False)
    assert exc is None and len(want) == len(laser_lines(kind, lines))
    if data.startswith(MAGIC):
        return  # bytes inserted at the start made it look compressed or packed: a whole-file error
    got, exc, path = read(data, skip=True)
    assert exc is None, repr(exc)
    joined = {n + 1 for n in edited if data.count(b"\n") < len(lines)}  # a joined line takes the next one with it
    if any(lines[n - 1].startswith("PARAM") for n in edited):
        return  # a damaged PARAM line changes how the lines after it read
    untouched = [rec for rec, n in zip(want, laser_lines(kind, lines)) if n not in edited and n not in joined]
    got_stamps = {rec.scan.stamp: rec for rec in got}
    for rec in untouched:
        assert rec.scan.stamp in got_stamps, f"laser line at {rec.scan.stamp} lost"
        assert got_stamps[rec.scan.stamp].scan == rec.scan


@settings(max_examples=100, **SETTINGS)
@given(damaged_archives(), st.booleans())
def test_damaged_compressed_data_reads_or_names_the_file_and_the_line(data: bytes, skip: bool) -> None:
    recs, exc, path = read(data, skip=skip)
    if exc is not None:
        assert isinstance(exc, LogFormatError), repr(exc)
        assert exc.path == path and str(exc).startswith(f"{path}:{exc.line_no}: " if exc.line_no else f"{path}: ")
        assert exc.line_no is not None or any(s in str(exc) for s in ("archive", "not a CARMEN log", "no laser lines",
                                                                      "no scan read: the pass stopped at line ")), exc
    for rec in recs:
        assert len(rec.scan) in (181, 361)
