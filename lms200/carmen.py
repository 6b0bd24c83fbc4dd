"""CARMEN log files: reader and writer for FLASER / RLASER, ROBOTLASER1 / 2, ODOM, TRUEPOS and PARAM.

Formats (one message a line, ``#`` comments; messages of other kinds, named in capitals, digits and ``_``
(NEFF, NMEA, SYNC, ...), are skipped, and a line that starts with no such name is malformed):

- ``FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp``
  (RLASER: the rear laser, same fields); no angle fields: the geometry comes from an override, the
  log's PARAM lines or the CARMEN convention from the count (:mod:`lms200.laser_geometry`).
- ``ROBOTLASER1 laser_type start_angle fov resolution max_range accuracy remission_mode n r1..rn
  m rem1..remm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety
  side_safety turn_axis ipc_timestamp hostname logger_timestamp`` (ROBOTLASER2: the rear laser);
  the declared field of view must hold the count at the declared resolution (fov = n x res, or
  (n - 1) x res), lines with the same declared geometry must carry the same count (of the first
  ``MAX_GEOMETRIES`` geometries a pass meets), max_range
  must lie in [MIN_RANGE_MAX_M, MAX_RANGE_M] and the resolution be at least MIN_RESOLUTION_RAD
  (:mod:`lms200.laser_geometry`).
- ``RAWLASER1`` .. ``RAWLASER4`` (CARMEN 0.7 loggers): the ROBOTLASER1 fields up to the remissions,
  then ``ipc_timestamp hostname logger_timestamp``; no poses, same checks: ``.odom`` is interpolated
  from the ODOM lines around the scan's stamp (:mod:`lms200.carmen_odom`), else None.
- ``ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp``
- ``TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp``

After the ipc_timestamp, lines of other writers may hold nothing, one word, or a hostname of several words
before the logger_timestamp (:func:`_tail_fits`); the laser lines of a pass must end alike (:class:`_Tails`).

Conventions: a record's poses are the laser's: the robot's moved by the laser's mounting on it (FLASER /
RLASER, ROBOTLASER1 / 2: the log's ``PARAM robot_frontlaser_*`` / ``robot_rearlaser_*`` lines,
:func:`laser_mount`, never a ROBOTLASER line's own laser pose; docs/data.md, "Laser mounting"), each
untouched where that is zero. A scan's ``stamp`` is the message's ipc_timestamp; ``.odom`` is the robot pose the laser
message carries (FLASER odom fields, ROBOTLASER1 robot fields); ``.truth`` is the pose of the last TRUEPOS
line before the laser message (ODOM, PARAM, other laser kinds between do not matter), when no laser line of
the kind read (even a malformed one) came between and their ipc_timestamps lie within TRUTH_MAX_GAP_S. SICK special codes stored as ranges (81.83 / 81.91 m in
cm mode, 8.183 / 8.191 m in mm mode) map to +inf / nan (REP-117). The range unit comes from the
ROBOTLASER1 accuracy field, a ``PARAM lmsbench_range_units mm|cm`` line (which this writer emits), or,
for FLASER logs without it, from the values themselves (see :func:`infer_units`). No CARMEN laser line
carries a ``range_min``: a scan's is 0 unless a ``PARAM lmsbench_range_min`` line (which this writer
emits wherever a scan's range_min differs from the one before, starting from 0: none for scans at 0)
gives it for the laser lines that follow.

One laser is read per pass (``topic``: a message kind); by default the first kind that carries
poses (FLASER, RLASER, ROBOTLASER1 / 2; from a line whose fields add up to its counts) up to
``DEFAULT_TOPIC_LINES`` lines after the first laser line, else the first RAWLASER kind: CARMEN 0.7 loggers write each reading twice, as RAWLASER1 and as ROBOTLASER1.
Every failure while reading (a malformed line, a count that is not a non-negative integer written in digits,
compressed data that cannot be decompressed, a line over ``MAX_LINE_CHARS``) is a ``LogFormatError`` naming
file and line; ``skip_bad_lines`` records it in ``stats.skipped`` (the first
``lms200.records.MAX_SKIPPED_KEPT``; ``stats.skipped_count`` counts them all) and goes on.
"""

from __future__ import annotations

import bz2
import difflib
import gzip
import io
import lzma
import math
import os
import re
import stat
import tarfile
import warnings
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Callable, Iterable, Iterator

import numpy as np

from .carmen_odom import CorrectedChain, OdomPairing, compose
from .codes import (
    CODE_ABOVE_MAXIMUM,
    CODE_NOT_VALID,
    CODES_INVALID,
    LMS200_MAX_RANGE,
    Units,
    decode_logged_ranges,
    finite_negative,
    infer_units,
    metres_per_unit,
)
from . import laser_geometry
from .errors import InputError, LmsbenchError, LmsbenchWarning, LogFormatError, LogNotFoundError
from .finite import fixed, is_one_of, underflow_problem
from .laser_geometry import LaserGeometry
from .records import MAX_COORD_M, MAX_HEADING_RAD, Pose2D, Record, SkipLog, pose_problem, stamp_problem  # noqa: F401 - carmen's names too
from .scan import Scan, snap_angle, valid_ranges
from .units import WatchedPasses

UNITS_PARAM = "lmsbench_range_units"
ODOMETRY_PARAM = "lmsbench_odometry"  # "absent": the pose fields of the scans that follow are not odometry
RANGE_MIN_PARAM = "lmsbench_range_min"  # m: range_min of the scans that follow (no CARMEN laser line has the field; 0 without it)
#: "exact": the start angle and resolution of the ROBOTLASER / RAWLASER lines that follow are taken as
#: written, not snapped onto the 0.05 deg grid (``snap_angle``), which the writer emits before the first
#: scan whose angles snapping would move (an angle_min 3e-7 rad off the grid read back on it); "grid": snapped again
EXACT_ANGLES_PARAM = "lmsbench_robotlaser_angles"
#: rad, exactly as written (the CARMEN PARAM lines are in degrees, which do not round-trip: -0.1 rad read
#: back as -0.10000000000000002): a FLASER / RLASER scan's (angle_min, angle_increment), used where they
#: agree with the geometry the other PARAM lines (or an override) give to within EXACT_GEOMETRY_AGREEMENT
EXACT_GEOMETRY_NAMES = {
    "FLASER": ("lmsbench_front_laser_angle_min", "lmsbench_front_laser_angle_increment"),
    "RLASER": ("lmsbench_rear_laser_angle_min", "lmsbench_rear_laser_angle_increment"),
}
EXACT_GEOMETRY_PARAMS = frozenset(n for names in EXACT_GEOMETRY_NAMES.values() for n in names)
EXACT_GEOMETRY_AGREEMENT = 1e-12  # rad, relative to max(1, |angle|): degrees to radians and back differ by ~1e-16
#: CARMEN's robot-module PARAM lines that place a FLASER / RLASER laser on the robot: (forward offset m,
#: side offset m (to the left), angular offset rad). Logs of CARMEN before 0.7 (Intel, ACES) carry only the
#: first (``robot_frontlaser_offset``, ``robot_rearlaser_offset``); 0.7 added the side and angular ones
#: (docs/data.md, "Laser mounting")
MOUNT_PARAM_NAMES = {
    "FLASER": ("robot_frontlaser_offset", "robot_frontlaser_side_offset", "robot_frontlaser_angular_offset"),
    "RLASER": ("robot_rearlaser_offset", "robot_rearlaser_side_offset", "robot_rearlaser_angular_offset"),
}
MOUNT_PARAMS = frozenset(n for names in MOUNT_PARAM_NAMES.values() for n in names)
POSED_LASER_KINDS = ("FLASER", "RLASER", "ROBOTLASER1", "ROBOTLASER2")  # laser messages that carry poses
RAW_LASER_KINDS = ("RAWLASER1", "RAWLASER2", "RAWLASER3", "RAWLASER4")  # laser messages without poses
LASER_KINDS = POSED_LASER_KINDS + RAW_LASER_KINDS  # laser messages read (one kind per pass)
#: why a pipe (``<(zcat LOG)``, a named pipe) is refused: a log is read more than once, which a pipe cannot be
PIPE_REASON = ("a log is read more than once (its first lines to choose the laser, then every line; compare and "
               "sim2real read it again, for its noise), which a pipe cannot be: give the log file itself (gzip, "
               "bzip2 and xz logs are read as they are) or save the stream to a file first (zcat LOG > FILE)")
DEFAULT_TOPIC_LINES = 10_000  # lines looked at to choose the default laser kind (and to tell junk from a log)
_MESSAGE_NAME = re.compile(r"[A-Z][A-Z0-9_]{2,}")  # how every CARMEN message line starts (ODOM, PARAM, FLASER, ...; a lone capital in binary junk is none)
# a TRUEPOS pose is the truth of the next scan of the kind read when their ipc_timestamps lie within
# this (s): CARMEN's simulator logs them within a cycle (~0.1 s); a TRUEPOS long before its scan is stale
TRUTH_MAX_GAP_S = 0.5
KNOWN_KINDS = frozenset(LASER_KINDS + ("ODOM", "TRUEPOS", "PARAM"))  # messages this reader reads
MAX_MESSAGE_KINDS = 64  # message kinds counted by name in ReadStats.messages (the kinds above always)
OTHER_KINDS = "other"  # where lines of further kinds are counted
ROBOTLASER_FIT_TOLERANCE_BEAMS = 0.5  # declared fov / resolution must be n or n - 1 steps to within this
#: declared ROBOTLASER geometries (start, fov, resolution as written) a pass remembers with their beam
#: count, to hold later lines of the same geometry to it: a log has a few; 1,000,000 lines of distinct
#: start angles were each remembered (407 MB resident; now 30 MB)
MAX_GEOMETRIES = 64
MAX_LINE_CHARS = 1 << 20  # a longer line is malformed (bounds memory on damaged files)
#: most blank or comment lines in a row a log may hold: a log's header comments are tens of lines, and a
#: gzip of 100 MB of blank lines was read twice to its end (48 s) to say it held no laser line
MAX_BLANK_RUN = 100_000
#: most lines that start with no message name a pass skips (``skip_bad_lines``) before it ends as junk
#: (``stats.stopped``): 1,000,000 junk lines, each skipped and recorded, peaked at 289 MB
MAX_JUNK_LINES = 10_000
READ_ERRORS = (OSError, EOFError, zlib.error, lzma.LZMAError)  # what damaged or truncated compressed data raises
# compressed logs are read in place, told apart by their first bytes (not their names)
COMPRESSIONS = {"gzip": (b"\x1f\x8b", gzip.open), "bzip2": (b"BZh", bz2.open), "xz": (b"\xfd7zXZ\x00", lzma.open)}
COMPRESSION_SUFFIXES = {".gz": "gzip", ".bz2": "bzip2", ".xz": "xz"}


@dataclass
class ReadStats(SkipLog):
    """What a pass over a log met.

    Attributes:
        messages: lines per message kind, read or not: every kind this reader knows, other kinds up
            to ``MAX_MESSAGE_KINDS`` of them (the rest under ``OTHER_KINDS``, "other").
        skipped: the bad lines skipped under ``skip_bad_lines``: (line number, reason), the first
            ``lms200.records.MAX_SKIPPED_KEPT`` of them; ``skipped_count`` counts them all.
        stopped: why reading ended early (undecompressable data under ``skip_bad_lines``), or None.
        laser: the laser message kind read (see ``topic``), None before the first one.
        mount: the laser's mounting on the robot (x m, y m, theta rad; :func:`laser_mount`) the last
            record given was moved onto, where one was not zero, else None (the last one only: ``mount_changes``
            says whether it varied); ``mounted``: records so moved.
        mount_changes: times a laser line of the kind read had another mounting than the one before it
            (a mounting PARAM line between them: it applies from its line on, so the scans before are in
            another frame); ``mount_changed_at``: the line number of the mounting PARAM line that made the
            first change, ``mount_before``: the mounting before it; None without a change.
    """

    messages: dict[str, int] = field(default_factory=dict)
    stopped: str | None = None
    laser: str | None = None
    mount: Pose2D | None = None
    mounted: int = 0
    mount_changes: int = 0
    mount_changed_at: int | None = None
    mount_before: Pose2D | None = None

    def count(self, kind: str) -> None:
        """Count a line of a message kind: the kinds this reader knows always, others up to
        ``MAX_MESSAGE_KINDS`` of them, then under ``OTHER_KINDS`` (1,000,000 unique names peaked at 88 MB)."""
        messages = self.messages
        if kind not in messages and kind not in KNOWN_KINDS and len(messages) >= MAX_MESSAGE_KINDS:
            kind = OTHER_KINDS
        messages[kind] = messages.get(kind, 0) + 1

    def other_lasers(self) -> dict[str, int]:
        """Laser message kinds in the log that were not read (kind -> lines)."""
        return {k: n for k, n in self.messages.items() if k in LASER_KINDS and k != self.laser}


