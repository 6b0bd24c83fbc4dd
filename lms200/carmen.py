"""CARMEN log files: reader and writer for FLASER, ROBOTLASER1, ODOM, TRUEPOS and PARAM messages.

Formats (one message a line, ``#`` comments, unknown messages skipped):

- ``FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp``;
  no angle fields: 361 beams = -90..+90 deg at 0.5 deg, 180 = -90..+89 deg at 1 deg,
  181 = -90..+90 deg at 1 deg.
- ``ROBOTLASER1 laser_type start_angle fov resolution max_range accuracy remission_mode n r1..rn
  m rem1..remm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety
  side_safety turn_axis ipc_timestamp hostname logger_timestamp``
- ``ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp``
- ``TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp``

Conventions: a scan's ``stamp`` is the message's ipc_timestamp; ``.odom`` is the robot pose the laser
message carries (FLASER odom fields, ROBOTLASER1 robot fields); ``.truth`` is the pose of a TRUEPOS
line directly preceding the laser message. SICK special codes stored as ranges (81.83 / 81.91 m in
cm mode, 8.183 / 8.191 m in mm mode) map to +inf / nan (REP-117). The range unit comes from the
ROBOTLASER1 accuracy field, a ``PARAM lmsbench_range_units mm|cm`` line (which this writer emits), or,
for FLASER logs without it, from the values themselves (see :func:`infer_units`).
"""

from __future__ import annotations

import gzip
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Iterable, Iterator

import numpy as np

from .codes import (
    CODE_ABOVE_MAXIMUM,
    CODES_INVALID,
    LMS200_MAX_RANGE,
    Units,
    decode_logged_ranges,
    infer_units,
    metres_per_unit,
)
from .errors import LogFormatError
from .records import Pose2D, Record
from .scan import Scan, snap_angle

UNITS_PARAM = "lmsbench_range_units"
ODOMETRY_PARAM = "lmsbench_odometry"  # "absent": the pose fields of the scans that follow are not odometry


@dataclass
class ReadStats:
    """What a pass over a log met: message counts and the bad lines skipped (line number, reason)."""

    messages: dict[str, int] = field(default_factory=dict)
    skipped: list[tuple[int, str]] = field(default_factory=list)


def open_text(path: str | Path) -> IO[str]:
    """Open a plain or gzip-compressed text file for reading (by magic bytes, not the name)."""
    path = Path(path)
    with open(path, "rb") as f:
        magic = f.read(2)
    if magic == b"\x1f\x8b":
        return io.TextIOWrapper(gzip.open(path, "rb"), encoding="ascii", errors="replace")
    return open(path, encoding="ascii", errors="replace")


def _flaser_geometry(n: int) -> tuple[float, float]:
    """(angle_min, angle_increment) of a FLASER scan of n beams; raises ValueError otherwise."""
    if n == 361:
        return -math.pi / 2, math.radians(0.5)
    if n in (180, 181):
        return -math.pi / 2, math.radians(1.0)
    if n == 401:
        return -math.radians(50.0), math.radians(0.25)
    raise ValueError(f"FLASER with {n} beams has no known geometry (expected 180, 181, 361 or 401)")


class CarmenReader:
    """Iterate a CARMEN log's laser messages as Records; iterable several times.

    Args:
        path: plain or ``.gz`` CARMEN log.
        skip_bad_lines: skip malformed lines (recorded in ``stats.skipped``) instead of raising.

    Raises:
        LogFormatError: naming the file and line, for a malformed line (unless skipped).
    """

    def __init__(self, path: str | Path, skip_bad_lines: bool = False) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise FileNotFoundError(f"no such log file: {self.path}")
        self.skip_bad_lines = skip_bad_lines
        self.stats = ReadStats()

    def __iter__(self) -> Iterator[Record]:
        self.stats = ReadStats()
        units: Units | None = None
        truth: Pose2D | None = None
        has_odometry = True
        with open_text(self.path) as f:
            line_no = 0
            while True:
                try:
                    line = f.readline()
                except (OSError, EOFError) as exc:  # truncated or corrupt gzip
                    raise LogFormatError(self.path, line_no + 1, f"cannot read on: {exc}") from None
                if not line:
                    break
                line_no += 1
                words = line.split()
                if not words or words[0].startswith("#"):
                    continue
                kind = words[0]
                self.stats.messages[kind] = self.stats.messages.get(kind, 0) + 1
                try:
                    if kind == "PARAM":
                        if len(words) >= 3 and words[1] == UNITS_PARAM:
                            if words[2] not in ("mm", "cm"):
                                raise ValueError(f"{UNITS_PARAM} must be mm or cm, got {words[2]!r}")
                            units = words[2]  # type: ignore[assignment]
                        if len(words) >= 3 and words[1] == ODOMETRY_PARAM:
                            has_odometry = words[2] != "absent"
                    elif kind == "TRUEPOS":
                        truth = _pose(words, 1, "TRUEPOS")
                        _require(len(words) >= 8, "TRUEPOS needs at least 7 numbers")
                    elif kind == "ODOM":
                        _require(len(words) >= 8, "ODOM needs x y theta tv rv accel timestamp")
                        _floats(words[1:8], "ODOM")
                    elif kind in ("FLASER", "ROBOTLASER1"):
                        if kind == "FLASER":
                            scan, odom = _parse_flaser(words, units)
                        else:
                            scan, odom = _parse_robotlaser1(words, units)
                        yield Record(scan=scan, odom=odom if has_odometry else None, truth=truth)
                        truth = None
                except ValueError as exc:
                    if not self.skip_bad_lines:
                        raise LogFormatError(self.path, line_no, f"malformed {kind} line: {exc}") from None
                    self.stats.skipped.append((line_no, f"{kind}: {exc}"))