UTF8_BOM = b"\xef\xbb\xbf"  # byte-order mark some editors put before a text file's first line


def compression(head: bytes) -> str | None:
    """The compression ("gzip", "bzip2", "xz") a file's first bytes announce, or None (plain)."""
    return next((name for name, (magic, _) in COMPRESSIONS.items() if head.startswith(magic)), None)


def open_bytes(path: str | Path) -> IO[bytes]:
    """Open a plain, gzip-, bzip2- or xz-compressed file for reading its (decompressed) bytes."""
    with open(path, "rb") as f:
        kind = compression(f.read(6))
    return COMPRESSIONS[kind][1](path, "rb") if kind else open(path, "rb")  # type: ignore[operator, return-value]


#: first bytes of packings the reader does not open: named in the error instead of reading them as
#: text (a zstd file, or a gzip of a gzip, was "not a CARMEN log: none of its 1 lines starts with a
#: message name"); gzip, bzip2 and xz here are a second compression inside the first
OTHER_PACKINGS = {b"\x28\xb5\x2f\xfd": "a zstd-compressed file", b"\x04\x22\x4d\x18": "an lz4-compressed file",
                  b"7z\xbc\xaf\x27\x1c": "a 7z archive", b"Rar!\x1a\x07": "a rar archive",
                  b"\x1f\x8b": "a gzip file compressed twice", b"BZh": "a bzip2 file compressed twice",
                  b"\xfd7zXZ\x00": "an xz file compressed twice"}


def archive_kind(head: bytes) -> str | None:
    """"a tar archive (first member ...)" or "a zip archive" when the (decompressed) first bytes
    (4096 name a tar's first member) are an archive's, else None: a log packed in an archive must be extracted first."""
    if head.startswith(b"PK\x03\x04"):
        return "a zip archive"
    packed = next((what for magic, what in OTHER_PACKINGS.items() if head.startswith(magic)), None)
    if packed:  # was "not a CARMEN log: none of its 1 lines starts with a message name"
        return packed
    if len(head) >= 262 and head[257:262] == b"ustar":
        try:  # the first member's header (and a pax header before it) lies in the first blocks
            with tarfile.open(fileobj=io.BytesIO(head), mode="r:") as tar:
                member = tar.next()
        except (tarfile.TarError, EOFError, OSError):
            member = None
        return f"a tar archive (first member {member.name!r})" if member else "a tar archive"
    return None


def open_text(path: str | Path) -> IO[str]:
    """Open a plain or compressed (gzip, bzip2, xz) text file for reading, by magic bytes, not
    the name; a leading UTF-8 byte-order mark is skipped. Lines end at "\\n" (a lone "\\r" is
    no line end; a "\\r\\n" line keeps its "\\r", whitespace to ``str.split``), or at "\\r" in a
    file whose first line ends at a "\\r" and whose first 4096 bytes hold no "\\n" (classic Mac line
    ends; :func:`_first_line_end`).

    Raises:
        LogFormatError: for an archive (tar, zip): the log must be extracted from it first.
    """
    path = Path(path)
    with open_bytes(path) as f:
        try:
            head = f.read(4096)
            ends = _first_line_end(head, f)
        except READ_ERRORS:
            head = ends = b""  # damaged data: reported with its line by the reader
    what = archive_kind(head)
    if what:
        raise LogFormatError(path, None, f"{what}, not a log: extract the log from it first")
    return text_lines(open_bytes(path), head, ends)


def text_lines(raw: IO[bytes], head: bytes, ends: bytes) -> io.TextIOWrapper:
    """``raw`` (a binary stream at its start, whose first bytes are ``head`` and whose first line ends
    in ``ends``: :func:`_first_line_end`) as text lines, as a CARMEN log's and every row file's are read
    (:func:`open_text`, ``lms200.logs.row_lines``): a leading UTF-8 byte-order mark skipped, ASCII with
    a replacement character for any other byte, lines ending as below."""
    if head.startswith(UTF8_BOM):  # a log saved by a Windows editor: the mark would hide line 1's message name
        raw.read(len(UTF8_BOM))
    # lines end at "\n" alone ("\r\n" too: the "\r" is whitespace to the word split), as the line numbers
    # of an editor or `sed -n Np` count them: the universal-newline default also ended a line at a lone
    # "\r", so a corrupted byte 0x0d split a line in two (both halves malformed, the line lost) and every
    # error after it named the line after the one at fault. A log whose first line ends at a "\r" not
    # followed by "\n" (and whose first 4096 bytes hold no "\n") has classic Mac line ends: its lines end
    # at "\r" (as before)
    mac = b"\r" in ends and b"\n" not in ends
    return io.TextIOWrapper(raw, encoding="ascii", errors="replace", newline=None if mac else "\n")


def _first_line_end(head: bytes, f: IO[bytes]) -> bytes:
    """The bytes that tell a file's line ends (see :func:`open_text`): its first 4096 bytes ``head``,
    read on from ``f`` (up to ``MAX_LINE_CHARS``) while they hold no "\n" and no "\r" followed by
    a byte: a Mac log whose first line passed 4096 bytes (a ROBOTLASER1 line with remissions) was
    read as one line of the whole file ("needs 746 fields, got 14920")."""
    ends = head
    while b"\n" not in ends and b"\r" not in ends[:-1] and len(ends) <= MAX_LINE_CHARS:
        more = f.read(65536)
        if not more:
            break
        ends += more
    return ends


def no_scan_read(stopped: str) -> str:
    """What a log whose pass ended before its first record is told (``ReadStats.stopped``: ``line N:
    why``): a compressed stream damaged from its start, or junk before any laser line
    (``MAX_JUNK_LINES``), said as the reason it stopped, not as a file that cannot be read."""
    return f"no scan read: the pass stopped at {stopped}"


class CarmenReader(WatchedPasses):
    """Iterate a CARMEN log's laser messages as Records; iterable several times.

    Args:
        path: CARMEN log, plain or compressed (gzip, bzip2 or xz, told by the first bytes).
        skip_bad_lines: skip malformed lines (recorded in ``stats.skipped``) instead of raising; a
            compressed stream that cannot be decompressed further, or more than MAX_JUNK_LINES lines
            of junk, ends the pass (``stats.stopped``), and is a LogFormatError where the pass gave no
            record before it (as every command refuses it: :func:`no_scan_read`).
        topic: the laser message kind to read (FLASER, RLASER, ROBOTLASER1 / 2, RAWLASER1 .. 4); by
            default the first kind with poses met in the log, else the first RAWLASER kind (see
            the module docstring; the others are counted in ``stats.messages``).
        geometry: FLASER / RLASER beam geometry that overrides the log's PARAM lines and the
            convention from the count (see :mod:`lms200.laser_geometry`); ROBOTLASER lines carry
            their own, except ``range_max``, which an override replaces there too.

    Raises:
        LogFormatError: naming the file and line, for a malformed line (unless skipped) or data that
            cannot be decompressed (under ``skip_bad_lines``: a pass that ends so, or at the junk
            limit, before any record, "no scan read").
        InputError: a ``topic`` that is no laser kind (the message lists the log's laser lines).
    """

    def __init__(self, path: str | Path, skip_bad_lines: bool = False, topic: str | None = None,
                 geometry: LaserGeometry | None = None) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            if self.path.exists() and stat.S_ISFIFO(self.path.stat().st_mode):
                raise LogNotFoundError(f"{self.path} is not a regular file but a pipe: {PIPE_REASON}")
            what = "is not a regular file (a device or a socket)" if self.path.exists() else "does not exist"
            raise LogNotFoundError(f"no such log file: {self.path} {what}")
        if topic is not None and topic not in LASER_KINDS:  # said "LOG:0: topic: ...", a line the log has not
            counts = self._laser_counts()
            has = (f"its laser lines: {', '.join(f'{k} ({n})' for k, n in counts.items())}" if counts
                   else "it has no laser lines")
            upper = str(topic).strip().upper()
            hint = f" (did you mean {upper}?)" if upper in counts or (upper in LASER_KINDS and not counts) else ""
            raise InputError(f"topic: {topic!r} is not a CARMEN laser message kind ({', '.join(LASER_KINDS)})"
                             f"{hint}; {self.path}: {has}")
        self.skip_bad_lines = skip_bad_lines
        self.topic = topic
        self.geometry = geometry or LaserGeometry()
        self.stats = ReadStats()
        self._held: list[_Held] = []  # the pass's lines held until their tail is told (:meth:`_read`)

    def _laser_counts(self) -> dict[str, int]:
        """Laser message kind -> lines of it in the log, in the order met (one pass, a line's first
        4096 characters at a time; damage ends the count where it is)."""
        counts: dict[str, int] = {}
        try:
            with open_text(self.path) as f:
                start = True  # this piece starts a line
                blank = 0  # blank or comment lines in a row: the count ends after MAX_BLANK_RUN
                for piece in iter(lambda: f.readline(4096), ""):
                    words = piece[:24].split(None, 1) if start else []
                    if words and words[0] in LASER_KINDS:
                        counts[words[0]] = counts.get(words[0], 0) + 1
                    blank = blank + 1 if start and (not words or words[0].startswith("#")) else 0
                    if blank > MAX_BLANK_RUN:
                        break
                    start = piece.endswith("\n")
        except (*READ_ERRORS, UnicodeError):
            pass
        return counts

    def last_stamp(self, largest: bool = False) -> float | None:
        """The ipc_timestamp (s) of the log's last laser line of the kind read (``stats.laser`` after a
        pass, else ``topic`` or the default kind) whose fields add up to its counts, found without
        reading the log's records: a plain file is read from its end back to that line; a compressed
        one is decompressed in one pass, each line only looked at for its message name (MIT CSAIL's
        872 KB gzip: 0.014 s, where reading its records takes 0.28 s). None where there is no such line
        (or the kind cannot be told); where the stream is damaged, the last such line before the damage.
        The last line's stamp is not the log's largest where the stamps go back at its end (lines the
        reader refuses, or drops under ``skip_bad_lines``); ``largest``: the largest stamp of all such
        lines instead, in one pass that parses each line of the kind (MIT CSAIL's gzip: 35 ms)."""
        kind = self.stats.laser or self.topic
        if kind is None:
            try:
                kind = self._survey()
            except LogFormatError:
                return None
        if kind is None:
            return None
        if largest:
            return _largest_stamp(self.path, kind)
        with open(self.path, "rb") as f:
            packed = compression(f.read(6)) is not None
        lines = _compressed_lines_of(self.path, kind) if packed else _lines_from_end(self.path)
        for line in lines:
            stamp = laser_line_stamp(line, kind)
            if stamp is not None:
                return stamp
        return None

    def _no_laser_reason(self, lines: int, quiet: int) -> str:
        """Why a pass that met no laser line (of any kind) is an error, by what the file held: a log
        that gives no scan is a failed recording or download, not a run of no scans (an empty file,
        a gzip of nothing or a file of comments read as no records, silently)."""
        kinds = " (FLASER, RLASER, ROBOTLASER1 / 2, RAWLASER1 .. 4)"
        if lines == 0:
            with open(self.path, "rb") as f:
                packed = compression(f.read(6))
            if packed:
                return f"its {packed} data decompresses to nothing: an empty log, no laser lines{kinds}"
            return f"an empty file (0 bytes): no laser lines{kinds}"
        if quiet == lines:
            return f"holds only blank or comment lines ({lines:,}): no laser lines{kinds}"
        met = ", ".join(f"{k} ({n:,})" for k, n in self.stats.messages.items())
        return f"holds no laser lines{kinds}, only other messages: {met}"

    def _lines(self) -> Iterator[tuple[int, str]]:
        """(line number, text) of every line; damage in the stream becomes LogFormatError."""
        line_no = 0
        with open_text(self.path) as f:
            while True:
                try:
                    line = f.readline(MAX_LINE_CHARS + 1)
                    too_long = len(line) > MAX_LINE_CHARS
                    if too_long and not self.skip_bad_lines:  # refused here, not read to its end first: a gzip
                        self._bad(line_no + 1, "overlong",  # of 4 GB of 'x' after a log's first scans took 42 s
                                  ValueError(f"longer than {MAX_LINE_CHARS} characters"))  # to be refused
                    rest = line  # the overlong line is skipped to its end, which may be the file's
                    while too_long and rest and not rest.endswith("\n"):
                        rest = f.readline(MAX_LINE_CHARS)
                except READ_ERRORS as exc:  # corrupt or truncated gzip data
                    reason = f"cannot read on (damaged or truncated file): {type(exc).__name__}: {exc}"
                    if not self.skip_bad_lines:
                        raise LogFormatError(self.path, line_no + 1, reason) from None
                    self.stats.stopped = f"line {line_no + 1}: {reason}"
                    self._skip(line_no + 1, reason)
                    return
                if not line:
                    return
                line_no += 1
                yield line_no, ("" if too_long else line)
                if too_long:
                    self._bad(line_no, "overlong", ValueError(f"longer than {MAX_LINE_CHARS} characters"))  # not "line line"

    def _bad(self, line_no: int, kind: str, exc: Exception) -> None:
        if not self.skip_bad_lines:
            raise LogFormatError(self.path, line_no, f"malformed {kind} line: {exc}") from None
        self._skip(line_no, f"{kind}: {exc}")

    def _skip(self, line_no: int, reason: str) -> None:
        """Record a skipped line; while laser lines are held until their tail is told (:class:`_Tails`), held
        beside them and recorded when they are released, so that ``stats.skipped`` is in log order (a line
        skipped among held lines was listed before a held line later found malformed: [3, 1])."""
        if self._held:
            self._held.append(_HeldSkip(line_no, reason))
        else:
            self.stats.skip(line_no, reason)

    def _check_override(self, kind: str) -> None:
        """A beam-geometry override for a log whose laser lines carry their own geometry is an
        error (it would be ignored): only range_max applies to ROBOTLASER lines."""
        g = self.geometry
        given = [name for name in ("fov", "resolution", "angle_min") if getattr(g, name) is not None]
        if kind not in ("FLASER", "RLASER") and given:
            raise LmsbenchError(f"{self.path}: its {kind} lines carry their own beam geometry; the override of "
                                f"{', '.join(given)} (--laser-*-deg) applies to FLASER / RLASER lines only")

    def _check_range_max(self, line_no: int, range_min: float) -> None:
        """A range_max override not above the scans' range_min (``PARAM lmsbench_range_min``) is an
        error of the override, not of every laser line (which it made malformed, one by one)."""
        rmax = self.geometry.range_max
        if rmax is not None and rmax <= range_min:
            raise LmsbenchError(f"{self.path}:{line_no}: the range_max override ({rmax:g} m, --laser-range-max) is "
                                f"not above this log's range_min ({range_min:g} m, PARAM {RANGE_MIN_PARAM}); "
                                "give a larger one")

    def _survey(self) -> str | None:
        """The laser kind read by default: the first with poses up to ``DEFAULT_TOPIC_LINES`` lines
        after the first laser line, else the first RAWLASER kind, else None (no laser line). A line
        of a kind with poses whose fields do not add up (:func:`_fields_fit`) chooses no laser: a
        damaged line named FLASER before a log's RAWLASER1 lines made FLASER the laser, and under
        ``skip_bad_lines`` the log gave no record.

        Raises:
            LogFormatError: when none of the first ``DEFAULT_TOPIC_LINES`` lines (comments aside)
                starts with a message name: a text file that is no CARMEN log is refused in
                bounded time instead of being read to its end for nothing.
        """
        raw, named, looked, since_raw = None, False, 0, 0
        blank = _BlankRun(self.path)
        line_no = 0
        starts = chars = 0  # the lines begun (comments aside) among the pieces looked at (a long line's pieces are
        # one), and the characters looked at
        at_start, first_ended = True, False  # the next piece begins a line; the first line (any) has ended
        try:
            with open_text(self.path) as f:
                # junk is told after DEFAULT_TOPIC_LINES lines; a log is looked at until its first laser
                # line and DEFAULT_TOPIC_LINES lines beyond it (a kind with poses may follow RAWLASER)
                while (named or looked < DEFAULT_TOPIC_LINES) and since_raw < DEFAULT_TOPIC_LINES:
                    line = f.readline(4096)  # the first word is enough; a longer line goes on as pieces
                    if not line:
                        break
                    line_no += 1  # pieces of a long line count as lines here: only a bound's place
                    chars += len(line)
                    start, at_start = at_start, line.endswith("\n")
                    first_ended = first_ended or at_start
                    if not start:  # the rest of a long line: counted towards the bound, its words no line's start
                        looked += 1  # (a 512 MB line of junk was "none of its first 10,000 lines ...")
                        since_raw += raw is not None
                        continue
                    words = line[:24].split(None, 1)
                    kind = words[0] if words else ""
                    if not kind or kind.startswith("#"):
                        blank.see(line_no)
                        continue
                    blank.reset()
                    looked += 1
                    starts += 1
                    since_raw += raw is not None
                    named = named or _MESSAGE_NAME.fullmatch(kind) is not None
                    if (kind in POSED_LASER_KINDS and _fields_fit(kind, line)) or (named and self.topic is not None):
                        return kind  # (a given topic is read whatever this returns)
                    raw = raw or (kind if kind in RAW_LASER_KINDS else None)
        except (*READ_ERRORS, UnicodeError):
            return raw  # damage is reported, with its line, by the pass itself
        names = "starts with a message name (FLASER, ROBOTLASER1, PARAM, ODOM, ...)"
        if looked >= DEFAULT_TOPIC_LINES and not named and not first_ended:  # what was seen: one line, unfinished
            raise LogFormatError(self.path, None, f"not a CARMEN log: its first line runs on past {chars:,} characters "
                                                  f"with no line end and {names.replace('with a', 'with no', 1)}")
        if looked >= DEFAULT_TOPIC_LINES and not named:
            first = f"first {DEFAULT_TOPIC_LINES:,} lines" if starts >= DEFAULT_TOPIC_LINES else (
                f"first {starts:,} lines (comments aside; long ones, {chars:,} characters looked at)")
            raise LogFormatError(self.path, None, f"not a CARMEN log: none of its {first} {names}")
        if looked and not named:  # a shorter file, read to its end: it gave no record, silently (binary junk)
            raise LogFormatError(self.path, None, f"not a CARMEN log: none of its {starts:,} lines (comments aside) "
                                                  f"{names}")
        return raw

    def _pass(self) -> Iterator[Record]:
        flushes: list[Callable[[], Iterator[Record]]] = []  # this pass's flush() of what holds records back
        # id(scan) -> the laser's pose on the robot (laser_mount) of each record read and not yet given: its
        # poses are the robot's until the corrected chain and the held tails are done with it (the ODOM
        # lines are the robot's), then the laser's (on_the_laser)
        mounts: dict[int, Pose2D] = {}

        def given(rec: Record) -> Record:
            mount = mounts.pop(id(rec.scan), None)
            moved = on_the_laser(rec, mount)
            if moved is not rec:
                self.stats.mount, self.stats.mounted = mount, self.stats.mounted + 1
            return moved

        n = 0  # records given
        try:
            for rec in self._read(flushes, mounts):
                n += 1
                yield given(rec)
        except Exception:  # a bad line ends the pass: the records held for a later line come first
            for flush in flushes:
                for rec in flush():
                    yield given(rec)
            raise
        if n == 0 and self.stats.stopped is not None:  # wholly damaged under skip_bad_lines: 0 records, silently,
            # where every command refused it (lmsbench info, compare: "no scan read"; a broken head in check_log)
            raise LogFormatError(self.path, None, no_scan_read(self.stats.stopped))

    def _read(self, flushes: list[Callable[[], Iterator[Record]]], mounts: dict[int, Pose2D]) -> Iterator[Record]:
        default = self._survey()
        self.stats = stats = ReadStats(laser=self.topic or default)
        if stats.laser is not None:
            self._check_override(stats.laser)
        units: Units | None = None
        truth: tuple[Pose2D, float] | None = None  # the last TRUEPOS pose and its stamp (s), not yet given
        last_stamp = -math.inf  # the last scan's stamp: a TRUEPOS stamped at or before it is its, not the next's
        has_odometry = True
        params: dict[str, float] = {}
        last_mount: Pose2D | None = None  # the mounting of the last laser line read (mount_changes)
        mount_line: int | None = None  # the last mounting PARAM line
        counts: dict[tuple[str, str, str], tuple[int, int]] = {}  # ROBOTLASER header -> (beams, first line), bounded
        blank = _BlankRun(self.path)
        range_words = _RangeWords()  # range word -> its number (_range_floats), for this pass
        tails = _Tails()  # the words after the laser lines' ipc_timestamps, line by line alike
        junk = 0  # lines that start with no message name
        # RAWLASER lines carry no pose: their odometry is interpolated from the log's ODOM lines
        pairing = OdomPairing() if stats.laser in RAW_LASER_KINDS else None
        # a Radish corrected log: the laser lines' poses are a SLAM solution, the ODOM lines the raw odometry
        chain = CorrectedChain() if pairing is None else None
        # laser lines held until their tail is told (_Tails), with the ODOM lines' (stamp, pose) and the lines
        # skipped among them, given to pairing / chain and recorded in log order when they are released; a held
        # line is taken (its truth given, the last stamp and its geometry's count set) only then: one later found
        # malformed leaves no trace (its stamp, read shifted, dropped the truth of the next scan)
        undecided: list[_Held] = []
        self._held = undecided

        def emit(rec: Record) -> Iterator[Record]:
            if pairing is not None:
                yield from pairing.scan(rec)
            elif chain is not None and stats.laser in ("FLASER", "RLASER"):  # every record's kind: the pass's laser
                yield from chain.laser(rec)
            else:
                yield rec

        def odometry(stamp: float, pose: Pose2D) -> Iterator[Record]:
            if undecided:
                undecided.append((stamp, pose))
            elif pairing is not None:  # odometry for the scans of a RAWLASER kind, which carry none
                yield from pairing.odom(stamp, pose)
            elif chain is not None:
                yield from chain.odom(pose, stamp)

        def held_tails_of(events: list[_Held]) -> list[tuple[int, int]]:
            return [(_Tails.measure(e.words)[0], e.line_no) for e in events if isinstance(e, _HeldLaser)]

        def held_tails() -> list[tuple[int, int]]:
            return held_tails_of(undecided)

        def take(line: _HeldLaser) -> Record:
            """The record of a laser line whose tail is the rule's: its geometry's beam count checked (and set,
            for the first line of a geometry), its truth given, the last stamp set (ValueError: malformed)."""
            nonlocal last_stamp, last_mount
            scan, header = line.scan, line.header
            if header is not None:
                first = counts.get(header)
                if first is None and len(counts) < MAX_GEOMETRIES and max(map(len, header)) <= MAX_CACHED_WORD_CHARS:
                    first = counts[header] = (len(scan), line.line_no)
                if first is not None:
                    _require(first[0] == len(scan),
                             f"carries {len(scan)} beams, but line {first[1]} with the same start angle, "
                             f"field of view and resolution carries {first[0]}")
            pose = line.truth
            given = (pose[0] if pose is not None and abs(pose[1] - scan.stamp) <= TRUTH_MAX_GAP_S
                     and (pose[1] > last_stamp or pose[1] == scan.stamp) else None)
            last_stamp = scan.stamp
            mounts[id(scan)] = line.mount if line.mount is not None else (0.0, 0.0, 0.0)
            if line.mount is not None:
                if last_mount is not None and line.mount != last_mount:  # a PARAM line changed it mid-log
                    stats.mount_changes += 1
                    if stats.mount_changed_at is None:
                        stats.mount_changed_at, stats.mount_before = line.mount_line, last_mount
                last_mount = line.mount
            return Record(scan=scan, odom=line.odom, truth=given)

        def release(strict: bool = True) -> Iterator[Record]:
            """The held lines, ODOM poses and skipped lines, in log order, once the rule is taken: each line of
            its tail taken, each of another malformed. ``strict=False``: a pass ended by an error, where the rule
            is taken as the pass would have taken it from the lines held (two of them share a tail, or HELD
            lines), or where they all end alike, or one ends as CARMEN writes (the tail the rule prefers where
            lines differ); lines of other differing tails tell no rule and are left out (the first's was taken:
            a damaged first line given, a good one after it dropped)."""
            if strict:
                tails.decide(held_tails(), final=True)
            elif not tails.decide(held_tails()):
                told = {t for t, _ in held_tails()}
                if len(told) == 1 or 2 in told:
                    tails.decide(held_tails(), final=True)
            held = undecided[:]
            undecided.clear()
            for event in held:
                if isinstance(event, _HeldSkip):
                    self.stats.skip(event.line_no, event.reason)
                    continue
                if not isinstance(event, _HeldLaser):
                    yield from odometry(*event)
                    continue
                wrong: str | None = tails.problem(event.words) if tails.rule is not None else "no rule"
                rec = None
                if wrong is None:
                    try:
                        rec = take(event)
                    except ValueError as exc:
                        wrong = str(exc)
                if rec is not None:
                    yield from emit(rec)
                elif strict or (self.skip_bad_lines and tails.rule is not None):
                    self._bad(event.line_no, event.kind, ValueError(wrong))
                elif self.skip_bad_lines:  # listed, in log order: it was left out without a word
                    words_after = ", ".join(map(str, sorted({t for t, _ in held_tails_of(held)})))
                    self._bad(event.line_no, event.kind, ValueError(
                        f"the pass ended by an error before the laser lines' ending could be told (the held lines "
                        f"have {words_after} words after their ipc_timestamp, none shared, none as CARMEN writes); "
                        "not read"))

        flushes += [lambda: release(strict=False)]
        flushes += [holder.flush for holder in (pairing, chain) if holder is not None]
        lines = quiet = 0  # lines read, and of them blank or comment lines (for a log of no laser line)
        releasing = False  # the held laser lines' tail was told at this line: release them
        for line_no, line in self._lines():
            lines = line_no
            words = line.split()
            if not words or words[0].startswith("#"):
                blank.see(line_no)
                quiet += 1
                continue
            blank.reset()
            kind = words[0]
            named = kind in KNOWN_KINDS or _MESSAGE_NAME.fullmatch(kind) is not None
            if named:
                stats.count(kind)
            else:
                junk += 1
                if junk > MAX_JUNK_LINES and self.skip_bad_lines:
                    reason = (f"more than {MAX_JUNK_LINES:,} lines that start with no CARMEN message name: junk from "
                              "here on, not read")
                    stats.stopped = f"line {line_no}: {reason}"
                    self._skip(line_no, f"message: {reason}")
                    break
            # a TRUEPOS pose is the truth of the next line of the laser kind read (that line, even when
            # malformed, takes it), when stamped within TRUTH_MAX_GAP_S of it: ODOM lines, other laser
            # kinds and other messages between do not drop it (CARMEN's simulator logs TRUEPOS, ODOM, FLASER)
            held = truth
            if kind == stats.laser or (stats.laser is None and kind in LASER_KINDS):
                truth = None
            try:
                if not named:  # 30 MB of random bytes after a log were read as 207k message kinds, none skipped
                    shown = kind if len(kind) <= 24 else kind[:24] + "..."
                    kind = "message"
                    raise ValueError(f"it starts with {shown!r}, which is no CARMEN message name (FLASER, ODOM, "
                                     "PARAM, ...: capitals, digits and '_'); junk or a damaged line")
                if kind == "PARAM":
                    units, has_odometry = _param(words, params, units, has_odometry)
                    if len(words) > 1 and words[1] in MOUNT_PARAMS:
                        mount_line = line_no
                elif kind == "TRUEPOS":
                    truth = None  # a malformed TRUEPOS sets none
                    pose = _pose(words, 1, "TRUEPOS")
                    _require(len(words) >= 8, "TRUEPOS needs at least 7 numbers")
                    _require(len(words) <= MAX_POSE_WORDS or _tail_fits(words, 8, 1), _too_many_words("TRUEPOS", len(words)))
                    truth = (pose, _stamps(words, _few_floats(words[7:8], "TRUEPOS timestamp")[0], _logger_at(words, 8)))
                elif kind == "ODOM":
                    _require(len(words) >= 8, "ODOM needs x y theta tv rv accel timestamp")
                    _require(len(words) <= MAX_POSE_WORDS or _tail_fits(words, 8, 1), _too_many_words("ODOM", len(words)))
                    values = _few_floats(words[1:8], "ODOM")
                    _finite_pose(values[0:3], "ODOM")  # nan or 1e308 m was chained into every scan's odometry
                    values[6] = _stamps(words, values[6], _logger_at(words, 8))
                    yield from odometry(values[6], (values[0], values[1], values[2]))
                elif kind in LASER_KINDS:
                    if stats.laser is None:
                        stats.laser = kind
                        self._check_override(kind)
                    if kind != stats.laser:
                        continue
                    self._check_range_max(line_no, params.get(RANGE_MIN_PARAM, 0.0))
                    odom: Pose2D | None
                    mount: Pose2D | None = None  # the laser's pose on the robot (None: RAWLASER, not known)
                    if kind in ("FLASER", "RLASER"):
                        declared = laser_geometry.from_params(kind, params)
                        geometry = self.geometry.merged(declared)
                        exact_min, exact_step = EXACT_GEOMETRY_NAMES[kind]
                        exact = (params.get(exact_min), params.get(exact_step))
                        # units is set only by a PARAM lmsbench_range_units line: this project's writer's log,
                        # whose maximum is written exact, so its grid words are valid readings (at_max_range)
                        scan, odom = _parse_flaser(words, units, geometry, params.get(RANGE_MIN_PARAM, 0.0), exact,
                                                   range_words, declared.range_max, grid_max=units is None)
                        mount = laser_mount(kind, params)
                    else:
                        scan, odom = _parse_robotlaser(words, units, self.geometry.range_max,
                                                       params.get(RANGE_MIN_PARAM, 0.0), range_words,
                                                       exact_angles=bool(params.get(EXACT_ANGLES_PARAM)),
                                                       grid_max=units is None)
                        # the mount of the log's PARAM lines, never the line's own laser pose: CARMEN's scan
                        # matcher (vasco) writes its corrected pose there beside the raw odometry (laser_mount)
                        if odom is not None:  # a ROBOTLASER line (RAWLASER lines carry no pose)
                            mount = laser_mount(kind, params)
                    wrong_tail = tails.problem(words)
                    _require(wrong_tail is None, wrong_tail or "")
                    line_held = _HeldLaser(scan, odom if has_odometry else None, held, words, line_no, kind,
                                           None if kind in ("FLASER", "RLASER") else (words[2], words[3], words[4]),
                                           mount, mount_line)
                    if tails.rule is not None:
                        yield from emit(take(line_held))
                    else:  # held until the pass's tail is told (_Tails)
                        undecided.append(line_held)
                        releasing = tails.decide(held_tails())
            except (ValueError, OverflowError, ArithmeticError) as exc:
                self._bad(line_no, kind, exc)
            # held beside the laser lines until their tail is told, and no more than HELD_EVENTS of them (a first
            # laser line and 500,000 ODOM lines held 130 MB more): beyond, the rule is taken from the laser lines held
            releasing = releasing or len(undecided) > _Tails.HELD_EVENTS
            if releasing:  # outside the line's try: a held line's error is its own, not this line's
                releasing = False
                yield from release()
        if undecided:
            yield from release()
        if pairing is not None:
            yield from pairing.flush()
        if chain is not None:
            yield from chain.flush()
        if not any(stats.messages.get(k) for k in LASER_KINDS) and not stats.skipped_count and stats.stopped is None:
            raise LogFormatError(self.path, None, self._no_laser_reason(lines, quiet))
        if self.topic is not None and not stats.messages.get(self.topic) and stats.other_lasers():
            # as a bag names its topics: the commands said "no laser messages found: not a CARMEN log"
            others = ", ".join(f"{k} ({n})" for k, n in stats.other_lasers().items())
            raise InputError(f"topic: {self.path} has no {self.topic} lines; its laser lines: {others}")