def _require(ok: bool, reason: str) -> None:
    if not ok:
        raise ValueError(reason)


def _floats(words: list[str], what: str) -> np.ndarray:
    try:
        values = np.array(words, dtype=np.float64)
    except ValueError:
        bad = next(w for w in words if not _is_number(w))
        raise ValueError(f"{what}: {bad!r} is not a number") from None
    return values


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _pose(words: list[str], start: int, what: str) -> Pose2D:
    _require(len(words) >= start + 3, f"{what} needs x y theta")
    x, y, t = _floats(words[start : start + 3], what)
    _require(bool(np.all(np.isfinite([x, y, t]))), f"{what} pose is not finite")
    return (float(x), float(y), float(t))


def _ranges(values: np.ndarray, units: Units | None, what: str) -> tuple[np.ndarray, Units]:
    if np.any(values < 0) or np.any(np.isnan(values)):
        raise ValueError(f"{what}: negative or nan range in the log")
    u = units or infer_units(values)
    return decode_logged_ranges(values, u), u


def _parse_flaser(words: list[str], units: Units | None) -> tuple[Scan, Pose2D]:
    _require(len(words) >= 2, "FLASER needs a beam count")
    n = int(_floats(words[1:2], "beam count")[0])
    _require(n > 0 and len(words) == n + 11, f"FLASER with {n} beams needs {n + 11} fields, got {len(words)}")
    ranges, u = _ranges(_floats(words[2 : 2 + n], "FLASER ranges"), units, "FLASER")
    tail = _floats(words[2 + n : 2 + n + 7], "FLASER poses and timestamp")
    angle_min, increment = _flaser_geometry(n)
    scan = Scan(ranges, angle_min, increment, 0.0, LMS200_MAX_RANGE[u], float(tail[6]))
    return scan, (float(tail[3]), float(tail[4]), float(tail[5]))


def _parse_robotlaser1(words: list[str], units: Units | None) -> tuple[Scan, Pose2D]:
    _require(len(words) >= 10, "ROBOTLASER1 is too short")
    head = _floats(words[1:9], "ROBOTLASER1 header")
    start, _fov, resolution, max_range, accuracy = head[1:6]
    n = int(head[7])
    _require(n > 0 and len(words) > 9 + n, f"ROBOTLASER1 announces {n} beams but has fewer fields")
    m = int(_floats(words[9 + n : 10 + n], "remission count")[0])
    expected = 10 + n + m + 14
    _require(m >= 0 and len(words) == expected, f"ROBOTLASER1 with {n} ranges and {m} remissions needs {expected} fields, got {len(words)}")
    _require(resolution > 0, f"angular resolution must be > 0, got {resolution}")
    if units is None and accuracy in (0.01, 0.001):
        units = "cm" if accuracy == 0.01 else "mm"
    ranges, _ = _ranges(_floats(words[9 : 9 + n], "ROBOTLASER1 ranges"), units, "ROBOTLASER1")
    tail = _floats(words[10 + n + m : 10 + n + m + 12], "ROBOTLASER1 poses and timestamp")
    range_max = float(max_range) if max_range > 0 else LMS200_MAX_RANGE["cm"]
    scan = Scan(ranges, snap_angle(start), snap_angle(resolution), 0.0, range_max, float(tail[11]))
    return scan, (float(tail[3]), float(tail[4]), float(tail[5]))