@dataclass
class _HeldLaser:
    """A laser line held until the pass's tail is told (:class:`_Tails`), parsed but not yet taken: its scan,
    odometry (None where the log has none), the TRUEPOS (pose, stamp) it may take as its truth, its words,
    line number and kind, and its declared geometry (start, fov, resolution as written; None for FLASER)."""

    scan: Scan
    odom: Pose2D | None
    truth: tuple[Pose2D, float] | None
    words: list[str]
    line_no: int
    kind: str
    header: tuple[str, str, str] | None
    mount: Pose2D | None = None  # the laser's pose on the robot at its line (laser_mount; None: not known)
    mount_line: int | None = None  # the last mounting PARAM line before it (ReadStats.mount_changed_at)


@dataclass
class _HeldSkip:
    """A line skipped (``skip_bad_lines``) while laser lines were held: recorded when they are released."""

    line_no: int
    reason: str


_Held = _HeldLaser | _HeldSkip | tuple[float, Pose2D]  # a held laser line, skipped line, or ODOM (stamp, pose)


#: most words of an ODOM or TRUEPOS line: its name, 6 numbers, ipc_timestamp, hostname, logger_timestamp.
#: More were taken without a word: a laser line that lost the newline before it (a damaged log) ran
#: into the ODOM line and was read as its tail, the scan lost silently
MAX_POSE_WORDS = 10


def _too_many_words(kind: str, n: int) -> str:
    """Why an ODOM / TRUEPOS line of ``n`` words is malformed."""
    return (f"{kind} has {n} fields, at most {MAX_POSE_WORDS} ({kind} and 6 numbers, ipc_timestamp, hostname, "
            "logger_timestamp): two lines run together (a lost line break)?")


#: most words a line's hostname may take where it is not one word ("my robot"): CARMEN writes one (the
#: host's name), but logs of other writers hold names with spaces
MAX_HOST_WORDS = 8


def _tail_fits(words: list[str], fixed: int, numbers_from: int) -> bool:
    """Whether a line whose fields up to its ipc_timestamp are ``words[:fixed]`` (``words[numbers_from:fixed]``
    the numbers before it: poses, speeds, the stamp) has a tail after it that CARMEN's readers take: two words
    (hostname, logger_timestamp) as CARMEN writes them; or, as logs of other writers (converters, older
    loggers) have them, none (the ipc_timestamp last), one (the hostname or the logger_timestamp alone) or a
    hostname of up to MAX_HOST_WORDS words, none of them a number, and the logger_timestamp. CARMEN's own
    readers take the fields in order and stop at the ipc_timestamp; a line that lost or gained a word
    (damage, two lines run together) leaves a hostname among the numbers or numbers in the hostname, and
    still does not fit: such lines were, and still are, malformed (those tails were all refused: "FLASER
    with 361 beams needs 372 fields, got 371")."""
    n = len(words)
    if n == fixed + 2:
        return True
    if not fixed <= n <= fixed + 1 + MAX_HOST_WORDS:
        return False
    return not any(map(_is_number, words[fixed:n - 1])) and all(map(_is_number, words[numbers_from:fixed]))


def _logger_at(words: list[str], fixed: int) -> int:
    """Index of a line's logger_timestamp (the last word after the ipc_timestamp at ``words[fixed - 1]``),
    or ``len(words)`` where it has none: no word after the ipc_timestamp, or one that is no number (the
    hostname alone). See :func:`_tail_fits`."""
    tail = len(words) - fixed
    if tail <= 0 or (tail == 1 and not _is_number(words[-1])):
        return len(words)
    return len(words) - 1


def laser_line_stamp(line: bytes, kind: str) -> float | None:
    """The ipc_timestamp (s) of a laser line of ``kind`` whose fields add up to its counts (as
    :func:`_fields_fit` tells them, its numbers up to the stamp numbers), None for any other line or
    a stamp no reader takes (:func:`stamp_problem`). Leading whitespace is passed over, as the reader does."""
    line = line.lstrip()
    if not line.startswith(kind.encode("ascii")):
        return None
    words = line.decode("ascii", "replace").split()
    if not words or words[0] != kind:
        return None
    try:
        if kind in ("FLASER", "RLASER"):
            n, m, numbers_from = _count(words[1], "beam count"), 0, 2 + _count(words[1], "beam count")
        else:
            n = _count(words[8], "beam count")
            m = _count(words[9 + n], "remission count")
            numbers_from = 10 + n + m
        fixed_words = _field_count(kind, n, m) - 2  # the words up to the ipc_timestamp
        if n <= 0 or not _tail_fits(words, fixed_words, numbers_from):
            return None
        stamp = float(words[fixed_words - 1])
    except (ValueError, IndexError):
        return None
    return stamp if stamp_problem(stamp, "ipc_timestamp") is None else None


LAST_LINES_BLOCK = 1 << 16  # bytes read at a time from a plain log's end (:func:`_lines_from_end`)


def _lines_from_end(path: Path) -> Iterator[bytes]:
    """A plain file's lines, its last first, without their newlines (a line the reader refuses as
    longer than ``MAX_LINE_CHARS``, its newline counted, is left out)."""
    with open(path, "rb") as f:
        pos = f.seek(0, os.SEEK_END)
        rest, long = b"", False  # the start of the line that ends the block read last; it runs on past MAX_LINE_CHARS
        ended = False  # the line yielded next ends in a newline (all but the file's last piece)

        def fits(line: bytes) -> bool:  # a piece of up to MAX_LINE_CHARS + a block: the reader reads a line whole
            return len(line) + ended <= MAX_LINE_CHARS

        while pos > 0:
            step = min(LAST_LINES_BLOCK, pos)
            pos -= step
            f.seek(pos)
            pieces = (f.read(step) + rest).split(b"\n")
            for line in reversed(pieces[1:]):
                if not long and fits(line):
                    yield line
                long, ended = False, True
            rest = pieces[0]
            if len(rest) > MAX_LINE_CHARS:
                rest, long = b"", True
        if not long and fits(rest):
            yield rest


def _compressed_lines_of(path: Path, kind: str, kept: int = 16) -> Iterator[bytes]:
    """The last ``kept`` lines of a compressed log that start with ``kind``, its last first, from one
    decompressing pass (damage ends the pass where it is), then the last line before them whose stamp
    :func:`laser_line_stamp` takes, if any: a log whose last ``kept`` lines of the kind were all damaged
    gave no stamp, where its plain file gave that line's. Lines that left the window are checked ``kept``
    at a time, newest first, so a sound log parses one line in ``kept`` and memory stays at 2 x ``kept``
    lines. A line longer than ``MAX_LINE_CHARS`` (which the reader refuses) is left out."""
    from collections import deque

    start = kind.encode("ascii")
    last: deque[bytes] = deque(maxlen=kept)
    gone: list[bytes] = []  # lines pushed out of ``last``, not yet checked, oldest first
    fallback: list[bytes] = []  # the newest line checked that gives a stamp
    try:
        with open_bytes(path) as f:
            whole = True  # the piece read next starts a line
            for line in iter(lambda: f.readline(MAX_LINE_CHARS + 1), b""):
                starts, whole = whole, line.endswith(b"\n")
                if not starts or len(line) > MAX_LINE_CHARS or not line.lstrip().startswith(start):
                    continue  # a piece of an overlong line, or another message
                if len(last) == kept:
                    gone.append(last[0])
                    if len(gone) == kept:
                        good = next((g for g in reversed(gone) if laser_line_stamp(g, kind) is not None), None)
                        fallback = [good] if good is not None else fallback
                        gone.clear()
                last.append(line)
    except READ_ERRORS:
        pass
    yield from reversed(last)
    yield from reversed(gone)
    yield from fallback


def _largest_stamp(path: Path, kind: str) -> float | None:
    """The largest stamp :func:`laser_line_stamp` takes among all the log's lines of ``kind``, in one pass
    (plain or compressed; damage ends it where it is): an upper bound of the stamps of the scans the
    reader gives, which :func:`_lines_from_end`'s last line is not where the stamps go back at the end
    (a line the reader drops under ``skip_bad_lines``). MIT CSAIL's gzip: 35 ms."""
    start = kind.encode("ascii")
    largest: float | None = None
    try:
        with open_bytes(path) as f:
            whole = True
            for line in iter(lambda: f.readline(MAX_LINE_CHARS + 1), b""):
                starts, whole = whole, line.endswith(b"\n")
                if starts and len(line) <= MAX_LINE_CHARS and line.lstrip().startswith(start):
                    stamp = laser_line_stamp(line, kind)
                    if stamp is not None and (largest is None or stamp > largest):
                        largest = stamp
    except READ_ERRORS:
        pass
    return largest


def _fields_fit(kind: str, line: str) -> bool:
    """Whether a FLASER / RLASER / ROBOTLASER1 / 2 line has the fields its counts announce (the
    beam count, and the remission count, against the number of words); True for a piece of a line
    longer than the survey reads at once (``line`` not ending in a newline), which is not judged."""
    if not line.endswith("\n"):
        return True
    words = line.split()
    try:
        if kind in ("FLASER", "RLASER"):
            n = _count(words[1], "beam count")
            return n > 0 and _tail_fits(words, _field_count(kind, n) - 2, 2 + n)
        n = _count(words[8], "beam count")
        m = _count(words[9 + n], "remission count")
        return n > 0 and _tail_fits(words, _field_count(kind, n, m) - 2, 10 + n + m)
    except (ValueError, IndexError):
        return False


def _field_count(kind: str, n: int, m: int = 0) -> int:
    """The words of a laser line of ``kind`` with ``n`` ranges and ``m`` remissions: FLASER / RLASER
    ranges, poses, timestamps and host; ROBOTLASER1 / 2 and RAWLASER1 .. 4 a header, the ranges and
    remissions and their tail (poses, speeds, safety, timestamps, host; RAWLASER timestamps and host)."""
    if kind in ("FLASER", "RLASER"):
        return n + 11
    return 10 + n + m + (3 if kind.startswith("RAWLASER") else 14)


class _Tails:
    """The words after the ipc_timestamp of a pass's laser lines (:func:`_tail_fits`) must be alike. The
    rule is the tail two of the first laser lines share (CARMEN's own, hostname and logger_timestamp,
    where the first three differ and one has it, else the first's; the first's too in a log of one or two
    lines that differ); until then the lines are held (:meth:`CarmenReader._read`), and a held line of
    another tail is malformed. A line that lost a range and its hostname fits a tail ending at the
    ipc_timestamp, its fields shifted by one: the first line's tail alone set the rule, so such a first
    line read silently (the lines after it had CARMEN's tail, which was taken from any line), and in a
    log of other tails a damaged first line made every good line malformed. In a log of lines that all
    end so, such a line cannot be told from a good one."""

    #: laser lines held at most before the rule is taken (the first's, where they share no tail)
    HELD = 3
    #: laser and ODOM lines held at most (memory bound on any log, as OdomPairing's MAX_RECENT_ODOM):
    #: beyond, the rule is taken from the laser lines held, as at the pass's end
    HELD_EVENTS = 4096

    def __init__(self) -> None:
        self.rule: tuple[int, int] | None = None  # (words after the ipc_timestamp, a line that has them)

    @staticmethod
    def measure(words: list[str]) -> tuple[int, int, str]:
        """(words after the ipc_timestamp, fields up to it, what the line is) of a parsed laser line."""
        kind = words[0]
        if kind in ("FLASER", "RLASER"):
            n = int(words[1])
            fixed, what = n + 9, f"{kind} with {n} beams"
        else:
            n = int(words[8])
            m = int(words[9 + n])
            fixed, what = _field_count(kind, n, m) - 2, f"{kind} with {n} ranges and {m} remissions"
        return len(words) - fixed, fixed, what

    def problem(self, words: list[str]) -> str | None:
        """Why a laser line's tail is not the rule's (None: it is, or no rule is taken yet)."""
        if self.rule is None:
            return None
        tail, fixed, what = self.measure(words)
        rule, line_no = self.rule
        if tail == rule:
            return None
        where = f"line {line_no} has {rule}" + (" (a hostname and a logger_timestamp)" if rule == 2 else "")
        return (f"{what} needs {fixed + rule} fields, got {len(words)}: {tail} word{'s' * (tail != 1)} after its "
                f"ipc_timestamp, where {where} (a word lost or gained?)")

    def decide(self, held: list[tuple[int, int]], final: bool = False) -> bool:
        """Take the rule from the held lines' (tail, line) where it can be told (two share a tail; or
        ``HELD`` lines, or the pass's end when ``final``); whether it is taken."""
        if self.rule is not None or not held:
            return self.rule is not None
        tails = [t for t, _ in held]
        shared = next((t for t in tails if tails.count(t) > 1), None)
        if shared is None and not final and len(held) < self.HELD:
            return False
        if shared is None:
            shared = 2 if 2 in tails else tails[0]
        self.rule = (shared, next(n for t, n in held if t == shared))
        return True


class _BlankRun:
    """Blank or comment lines in a row; more than MAX_BLANK_RUN is a LogFormatError at the first of
    them (a gzip of 100 MB of blank lines was read twice to its end, 48 s, to say it held no laser line)."""

    def __init__(self, path: Path) -> None:
        self.path, self.first, self.count = path, 0, 0

    def see(self, line_no: int) -> None:
        self.first = self.first if self.count else line_no
        self.count += 1
        if self.count > MAX_BLANK_RUN:
            raise LogFormatError(self.path, self.first, f"more than {MAX_BLANK_RUN:,} blank or comment lines in a row "
                                 "from here on: not a CARMEN log, or a damaged one (a log's comments are a few lines)")

    def reset(self) -> None:
        self.count = 0


LMSBENCH_PARAM_PREFIX = "lmsbench_"  # the PARAM names this package writes and reads
PARAM_NEAR_MISS = 0.8  # difflib ratio (of the names after the prefix) from which an unknown lmsbench_* name misspells a known one
PARAM_KEY_WORDS = ("units", "odometry", "robotlaser")  # words of a known name that only it has: an unknown name with one misspells it
LMSBENCH_PARAMS = frozenset({UNITS_PARAM, ODOMETRY_PARAM, RANGE_MIN_PARAM, EXACT_ANGLES_PARAM} | EXACT_GEOMETRY_PARAMS)


def _param(words: list[str], params: dict[str, float], units: Units | None,
           has_odometry: bool) -> tuple[Units | None, bool]:
    """Apply a PARAM line: the range unit, odometry flag, range_min and laser geometry; returns (units, odometry)."""
    _require(len(words) >= 3, "PARAM needs a name and a value")
    _param_stamps(words)
    name, value = words[1], words[2]
    if name == UNITS_PARAM:
        _require(value in ("mm", "cm"), f"{UNITS_PARAM} must be mm or cm, got {value!r}")
        units = value  # type: ignore[assignment]
    elif name == ODOMETRY_PARAM:  # any other value read as present ("maybe", "no", "Absent"), silently
        _require(value in ("absent", "present"), f"{ODOMETRY_PARAM} must be absent or present, got {value!r}")
        has_odometry = value == "present"
    elif name in EXACT_GEOMETRY_PARAMS:  # nan or inf was taken and then passed over as disagreeing, silently
        number = float(_floats([value], name)[0])
        _require(math.isfinite(number), f"{name} must be a finite number (rad), got {value!r}")
        params[name] = number
    elif name == EXACT_ANGLES_PARAM:
        _require(value in ("exact", "grid"), f"{EXACT_ANGLES_PARAM} must be exact or grid, got {value!r}")
        params[name] = float(value == "exact")
    elif name in MOUNT_PARAMS:  # a laser's mounting on the robot (laser_mount)
        number = float(_floats([value], name)[0])
        angular = name.endswith("_angular_offset")
        _require(math.isfinite(number) and (angular or abs(number) <= MAX_COORD_M),
                 f"{name} must be a finite number ({'rad' if angular else f'm, within +-{MAX_COORD_M:g}'}), got {value!r}")
        params[name] = number
    elif name == RANGE_MIN_PARAM:
        number = float(_floats([value], name)[0])
        _require(math.isfinite(number) and number >= 0, f"{name} must be a finite number >= 0 (m), got {value!r}")
        params[name] = number
    elif name.startswith(LMSBENCH_PARAM_PREFIX) and name not in LMSBENCH_PARAMS:
        # a misspelt one (lmsbench_range_unit mm) was passed over: the unit inferred, the scans read otherwise;
        # a name near none of ours (a later version's, a lab's own lmsbench_writer_version) is passed over
        # with a warning, as a whole log refused for it would lose every scan
        near = _misspelt_param(name)
        if near:
            raise ValueError(f"{name!r} is no lmsbench PARAM: {near!r} misspelt? (known: "
                             f"{', '.join(sorted(LMSBENCH_PARAMS))})")
        warnings.warn(f"PARAM {name}: no lmsbench PARAM this version reads (known: {', '.join(sorted(LMSBENCH_PARAMS))}); "
                      "passed over, as other programs' PARAM lines are", LmsbenchWarning, stacklevel=2)
    elif name in laser_geometry.GEOMETRY_PARAMS:
        number = float(_floats([value], name)[0])
        _require(math.isfinite(number) and number > 0, f"{name} must be a finite number > 0, got {value!r}")
        # checked here, not when a laser line uses it: `laser_front_laser_fov 720` was blamed on every
        # FLASER line (all skipped under skip_bad_lines) instead of on itself (a review's reproduction)
        laser_field = laser_geometry.GEOMETRY_PARAMS[name][1]
        try:
            LaserGeometry(**{laser_field: number if laser_field == "range_max" else math.radians(number)})
        except ValueError as exc:
            raise ValueError(f"{name} {value}: {exc}") from None
        params[name] = number
    return units, has_odometry


def _param_stamps(words: list[str]) -> None:
    """A PARAM line's last stamp, where it has one, checked as other lines' are (:func:`_stamps`: a number in
    0 .. ``records.MAX_STAMP_S``; it was not read at all, so `PARAM ... nohost 1e300` or `nan` passed).
    CARMEN writes ``PARAM name value hostname ipc_timestamp`` (the logs of ../shared/data, this package's
    writer) or, since 0.7, ``PARAM name value ipc_timestamp ipc_hostname logger_timestamp``, and a value may
    hold spaces, so the two cannot be told apart (`PARAM offsets 0.5 -0.5 nohost 0` is either); in both a
    line ends with a stamp, which is checked in a line of 5 words or more. A line of 3 or 4 words (written
    by hand) has none."""
    if len(words) >= 5:
        problem = stamp_problem(_few_floats(words[-1:], "timestamp")[0], "timestamp")
        _require(problem is None, problem or "")