# ---------------------------------------------------------------------------------------------
def _units_of(scan: Scan) -> Units:
    return "mm" if scan.range_max <= LMS200_MAX_RANGE["mm"] + 1e-9 else "cm"


def _format_ranges(scan: Scan, units: Units) -> str:
    """Ranges rounded to the unit, with +inf / nan written as the SICK codes 8183 / 8191."""
    scale = metres_per_unit(units)
    decimals = 3 if units == "mm" else 2
    r = np.where(np.isposinf(scan.ranges), CODE_ABOVE_MAXIMUM * scale, scan.ranges)
    r = np.where(np.isnan(r), CODES_INVALID[-1] * scale, r)
    return " ".join(f"{v:.{decimals}f}" for v in r)


def _pose_text(pose: Pose2D | None) -> str:
    x, y, t = pose if pose is not None else (0.0, 0.0, 0.0)
    return f"{x:.6f} {y:.6f} {t:.6f}"


def write_carmen(
    path: str | Path,
    records: Iterable[Record],
    fmt: str = "robotlaser1",
    hostname: str = "lmsbench",
    flush: bool = False,
) -> int:
    """Write Records as a CARMEN log (plain, or gzip when the name ends in ``.gz``).

    Each scan becomes one FLASER or ROBOTLASER1 line (``fmt``), preceded by a TRUEPOS line when the
    record has a true pose. Ranges are written at the sensor unit (mm when range_max <= 8.183 m,
    else cm), +inf / nan as SICK codes 8183 / 8191; a ``PARAM lmsbench_range_units`` line records
    the unit, and ``PARAM lmsbench_odometry absent|present`` lines mark records without odometry
    (their pose fields are written as zeros). ``flush=True`` pushes every scan to the file as soon
    as it is written (for recorders: a crash or Ctrl-C loses nothing already received).
    Returns the number of scans written.
    """
    if fmt not in ("robotlaser1", "flaser"):
        raise ValueError(f"fmt: must be 'robotlaser1' or 'flaser', got {fmt!r}")
    path = Path(path)
    opener = gzip.open if path.suffix == ".gz" else open
    count = 0
    units: Units | None = None
    odometry: bool | None = None
    with opener(path, "wt", encoding="ascii") as f:  # type: ignore[operator]
        f.write("# CARMEN log written by lmsbench\n")
        f.write("# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp\n")
        f.write("# ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy remission_mode num_readings [range_readings] num_remissions [remissions] laser_pose_x laser_pose_y laser_pose_theta robot_pose_x robot_pose_y robot_pose_theta laser_tv laser_rv forward_safety_dist side_safty_dist turn_axis ipc_timestamp hostname logger_timestamp\n")
        for rec in records:
            scan = rec.scan
            u = _units_of(scan)
            if units is None:
                units = u
                f.write(f"PARAM {UNITS_PARAM} {units} {hostname} 0\n")
            elif u != units:
                raise ValueError(f"records: scan at {scan.stamp} is in {u} mode, earlier scans in {units}")
            if odometry is None or odometry != (rec.odom is not None):
                odometry = rec.odom is not None
                f.write(f"PARAM {ODOMETRY_PARAM} {'present' if odometry else 'absent'} {hostname} 0\n")
            stamp = f"{scan.stamp:.6f} {hostname} {scan.stamp:.6f}"
            if rec.truth is not None:
                f.write(f"TRUEPOS {_pose_text(rec.truth)} {_pose_text(rec.odom)} {stamp}\n")
            ranges = _format_ranges(scan, u)
            odom = _pose_text(rec.odom)
            if fmt == "flaser":
                geometry = (scan.angle_min, scan.angle_increment)
                try:
                    known = _flaser_geometry(len(scan))
                except ValueError:
                    known = None
                if known is None or not np.allclose(geometry, known, atol=1e-9):
                    raise ValueError(
                        f"records: FLASER cannot carry a {len(scan)}-beam scan from {math.degrees(scan.angle_min):.2f} deg "
                        f"at {math.degrees(scan.angle_increment):.3f} deg; use fmt='robotlaser1'"
                    )
                f.write(f"FLASER {len(scan)} {ranges} {odom} {odom} {stamp}\n")
            else:
                fov = scan.angle_max - scan.angle_min
                f.write(
                    f"ROBOTLASER1 0 {scan.angle_min:.6f} {fov:.6f} {scan.angle_increment:.6f} "
                    f"{scan.range_max:.6f} {metres_per_unit(u):.6f} 0 {len(scan)} {ranges} 0 "
                    f"{odom} {odom} 0.000000 0.000000 0.000000 0.000000 0.000000 {stamp}\n"
                )
            count += 1
            if flush:
                f.flush()
    return count