def _misspelt_param(name: str) -> str | None:
    """The known lmsbench PARAM that an unknown ``lmsbench_*`` name misspells, or None. The names are
    compared after the shared prefix (whole, the prefix made every pair look alike); a name that
    extends a known one (``lmsbench_odometry_frame``, ``lmsbench_range_min_m``: a later version's) is
    no misspelling; nor is one near none of them by difflib's ratio (``PARAM_NEAR_MISS``) or by a word
    (``lmsbench_unit``: units)."""
    stem = name[len(LMSBENCH_PARAM_PREFIX):]
    known = {p[len(LMSBENCH_PARAM_PREFIX):]: p for p in LMSBENCH_PARAMS}
    if any(stem.startswith(k + "_") for k in known):
        return None
    near = difflib.get_close_matches(stem, list(known), n=1, cutoff=PARAM_NEAR_MISS)
    if near:
        return known[near[0]]
    words = {w.rstrip("s") for w in stem.split("_") if len(w) > 3}
    shared = [p for k, p in sorted(known.items()) if words & {w.rstrip("s") for w in k.split("_") if w in PARAM_KEY_WORDS}]
    return shared[0] if len(shared) == 1 else None


def _require(ok: bool, reason: str) -> None:
    if not ok:
        raise ValueError(reason)


def _word(word: str) -> str:
    """A log's word quoted for a message: the reader decodes ASCII, each other byte a replacement
    character, which a quote alone showed as mojibake ('\ufffd\ufffd' for an Arabic-Indic digit's two bytes)."""
    n = word.count("\ufffd")
    return f"{word!r} ({n} byte{'s' * (n != 1)} not ASCII, each shown as U+FFFD)" if n else repr(word)


def _floats(words: list[str], what: str) -> np.ndarray:
    """Numbers as CARMEN's strtod reads them: Python's float() also takes ``1_000`` (read as 1000 m)
    and turns ``1e400`` into inf, which CARMEN does not: both make the line malformed (a review's
    reproduction); ``inf`` / ``nan`` written as words keep their meaning (logs converted from ROS).
    A number written nonzero but read as 0 (``1e-400``, below float64's smallest, 4.9e-324) makes it
    malformed too: float() reads it as 0.0, which as a range is a logger's "no reading", silently
    (strtod sets ERANGE for ``1e-310`` too, a subnormal read nonzero: that one is taken, as it is)."""
    if "_" in "".join(words):
        bad = next(w for w in words if "_" in w)
        raise ValueError(f"{what}: {bad!r} is not a number (no '_' in a CARMEN number)")
    try:
        values = np.array(words, dtype=np.float64)
    except ValueError:
        bad = next(w for w in words if not _is_number(w))
        raise ValueError(f"{what}: {_word(bad)} is not a number") from None
    infinite = np.isinf(values)
    if infinite.any():
        for i in np.flatnonzero(infinite):
            if words[i].lstrip("+-").lower() not in INF_WORDS:
                raise ValueError(f"{what}: {words[i]!r} is beyond float64's range")
    for i in np.flatnonzero(values == 0.0):  # written nonzero, read as 0: '1e-400', a range's 'no reading'
        if _may_underflow(words[i]) and underflow_problem(words[i], 0.0) is not None:
            raise ValueError(f"{what}: {words[i]!r} is below float64's range (nonzero, it would read as 0)")
    return values


#: a word read as 0 without an exponent and shorter than this cannot be a nonzero number read as 0
#: (that needs 323 zeros after the point): only longer words and those with an 'e' are checked
UNDERFLOW_MIN_PLAIN_CHARS = 320


def _may_underflow(word: str) -> bool:
    """Whether ``word``, read as 0.0, may be written nonzero (``underflow_problem`` needs asking): it has
    an exponent or is UNDERFLOW_MIN_PLAIN_CHARS long. Asked of every '0' of a log's ranges (the Intel
    log's 45,737) it made reading it ~30 % slower."""
    return "e" in word or "E" in word or len(word) >= UNDERFLOW_MIN_PLAIN_CHARS


def _few_floats(words: list[str], what: str) -> list[float]:
    """:func:`_floats` of a few numbers (poses, speeds, stamps, a header) as Python floats, the same
    values and errors: numpy parses each word with float() itself, so float() is that parse, and
    _floats' checks (an ``_``, an overflow) run only when a word may need them (an ``_`` in the
    words, a sum that is not finite: an inf, a nan or an overflow). Those checks and numpy's
    overhead cost as much as the parse: on the Intel log's 14,541 ODOM lines 50 ms against 21."""
    try:
        values = list(map(float, words))
    except ValueError:
        return _floats(words, what).tolist()  # raises with its message
    if (math.isfinite(sum(values)) and "_" not in "".join(words)
            and (0.0 not in values or not any(v == 0.0 and _may_underflow(w) and underflow_problem(w, v) is not None
                                              for w, v in zip(words, values)))):
        return values
    return _floats(words, what).tolist()


#: distinct words a pass keeps parsed for the ranges of its laser lines (word -> float): a log writes
#: the same few thousand (LMS200 codes times the unit: 2,873 in MIT CSAIL's 717,668 ranges), so
#: each is parsed once; the bounds keep a log of unique words at a few MB. A full cache is emptied
#: at its next new word (what a noisy start left would otherwise make every later new word miss)
MAX_CACHED_WORDS = 16_384
MAX_CACHED_WORD_CHARS = 32
#: at most this many laser lines in a row parsed in bulk (numpy, no cache) after lines of many new words
MAX_BULK_LINES = 128


class _RangeWords(dict[str, float]):
    """Range words already parsed, with their numbers, for one pass (see :func:`_range_floats`),
    and when to skip them: a word not met before costs ~550 ns (float() and the checks in Python),
    numpy's parse of a whole line 190-310 ns a word, a word met before 40 ns. A log of unique words
    (full-precision floats, as converted from ROS: 2.1M distinct words in 6,000 scans) read 44 %
    slower through the cache than by numpy, so lines of many new words turn to numpy for a while,
    and lines whose sampled words were all met before (codes) keep the cache."""

    def __init__(self) -> None:
        super().__init__()
        self.misses = 0  # new words met in the line being parsed
        self.bulk = 0  # lines still to parse in bulk
        self.backoff = 1  # lines to parse in bulk after the next line of many new words
        self.last = self.before = math.inf  # share of new words in the last two lines judged

    def __missing__(self, word: str) -> float:
        """A word not met before, parsed as :func:`_floats` parses it; ValueError for any word
        _floats refuses (the caller asks _floats itself for the message, which names the line's
        first such word)."""
        self.misses += 1
        value = float(word)
        if ("_" in word or (math.isinf(value) and word.lstrip("+-").lower() not in INF_WORDS)
                or (value == 0.0 and _may_underflow(word) and underflow_problem(word, value) is not None)):
            raise ValueError(word)
        if len(word) <= MAX_CACHED_WORD_CHARS:
            if len(self) >= MAX_CACHED_WORDS:
                self.clear()  # full: keep the words met from now on, not those of the log's start
            self[word] = value
        return value

    def judge(self, n: int) -> None:
        """After a line of ``n`` words parsed through the cache though its sample held new words: if
        many were new (> 1/4, where the cache stops paying), parse the next ``backoff`` such lines in
        bulk and double ``backoff`` (up to MAX_BULK_LINES), unless the cache is learning (a share of new words falling by a quarter
        twice in a row: a log's first lines, the first after a noisy start; not lines of two kinds
        in turn). A log of unique words, or of a third of them, pays the cache on about one line in
        MAX_BULK_LINES + 1."""
        share = self.misses / n if n else 0.0
        if share > 0.25:
            if share < 0.75 * self.last and self.last <= self.before:  # learning: keep the cache
                self.backoff = max(self.backoff // 2, 1)
            else:
                self.bulk = self.backoff
                self.backoff = min(2 * self.backoff, MAX_BULK_LINES)
        else:
            self.backoff = 1
        self.last, self.before = share, self.last


def _range_floats(words: list[str], what: str, cache: _RangeWords | None) -> np.ndarray:
    """:func:`_floats` of a laser line's ranges, the same values and errors, each word looked up in
    ``cache`` and parsed only the first time: parsing every range was about two thirds of reading
    MIT CSAIL (130 of 350 ms in numpy's parse, 0.3 us a word on this machine). A line with more than
    1 in 8 of its sampled words (up to 8) new goes to _floats itself while :meth:`_RangeWords.judge`
    says so (lines of unique words seen lately), else through the cache and is judged. No cache: a new one."""
    cache = _RangeWords() if cache is None else cache
    sample = words[:: len(words) // 8 + 1]  # up to 8 words spread over the line
    if 8 * sum(map(cache.__contains__, sample)) >= 7 * len(sample):  # 7 in 8 met before: the cache pays
        try:
            return np.fromiter(map(cache.__getitem__, words), np.float64, len(words))
        except ValueError:
            return _floats(words, what)  # raises with the message naming the first bad word
    if cache.bulk:
        cache.bulk -= 1
        return _floats(words, what)
    cache.misses = 0
    try:
        values = np.fromiter(map(cache.__getitem__, words), np.float64, len(words))
    except ValueError:
        return _floats(words, what)
    cache.judge(len(words))
    return values


INF_WORDS = ("inf", "infinity")  # how an infinite number is written as text (not 1e400, an overflow)


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return "_" not in word


def _count(word: str, what: str) -> int:
    """A count field: a non-negative integer written as one (``361``; not ``361.0``, ``3.61e2`` or
    ``3_0``): CARMEN reads a count with atoi, which takes ``3.61e2`` as 3, so a count in any other
    form is no count CARMEN's own tools read alike (``361.0`` was taken as 361, here and nowhere else)."""
    if _DIGITS.fullmatch(word) is None:
        try:
            float(word)
            _require("_" not in word, "")
        except ValueError:
            raise ValueError(f"{what} {_word(word)} is not a number") from None
        raise ValueError(f"{what} must be a non-negative integer written in digits, got {word!r}")
    return int(word)


_DIGITS = re.compile(r"[0-9]+")  # ASCII digits only: int() also takes '٣' and '+3'


def _stamps(words: list[str], ipc: float, logger_at: int) -> float:
    """``ipc``, a line's ipc_timestamp (s), once it and the line's logger_timestamp (``words[logger_at]``,
    where the line has it) are checked against :data:`lms200.records.MAX_STAMP_S` (a stamp of 1e300 s
    was read; the logger_timestamp, not used, was not even read as a number)."""
    problem = stamp_problem(ipc, "ipc_timestamp")
    if problem is None and logger_at < len(words):
        logger = _few_floats(words[logger_at : logger_at + 1], "logger_timestamp")[0]
        problem = stamp_problem(logger, "logger_timestamp")
    _require(problem is None, problem or "")
    return ipc


def _pose(words: list[str], start: int, what: str) -> Pose2D:
    _require(len(words) >= start + 3, f"{what} needs x y theta")
    return _finite_pose(_few_floats(words[start : start + 3], what), what)


def _finite_pose(values: list[float], what: str) -> Pose2D:
    x, y, t = values
    _require(math.isfinite(x) and math.isfinite(y) and math.isfinite(t), f"{what} pose is not finite")
    problem = pose_problem(x, y, t, f"{what} pose")
    _require(problem is None, problem or "")
    return (x, y, t)


def _ranges(values: np.ndarray, units: Units | None, what: str,
            declared_max: float | None = None, grid_max: bool = True) -> tuple[np.ndarray, Units]:
    """Logged ranges (m) in REP-117 form: SICK codes decoded; ``nan`` / ``inf`` written as text
    (logs converted from ROS) keep their REP-117 meaning, ``-inf`` too (an object too close to
    measure); a finite negative range is malformed. A reading at the maximum range the log
    declares for the line (``declared_max``: ROBOTLASER / RAWLASER's max_range field, FLASER's
    ``PARAM robot_front_laser_max``; equal to it, or the grid word of the line's unit it rounds to,
    :func:`at_max_range`; the grid word only with ``grid_max``) is the logger's max-range reading:
    +inf (no return), as the LMS200's code 8183, its own maximum range, is."""
    negative = finite_negative(values)
    if np.any(negative):
        raise ValueError(f"{what}: negative range {values[negative][0]:g} in the log")
    u = units or infer_units(values)
    return at_max_range(decode_logged_ranges(values, u), declared_max, u, grid_max), u


def at_max_range(ranges: np.ndarray, declared_max: float | None, units: Units | None = None,
                 grid_max: bool = True) -> np.ndarray:
    """``ranges`` with each reading CARMEN writes for ``declared_max`` (a CARMEN line's declared maximum range,
    or None) made +inf, in place: CARMEN loggers write a beam with no return as the sensor's maximum
    range (a Hokuyo's 30 m), and CARMEN's tools count a reading at the maximum range as no hit; read
    as a valid reading, a 270 deg scan's open sectors became arcs of points at 30 m, which the
    extractors fitted lines to (17.0 lines a scan against 13.0 where the same beams were written
    above the maximum). The readings so taken are ``declared_max`` itself and, on the grid of the
    line's ``units`` (cm: 0.01 m, mm: 0.001 m), the grid values within half a unit of it: a maximum
    off the grid is written rounded (4.095 m with %.2f as "4.09" or "4.10"), and "4.09" was read as a
    valid reading 5 mm short of the maximum. A maximum on the grid has itself alone; a reading off the
    grid (written with more digits) is no such word, so a valid reading just below the maximum is kept.

    ``grid_max`` False (a log with a ``PARAM lmsbench_range_units`` line, which only this project's
    writer writes): ``declared_max`` itself alone. That writer writes the exact maximum and no return
    as a SICK code, never a rounded maximum, and its older versions wrote a valid reading near a
    maximum just off the grid (a ROS float32 range_max, 6.3 stored as 6.300000190734863) as the grid
    word ("6.300"), which the grid rule read as no return."""
    if declared_max is None:
        return ranges
    at = ranges == declared_max
    if units is not None and grid_max:
        scale = metres_per_unit(units)
        for code in {math.floor(declared_max / scale), math.ceil(declared_max / scale)}:
            word = code * scale
            if abs(word - declared_max) <= scale / 2 * (1 + 1e-9):  # the maximum rounded to the grid, either way at a tie
                at |= np.abs(ranges - word) <= GRID_WORD_TOLERANCE * max(1.0, abs(word))
    ranges[at] = np.inf
    return ranges


#: relative: a reading this close to a grid value (code x unit) is that value as written (4.09 read as
#: 4.09, computed as 409 x 0.01 = 4.0900000000000003)
GRID_WORD_TOLERANCE = 1e-12


def laser_mount(kind: str, params: dict[str, float]) -> Pose2D:
    """The pose of a laser on the robot (x forward m, y left m, theta rad), from the log's PARAM lines so
    far (``MOUNT_PARAM_NAMES``), as CARMEN's robot module placed it (docs/data.md, "Laser mounting"): the
    front laser (FLASER, ROBOTLASER1) at (offset, side offset, angular offset), each 0 where the log has
    no line. A rear laser (RLASER) whose log has no ``robot_rearlaser_side_offset`` / ``_angular_offset``
    line is placed as CARMEN's robot module before 0.7 placed it, the one that wrote RLASER lines: turned
    by pi, and ``robot_rearlaser_offset`` along its own heading, (-offset, 0, pi); with either line, as
    0.7's module does, (offset, side offset, angular offset). ROBOTLASER2 (0.7's rear laser) is placed as
    0.7's module places it, (offset, side offset, angular offset), with no pi of its own. A ROBOTLASER
    line's own laser pose is not used: CARMEN's scan matcher (vasco) writes its corrected pose there,
    beside the raw odometry as robot pose, so the two need not differ by the mount."""
    forward, side, angular = MOUNT_PARAM_NAMES["FLASER" if kind in ("FLASER", "ROBOTLASER1") else "RLASER"]
    if kind == "RLASER" and side not in params and angular not in params:
        return (-params.get(forward, 0.0), 0.0, math.pi)
    return (params.get(forward, 0.0), params.get(side, 0.0), params.get(angular, 0.0))


def on_the_laser(rec: Record, mount: Pose2D | None) -> Record:
    """``rec`` with its robot poses (odometry, truth, corrected pose) moved onto the laser mounted at
    ``mount`` on the robot (:func:`laser_mount`): each pose (+) mount. A zero or unknown (None) mount
    leaves the record as it is, bit for bit."""
    if mount is None or mount == (0.0, 0.0, 0.0):
        return rec

    def moved(pose: Pose2D | None) -> Pose2D | None:
        return None if pose is None else compose(pose, mount)

    return Record(scan=rec.scan, odom=moved(rec.odom), truth=moved(rec.truth), corrected=moved(rec.corrected))


def _parse_flaser(words: list[str], units: Units | None, geometry: LaserGeometry,
                  range_min: float = 0.0,
                  exact: tuple[float | None, float | None] = (None, None),
                  cache: _RangeWords | None = None, declared_max: float | None = None,
                  grid_max: bool = True) -> tuple[Scan, Pose2D]:
    """A FLASER / RLASER line's scan and odometry (the robot's: its second pose, odom_x odom_y odom_theta;
    the first, x y theta, is the laser's by CARMEN's robot module or a scan matcher's corrected pose, not
    read); ``cache``: the pass's range words (:func:`_range_floats`);
    ``declared_max``: the maximum range of the log's PARAM lines (a reading at it is no return, :func:`_ranges`;
    its grid words too with ``grid_max``)."""
    kind = words[0]
    _require(len(words) >= 2, f"{kind} needs a beam count")
    n = _count(words[1], "beam count")
    _require(n > 0, f"{kind} needs at least one beam, got a beam count of {n}")  # was "needs 11 fields, got 11"
    _require(_tail_fits(words, _field_count(kind, n) - 2, 2 + n),
             f"{kind} with {n} beams needs {_field_count(kind, n)} fields, got {len(words)}")
    ranges, u = _ranges(_range_floats(words[2 : 2 + n], f"{kind} ranges", cache), units, kind, declared_max, grid_max)
    tail = _few_floats(words[2 + n : 2 + n + 7], f"{kind} poses and timestamp")
    _stamps(words, tail[6], _logger_at(words, 2 + n + 7))
    angle_min, increment = laser_geometry.beam_angles(n, geometry)
    angle_min, increment = _exact_or_snapped(angle_min, exact[0]), _exact_or_snapped(increment, exact[1])
    range_max = geometry.range_max if geometry.range_max is not None else LMS200_MAX_RANGE[u]
    scan = Scan(ranges, angle_min, increment, range_min, range_max, tail[6])
    _finite_pose(tail[0:3], f"{kind} laser")  # (not read, but no pose: nan was taken)
    return scan, _finite_pose(tail[3:6], f"{kind} odometry")


def _exact_or_snapped(angle: float, exact: float | None) -> float:
    """The exact angle a ``PARAM lmsbench_*_laser_angle_*`` line gives where it agrees with the one
    rebuilt from degrees, else that one snapped onto the 0.05 deg grid (:func:`snap_angle`)."""
    if exact is not None and abs(exact - angle) <= EXACT_GEOMETRY_AGREEMENT * max(1.0, abs(angle)):
        return exact
    return snap_angle(angle)


def _parse_robotlaser(words: list[str], units: Units | None, range_max_override: float | None,
                      range_min: float = 0.0, cache: _RangeWords | None = None,
                      exact_angles: bool = False, grid_max: bool = True) -> tuple[Scan, Pose2D | None]:
    """A ROBOTLASER1 / 2 line (robot pose as odometry) or a RAWLASER1 .. 4 line (no pose); its start
    angle and resolution snapped onto the 0.05 deg grid where only text rounding explains their
    distance from it (:func:`snap_angle`), or taken as written with ``exact_angles`` (``PARAM
    lmsbench_robotlaser_angles exact``); ``grid_max``: a reading at the max_range field's grid word is
    no return too (:func:`at_max_range`)."""
    kind = words[0]
    _require(len(words) >= 10, f"{kind} is too short")
    head = _few_floats(words[1:8], f"{kind} header")
    start, fov, resolution, max_range, accuracy = head[1:6]
    n = _count(words[8], "beam count")
    _require(n > 0, f"{kind} needs at least one beam, got a beam count of {n}")
    _require(len(words) > 9 + n, f"{kind} announces {n} beams but has fewer fields")
    m = _count(words[9 + n], "remission count")
    expected = _field_count(kind, n, m)
    _require(_tail_fits(words, expected - 2, 10 + n + m),
             f"{kind} with {n} ranges and {m} remissions needs {expected} fields, got {len(words)}")
    _require(all(map(math.isfinite, head)), f"{kind} header is not finite")
    _require(resolution > 0, f"angular resolution must be > 0, got {resolution}")
    _require(fov >= 0, f"field of view must be >= 0, got {fov}")
    steps = fov / resolution  # CARMEN loggers write fov = n x res (csail) or (n - 1) x res
    _require(min(abs(steps - n), abs(steps - (n - 1))) <= ROBOTLASER_FIT_TOLERANCE_BEAMS,
             f"declares a field of view of {fixed(math.degrees(fov), 3)} deg at {fixed(math.degrees(resolution), 4)} deg, "
             f"which holds {fixed(steps, 1)} steps, but carries {n} beams (fov must be n or n - 1 steps)")
    # the bound of the geometry overrides and the bag reader: 1e-7 rad was read
    _require(resolution >= laser_geometry.MIN_RESOLUTION_RAD,
             f"angular resolution must be at least {laser_geometry.MIN_RESOLUTION_RAD:g} rad "
             f"({math.degrees(laser_geometry.MIN_RESOLUTION_RAD):.5f} deg; finer than any rangefinder's step), "
             f"got {words[4]}")
    if units is None and accuracy in (0.01, 0.001):
        units = "cm" if accuracy == 0.01 else "mm"
    declared = max_range if laser_geometry.MIN_RANGE_MAX_M <= max_range <= laser_geometry.MAX_RANGE_M else None
    ranges, _ = _ranges(_range_floats(words[9 : 9 + n], f"{kind} ranges", cache), units, kind, declared, grid_max)
    tail = _few_floats(words[10 + n + m : 10 + n + m + (1 if kind.startswith("RAWLASER") else 12)],
                       f"{kind} timestamp" if kind.startswith("RAWLASER") else f"{kind} poses and timestamp")
    stamp = _stamps(words, tail[-1], _logger_at(words, expected - 2))
    # max_range 1e-300 made every reading invalid, silently, and -5 became 81.83 m (a review's reproduction)
    # (an override replaces it: a converter's placeholder 0 is then no error)
    _require(range_max_override is not None or laser_geometry.MIN_RANGE_MAX_M <= max_range <= laser_geometry.MAX_RANGE_M,
             f"maximum range must be in [{laser_geometry.MIN_RANGE_MAX_M:g}, {laser_geometry.MAX_RANGE_M:g}] m, "
             f"got {words[5]}")
    range_max = range_max_override if range_max_override is not None else max_range
    snap = (lambda angle: angle) if exact_angles else snap_angle
    scan = Scan(ranges, snap(start), snap(resolution), range_min, range_max, stamp)
    if kind.startswith("RAWLASER"):
        return scan, None
    # the laser pose (laser_mount: not the mount), speeds, safety distances and turn axis are not read, but nan
    # or inf is no such value (was taken)
    _finite_pose(tail[0:3], f"{kind} laser")
    _require(all(map(math.isfinite, tail[6:11])), f"{kind} speeds, safety distances or turn axis are not finite")
    return scan, _finite_pose(tail[3:6], f"{kind} robot")


# ---------------------------------------------------------------------------------------------
def _units_of(scan: Scan) -> Units:
    return "mm" if scan.range_max <= LMS200_MAX_RANGE["mm"] + 1e-9 else "cm"


def _format_ranges(scan: Scan, units: Units) -> str:
    """Ranges rounded to the unit, with +inf / nan written as the SICK codes 8183 / 8191, each word
    read back as the reader will (:func:`_read_back`): a beam whose rounded word would change its
    meaning is written with the digits it needs instead (:func:`_kept_word`). Rounding alone turned a
    valid reading just below range_max into one above it (4.9996 m at a range_max of 4.9996 m: 5.000),
    a tie onto the special band (81.825 m in cm mode: "81.83", +inf; the check rounded half to even,
    the text half up), a valid reading below half a unit into 0 (no reading), one just above
    range_min below it, and an invalid one just above range_max (or below range_min) into a valid one."""
    scale = metres_per_unit(units)
    decimals = 3 if units == "mm" else 2
    r = np.where(np.isposinf(scan.ranges), CODE_ABOVE_MAXIMUM * scale, scan.ranges)
    r = np.where(np.isnan(r), CODES_INVALID[-1] * scale, r)
    words = [f"{v:.{decimals}f}" for v in r]
    # only beams within 2 units of range_min, range_max, 0 or the special band can change meaning
    # (reading every word back cost the writer 1.7x its time)
    x = scan.ranges
    with np.errstate(invalid="ignore", over="ignore"):
        near = np.isfinite(x) & ((np.abs(x - scan.range_max) <= 2 * scale) | (np.abs(x - scan.range_min) <= 2 * scale)
                                 | (x <= 2 * scale) | (np.abs(x / scale - SPECIAL_BAND_MIDDLE) <= SPECIAL_BAND_HALF + 2))
    index = np.flatnonzero(near)  # read back together: one at a time cost ~35 us a beam, 20x the writer's
    if index.size:  # time on scans whose no-returns are 0 or range_max
        changed = _meaning_changed(scan, _read_back([words[i] for i in index], units, scan.range_max), scale, index)
        for i in index[changed]:
            words[i] = _kept_word(scan, int(i), units)
    return " ".join(words)


def _read_back(words: list[str], units: Units, declared_max: float) -> np.ndarray:
    """The ranges (m, REP-117) a reader takes ``words`` (range words of ``units``, on a line that
    declares ``declared_max`` as its maximum range, as the writer's lines do) for: the writer's log has a
    ``PARAM lmsbench_range_units`` line, so the maximum's grid words are valid readings (``grid_max`` False)."""
    return at_max_range(decode_logged_ranges(np.array(words, dtype=np.float64), units), declared_max, units,
                        grid_max=False)


#: units: the SICK special codes (CODE_ABOVE_MAXIMUM .. CODE_NOT_VALID) as a middle and half width
SPECIAL_BAND_MIDDLE = (CODE_ABOVE_MAXIMUM + CODE_NOT_VALID) / 2
SPECIAL_BAND_HALF = (CODE_NOT_VALID - CODE_ABOVE_MAXIMUM) / 2


def _meaning_changed(scan: Scan, back: np.ndarray, scale: float, index: np.ndarray | int) -> np.ndarray:
    """Whether each beam of ``index`` (an array, or one beam) has a read-back value (``back``, one
    a beam) that means something else than the scan's: valid where it was not, or not where it was; a valid one more than half a unit off;
    +inf (no return), nan or -inf turned into another of them (a finite reading that is not valid may read back as +inf:
    8.183 m beyond a range_max of 8 m is the code for no return within range)."""
    r = scan.ranges[np.atleast_1d(index)]
    valid, valid_back = (valid_ranges(a, scan.range_min, scan.range_max) for a in (r, back))
    with np.errstate(invalid="ignore"):
        off = valid & (np.abs(back - r) > scale / 2 * (1 + 1e-9))
    kind = ~np.isfinite(r) & ((np.isposinf(r) != np.isposinf(back)) | (np.isnan(r) != np.isnan(back)))
    return (valid != valid_back) | off | kind


def _kept_word(scan: Scan, i: int, units: Units) -> str:
    """Beam ``i``'s range written with the digits it needs to keep its meaning: the shortest
    decimal that reads back as the same float64, or, for a valid reading whose exact value is a
    special code (8.183 m in mm mode at range_max 8.183 m, 81.86 m in cm mode at range_max 100 m),
    the one half a unit below or above it, or a quarter unit below or above it (off the grid)."""
    scale = metres_per_unit(units)
    decimals = 3 if units == "mm" else 2
    r = float(scan.ranges[i])
    words = [_num(r) if math.isfinite(r) else f"{r}"]
    if math.isfinite(r):
        code = round(r / scale)
        words += [f"{(code - 0.5) * scale:.{decimals + 1}f}", f"{(code + 0.5) * scale:.{decimals + 1}f}",
                  # off the grid, a quarter unit away: a valid reading at a range_max off the grid (30.005 m in cm
                  # mode), whose grid words and own value all read as no return (:func:`at_max_range`)
                  f"{r - scale / 4:.{decimals + 2}f}", f"{r + scale / 4:.{decimals + 2}f}"]
    for word in words:
        back = _read_back([word], units, scan.range_max)
        if not _meaning_changed(scan, back, scale, i)[0]:
            return word
    raise AssertionError(f"no CARMEN word keeps range {r!r} m as it is (a bug)")  # pragma: no cover


def _num(value: float) -> str:
    """A float as the shortest plain decimal that reads back as the same float64 (no exponent, for
    CARMEN tools): 6 decimals lost precision (a stamp 1700000000.1234567 came back 238 ns off,
    3.0000004 as 3.0; 1024 beams at 2 pi / 1024 rad ended 7.9e-5 rad off; a review's reproduction)."""
    return np.format_float_positional(float(value), unique=True, trim="0")


def _pose_text(pose: Pose2D | None) -> str:
    x, y, t = pose if pose is not None else (0.0, 0.0, 0.0)
    return f"{_num(x)} {_num(y)} {_num(t)}"


def _flaser_params(scan: Scan) -> dict[str, str]:
    """The PARAM lines (CARMEN names, deg and m) that give a FLASER reader this scan's geometry.

    Raises:
        InputError: for a scan that is not centred on the sensor's x axis (FLASER has no start angle).
    """
    res = math.degrees(scan.angle_increment)
    fov = -2.0 * math.degrees(scan.angle_min)
    n = len(scan)
    if n < 2:  # its field of view, (n - 1) x res, is 0, which no reader's geometry takes
        raise InputError("records: FLASER cannot carry a scan of one beam (its field of view would be 0 deg, which "
                         "the reader refuses); use fmt='robotlaser1'")
    centred = abs(fov / res - (n - 1)) < 1e-6 or abs(fov / res - n) < 1e-6
    if not centred:
        raise InputError(
            f"records: FLASER cannot carry a {n}-beam scan from {math.degrees(scan.angle_min):.2f} deg "
            f"at {res:.3f} deg (not centred ahead); use fmt='robotlaser1'"
        )
    names = laser_geometry.PARAM_NAMES["FLASER"]
    exact = EXACT_GEOMETRY_NAMES["FLASER"]
    return {names[0]: _num(res), names[1]: _num(fov), names[2]: _num(scan.range_max),
            exact[0]: _num(scan.angle_min), exact[1]: _num(scan.angle_increment)}


def write_carmen(
    path: str | Path,
    records: Iterable[Record],
    fmt: str = "robotlaser1",
    hostname: str = "lmsbench",
    flush: bool = False,
) -> int:
    """Write Records as a CARMEN log (plain, or compressed when the name ends in ``.gz``, ``.bz2`` or ``.xz``).

    Each scan becomes one FLASER or ROBOTLASER1 line (``fmt``), preceded by a TRUEPOS line when the
    record has a true pose (a record's ``corrected`` pose is not written: its odometry is). FLASER logs get ``PARAM laser_front_laser_resolution / _fov`` and
    ``robot_front_laser_max`` lines, so any scan centred ahead reads back with its geometry. Ranges
    are written at the sensor unit (mm when range_max <= 8.183 m, else cm), +inf / nan as SICK codes 8183 / 8191
    (a reading whose rounded word would read back with another meaning, :func:`_format_ranges`, with the
    digits it needs: valid stays valid, within half a unit); a ``PARAM lmsbench_range_units`` line records
    the unit, and ``PARAM lmsbench_odometry absent|present`` lines mark records without odometry
    (their pose fields are written as zeros); no CARMEN laser line has a range_min field, so a
    ``PARAM lmsbench_range_min`` line gives it before the first scan whose
    range_min differs from the one before (0 before the first scan, as the reader assumes). ``flush=True`` pushes every scan to the file as soon
    as it is written (for recorders: a crash or Ctrl-C loses nothing already received), and a write
    that fails (a full disk) leaves a plain log cut after its last whole line, not within a scan's.
    Stamps, poses, angles and PARAM values are written as the shortest plain decimal that reads back
    as the same float64 (FLASER logs also get ``PARAM lmsbench_front_laser_angle_min / _increment``
    in rad; a ROBOTLASER1 log ``PARAM lmsbench_robotlaser_angles exact`` before the first scan whose
    angles the reader would snap onto the 0.05 deg grid), so a scan written and read back is equal to it.
    Returns the number of scans written.

    Raises:
        InputError: an unknown ``fmt``, a ``hostname`` that is not one word of printable ASCII, scans of mixed units, or a scan whose range_max lies outside
            [MIN_RANGE_MAX_M, MAX_RANGE_M] (0.1 to 10000 m), an angle_increment under MIN_RESOLUTION_RAD
            (1e-5 rad), a stamp outside 0 .. ``records.MAX_STAMP_S`` (2^32 s) or an odometry or truth pose
            beyond +-``MAX_COORD_M`` (1e9 m) or with a heading beyond +-``MAX_HEADING_RAD`` (1e6 rad), which the
            reader refuses (such a log was written, and could not be read back).
    """
    if not is_one_of(fmt, ("robotlaser1", "flaser")):
        raise InputError(f"fmt: must be 'robotlaser1' or 'flaser', got {fmt!r}")
    if not isinstance(hostname, str) or not re.fullmatch(r"[!-~]+", hostname):  # "my host": two words, no line read back
        raise InputError(f"hostname: must be one word of printable ASCII (a CARMEN line's field), got {hostname!r}")
    path = Path(path)
    kind = COMPRESSION_SUFFIXES.get(path.suffix)
    opener = COMPRESSIONS[kind][1] if kind else open
    count = 0
    units: Units | None = None
    odometry: bool | None = None
    range_min = 0.0  # what the reader assumes without a PARAM line
    exact_angles = False  # PARAM lmsbench_robotlaser_angles exact written
    flaser_params: dict[str, str] = {}
    whole = 0  # bytes of a plain log written with flush up to the end of its last whole line
    try:
        with opener(path, "wt", encoding="ascii") as f:  # type: ignore[operator]
            f.write("# CARMEN log written by lmsbench\n")
            f.write("# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp\n")
            f.write("# ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy remission_mode num_readings [range_readings] num_remissions [remissions] laser_pose_x laser_pose_y laser_pose_theta robot_pose_x robot_pose_y robot_pose_theta laser_tv laser_rv forward_safety_dist side_safty_dist turn_axis ipc_timestamp hostname logger_timestamp\n")
            for rec in records:
                scan = rec.scan
                if not laser_geometry.MIN_RANGE_MAX_M <= scan.range_max <= laser_geometry.MAX_RANGE_M:
                    raise InputError(f"records: item {count}: range_max {scan.range_max:g} m is outside "
                                     f"[{laser_geometry.MIN_RANGE_MAX_M:g}, {laser_geometry.MAX_RANGE_M:g}] m, which "
                                     "the CARMEN reader refuses (the log could not be read back)")
                if scan.angle_increment < laser_geometry.MIN_RESOLUTION_RAD:
                    raise InputError(f"records: item {count}: angle_increment {scan.angle_increment:g} rad is finer "
                                     f"than {laser_geometry.MIN_RESOLUTION_RAD:g} rad, which the CARMEN reader refuses "
                                     "(the log could not be read back)")
                problem = stamp_problem(scan.stamp, "stamp")
                if problem is not None:
                    raise InputError(f"records: item {count}: {problem}; the CARMEN reader refuses it (the log could "
                                     "not be read back)")
                for which, pose in (("odom", rec.odom), ("truth", rec.truth)):
                    problem = None if pose is None else pose_problem(*pose, f"{which} pose")
                    if problem is not None:
                        raise InputError(f"records: item {count}: {problem}, which the CARMEN reader refuses (the log "
                                         "could not be read back)")
                u = _units_of(scan)
                if units is None:
                    units = u
                    f.write(f"PARAM {UNITS_PARAM} {units} {hostname} 0\n")
                elif u != units:
                    raise InputError(f"records: scan at {scan.stamp} is in {u} mode, earlier scans in {units}")
                if odometry is None or odometry != (rec.odom is not None):
                    odometry = rec.odom is not None
                    f.write(f"PARAM {ODOMETRY_PARAM} {'present' if odometry else 'absent'} {hostname} 0\n")
                if scan.range_min != range_min:
                    range_min = scan.range_min
                    f.write(f"PARAM {RANGE_MIN_PARAM} {_num(range_min)} {hostname} 0\n")
                stamp = f"{_num(scan.stamp)} {hostname} {_num(scan.stamp)}"
                ranges = _format_ranges(scan, u)
                odom = _pose_text(rec.odom)
                if fmt != "flaser" and not exact_angles and (snap_angle(scan.angle_min) != scan.angle_min
                                                             or snap_angle(scan.angle_increment) != scan.angle_increment):
                    exact_angles = True  # the reader would snap them onto the grid: it is told to take them as written
                    f.write(f"PARAM {EXACT_ANGLES_PARAM} exact {hostname} 0\n")
                if fmt == "flaser":
                    params = _flaser_params(scan)
                    if params != flaser_params:
                        flaser_params = params
                        for name, value in params.items():
                            f.write(f"PARAM {name} {value} {hostname} 0\n")
                if rec.truth is not None:  # directly before its laser line, as the reader takes it
                    f.write(f"TRUEPOS {_pose_text(rec.truth)} {_pose_text(rec.odom)} {stamp}\n")
                if fmt == "flaser":
                    f.write(f"FLASER {len(scan)} {ranges} {odom} {odom} {stamp}\n")
                else:
                    fov = scan.angle_max - scan.angle_min
                    f.write(
                        f"ROBOTLASER1 0 {_num(scan.angle_min)} {_num(fov)} {_num(scan.angle_increment)} "
                        f"{_num(scan.range_max)} {_num(metres_per_unit(u))} 0 {len(scan)} {ranges} 0 "
                        f"{odom} {odom} 0.000000 0.000000 0.000000 0.000000 0.000000 {stamp}\n"
                    )
                count += 1
                if flush:
                    f.flush()
                    if kind is None:
                        whole = f.buffer.tell()
    except OSError:
        if flush and kind is None:  # a full disk cut the line being written: a recording keeps its whole lines
            try:  # (the reader refused the cut last line; a recorder says how many scans it kept)
                os.truncate(path, whole)
            except OSError:
                pass
        raise
    return count
