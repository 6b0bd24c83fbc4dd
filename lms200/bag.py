"""ROS 1 and ROS 2 bags: ``sensor_msgs/LaserScan`` in and out, through the ``rosbags`` library.

No ROS installation is needed. Writing: a ``.bag`` path gives a ROS 1 bag, any other path a ROS 2
bag folder (sqlite3 storage). Scans go to ``/scan`` (frame ``laser``); a record's odometry and true
pose, when present, go to ``/odom`` and ``/ground_truth`` as ``geometry_msgs/PoseStamped`` with the
scan's stamp, written just before the scan; bag times are the stamps, moved 1 ns past the message
before where needed, so messages read back in the order written. Reading: the bag's LaserScan
topic (a bag with several is refused unless one is named) in bag-time order; odometry from
``/odom`` and truth from ``/ground_truth`` (PoseStamped or nav_msgs/Odometry) by header stamps
(:class:`_PoseMatcher`): a pose stamped like the scan, else the latest one stamped before it
within half the bag's median scan period (``pose_tolerance``) that is no other scan's, else None;
so a record written without odometry or truth reads back without it.
"""

from __future__ import annotations

import io
import math
import os
import struct
import time
from contextvars import ContextVar
from bisect import bisect_left, insort
from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, ClassVar, Iterable, Iterator

import numpy as np

from .codes import finite_negative
from .errors import InputError, LmsbenchError, LogNotFoundError, one_line
from . import laser_geometry
from .records import Pose2D, Record, SkipLog, pose_problem, stamp_problem
from .scan import Scan, snap_float32_angle
from .units import WatchedPasses
from .tum import MAX_TILT_DEG, quaternion_to_yaw, tilt_deg
from .timing import lms200_shaped, mirror_time_increment, scan_period, smallest_range

SCAN_TOPIC = "/scan"
ODOM_TOPIC = "/odom"
TRUTH_TOPIC = "/ground_truth"
_POSE_TYPES = ("geometry_msgs/msg/PoseStamped", "nav_msgs/msg/Odometry")
#: the message types lmsbench deserializes from a bag; the others' definitions are not parsed (see _recovering_reader)
READ_TYPES = frozenset(("sensor_msgs/msg/LaserScan", *_POSE_TYPES))


#: s: how often ``lmsbench lms200 record`` writes a bag's messages out as a chunk (``write_bag(flush_s=...)``)
RECORD_FLUSH_S = 1.0

#: ns: a stamp a ROS 2 bag stores: 0 <= stamp < 2**31 s (builtin_interfaces/Time's sec is int32: 2038-01-19)
MAX_STAMP_NS = 2**31 * 1_000_000_000
#: ns: a stamp a ROS 1 bag stores: 0 <= stamp < 2**32 s (ROS 1's time is uint32 seconds: up to 2^32 - 1 s plus
#: 999999999 ns, 2106-02-07), what the readers take (``records.MAX_STAMP_S``) but 2^32 s itself
MAX_STAMP_NS_ROS1 = 2**32 * 1_000_000_000


class BagError(LmsbenchError):
    """A bag that cannot be read as laser scans; its message is one line (rosbags' own errors, which
    it quotes, span lines: a message definition it cannot parse, quoted whole, or PyYAML's error on
    a ROS 2 bag's metadata.yaml with the text under a caret; found by fuzzing ``read_log``)."""

    def __init__(self, message: object = "", *args: object) -> None:
        super().__init__(one_line(str(message)), *args)


#: characters of a rosbags error quoted in a BagError (a message definition it cannot parse is quoted whole)
MAX_QUOTED_CHARS = 300


def _quoted(exc: BaseException) -> str:
    """``exc``'s text (or its type's name) in one line of at most MAX_QUOTED_CHARS characters."""
    text = one_line(str(exc)) or type(exc).__name__
    return text if len(text) <= MAX_QUOTED_CHARS else text[: MAX_QUOTED_CHARS - 3] + "..."


class BagTooLargeError(BagError):
    """A compressed ROS 1 chunk or ROS 2 message that decompresses to more than
    :data:`MAX_DECOMPRESSED_BYTES` (a compression bomb): refused, never skipped."""


#: bytes: the most one compressed ROS 1 chunk (bz2, lz4) or ROS 2 message (zstd) may decompress to. rosbags
#: decompresses each whole, in memory: a 4 MB lz4 chunk of zeros became 1 GiB (a bz2 one of 79 bytes is 64 MiB).
#: A chunk is ``rosbag record``'s chunk size (768 KiB by default) and one message more.
MAX_DECOMPRESSED_BYTES = 128 * 2**20


#: bytes: the most one storage file of a file-compressed ROS 2 bag (``compression_mode: file``, zstd) may
#: decompress to. rosbags decompresses each whole to a temporary file before it reads a message (sqlite3 and
#: mcap need the file): its memory is bounded, its disk was not (a 1 MB file of zeros filled 1 GiB of the
#: temporary folder, a bomb of a few MB the disk). An hour of 361-beam scans at 75 Hz is about 0.4 GB.
MAX_DECOMPRESSED_FILE_BYTES = 4 * 2**30

#: bytes: what a file-compressed ROS 2 bag's decompression leaves free in the temporary folder at least
#: (``tempfile.gettempdir()``, ``$TMPDIR``), or half of what was free when it began where that is less
#: (a bag of 2 KB was refused on a folder with 900 MiB free); it is refused before it would leave less.
MIN_FREE_TEMP_BYTES = 1 * 2**30

#: bytes decompressed between two looks at the temporary folder's free space
FREE_CHECK_BYTES = 64 * 2**20


#: True only while lmsbench itself reads a bag (:func:`_lmsbench_read`, :func:`_read_inside`): rosbags' functions
#: that lms200.bag replaces (mcap ``read_sized`` / ``read_exact`` / ``skip_exact`` / ``decompress``, the storage
#: readers' ``_open`` and ``McapReader.messages``, AnyReader's definition parsers, the ROS 2 reader's zstd) are
#: replaced for the whole process, and pass straight through to rosbags' own unless it is set: another user of
#: rosbags in the process, after an lmsbench read, got lmsbench's bounds and messages
_IN_LMSBENCH_READ: ContextVar[bool] = ContextVar("lmsbench_bag_read", default=False)


class _lmsbench_read:
    """Within it, rosbags' functions that lms200.bag replaces apply its bounds (:data:`_IN_LMSBENCH_READ`)."""

    def __enter__(self) -> None:
        self._token = _IN_LMSBENCH_READ.set(True)

    def __exit__(self, *exc: object) -> None:
        _IN_LMSBENCH_READ.reset(self._token)


def _read_inside(items: Iterator[Any]) -> Iterator[Any]:
    """``items`` (rosbags' messages) with each step taken inside :class:`_lmsbench_read`, and the caller's code
    between steps outside it (a context variable set in a generator is its caller's)."""
    while True:
        with _lmsbench_read():
            try:
                item = next(items)
            except StopIteration:
                return
        yield item


def _too_large(what: str) -> BagTooLargeError:
    return BagTooLargeError(f"{what} decompresses to more than {MAX_DECOMPRESSED_BYTES / 2**20:g} MiB "
                            "(lms200.bag.MAX_DECOMPRESSED_BYTES): a compression bomb, or chunks or messages "
                            "far larger than a bag of laser scans holds; not read")


def _bounded(data: bytes, new_decompressor: Callable[[], Any], what: str, all_frames: bool) -> bytes:
    """``data`` decompressed frame after frame (bz2 streams, zstd frames; only the first lz4 frame,
    as ``lz4.frame.decompress``), never more than MAX_DECOMPRESSED_BYTES + 1 bytes of output at
    once: BagTooLargeError beyond it; ValueError for data that ends inside a frame."""
    out = bytearray()
    rest = bytes(data)
    while rest:
        d = new_decompressor()
        out += d.decompress(rest, max_length=MAX_DECOMPRESSED_BYTES + 1 - len(out))
        if len(out) > MAX_DECOMPRESSED_BYTES:
            raise _too_large(what)
        if not d.eof:
            raise ValueError("compressed data ended before the end-of-stream marker was reached")
        rest = d.unused_data if all_frames else b""
    return bytes(out)


def _bound_decompression(reader: Any, path: Path) -> None:  # noqa: ANN401 - rosbags' AnyReader
    """Bound what ``reader`` (an open rosbags AnyReader) decompresses at once (MAX_DECOMPRESSED_BYTES):
    rosbags decompresses a ROS 1 chunk whole (``Chunk.decompressor``) and a ROS 2 message whole
    (``zstd.decompress`` in ``rosbags.rosbag2.reader``); each is replaced by a bounded decompression."""
    import bz2

    import lz4.frame

    from rosbags.rosbag1 import reader as reader1

    bounded = {
        reader1.decompressors["bz2"]: lambda data: _bounded(data, bz2.BZ2Decompressor, f"{path}: a bz2 chunk", True),
        reader1.decompressors["lz4"]: lambda data: _bounded(data, lz4.frame.LZ4FrameDecompressor,
                                                             f"{path}: an lz4 chunk", False),
    }
    for r in getattr(reader, "readers", ()):
        chunks = getattr(r, "chunks", None)
        if isinstance(chunks, dict):
            r.chunks = {pos: c._replace(decompressor=bounded.get(c.decompressor, c.decompressor))
                        for pos, c in chunks.items()}
    _bound_zstd_messages()


def _bound_zstd_messages() -> None:
    """rosbags' ROS 2 reader decompresses a message with its module's ``zstd.decompress`` and a
    file-compressed bag's storage files with its ``zstd.open`` (streamed to a temporary file): that
    name is pointed at a module whose both are bounded (:class:`_BoundedZstd`)."""
    from rosbags.rosbag2 import reader as reader2

    if isinstance(reader2.zstd, _BoundedZstd):
        return
    reader2.zstd = _BoundedZstd(reader2.zstd)  # type: ignore[assignment]


class _BoundedZstd:
    """The zstd module rosbags' ROS 2 reader uses, with a ``decompress`` bounded by MAX_DECOMPRESSED_BYTES."""

    def __init__(self, module: Any) -> None:  # noqa: ANN401 - a module
        self._module = module

    def __getattr__(self, name: str) -> Any:  # noqa: ANN401
        return getattr(self._module, name)

    def decompress(self, data: bytes) -> bytes:
        if not _IN_LMSBENCH_READ.get():
            return self._module.decompress(data)  # type: ignore[no-any-return]
        try:
            return _bounded(data, self._module.ZstdDecompressor, "a zstd-compressed message", True)
        except BagTooLargeError as exc:
            raise _unnamed(exc) from None

    def open(self, file: Any, mode: str = "rb", **kwargs: Any) -> Any:  # noqa: ANN401
        """rosbags opens a file-compressed bag's storage file so and copies it whole to a temporary
        file: the stream read is bounded (:class:`_BoundedZstdFile`)."""
        stream = self._module.open(file, mode, **kwargs)
        if not _IN_LMSBENCH_READ.get():
            return stream
        return _BoundedZstdFile(stream, str(getattr(file, "name", file))) if "r" in mode else stream


def _unnamed(exc: BagTooLargeError) -> BagTooLargeError:
    """``exc``, marked as naming no file: :class:`BagReader` puts the bag's path before its message
    (told by the mark, not by the path's text within the message: a bag named ``bag`` or ``msg``
    was found in any message and went unnamed)."""
    exc.lmsbench_unnamed = True  # type: ignore[attr-defined]
    return exc


def _free_temp_bytes() -> int:
    """Free bytes in the temporary folder, where rosbags decompresses a file-compressed ROS 2 bag."""
    import shutil
    import tempfile

    return shutil.disk_usage(tempfile.gettempdir()).free


class _BoundedZstdFile:
    """A file-compressed ROS 2 bag's storage file as rosbags reads it to decompress it to a temporary
    file: BagTooLargeError naming the file once more than MAX_DECOMPRESSED_FILE_BYTES are read, or
    before what is read would leave less than MIN_FREE_TEMP_BYTES free in the temporary folder
    (looked at every FREE_CHECK_BYTES and at the start)."""

    def __init__(self, stream: Any, name: str) -> None:  # noqa: ANN401
        self._stream, self._name = stream, name
        self._read = 0
        self._checked = -FREE_CHECK_BYTES  # the free space is looked at before the first read
        self._free = 0
        self._reserve = -1  # bytes to leave free: MIN_FREE_TEMP_BYTES, or half the free space at the start

    def __enter__(self) -> "_BoundedZstdFile":
        return self

    def __exit__(self, *exc: object) -> None:
        self._stream.close()

    def __getattr__(self, name: str) -> Any:  # noqa: ANN401
        return getattr(self._stream, name)

    def read(self, size: int = -1) -> bytes:
        limit = MAX_DECOMPRESSED_FILE_BYTES + 1 - self._read
        data = self._stream.read(limit if size is None or size < 0 else min(size, limit))
        self._count(len(data))
        return data

    def readinto(self, buffer: Any) -> int:  # noqa: ANN401
        view = memoryview(buffer)[: MAX_DECOMPRESSED_FILE_BYTES + 1 - self._read]
        n = self._stream.readinto(view)
        self._count(n)
        return n

    def _count(self, n: int) -> None:
        self._read += n
        if self._read > MAX_DECOMPRESSED_FILE_BYTES:
            raise BagTooLargeError(
                f"{self._name}: a zstd-compressed storage file (compression_mode: file) decompresses to more than "
                f"{MAX_DECOMPRESSED_FILE_BYTES / 2**20:g} MiB (lms200.bag.MAX_DECOMPRESSED_FILE_BYTES): a "
                "compression bomb, or a bag far larger than one of laser scans; not read")
        if self._read - self._checked >= FREE_CHECK_BYTES:
            self._free, self._checked = _free_temp_bytes(), self._read
            if self._reserve < 0:
                self._reserve = min(MIN_FREE_TEMP_BYTES, self._free // 2)
        if self._free - (self._read - self._checked) < self._reserve:
            import tempfile

            raise BagTooLargeError(
                f"{self._name}: a zstd-compressed storage file (compression_mode: file), decompressed to the "
                f"temporary folder {tempfile.gettempdir()} (where rosbags reads it), would leave less than "
                f"{self._reserve / 2**20:.0f} MiB free there (lms200.bag.MIN_FREE_TEMP_BYTES, or half the free space "
                "at the start; "
                f"{self._read / 2**20:.0f} MiB decompressed so far); not read (TMPDIR names a folder with more room)")


#: bytes: the largest ROS 2 metadata.yaml read (a bag's is a few KB; a thousand topics with their QoS
#: strings, or thousands of split storage files, stay under it). Both this reader and rosbags parse it
#: whole in pure Python, about 50 s and 180 MB a MiB: a 5.5 MB one held `lmsbench info` 267 s at 1 GB
MAX_METADATA_BYTES = 1 << 20


def check_metadata_size(folder: Path) -> None:
    """BagError for a ROS 2 bag folder whose metadata.yaml is larger than MAX_METADATA_BYTES, before
    anything parses it (the command line's check, this reader and rosbags each parsed it whole: a
    5.5 MB one held `lmsbench info` 340 s at 1 GB resident, and memory grows with it)."""
    meta = folder / "metadata.yaml"
    size = meta.stat().st_size
    if size > MAX_METADATA_BYTES:
        raise BagError(f"{meta}: {size:,} bytes, more than the {MAX_METADATA_BYTES:,} a ROS 2 bag's metadata.yaml may "
                       "hold (refused unread: a bag's is a few KB, one of a thousand topics or of thousands of storage "
                       "files well under 1 MiB)")


def _check_storage_files(path: Path) -> None:
    """BagError for a ROS 2 bag whose metadata.yaml lists one storage file more than once
    (``relative_file_paths``; rosbags takes each by its name): its messages were read once for each
    listing (3 scans read as 6, stamps going back, exit 0). A metadata.yaml that does not read is
    left to rosbags, which says why."""
    from pathlib import PurePath

    from .yamlio import load

    try:
        info = load((path / "metadata.yaml").read_text(encoding="utf-8"), words=True)  # rosbag2 wrote it
        listed = [PurePath(str(x)).name for x in info["rosbag2_bagfile_information"]["relative_file_paths"]]
    except Exception:  # noqa: BLE001 - rosbags reads it next, and says what is wrong
        return
    twice = sorted({name for name in listed if listed.count(name) > 1})
    if twice:
        raise BagError(f"{path}: its metadata.yaml lists the storage file{'s' if len(twice) > 1 else ''} "
                       f"{', '.join(twice)} more than once (relative_file_paths); each message would be read once "
                       "for each listing")


class BagExistsError(InputError, FileExistsError):
    """``write_log`` to a bag path that exists (a bag is never written over)."""


def is_bag(path: str | Path) -> bool:
    """True for a ROS 1 ``.bag`` file or a ROS 2 bag folder (with ``metadata.yaml``)."""
    p = Path(path)
    return (p.is_file() and p.suffix == ".bag") or (p.is_dir() and (p / "metadata.yaml").is_file())


def _typestore(ros1: bool):  # noqa: ANN202 - rosbags' Typestore
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


def _stamp_ns(t: float) -> int:
    """A float stamp (s) as the nearest integer nanosecond, computed exactly (``round(t * 1e9)``
    in float64 was off by up to 119 ns for epoch stamps: 1602566218.7060776 stored ...706077696)."""
    return round(Fraction(t) * 1_000_000_000)


def _ns_stamp(ns: int) -> float:
    """Integer nanoseconds as the float (s) nearest to them (``sec + nanosec * 1e-9`` was not)."""
    return float(Fraction(ns, 1_000_000_000))


def write_bag(path: str | Path, records: Iterable[Record | None], topic: str = SCAN_TOPIC,
              flush_s: float | None = None) -> int:
    """Write Records to a ROS 1 (``*.bag``) or ROS 2 (folder) bag; returns the number of scans.

    Ranges are stored as float32 (the message type), +inf / nan kept as they are (REP-117).
    The fields a Scan does not carry come from the LMS200 (``lms200.timing``): ``time_increment``
    the mirror's time per beam step (0.5 deg: 18.5 us), ``scan_time`` the sensor's scan period
    (0.5 deg: 26.7 ms), both 0 (unknown, as ROS allows) for a scan no LMS200 takes
    (``lms200_shaped``), ``range_min`` the scan's own, or one code unit (1 mm, or 1 cm for cm-mode
    scans) where that is 0.

    ``flush_s`` (ROS 1 only; ``lmsbench lms200 record`` gives ``RECORD_FLUSH_S``): the messages
    held in memory are written to the file as a chunk and flushed (and synced to the disk) after the
    first scan, and then once this many seconds have passed since the last chunk, so a writer killed
    (SIGKILL, a power cut) before it closes the bag and writes its index leaves every chunk before
    the kill readable (``BagReader`` recovers an unindexed bag from its chunks, with a warning). By
    default rosbags holds a chunk until it passes 1 MiB: a killed recording of a few seconds was a
    file of the bag's header alone (and one killed in its first second, before its first chunk, was
    so still). An item None of ``records`` is no record but a tick: the messages held are written out
    if they are due, so a source that has no scan for a while (a device gone silent) gives None
    meanwhile (``LMS200.scans(idle_s=...)``) and its last scans reach the file on time: they waited
    for the next scan, and a recording killed in a stall lost them.

    Raises:
        BagExistsError: (an ``InputError`` and a ``FileExistsError``) ``path`` exists.
        InputError: a scan stamp outside 0 <= stamp < 2**32 s in a ROS 1 bag (uint32 seconds), outside
            0 <= stamp < 2**31 s in a ROS 2 bag (int32 seconds) (naming the item and the stamp). The
            records before the refused one are left in ``path`` as a readable bag.
    """
    path = Path(path)
    ros1 = path.suffix == ".bag"
    if path.exists() or path.is_symlink():  # was a bare FileExistsError
        raise BagExistsError(f"path: {path} exists; a bag is never written over: remove it or name another")
    ts = _typestore(ros1)
    T = ts.types
    LaserScan, Header, Time = T["sensor_msgs/msg/LaserScan"], T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    PoseStamped, Pose = T["geometry_msgs/msg/PoseStamped"], T["geometry_msgs/msg/Pose"]
    Point, Quaternion = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    writer: Any
    if ros1:
        from rosbags.rosbag1 import Writer as Writer1

        writer = Writer1(path)
    else:
        from rosbags.rosbag2 import Writer as Writer2

        writer = Writer2(path, version=8)
    limit_ns = MAX_STAMP_NS_ROS1 if ros1 else MAX_STAMP_NS
    holds = (f"a ROS 1 bag holds 0 <= stamp < 2**32 s = {MAX_STAMP_NS_ROS1 // 1_000_000_000} s, uint32 seconds" if ros1
             else f"a ROS 2 bag holds 0 <= stamp < 2**31 s = {MAX_STAMP_NS // 1_000_000_000} s, int32 seconds; "
                  "a ROS 1 bag (*.bag) holds stamps to 2**32 s")
    count = 0
    last = [-1]  # the bag time of the message written last (ns)
    flushed = [-math.inf]  # when the last chunk was written (time.monotonic()): the first scan's at once

    def flush() -> None:
        """The messages held written out as a chunk, and the file flushed (see ``flush_s``), when
        there are any and the last chunk is ``flush_s`` old."""
        if flush_s is None or not ros1 or time.monotonic() - flushed[0] < flush_s:
            return
        if writer.chunks[-1].data.tell() == 0:  # nothing held: a tick after the last chunk (no fsync for nothing)
            return
        writer.write_chunk(writer.chunks[-1])
        writer.bio.flush()
        os.fsync(writer.bio.fileno())  # on the disk, not only the OS's cache: a power cut keeps it too
        flushed[0] = time.monotonic()

    def bag_time(ns: int) -> int:
        """The stamp, or 1 ns after the message before: ROS 1 orders messages of one bag time by
        topic, so a record's poses and scan, or records of one stamp, came back out of the order
        written and could not be told apart."""
        last[0] = max(ns, last[0] + 1)
        if last[0] >= limit_ns:  # records of the last stamp a bag holds, moved past it (was struct.error)
            raise InputError(f"records: item {count}: bag time {last[0]} ns (the stamp, moved 1 ns past the message "
                             f"before) cannot be stored in a bag ({holds})")
        return last[0]

    with writer:
        kw = {"typestore": ts}
        conns: dict[str, object] = {}

        def conn(name: str, msgtype: str):  # noqa: ANN202
            if name not in conns:
                conns[name] = writer.add_connection(name, msgtype, **kw)
            return conns[name]

        try:
            for rec in records:
                if rec is None:  # a tick: no record (see flush_s)
                    flush()
                    continue
                seq = count
                scan = rec.scan
                ns = _stamp_ns(scan.stamp)
                if scan.stamp < 0 or ns >= limit_ns:  # was struct.error from rosbags' serialiser
                    raise InputError(f"records: item {seq}: stamp {scan.stamp!r} s cannot be stored in a bag ({holds})")
                if np.float32(scan.angle_increment) == 0:  # stored as 0, which no reader takes ("must be > 0, got 0.0")
                    raise InputError(f"records: item {seq}: angle_increment {scan.angle_increment:g} rad cannot be stored "
                                     f"in a bag (a LaserScan's fields are float32, in which it is 0)")
                if scan.angle_increment < laser_geometry.MIN_RESOLUTION_RAD:  # a bag its own reader refuses
                    raise InputError(f"records: item {seq}: angle_increment {scan.angle_increment:g} rad is finer than "
                                     f"{laser_geometry.MIN_RESOLUTION_RAD:g} rad, which the bag reader refuses")
                if scan.range_max > FLOAT32_MAX or np.any(np.isfinite(scan.ranges) & (scan.ranges > FLOAT32_MAX)):
                    raise InputError(f"records: item {seq}: a range or range_max beyond {FLOAT32_MAX:.4g} m cannot be "
                                     f"stored in a bag (a LaserScan's fields are float32), got range_max {scan.range_max:g} m")
                if not laser_geometry.MIN_RANGE_MAX_M <= scan.range_max <= laser_geometry.MAX_RANGE_M:
                    raise InputError(f"records: item {seq}: range_max {scan.range_max:g} m is outside "
                                     f"[{laser_geometry.MIN_RANGE_MAX_M:g}, {laser_geometry.MAX_RANGE_M:g}] m, which "
                                     "the bag reader refuses")
                sec, nsec = divmod(ns, 1_000_000_000)
                if sec >= 2**31:  # ROS 1's uint32 seconds, which rosbags packs as int32: the same four bytes
                    sec -= 2**32
                header_kw = {"stamp": Time(sec=sec, nanosec=nsec), "frame_id": "laser"}

                if ros1:
                    header_kw["seq"] = seq
                for name, pose in ((ODOM_TOPIC, rec.odom), (TRUTH_TOPIC, rec.truth)):
                    if pose is None:
                        continue
                    x, y, th = pose
                    problem = pose_problem(x, y, th, f"{'odom' if name == ODOM_TOPIC else 'truth'} pose")
                    if problem is not None:  # a bag its own reader refuses (1e300 rad: its quaternion noise, read back as one)
                        raise InputError(f"records: item {seq}: {problem}, which the bag reader refuses")
                    msg = PoseStamped(
                        header=Header(**{**header_kw, "frame_id": "map" if name == TRUTH_TOPIC else "odom"}),
                        pose=Pose(
                            position=Point(x=float(x), y=float(y), z=0.0),
                            orientation=Quaternion(x=0.0, y=0.0, z=float(np.sin(th / 2)), w=float(np.cos(th / 2))),
                        ),
                    )
                    c = conn(name, "geometry_msgs/msg/PoseStamped")
                    writer.write(c, bag_time(ns), serialize(msg, "geometry_msgs/msg/PoseStamped"))
                if lms200_shaped(len(scan), scan.angle_increment):
                    time_increment, scan_time = mirror_time_increment(scan.angle_increment), scan_period(scan.angle_increment)
                else:  # another scanner: its timing is unknown (the LMS200's mirror's was written, as if it were one)
                    time_increment = scan_time = 0.0
                range_min = max(scan.range_min, smallest_range(scan.range_max))
                msg = LaserScan(
                    header=Header(**header_kw),
                    angle_min=scan.angle_min,
                    angle_max=scan.angle_max,
                    angle_increment=scan.angle_increment,
                    time_increment=time_increment,
                    scan_time=scan_time,
                    range_min=range_min,
                    range_max=scan.range_max,
                    ranges=float32_ranges(scan.ranges, range_min, scan.range_max),
                    intensities=np.zeros(0, dtype=np.float32),
                )
                writer.write(conn(topic, "sensor_msgs/msg/LaserScan"), bag_time(ns), serialize(msg, "sensor_msgs/msg/LaserScan"))
                count += 1
                flush()
        except InputError:  # a refused scan: the ones before it stay a readable bag, as a CARMEN log's do
            # (the writer was left to rosbags' abort, unindexed, "Bag is not indexed": `lms200 record` said
            # "the 3 scans before it are saved" of a bag that could not be read; found by the session's review)
            writer.close()
            raise
    return count


def _pose_of(msg) -> Pose2D:  # noqa: ANN001
    """A PoseStamped's or Odometry's (x, y, yaw); ValueError for a position that is not finite or a
    zero or non-finite quaternion (normalised otherwise: (0, 0, 1, 1) is 90 deg, was 116.57 deg; (0, 0, 0, 0) was yaw 0)."""
    pose = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
    q = pose.orientation
    yaw = float(quaternion_to_yaw(np.array([q.x, q.y, q.z, q.w], dtype=float))[0])
    if np.isnan(yaw):
        raise ValueError(f"orientation (x, y, z, w) = ({q.x!r}, {q.y!r}, {q.z!r}, {q.w!r}) is no rotation "
                         "(a quaternion must have a positive finite norm)")
    tilt = tilt_deg(np.array([q.x, q.y, q.z, q.w], dtype=float))
    if tilt > MAX_TILT_DEG:  # as read_tum: its yaw is no heading in the plane (was read as one, silently)
        raise ValueError(f"orientation (x, y, z, w) = ({q.x!r}, {q.y!r}, {q.z!r}, {q.w!r}) is tilted {tilt:.1f} deg "
                         f"from upright (roll or pitch; at most {MAX_TILT_DEG:g} deg): its z axis is not up, so its "
                         "yaw is no heading in the plane")
    x, y = float(pose.position.x), float(pose.position.y)
    if not (np.isfinite(x) and np.isfinite(y)):  # was Record's "odom: must be finite", without bag, topic or index
        raise ValueError(f"position (x, y) = ({x!r}, {y!r}) is not finite")
    problem = pose_problem(x, y, yaw, "pose")  # as the CARMEN, TUM and relations readers: 1e300 m was read (a review)
    if problem is not None:
        raise ValueError(problem)
    return (x, y, yaw)


def _stamp_of(msg) -> float:  # noqa: ANN001
    return _ns_stamp(_header_ns(msg))


def _header_ns(msg) -> int:  # noqa: ANN001
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


def _unsigned_ros1_stamp(msg):  # noqa: ANN001, ANN202
    """``msg`` with its header stamp's seconds read as ROS 1 has them, uint32: rosbags decodes them
    as int32, so a ROS 1 stamp from 2^31 s (2038-01-19) read negative and was refused."""
    stamp = msg.header.stamp
    if stamp.sec < 0:
        stamp.sec += 2**32
    return msg


def _checked_pose_ns(msg) -> int:  # noqa: ANN001
    """A pose message's header stamp (ns); ValueError for one outside 0 .. ``records.MAX_STAMP_S``
    (as a scan's: a pose stamped 1e300 s or negative was matched on, silently)."""
    ns = _header_ns(msg)
    problem = stamp_problem(_ns_stamp(ns), "header stamp")
    if problem is not None:
        raise ValueError(problem)
    return ns


#: what a user can do about a LaserScan's range_max that no Scan takes
RANGE_MAX_HINT = ("give the sensor's maximum range instead: --laser-range-max M "
                  "(read_log(..., geometry=LaserGeometry(range_max=M)))")


def float32_ranges(ranges: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
    """``ranges`` (m) as a LaserScan's float32, each on the side of ``range_min`` and ``range_max``
    (written as float32 too) it lies on: REP-117 takes a reading above range_max (or below range_min)
    for out of range, and a reader compares in the message's float32, where rounding put a reading
    just above range_max onto it (8.18300005 m under 8.183 m: both 8.1829996 m), read back valid.
    Such a reading is written as the next float32 beyond the limit; every other as its nearest float32."""
    low, high = np.float32(range_min), np.float32(range_max)
    with np.errstate(invalid="ignore"):  # a signalling nan's cast warned ("invalid value encountered in cast")
        out = ranges.astype(np.float32)
        out[(ranges > range_max) & (out <= high)] = np.nextafter(high, np.float32(np.inf))
        out[(ranges < range_min) & (ranges > 0) & (out >= low)] = np.nextafter(low, np.float32(0))
    return out


def _scan_of(msg, range_max: float | None = None) -> Scan:  # noqa: ANN001
    """A LaserScan message as a Scan, its range_max replaced by ``range_max`` when given (a reading
    stored as its float32 is at that limit); raises
    ValueError for fields a scan cannot have."""
    range_min = float(msg.range_min)
    override = range_max is not None
    if range_max is None:
        range_max = float(msg.range_max)
        if not math.isfinite(range_max) or (math.isfinite(range_min) and range_max <= range_min):
            # was "range_max: must be finite, got inf", no word of what to do
            what = ("inf (no limit, as some drivers write)" if range_max == math.inf
                    else f"{range_max:g}" if not math.isfinite(range_max)
                    else f"{range_max:g} m, not above range_min ({range_min:g} m)")
            raise ValueError(f"range_max is {what}, which no scan takes (a reading's validity is judged against "
                             f"it); {RANGE_MAX_HINT}")
        # the CARMEN reader's and --laser-range-max's bounds: range_max 1e30 m was read (a 0.05 m one too)
        if not laser_geometry.MIN_RANGE_MAX_M <= range_max <= laser_geometry.MAX_RANGE_M:
            raise ValueError(f"range_max is {range_max:g} m, outside [{laser_geometry.MIN_RANGE_MAX_M:g}, "
                             f"{laser_geometry.MAX_RANGE_M:g}] m, which no laser rangefinder's maximum range lies "
                             f"outside; {RANGE_MAX_HINT}")
    elif math.isfinite(range_min) and range_max <= range_min:
        raise ValueError(f"the range_max override ({range_max:g} m, --laser-range-max) is not above the scan's "
                         f"range_min ({range_min:g} m); give a larger one")
    with np.errstate(invalid="ignore"):  # a signalling nan (float32 0x7f800001, a driver's raw bits) is a nan:
        ranges = np.asarray(msg.ranges, dtype=np.float64)  # its cast warned, two lines a scan on stderr, exit 0
    if override and range_max <= FLOAT32_MAX and np.asarray(msg.ranges).dtype == np.float32:
        # compared in the message's float32, as its own range_max is: a reading stored as float32(M), just above
        # M for about half of all M (81.83 m -> 81.83000183), is at the limit, not beyond it (it read invalid)
        at_limit = float(np.float32(range_max))
        if at_limit > range_max:
            ranges[ranges == at_limit] = range_max
    ranges[finite_negative(ranges)] = np.nan  # some drivers mark invalid beams with negative values; -inf is REP-117's "too close"
    angle_min, increment = float(msg.angle_min), float(msg.angle_increment)
    if increment < 0 and ranges.size > 0:  # a laser mounted upside down sweeps clockwise: same bearings, ascending
        ranges, angle_min, increment = ranges[::-1].copy(), angle_min + (ranges.size - 1) * increment, -increment
    # the bound of the CARMEN reader and the geometry overrides, compared in the message's float32 (in which
    # 1e-5 rad is 9.99999975e-06): an angle_increment of 1e-30 rad was read
    if 0 < increment < MIN_INCREMENT_FLOAT32:
        raise ValueError(f"angle_increment is {increment:.6g} rad ({math.degrees(increment):.6g} deg), finer than any "
                         f"rangefinder's step (at least {laser_geometry.MIN_RESOLUTION_RAD:g} rad, "
                         f"{math.degrees(laser_geometry.MIN_RESOLUTION_RAD):.5f} deg)")
    stamp = _stamp_of(msg)
    problem = stamp_problem(stamp, "header stamp")
    if problem is not None:  # a ROS 2 stamp may be negative (int32 seconds); a ROS 1 one is read unsigned
        raise ValueError(problem)
    return Scan(
        ranges,
        snap_float32_angle(angle_min),  # float32 in the message: back onto the 0.05 deg grid where its rounding explains
        snap_float32_angle(increment),
        range_min,
        range_max,
        stamp,
    )


#: m: the largest finite float32, a LaserScan's range fields (1e300 was rosbags' raw OverflowError
#: "float too large to pack with f format" and a RuntimeWarning from the float32 cast)
FLOAT32_MAX = float(np.finfo(np.float32).max)
#: rad: ``laser_geometry.MIN_RESOLUTION_RAD`` as a LaserScan's float32 stores it (a bag's finest angle_increment)
MIN_INCREMENT_FLOAT32 = float(np.float32(laser_geometry.MIN_RESOLUTION_RAD))

_TIME = "builtin_interfaces/msg/Time"
#: how ROS lays out the start of a LaserScan (its header, then the header's stamp), ROS 1 and ROS 2:
#: either way the stamp's sec (int32) and nanosec (uint32) are bytes 4 to 11 of the serialized
#: message (ROS 1: after the header's seq; ROS 2: after CDR's 4-byte encapsulation header)
_SCAN_LAYOUT = {
    "sensor_msgs/msg/LaserScan": ("header", "std_msgs/msg/Header"),
    "ros1 std_msgs/msg/Header": (("seq", ("uint32", 0)), ("stamp", _TIME)),
    "ros2 std_msgs/msg/Header": (("stamp", _TIME),),
    _TIME: (("sec", ("int32", 0)), ("nanosec", ("uint32", 0))),
}
_STAMP_CDR_LE, _STAMP_BE = struct.Struct("<iI"), struct.Struct(">iI")
_STAMP_ROS1 = struct.Struct("<II")  # ROS 1: uint32 seconds (as _unsigned_ros1_stamp reads the decoded message)


def _raw_stamp_reader(reader) -> Callable[[bytes], int | None] | None:  # noqa: ANN001 - rosbags' AnyReader
    """A function giving a serialized LaserScan's header stamp (ns), as :func:`_header_ns` of the
    decoded message gives it, read from its bytes 4 to 11 (None for bytes that cannot hold one),
    when the bag's message definitions lay the message out as ROS does; else None (then scans are
    decoded for their stamps)."""
    ros2 = bool(reader.is2)
    try:
        defs = reader.typestore.fielddefs
        layout = (
            tuple((name, typ) for name, (_, typ) in defs["sensor_msgs/msg/LaserScan"][1][:1])[0],
            tuple((name, typ) for name, (_, typ) in defs["std_msgs/msg/Header"][1][: 1 if ros2 else 2]),
            tuple((name, typ) for name, (_, typ) in defs[_TIME][1]),
        )
    except (KeyError, IndexError, TypeError, ValueError):
        return None
    header = "ros2 std_msgs/msg/Header" if ros2 else "ros1 std_msgs/msg/Header"
    if layout != (_SCAN_LAYOUT["sensor_msgs/msg/LaserScan"], _SCAN_LAYOUT[header], _SCAN_LAYOUT[_TIME]):
        return None

    def stamp(raw: bytes) -> int | None:
        if len(raw) < 12 or (ros2 and (raw[0] != 0 or raw[1] > 1)):
            return None
        sec, nanosec = (_STAMP_ROS1 if not ros2 else _STAMP_CDR_LE if raw[1] else _STAMP_BE).unpack_from(raw, 4)
        return sec * 1_000_000_000 + nanosec

    return stamp


STAMP_EPS_S = 1e-6  # s: the least pose tolerance; scans stamped this close have one stamp


def pose_tolerance(scan_stamps_ns: Iterable[int]) -> float:
    """How far (s) a pose's stamp may lie before a scan's for the pose to be attached to the scan:
    half the median period between consecutive scans by header stamp (the stamps matching compares;
    bag times of a bulk-converted or bursty bag can lie microseconds apart), steps of
    ``STAMP_EPS_S`` or less (scans of one stamp) being no period; at least ``STAMP_EPS_S``; a
    single scan gets ``STAMP_EPS_S``."""
    t = np.sort(np.fromiter(scan_stamps_ns, dtype=np.int64))
    periods = np.diff(t)
    periods = periods[periods > STAMP_EPS_S * 1e9]  # a microsecond or less: one stamp
    if periods.size == 0:
        return STAMP_EPS_S
    return max(0.5 * float(np.median(periods)) * 1e-9, STAMP_EPS_S)


@dataclass
class BagReadStats(SkipLog):
    """What a pass over a bag met.

    Attributes:
        messages: messages per topic read (scan and pose topics).
        skipped: the bad messages skipped under ``skip_bad_lines``: (message index on its topic, reason),
            the first ``lms200.records.MAX_SKIPPED_KEPT`` of them; ``skipped_count`` counts them all.
        stopped: why reading ended early (the bag cannot be iterated further), or None.
        laser: the LaserScan topic read.
    """

    messages: dict[str, int] = field(default_factory=dict)
    stopped: str | None = None
    laser: str | None = None
    time_increment_range: tuple[float, float] | None = None  # the least and largest time_increment read (s)
    time_increment_sum: float = 0.0  # of the scans' time_increment values (s), for their mean
    timed_scans: int = 0  # scans whose time_increment was noted
    clockwise: bool = False  # some scan swept clockwise (negative angle_increment; read reversed)

    #: time_increment values within this ratio of each other are one timing (drivers that measure
    #: each scan's period, such as rplidar_ros, give a slightly different value in every scan)
    TIMING_SPREAD: ClassVar[float] = 1.05

    @property
    def time_increment(self) -> float | None:
        """The seconds between consecutive beams the LaserScans give (``time_increment``; their
        mean where they lie within TIMING_SPREAD of each other), in the order the scans are read;
        None where any gives 0 (unknown) or they differ more, or any scan swept clockwise (read
        reversed, its last beam first)."""
        if self.clockwise or self.time_increment_range is None:
            return None
        low, high = self.time_increment_range
        if not (math.isfinite(high) and low > 0 and high <= self.TIMING_SPREAD * low):
            return None
        return low if low == high else self.time_increment_sum / self.timed_scans  # one value: exactly it

    def see_timing(self, time_increment: float, angle_increment: float) -> None:
        """Note one LaserScan's ``time_increment`` (s) and ``angle_increment`` (rad)."""
        self.clockwise |= angle_increment < 0
        if not math.isfinite(time_increment):
            time_increment = 0.0  # unknown
        low, high = self.time_increment_range or (time_increment, time_increment)
        self.time_increment_range = (min(low, time_increment), max(high, time_increment))
        self.time_increment_sum += time_increment
        self.timed_scans += 1


#: bytes: the largest record header an unindexed ROS 1 bag's sequential scan takes (a connection's
#: header holds its message definition: a few KB); a larger one is damage, not a record
MAX_RECORD_HEADER_BYTES = 16 * 2**20

#: bytes: the most a ROS 1 connection record's fields (type, md5sum, callerid and the message
#: definition, with those of every type it uses and their comments) may hold. rosbags reads each
#: whole and parses the definition with a parser that costs about 1-10 us and 50 bytes of memory a
#: byte: a 5.6 MB definition of comment lines took 6 s and 65 MB in `lmsbench info` (58 s and 340 MB as
#: field lines). A definition is a few KB: the largest rosbags' Noetic store writes (visualization_msgs/
#: InteractiveMarkerUpdate, with every type it uses) is 3 KB without comments; a larger one is refused unread
#: (a ROS 2 bag's definition, read from its storage file, unparsed: :func:`_bound_definitions`).
MAX_CONNECTION_BYTES = 256 * 2**10

#: bytes: the most all the connection records of a ROS 1 bag may hold together (rosbags reads each
#: whole and keeps its definition): a few hundred connections of a few KB each
MAX_CONNECTIONS_TOTAL_BYTES = 4 * 2**20

#: field lines (lines that are neither blank, nor comments, nor a section's separator or header) the
#: distinct message definitions of one bag may hold together, every IDL section counted. Most of what
#: an absurd definition costs is rosbags' ``Typestore.register``, which generates code for each field:
#: 20,000 field lines (250 KB, under MAX_CONNECTION_BYTES) held `lmsbench info` 13 s at 280 MB, three
#: such connections 44 s at 556 MB; 4,000 cost 0.3 s to parse and 0.6 s to register. The 164 types of
#: rosbags' ROS Noetic store, each as a bag holds it (with the definitions it nests), total 2,011 field lines
#: (74 KB; their own fields alone 529); LaserScan's definition with its Header is 13 lines.
MAX_DEFINITION_FIELDS = 4096

#: characters the distinct message definitions of one bag may hold together (parsing costs about
#: 1 us a character of comment lines, 6 of field lines); the same definition on many connections counts once
MAX_DEFINITIONS_BYTES = 1 * 2**20


def _connection_too_large(path: object, cid: int | None, topic: str | None, size: int) -> BagTooLargeError:
    """The error of a connection record whose fields (its message definition) exceed MAX_CONNECTION_BYTES,
    or (``cid`` None) whose record header (op, conn and topic: a few bytes) does."""
    if cid is None:
        return BagTooLargeError(f"{path}: a connection record's header (its op, conn and topic) holds {size:,} bytes, "
                                f"more than the {MAX_CONNECTION_BYTES:,} a ROS 1 bag's connection may "
                                "(lms200.bag.MAX_CONNECTION_BYTES): damage; not read")
    which = f"connection {cid}" + (f" ({topic})" if topic else "")
    return BagTooLargeError(f"{path}: {which} holds {size:,} bytes of type, md5sum and message definition, more than "
                            f"the {MAX_CONNECTION_BYTES:,} a ROS 1 bag's connection may (lms200.bag.MAX_CONNECTION_BYTES): "
                            "an absurd message definition, or damage; not read")


def _connections_too_large(path: object, count: int, size: int) -> BagTooLargeError:
    return BagTooLargeError(f"{path}: its {count:,} connections hold {size:,} bytes of type, md5sum and message "
                            f"definition together, more than the {MAX_CONNECTIONS_TOTAL_BYTES:,} a ROS 1 bag's may "
                            "(lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES): absurd message definitions, or damage; not read")


class _DefinitionBudget:
    """What the message definitions of one bag opened have cost so far (:func:`_bound_definitions`)."""

    def __init__(self) -> None:
        self.chars = 0
        self.fields = 0
        self.parsed: dict[tuple, Any] = {}  # (parser, text, args): its types, parsed once
        self.mcap: dict[str, dict[int, int]] = {}  # the mcap file's schemas or channels: id -> characters held
        self.storage = ""  # the name of the mcap storage file being opened (its count's messages name it)
        self.mcap_chars = 0  # the characters of the latest record of each id in ``mcap``, both kinds together


#: the budget of the bag being opened (:meth:`BagReader._open`); None: each definition on its own
_BUDGET: ContextVar[_DefinitionBudget | None] = ContextVar("lmsbench_definition_budget", default=None)


def _field_lines(text: str) -> int:
    """Lines of a message definition (MSG or IDL) that are neither blank, nor comments, nor a
    section's separator or header, nor an IDL annotation line that declares nothing (``@verbatim
    (language="comment", text=``, ``@unit (value="rad")``: a field's declaration ends in ``;``) or a
    quoted-string line continuing one (ros2idl definitions carry each .msg comment that way: counted,
    they made a definition 5-8x its fields): a bound on its fields (and the constants and IDL syntax)."""
    return sum(1 for line in text.splitlines()
               if (s := line.strip()) and not s.startswith(("#", "//", "/*", "*", "==", "MSG:", "IDL:", '"'))
               and not (s.startswith("@") and ";" not in s))


def _bound_definitions() -> None:
    """rosbags' AnyReader parses every connection's message definition (``get_types_from_msg``,
    ``get_types_from_idl`` of its module, called for each IDL section) and registers the types (code
    generated for each field) when it opens a bag: those names are pointed at parsers that first refuse
    a definition of more than MAX_CONNECTION_BYTES characters, and a bag whose distinct definitions
    together pass MAX_DEFINITION_FIELDS field lines or MAX_DEFINITIONS_BYTES characters (a
    BagTooLargeError, which :meth:`BagReader._open` names the bag in); the same definition is parsed
    once a bag. A ROS 1 bag's is refused by its length before it is read (:func:`_check_index_connections`);
    a ROS 2 bag's comes from its storage file (sqlite3, mcap): one of 5.6 MB of comment lines held
    `lmsbench info` 4.5 s at 63 MB. A rosbags without one of those names is left as it is."""
    from rosbags.highlevel import anyreader

    for name in ("get_types_from_msg", "get_types_from_idl"):
        parse = getattr(anyreader, name, None)
        if parse is None or getattr(parse, "lmsbench_bounded", False):
            continue

        def bounded(text: str, *args: Any, _parse: Callable[..., Any] = parse, _name: str = name,  # noqa: ANN401
                    **kwargs: Any) -> Any:  # noqa: ANN401
            if not _IN_LMSBENCH_READ.get():
                return _parse(text, *args, **kwargs)
            which = f"{args[0]}'s message definition" if args else "a message definition (IDL)"
            if len(text) > MAX_CONNECTION_BYTES:
                raise _unnamed(BagTooLargeError(
                    f"{which} holds {len(text):,} characters, more than the {MAX_CONNECTION_BYTES:,} a bag's may "
                    "(lms200.bag.MAX_CONNECTION_BYTES): an absurd message definition, or damage; not parsed"))
            budget = _BUDGET.get() or _DefinitionBudget()
            key = (_name, text, args) if not kwargs else None
            if key is not None and key in budget.parsed:
                return dict(budget.parsed[key])
            budget.chars += len(text)
            budget.fields += _field_lines(text)
            if budget.fields > MAX_DEFINITION_FIELDS:
                raise _unnamed(BagTooLargeError(
                    f"{which} brings the field lines of the bag's message definitions to {budget.fields:,}, more "
                    f"than the {MAX_DEFINITION_FIELDS:,} a bag's may (lms200.bag.MAX_DEFINITION_FIELDS; the 164 ROS "
                    "Noetic types, each with the definitions it nests, total 2,011): absurd message definitions, or "
                    "damage; not parsed"))
            if budget.chars > MAX_DEFINITIONS_BYTES:
                raise _unnamed(BagTooLargeError(
                    f"{which} brings the bag's message definitions to {budget.chars:,} characters, more than the "
                    f"{MAX_DEFINITIONS_BYTES:,} a bag's may (lms200.bag.MAX_DEFINITIONS_BYTES): absurd message "
                    "definitions, or damage; not parsed"))
            types = _parse(text, *args, **kwargs)
            if key is not None:
                budget.parsed[key] = types
            return types

        bounded.lmsbench_bounded = True  # type: ignore[attr-defined]
        setattr(anyreader, name, bounded)


#: topics (connections) and message definitions one storage file of a ROS 2 bag may list, each
#: (sqlite3: rows of its topics and message_definitions tables; mcap: distinct channel and schema
#: ids). rosbags reads them all when it opens the file, before lmsbench sees one: the definitions
#: parsed count each distinct one once (MAX_DEFINITION_FIELDS), but 20,000 rows of one 256 KB definition
#: are 5 GB held. A bag has a few dozen topics; the characters of a storage file's topics and message
#: definitions together (one total) are bounded by MAX_CONNECTIONS_TOTAL_BYTES, as a ROS 1 bag's connection
#: records are.
MAX_CONNECTIONS = 4096


def _storage_too_many(what: str, name: str, count: int | None = None) -> BagTooLargeError:
    """The error of a ROS 2 storage file (named ``name``) listing more than MAX_CONNECTIONS ``what``
    (topics, message definitions): ``count`` of them (sqlite3, counted whole), or None where counting
    stopped at the first too many (mcap, counted as read)."""
    lists = f"lists {count:,} {what}, more than the {MAX_CONNECTIONS:,}" if count is not None else \
        f"lists more than {MAX_CONNECTIONS:,} {what}, the most"
    return _unnamed(BagTooLargeError(
        f"its storage file{name and ' ' + name} {lists} a ROS 2 bag's may (lms200.bag.MAX_CONNECTIONS): absurd, or "
        "damage; not read"))


def _storage_too_full(what: str, name: str, size: int | None = None) -> BagTooLargeError:
    """The error of a ROS 2 storage file (named ``name``) whose topics and message definitions (``what``:
    their counts, sqlite3) hold more than MAX_CONNECTIONS_TOTAL_BYTES characters together: ``size`` of
    them (sqlite3, counted whole), or None where counting stopped (mcap, counted as read)."""
    hold = f"hold {size:,} characters together, more than the {MAX_CONNECTIONS_TOTAL_BYTES:,}" if size is not None \
        else f"hold more than {MAX_CONNECTIONS_TOTAL_BYTES:,} characters together, the most"
    return _unnamed(BagTooLargeError(
        f"its storage file{name and ' ' + name}'s {what} {hold} a ROS 2 bag's may "
        "(lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES): absurd message definitions, or damage; not read"))


def _check_sqlite_connections(path: Any) -> None:  # noqa: ANN401 - a Path
    """BagTooLargeError for a ROS 2 sqlite3 storage file whose topics or message_definitions tables hold
    more than MAX_CONNECTIONS rows, or whose definitions and topics' names, types and QoS more than
    MAX_CONNECTIONS_TOTAL_BYTES characters together (both tables in one total), counted by sqlite before
    rosbags reads the rows whole. A file sqlite cannot read so is left to rosbags, which says what is wrong."""
    import sqlite3
    from urllib.request import pathname2url

    try:  # read-only: a name with ? or # in it must not be taken as another file, nor create one
        db = sqlite3.connect(f"file:{pathname2url(os.path.abspath(path))}?mode=ro&immutable=1", uri=True)
    except sqlite3.Error:
        return
    try:
        tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        wanted = {"topics": ("name", "type", "serialization_format", "offered_qos_profiles", "type_description_hash"),
                  "message_definitions": ("topic_type", "encoding", "encoded_message_definition",
                                          "type_description_hash")}
        counted: list[str] = []  # "5 topics", "5 message definitions": the tables counted
        total = 0  # the characters of both tables together (the topics' and the definitions' were bounded apart: 2x)
        for table, what in (("topics", "topics"), ("message_definitions", "message definitions")):
            if table not in tables:
                continue
            columns = [row[1] for row in db.execute(f"PRAGMA table_info({table})") if row[1] in wanted[table]]
            size = " + ".join(f"coalesce(length({c}), 0)" for c in columns) or "0"
            count, chars = db.execute(f"SELECT count(*), coalesce(sum({size}), 0) FROM {table}").fetchone()
            if count > MAX_CONNECTIONS:
                raise _storage_too_many(what, Path(path).name, count)
            counted.append(f"{count:,} {what}")
            total += chars
        if total > MAX_CONNECTIONS_TOTAL_BYTES:
            raise _storage_too_full(" and ".join(counted), Path(path).name, total)
    except sqlite3.Error:
        return
    finally:
        db.close()


#: the Schema rosbags' mcap reader makes for each channel, as the default of ``schemas.get(id, ...)``
#: (evaluated whether or not the channel's schema is listed): no record of the file, not counted (counted,
#: it made 4 distinct types under MAX_CONNECTIONS = 4 too many). MCAP reserves schema id 0 for "no schema".
_SCHEMALESS = (0, "__schemaless__", "cdr", "")


class _CountedRecords:
    """A NamedTuple type of rosbags' mcap reader (Schema, Channel) whose records, made while a storage
    file of a bag is opened (:data:`_BUDGET`, its ``storage`` the file's name), are counted: more than
    MAX_CONNECTIONS distinct ids of a type, or more than MAX_CONNECTIONS_TOTAL_BYTES of text held by the
    latest record of each id of both types together, is a BagTooLargeError naming the storage file."""

    def __init__(self, typ: Any, what: str) -> None:  # noqa: ANN401 - a NamedTuple type
        self.typ, self.what = typ, what

    def __getattr__(self, name: str) -> Any:  # noqa: ANN401
        return getattr(self.typ, name)

    def __call__(self, *args: Any) -> Any:  # noqa: ANN401
        record = self.typ(*args)
        budget = _BUDGET.get() if _IN_LMSBENCH_READ.get() else None
        if budget is not None and tuple(record) != _SCHEMALESS:
            held = budget.mcap.setdefault(self.what, {})
            chars = sum(len(v) for v in record[1:] if isinstance(v, (str, bytes)))
            # a running total: summed anew at each record it was quadratic (8,192 records under the bound: 67
            # million additions)
            budget.mcap_chars += chars - held.get(record[0], 0)
            held[record[0]] = chars
            if len(held) > MAX_CONNECTIONS:
                raise _storage_too_many(self.what, budget.storage)
            if budget.mcap_chars > MAX_CONNECTIONS_TOTAL_BYTES:
                raise _storage_too_full("topics (channels) and message definitions (schemas)", budget.storage)
        return record


#: the kinds of mcap record (by opcode) whose declared length :func:`_bounded_read_sized` bounds by
#: MAX_CONNECTIONS_TOTAL_BYTES before rosbags reads them whole: a schema or channel record holds one
#: message definition or one topic's name, type and QoS, which the file's schemas and channels together
#: may hold at most that many characters of anyway (:class:`_CountedRecords`, counted once read)
_MCAP_BOUNDED_RECORDS = {0x03: "schema", 0x04: "channel"}
#: the names of the other mcap records (by opcode), bounded by MAX_MCAP_RECORD_BYTES
_MCAP_RECORDS = {0x01: "header", 0x02: "footer", 0x05: "message", 0x06: "chunk", 0x07: "message index",
                 0x08: "chunk index", 0x09: "attachment", 0x0A: "attachment index", 0x0B: "statistics",
                 0x0C: "metadata", 0x0D: "metadata index", 0x0E: "summary offset", 0x0F: "data end"}
#: bytes: the most any other mcap record (header, message, chunk, summary records) may declare, read whole by
#: rosbags: a chunk of MAX_DECOMPRESSED_BYTES stored uncompressed and its fields. Such records were bounded only
#: by the file's size (a 300 MB chunk record held `lmsbench info` at 648 MB; a chunk record or a header declaring
#: 1 TiB in a 5 KB file was `cannot open as a ROS bag: MemoryError:`)
MAX_MCAP_RECORD_BYTES = MAX_DECOMPRESSED_BYTES + 2**16


#: the mcap storage file whose messages are being read (:func:`_bound_storage_connections`): a chunk is
#: decompressed, and a message read, while the bag's messages are iterated, after the file was opened
_MCAP_READING: ContextVar[str] = ContextVar("lmsbench_mcap_reading", default="")


def _mcap_storage_name() -> str:
    """" NAME": the mcap storage file being opened (:data:`_BUDGET`) or read (:data:`_MCAP_READING`), or ""
    where none is known."""
    budget = _BUDGET.get()
    name = (budget.storage if budget is not None else "") or _MCAP_READING.get()
    return name and " " + name


def _mcap_too_large(what: str, size: int, bound: int, bound_name: str, may: str = "a ROS 2 bag's mcap record may hold",
                    declares: str = "") -> BagTooLargeError:
    return _unnamed(BagTooLargeError(
        f"its storage file{_mcap_storage_name()}'s {what} declares {size:,} bytes{declares}, more than the {bound:,} "
        f"{may} (lms200.bag.{bound_name}): damage, or no bag of laser scans; not read"))


def _bounded_read_exact(bio: Any, size: int, _real: Callable[[Any, int], bytes]) -> bytes:  # noqa: ANN401
    """rosbags' mcap ``read_exact``, refusing a read of more than MAX_MCAP_RECORD_BYTES (a message's data, a
    chunk's compressed data, told by a declared length) before it is made: Python allocates the whole
    length a read asks for, whatever the file holds."""
    if size > MAX_MCAP_RECORD_BYTES:
        start = bio.tell()
        raise _mcap_too_large(f"record data at byte {start:,}", size, MAX_MCAP_RECORD_BYTES, "MAX_MCAP_RECORD_BYTES")
    return _real(bio, size)


def _bounded_skip_exact(bio: Any, size: int, _real: Callable[[Any, int], None]) -> None:  # noqa: ANN401
    """rosbags' mcap ``skip_exact``, refusing a skip past the end of the file (or chunk) that holds the record:
    a seek there succeeds, and the scan ended at it as at the data's end, so a record whose length was damaged
    (declaring 1 TiB) dropped every message after it without a word (1 of 3 scans read, exit 0)."""
    from rosbags.rosbag2.errors import ReaderError

    pos = bio.tell()
    end = bio.seek(0, 2)
    bio.seek(pos)
    if pos + size > end:
        raise ReaderError(f"its storage file{_mcap_storage_name()}'s record data at byte {pos:,} declares {size:,} "
                          f"bytes, past the end of the {'chunk' if isinstance(bio, io.BytesIO) else 'file'} that holds "
                          f"it ({end - pos:,} bytes on): damage; not read")
    _real(bio, size)


def _bounded_decompress(data: bytes, compression: str, size: int, crc: int,
                        _real: Callable[[bytes, str, int, int], bytes]) -> bytes:
    """rosbags' mcap chunk ``decompress``, refusing a chunk that declares more than MAX_DECOMPRESSED_BYTES
    uncompressed before decompressing it, and decompressing at most one byte more than it declares: rosbags
    decompressed the whole chunk first (37 KB of zstd declaring 1 GiB, or 1 KiB, held `lmsbench info` at 2.1 GB;
    declared as 1 KiB it then said "Chunk size mismatch")."""
    if size > MAX_DECOMPRESSED_BYTES:
        raise _mcap_too_large("chunk", size, MAX_DECOMPRESSED_BYTES, "MAX_DECOMPRESSED_BYTES",
                              "a chunk may decompress to", f" uncompressed ({compression or 'not compressed'})")
    if compression == "zstd":
        from rosbags.rosbag2 import storage_mcap

        make: Callable[[], Any] = storage_mcap.zstd.ZstdDecompressor
    elif compression == "lz4":
        from lz4.frame import LZ4FrameDecompressor

        make = LZ4FrameDecompressor
    else:
        return _real(data, compression, size, crc)  # none, or one rosbags refuses
    pieces, got, rest = [], 0, data
    while rest and got <= size:  # frame by frame, as rosbags' decompress reads them, each to the bound left
        frame = make()
        piece = frame.decompress(rest, max_length=size + 1 - got)
        pieces.append(piece)
        got += len(piece)
        if not frame.eof:
            break  # the bound reached, or data ending inside a frame (said below as rosbags says it)
        rest = frame.unused_data
    raw = b"".join(pieces)
    if len(raw) > size:
        raise _unnamed(BagTooLargeError(
            f"its storage file{_mcap_storage_name()}'s {compression} chunk decompresses to more than the {size:,} "
            "bytes it declares: damage, or a compression bomb; not read"))
    return _real(raw, "", size, crc)  # the size and checksum checked as rosbags checks them


def _bounded_read_sized(bio: Any, _real: Callable[[Any], bytes]) -> bytes:  # noqa: ANN401 - a binary file
    """rosbags' mcap ``read_sized`` (a record's uint64 length, then that many bytes, read whole), refusing a
    schema or channel record (told by the opcode byte before the length) whose declared length exceeds
    MAX_CONNECTIONS_TOTAL_BYTES, or any other record whose declared length exceeds MAX_MCAP_RECORD_BYTES,
    before reading it: a BagTooLargeError naming the storage file, the record and where it starts. Such a record was read whole, bounded only by the file's size (a 300 MB schema
    record held `lmsbench info` at 928 MB before the total's count refused it; one declaring 1 TiB in a
    small file was a MemoryError)."""
    start = bio.tell()
    if start >= 1:
        head = bio.read(8)
        bio.seek(start - 1)
        op = bio.read(1)
        bio.seek(start)
        kind = _MCAP_BOUNDED_RECORDS.get(op[0]) if len(op) == 1 else None
        if kind is None and len(op) == 1 and len(head) == 8:  # any other record: MAX_MCAP_RECORD_BYTES
            size = struct.unpack("<Q", head)[0]
            if size > MAX_MCAP_RECORD_BYTES:
                what = _MCAP_RECORDS.get(op[0], f"record of opcode {op[0]:#04x}")
                raise _mcap_too_large(f"{what} record at byte {start - 1:,}", size, MAX_MCAP_RECORD_BYTES,
                                      "MAX_MCAP_RECORD_BYTES")
        if kind is not None and len(head) == 8:
            size = struct.unpack("<Q", head)[0]
            if size > MAX_CONNECTIONS_TOTAL_BYTES:
                budget = _BUDGET.get()
                name = budget.storage if budget is not None else ""
                raise _unnamed(BagTooLargeError(
                    f"its storage file{name and ' ' + name}'s {kind} record at byte {start - 1:,} declares {size:,} "
                    f"bytes, more than the {MAX_CONNECTIONS_TOTAL_BYTES:,} a ROS 2 bag's topics and message "
                    "definitions may hold together (lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES): an absurd message "
                    "definition, or damage; not read"))
    return _real(bio)


#: the first rosbags with the mcap functions lms200.bag bounds (read_exact, skip_exact, decompress): 0.10.0 ..
#: 0.11.5 lack them, and the bounds were silently left out (an mcap bag read unbounded)
ROSBAGS_MCAP_SINCE = "0.11.6"
#: the rosbags mcap functions lms200.bag replaces, with the parameters it calls them with (those of 0.11.6 .. 0.11.9)
_MCAP_PATCHED = {"read_sized": ("bio",), "read_exact": ("bio", "size"), "skip_exact": ("bio", "size"),
                 "decompress": ("data", "compression", "size", "crc"), "McapReader._open": ("self",),
                 "McapReader.messages": ("self", "connections", "start", "stop")}
#: why this rosbags' mcap reader cannot be bounded (a function missing or of other parameters), or "" where it can
#: (:func:`_bound_storage_connections`); an mcap bag is then refused (:meth:`BagReader._open`)
_mcap_unsupported = ""


def _mcap_support_problem(storage_mcap: Any) -> str:  # noqa: ANN401 - a module
    """Why rosbags' ``storage_mcap`` lacks the functions lms200.bag replaces with the parameters it expects, or ""."""
    import inspect

    for name, expected in _MCAP_PATCHED.items():
        owner, _, attr = name.rpartition(".")
        real = getattr(getattr(storage_mcap, owner, None) if owner else storage_mcap, attr, None)
        real = getattr(real, "lmsbench_real", real)  # already replaced: the original's
        if real is None:
            return f"it has no rosbags.rosbag2.storage_mcap.{name}"
        try:
            got = tuple(inspect.signature(real).parameters)
        except (TypeError, ValueError):
            return f"its rosbags.rosbag2.storage_mcap.{name} has no signature to check"
        if got != expected:
            return (f"its rosbags.rosbag2.storage_mcap.{name} takes ({', '.join(got)}), "
                    f"not ({', '.join(expected)})")
    return ""


def _rosbags_version() -> str:
    try:
        from importlib.metadata import version

        return version("rosbags")
    except Exception:  # noqa: BLE001 - an install without metadata
        return "of unknown version"


def _bound_storage_connections() -> None:
    """Bound what rosbags' ROS 2 storage readers hold of a bag's topics and message definitions when they
    open a storage file (MAX_CONNECTIONS, MAX_CONNECTIONS_TOTAL_BYTES): a sqlite3 file is counted by
    sqlite first (:func:`_check_sqlite_connections`), an mcap file's schema and channel records as they
    are read (:class:`_CountedRecords`), each file on its own, named. A rosbags without those names is
    left as it is."""
    global _mcap_unsupported
    from rosbags.rosbag2 import storage_mcap, storage_sqlite3

    _mcap_unsupported = _mcap_support_problem(storage_mcap)
    if not _mcap_unsupported:
        _bound_mcap(storage_mcap)
    reader = getattr(storage_sqlite3, "Sqlite3Reader", None)
    real_open = getattr(reader, "_open", None)
    if real_open is not None and not getattr(real_open, "lmsbench_bounded", False):
        def _open(self: Any, _real: Callable[[Any], None] = real_open) -> None:  # noqa: ANN401
            if _IN_LMSBENCH_READ.get():
                _check_sqlite_connections(self.path)
            _real(self)

        _replace(reader, "_open", _open, real_open)


def _replace(owner: Any, name: str, wrapper: Callable[..., Any], real: Callable[..., Any]) -> None:  # noqa: ANN401
    """Put ``wrapper`` in ``owner.name`` in place of rosbags' ``real``, marked ``lmsbench_bounded`` (never
    wrapped twice) and keeping ``real`` as ``lmsbench_real``."""
    wrapper.lmsbench_bounded = True  # type: ignore[attr-defined]
    wrapper.lmsbench_real = real  # type: ignore[attr-defined]
    setattr(owner, name, wrapper)


def _bound_mcap(storage_mcap: Any) -> None:  # noqa: ANN401 - a module
    """Replace rosbags' mcap functions (:data:`_MCAP_PATCHED`, checked by :func:`_mcap_support_problem`) by
    bounded ones, each keeping the original as ``lmsbench_real``."""
    mcap = storage_mcap.McapReader
    mcap_open = getattr(mcap, "_open", None)
    if mcap_open is not None and not getattr(mcap_open, "lmsbench_bounded", False):
        def _open_mcap(self: Any, _real: Callable[[Any], None] = mcap_open) -> None:  # noqa: ANN401
            budget = _BUDGET.get()
            if budget is not None and _IN_LMSBENCH_READ.get():  # this storage file's records, counted apart from another file's, name it
                budget.mcap, budget.mcap_chars, budget.storage = {}, 0, Path(str(self.path)).name
            _real(self)

        _replace(mcap, "_open", _open_mcap, mcap_open)
    mcap_messages = getattr(mcap, "messages", None)
    if mcap_messages is not None and not getattr(mcap_messages, "lmsbench_bounded", False):
        def _messages(self: Any, *args: Any, _real: Callable[..., Any] = mcap_messages,  # noqa: ANN401
                      **kwargs: Any) -> Iterator[Any]:  # noqa: ANN401
            """rosbags' messages of an mcap file, each read with the file's name known (:data:`_MCAP_READING`),
            for the errors of its records and chunks to name it; rosbags' own outside an lmsbench read."""
            if not _IN_LMSBENCH_READ.get():
                return _real(self, *args, **kwargs)  # type: ignore[no-any-return]
            return _named_messages(_real(self, *args, **kwargs), Path(str(self.path)).name)

        def _named_messages(messages: Iterator[Any], name: str) -> Iterator[Any]:
            while True:
                token = _MCAP_READING.set(name)
                try:
                    item = next(messages)
                except StopIteration:
                    return
                finally:
                    _MCAP_READING.reset(token)
                yield item

        _replace(mcap, "messages", _messages, mcap_messages)
    read_sized = getattr(storage_mcap, "read_sized", None)
    if read_sized is not None and not getattr(read_sized, "lmsbench_bounded", False):
        def _read_sized(bio: Any, _real: Callable[[Any], bytes] = read_sized) -> bytes:  # noqa: ANN401
            return _bounded_read_sized(bio, _real) if _IN_LMSBENCH_READ.get() else _real(bio)

        _replace(storage_mcap, "read_sized", _read_sized, read_sized)
    read_exact = getattr(storage_mcap, "read_exact", None)
    if read_exact is not None and not getattr(read_exact, "lmsbench_bounded", False):
        def _read_exact(bio: Any, size: int, _real: Callable[[Any, int], bytes] = read_exact) -> bytes:  # noqa: ANN401
            return _bounded_read_exact(bio, size, _real) if _IN_LMSBENCH_READ.get() else _real(bio, size)

        _replace(storage_mcap, "read_exact", _read_exact, read_exact)
    skip_exact = getattr(storage_mcap, "skip_exact", None)
    if skip_exact is not None and not getattr(skip_exact, "lmsbench_bounded", False):
        def _skip_exact(bio: Any, size: int, _real: Callable[[Any, int], None] = skip_exact) -> None:  # noqa: ANN401
            if _IN_LMSBENCH_READ.get():
                _bounded_skip_exact(bio, size, _real)
            else:
                _real(bio, size)

        _replace(storage_mcap, "skip_exact", _skip_exact, skip_exact)
    decompress = getattr(storage_mcap, "decompress", None)
    if decompress is not None and not getattr(decompress, "lmsbench_bounded", False):
        def _decompress(data: bytes, compression: str, size: int, crc: int,
                        _real: Callable[[bytes, str, int, int], bytes] = decompress) -> bytes:
            if not _IN_LMSBENCH_READ.get():
                return _real(data, compression, size, crc)
            return _bounded_decompress(data, compression, size, crc, _real)

        _replace(storage_mcap, "decompress", _decompress, decompress)
    for name, what in (("Schema", "message definitions (schemas)"), ("Channel", "topics (channels)")):
        typ = getattr(storage_mcap, name, None)
        if typ is not None and not isinstance(typ, _CountedRecords):
            setattr(storage_mcap, name, _CountedRecords(typ, what))


def _check_index_connections(path: Any) -> None:  # noqa: ANN401 - a Path, or rosbags' RPath
    """BagTooLargeError naming the file for an indexed ROS 1 bag whose index holds a connection record
    of more than MAX_CONNECTION_BYTES of fields, told from the record lengths alone before rosbags
    reads the index (it reads each connection whole and parses its message definition). A bag whose
    header or index cannot be followed is left to rosbags, which says what is wrong."""
    from rosbags.rosbag1 import reader as r1

    try:
        with path.open("rb") as bio:
            size = os.fstat(bio.fileno()).st_size
            if bio.read(13) != b"#ROSBAG V2.0\n":
                return
            header = r1.Header.read(bio, r1.RecordType.BAGHEADER)
            index_pos, conn_count = header.get_uint64("index_pos"), header.get_uint32("conn_count")
            if index_pos == 0 or index_pos >= size:
                return
            bio.seek(index_pos)
            total = 0
            for _ in range(conn_count):
                hlen = r1.read_uint32(bio)
                if hlen > MAX_CONNECTION_BYTES:  # op, conn and topic: a few bytes
                    raise _connection_too_large(path, None, None, hlen)
                bio.seek(-4, os.SEEK_CUR)
                rec = r1.Header.read(bio, r1.RecordType.CONNECTION)
                dlen = r1.read_uint32(bio)
                if dlen > MAX_CONNECTION_BYTES:
                    raise _connection_too_large(path, rec.get_uint32("conn"), rec.get_string("topic"), dlen)
                total += dlen
                if total > MAX_CONNECTIONS_TOTAL_BYTES:
                    raise _connections_too_large(path, conn_count, total)
                bio.seek(dlen, os.SEEK_CUR)
    except (OSError, r1.ReaderError, KeyError, UnicodeDecodeError, struct.error):
        return


@dataclass
class Recovered:
    """What the sequential scan of an unindexed ROS 1 bag found (:func:`_recovering_reader`)."""

    messages: int = 0  # messages in whole chunks
    chunks: int = 0
    dropped_at: int | None = None  # the byte offset of a truncated last record, dropped


def _unread_set_aside(connections: list) -> list:
    """``connections`` (rosbags Connections) with the message definitions of the types lmsbench never
    reads (not in READ_TYPES) set aside (format NONE), so rosbags' AnyReader neither parses them nor checks
    them against the connection's hash (ROS 1 md5sum, ROS 2 type_description_hash): one bad unrelated
    topic refused the whole bag. A type read is still parsed and checked."""
    from rosbags.interfaces import MessageDefinition, MessageDefinitionFormat

    none = MessageDefinition(MessageDefinitionFormat.NONE, "")
    return [c if c.msgtype in READ_TYPES else c._replace(msgdef=none) for c in connections]


def _read_types_reader2(path: Path) -> Any:  # noqa: ANN401 - a rosbags rosbag2 Reader
    """A rosbags ROS 2 reader of the bag folder ``path`` whose connections, once open, carry only the
    message definitions of the types lmsbench reads (:func:`_unread_set_aside`), as a ROS 1 bag's
    (:func:`_recovering_reader`): a /tf topic whose stored type_description_hash disagrees with its
    definition refused the whole bag ("hash mismatch"), its LaserScan topic unread."""
    from rosbags.rosbag2 import Reader

    class ReadTypesReader(Reader):
        def open(self) -> None:
            super().open()
            connections = self.connections  # the storage's own list, which messages() matches against
            connections[:] = _unread_set_aside(connections)

    return ReadTypesReader(path)


def _recovering_reader(path: Path) -> Any:  # noqa: ANN401 - a rosbags rosbag1 Reader
    """A rosbags ROS 1 reader of ``path`` that also opens a bag that was never closed (a recording
    killed by SIGKILL or a power cut): its header says index_pos 0 and it has no index, which rosbags
    refuses ("Bag is not indexed, reindex before reading"). Such a bag is scanned record by record
    from its start (ROS bag 2.0: chunk records holding connection and message data records, each
    chunk followed by its index data records) and the index rosbags keeps is built from what the
    chunks hold, one chunk decompressed at a time (bounded by MAX_DECOMPRESSED_BYTES); messages then
    read as from an indexed bag. A record that runs past the end of the file (the one being written
    when the recording was cut) is dropped (``recovered.dropped_at``); a record that cannot be parsed
    is a BagError naming its byte offset. ``recovered`` is None for an indexed bag."""
    from collections import defaultdict
    from io import BytesIO

    from rosbags.interfaces import Connection, ConnectionExtRosbag1, MessageDefinition, MessageDefinitionFormat
    from rosbags.rosbag1 import reader as r1
    from rosbags.typesys.msg import normalize_msgtype

    class RecoveringReader(r1.Reader):
        recovered: Recovered | None = None

        def _unindexed(self) -> bool:
            """The bag's header record (ROS bag format 2.0: after the "#ROSBAG V2.0" line) says
            index_pos 0: the bag was never closed. Told from the header itself, not from the text
            of rosbags' refusal ("Bag is not indexed, ..."), which a rosbags version may word
            otherwise. False for a file whose header cannot be read, or that is encrypted: rosbags
            says what is wrong with it."""
            try:
                with self.path.open("rb") as bio:
                    if bio.read(13) != b"#ROSBAG V2.0\n":  # the version line (rosbags refuses another)
                        return False
                    header = r1.Header.read(bio, r1.RecordType.BAGHEADER)
                    if "encryptor" in header and header.get_string("encryptor"):
                        return False
                    return header.get_uint64("index_pos") == 0
            except (OSError, r1.ReaderError, KeyError, struct.error):
                return False

        def open(self) -> None:
            if not self._unindexed():
                _check_index_connections(self.path)
                super().open()
            else:
                self.bio = self.path.open("rb")
                try:
                    self._scan()
                except BaseException:
                    bio, self.bio = self.bio, None
                    if bio is not None:
                        bio.close()
                    raise
            # a /tf connection recorded by goroslib or rosnodejs (an empty definition, md5 d41d8cd9... computed)
            # or an edited one refused the whole bag, its LaserScan topic too ("hash mismatch")
            self.connections = _unread_set_aside(self.connections)

        def _damaged(self, pos: int, what: str) -> BagError:
            return BagError(f"{self.path}: an unindexed bag (not closed) whose record at byte {pos} is damaged: {what}"
                            + (" (a chunk offset counts bytes of the chunk's data, decompressed)" if "chunk offset" in what else ""))

        def _scan(self) -> None:
            bio = self.bio
            assert bio is not None
            size = os.fstat(bio.fileno()).st_size
            bio.readline()
            try:
                r1.Header.read(bio, r1.RecordType.BAGHEADER)
                padding = r1.read_uint32(bio)
            except r1.ReaderError:
                padding = -1
            if padding < 0 or bio.tell() + padding > size:
                raise BagError(f"{self.path}: the bag was not closed and ends within its header ({size} bytes: a "
                               "recording killed before its first messages were written); no message to recover")
            bio.seek(padding, os.SEEK_CUR)
            found = Recovered()
            conns: dict[int, Any] = {}
            indexes: dict[int, list] = defaultdict(list)
            while (pos := bio.tell()) < size:
                # a length no record has is damage, whether or not it runs past the file's end; only a
                # plausible record cut by the file's end is the truncated last one (a damaged length in
                # the middle was taken for the end: every chunk after it dropped, under a warning)
                head = bio.read(4)
                if len(head) < 4:
                    found.dropped_at = pos
                    break
                hlen = struct.unpack("<I", head)[0]
                if hlen > MAX_RECORD_HEADER_BYTES:
                    raise self._damaged(pos, f"a header of {hlen} bytes (at most {MAX_RECORD_HEADER_BYTES})")
                if pos + 4 + hlen + 4 > size:
                    found.dropped_at = pos
                    break
                bio.seek(pos)
                try:
                    header = r1.Header.read(bio)
                    op = header.get_uint8("op")
                    dlen = r1.read_uint32(bio)
                    if dlen > MAX_DECOMPRESSED_BYTES:  # read whole below: bounded before the read
                        raise ValueError(f"a data length of {dlen} bytes (at most {MAX_DECOMPRESSED_BYTES})")
                    if op == r1.RecordType.CHUNK and header.get_string("compression") == "none" \
                            and dlen != header.get_uint32("size"):
                        raise ValueError(f"an uncompressed chunk of {dlen} bytes that declares "
                                         f"{header.get_uint32('size')}")
                except (r1.ReaderError, KeyError, ValueError, struct.error) as exc:
                    raise self._damaged(pos, str(exc) or type(exc).__name__) from None
                datapos = bio.tell()
                if datapos + dlen > size:
                    found.dropped_at = pos
                    break
                try:
                    if op == r1.RecordType.CHUNK:
                        self._chunk(pos, header, bio.read(dlen), datapos, conns, indexes, found)
                    elif op == r1.RecordType.CONNECTION:
                        self._connection(header, BytesIO(bio.read(dlen)), dlen, conns)
                    elif op in (r1.RecordType.IDXDATA, r1.RecordType.CHUNK_INFO):
                        bio.seek(dlen, os.SEEK_CUR)
                    else:
                        raise self._damaged(pos, f"op code {op}, which no record between a bag's header and its "
                                                 "index has (chunk 5, index data 4, connection 7)")
                except BagError:
                    raise
                except (r1.ReaderError, KeyError, ValueError, struct.error) as exc:
                    raise self._damaged(pos, str(exc) or type(exc).__name__) from None
            self.connections = [c._replace(msgcount=len(indexes[c.id])) for c in conns.values()]
            self.indexes = {c.id: sorted(indexes[c.id]) for c in conns.values()}
            self.recovered = found

        def _connection(self, header: Any, data: Any, dlen: int, conns: dict) -> None:  # noqa: ANN401
            cid = header.get_uint32("conn")
            topic = header.get_string("topic")
            if dlen > MAX_CONNECTION_BYTES:
                raise _connection_too_large(self.path, cid, topic, dlen)
            if cid not in conns:  # a chunk repeats the connections of the chunks before it
                self.connection_bytes = getattr(self, "connection_bytes", 0) + dlen
                if self.connection_bytes > MAX_CONNECTIONS_TOTAL_BYTES:
                    raise _connections_too_large(self.path, len(conns) + 1, self.connection_bytes)
            fields = r1.Header.read(BytesIO(struct.pack("<I", dlen) + data.read(dlen)))
            latching = fields.get_string("latching") if "latching" in fields else None
            if cid not in conns:
                conns[cid] = Connection(
                    cid, r1.normalize(topic), normalize_msgtype(fields.get_string("type")),
                    MessageDefinition(MessageDefinitionFormat.MSG, fields.get_string("message_definition")),
                    fields.get_string("md5sum"), 0,
                    ConnectionExtRosbag1(fields.get_string("callerid") if "callerid" in fields else None,
                                         int(latching) if latching not in (None, "") else None),
                    self)

        def _chunk(self, pos: int, header: Any, raw: bytes, datapos: int, conns: dict,  # noqa: ANN401
                   indexes: dict, found: Recovered) -> None:
            compression = header.get_string("compression")
            declared = header.get_uint32("size")
            if declared > MAX_DECOMPRESSED_BYTES:
                raise _too_large(f"{self.path}: the chunk at byte {pos}")
            if compression == "none":
                decompress = r1.decompressors["none"]
            elif compression == "bz2":
                import bz2

                decompress = lambda data: _bounded(data, bz2.BZ2Decompressor, f"{self.path}: a bz2 chunk", True)  # noqa: E731
            elif compression == "lz4":
                import lz4.frame

                decompress = lambda data: _bounded(data, lz4.frame.LZ4FrameDecompressor,  # noqa: E731
                                                   f"{self.path}: an lz4 chunk", False)
            else:
                raise self._damaged(pos, f"chunk compression {compression!r} (none, bz2 or lz4)")
            data = decompress(raw)
            inner, end, count = BytesIO(data), len(data), 0
            start, stop = 2**63 - 1, 0
            counts: dict[int, int] = {}
            while (offset := inner.tell()) < end:
                try:
                    rec = r1.Header.read(inner)
                    op = rec.get_uint8("op")
                    n = r1.read_uint32(inner)
                except (r1.ReaderError, KeyError, struct.error) as exc:  # named by the chunk's byte alone before
                    raise ValueError(f"its record at chunk offset {offset}: {str(exc) or type(exc).__name__}") from None
                if inner.tell() + n > end:
                    raise ValueError(f"a record at chunk offset {offset} runs past the chunk's end")
                if op == r1.RecordType.CONNECTION:
                    self._connection(rec, inner, n, conns)
                elif op == r1.RecordType.MSGDATA:
                    cid, t = rec.get_uint32("conn"), rec.get_time("time")
                    if cid not in conns:
                        raise ValueError(f"a message at chunk offset {offset} of connection {cid}, which no "
                                         "connection record before it defines")
                    indexes[cid].append(r1.IndexData(t, pos, offset))
                    counts[cid] = counts.get(cid, 0) + 1
                    start, stop, count = min(start, t), max(stop, t + 1), count + 1
                    inner.seek(n, os.SEEK_CUR)
                else:
                    raise ValueError(f"op code {op} at chunk offset {offset} (a chunk holds connections, 7, "
                                     "and messages, 2)")
            self.chunks[pos] = r1.Chunk(len(raw), datapos, decompress)
            self.chunk_infos.append(r1.ChunkInfo(pos, start, stop, counts))
            found.messages += count
            found.chunks += 1

    reader = RecoveringReader(path)
    return reader


class BagReader(WatchedPasses):
    """Iterate the LaserScans of a ROS 1 or ROS 2 bag as Records (iterable several times).

    Args:
        path: ``*.bag`` file or ROS 2 bag folder.
        topic: the LaserScan topic; may be left out when the bag has exactly one.
        skip_bad_lines: skip messages that cannot be read as scans (recorded in ``stats.skipped``)
            instead of raising; damage that stops iteration ends the pass (``stats.stopped``).
        range_max: m, replaces every scan's ``range_max`` (``read_log(..., geometry=LaserGeometry(range_max=M))``,
            ``--laser-range-max M``): for a driver that writes inf (no limit) or 0, which no Scan takes.

    Raises:
        BagError: (while iterating) a bag that cannot be opened, several LaserScan topics and no
            ``topic``, a missing topic, or a message that cannot be read (naming topic and index).
    """

    def __init__(self, path: str | Path, topic: str | None = None, skip_bad_lines: bool = False,
                 range_max: float | None = None) -> None:
        self.path = Path(path)
        if not self.path.exists():
            raise LogNotFoundError(f"no such bag: {self.path}")
        self.topic = topic
        self.range_max = range_max
        self.skip_bad_lines = skip_bad_lines
        self.stats = BagReadStats()
        self._warned = False  # the warning of a bag never closed: once

    def _open(self):  # noqa: ANN202 - rosbags' AnyReader
        from rosbags.highlevel import AnyReader

        if self.path.is_dir():  # a ROS 2 bag's storage files: a pipe's open waited for ever, SIGTERM too
            for entry in sorted(self.path.iterdir()):
                if entry.exists() and not entry.is_file() and not entry.is_dir():
                    raise BagError(f"{entry}: not a regular file (a pipe, a device or a socket) in the ROS 2 bag "
                                   f"{self.path}; a bag's files must be regular files (give the files themselves)")
        if self.path.is_dir():
            check_metadata_size(self.path)
            _check_storage_files(self.path)
        _bound_zstd_messages()  # before open: a file-compressed ROS 2 bag is decompressed there
        _bound_definitions()
        _bound_storage_connections()
        if _mcap_unsupported and self._holds_mcap():  # read unbounded, silently, before
            raise BagError(f"{self.path}: an mcap bag cannot be read with the installed rosbags {_rosbags_version()}: "
                           f"{_mcap_unsupported} (lmsbench needs rosbags>={ROSBAGS_MCAP_SINCE} to bound its reads)")
        budget = _BUDGET.set(_DefinitionBudget())  # the definitions of this bag together
        try:
            with _lmsbench_read():  # the replaced rosbags functions bound this read only
                reader = AnyReader([self.path], default_typestore=_typestore(self.path.suffix == ".bag"))
                if not reader.is2:  # a bag never closed (a killed recording) is read from its chunks
                    reader.readers = [_recovering_reader(self.path)]
                else:  # as the ROS 1 reader: only the definitions of the types read are checked
                    reader.readers = [_read_types_reader2(self.path)]
                reader.open()
        except BagTooLargeError as exc:
            if getattr(exc, "lmsbench_unnamed", False):  # a message definition's (_bound_definitions knows no file)
                raise BagTooLargeError(f"{self.path}: {exc}") from None
            raise
        except BagError:
            raise
        except Exception as exc:  # rosbags raises its own types for every kind of damage
            raise BagError(f"{self.path}: cannot open as a ROS bag: {type(exc).__name__}: {_quoted(exc)}") from None
        finally:
            _BUDGET.reset(budget)
        _bound_decompression(reader, self.path)
        found = getattr(reader.readers[0], "recovered", None)
        if found is not None and not self._warned:
            import warnings

            from .errors import LmsbenchWarning

            self._warned = True
            cut = f"; a truncated last record at byte {found.dropped_at} dropped" if found.dropped_at is not None else ""
            warnings.warn(f"{self.path}: the bag was not closed (a recording killed or cut by a power failure): it has "
                          f"no index; {found.messages} messages recovered from its {found.chunks} whole chunks{cut}",
                          LmsbenchWarning, stacklevel=3)
        return reader

    def _holds_mcap(self) -> bool:
        """Whether the bag is a ROS 2 bag with an mcap storage file (its own, or one compressed whole)."""
        return self.path.is_dir() and any(p.name.endswith((".mcap", ".mcap.zstd")) for p in self.path.iterdir())

    def _scan_connections(self, reader) -> list:  # noqa: ANN001
        scans = [c for c in reader.connections if c.msgtype == "sensor_msgs/msg/LaserScan"]
        names = sorted({c.topic for c in scans})
        if self.topic is not None:
            scans = [c for c in scans if c.topic == self.topic]
        other = sorted({c.msgtype for c in reader.connections if c.topic == self.topic}) if self.topic else []
        if not scans and other:  # said "no topic '/odom'; topics: ['/odom (geometry_msgs/msg/PoseStamped)', ...]"
            raise BagError(f"{self.path}: topic {self.topic!r} holds {', '.join(other)} messages, not "
                           f"sensor_msgs/LaserScan; its LaserScan topics: {', '.join(names) or 'none'}")
        if not scans:
            topics = sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})
            wanted = f"topic {self.topic!r}" if self.topic else "sensor_msgs/LaserScan topic"
            # was "no any sensor_msgs/LaserScan topic; topics: []" for a bag of no message (write_bag of no record, other tools')
            held = f"topics: {', '.join(topics)}" if topics else "it holds no topic (an empty bag)"
            raise BagError(f"{self.path}: no {wanted}; {held}")
        if len(names) > 1 and self.topic is None:
            raise BagError(f"{self.path}: {len(names)} LaserScan topics ({', '.join(names)}); choose one "
                           "(--topic TOPIC, or read_log(path, topic=...))")
        return scans

    def _fail(self, where: str, exc: Exception, index: int, fatal: bool) -> None:
        if isinstance(exc, BagTooLargeError):  # not a damaged message to skip: memory is at stake
            if getattr(exc, "lmsbench_unnamed", False):  # a ROS 2 message's (rosbags' zstd knows no file)
                raise BagTooLargeError(f"{self.path}: {where}: {exc}") from None
            raise exc
        reason = f"{type(exc).__name__}: {_quoted(exc)}" if not isinstance(exc, ValueError) else _quoted(exc)
        if not self.skip_bad_lines:
            raise BagError(f"{self.path}: {where}: cannot read: {reason}") from None
        self.stats.skip(index, f"{where}: {reason}")
        if fatal:
            self.stats.stopped = f"{where}: {reason}"

    def _pass(self) -> Iterator[Record]:
        self.stats = stats = BagReadStats(laser=self.topic)
        reader = self._open()
        try:
            scans = self._scan_connections(reader)
            stats.laser = scans[0].topic
            poses = [c for c in reader.connections if c.msgtype in _POSE_TYPES and c.topic in (ODOM_TOPIC, TRUTH_TOPIC)]
            try:
                tolerance = pose_tolerance(self._scan_stamps(reader, scans)) if poses else 0.0
            except Exception as exc:  # damaged chunks, bad index: rosbags' own exception types
                self._fail(f"topic {stats.laser}", exc, 0, fatal=True)
                return
            matcher = _PoseMatcher(sorted({c.topic for c in poses}), round(tolerance * 1e9))
            messages = _read_inside(reader.messages(connections=scans + poses))
            while True:
                try:
                    item = next(messages, None)
                except Exception as exc:  # noqa: BLE001 - iteration errors of a damaged bag
                    self._fail(f"topic {stats.laser} after message {stats.messages.get(stats.laser, 0)}", exc,
                               stats.messages.get(stats.laser, 0), fatal=True)
                    break
                if item is None:
                    break
                conn, t, raw = item
                index = stats.messages.get(conn.topic, 0)
                stats.messages[conn.topic] = index + 1
                try:
                    msg = reader.deserialize(raw, conn.msgtype)
                    if not reader.is2:
                        msg = _unsigned_ros1_stamp(msg)
                    if conn.msgtype != "sensor_msgs/msg/LaserScan":
                        matcher.add_pose(conn.topic, _checked_pose_ns(msg), _pose_of(msg))
                    else:
                        matcher.add_scan(_header_ns(msg), _scan_of(msg, self.range_max), index, t)
                        stats.see_timing(float(msg.time_increment), float(msg.angle_increment))
                except Exception as exc:  # noqa: BLE001 - deserialisation errors are rosbags' own types
                    self._fail(f"topic {conn.topic} message {index}", exc, index, fatal=False)
                yield from self._records(matcher.ready(t))
            yield from self._records(matcher.ready(None))
            late = {topic: n for topic, n in matcher.late.items() if n}
            if late:  # they were read without their poses, silently (a bag's topics written one after the other)
                import warnings

                from .errors import LmsbenchWarning

                said = ", ".join(f"{n} on {topic}" for topic, n in late.items())
                warnings.warn(f"{self.path}: poses came more than {LOOKAHEAD_S:g} s of bag time after the scans they are "
                              f"stamped for ({said}): those scans were read without them (the bag's topics written one "
                              "after the other, or a pose topic recorded late); write the bag in header-stamp order",
                              LmsbenchWarning, stacklevel=2)
            if not stats.messages.get(stats.laser) and not stats.skipped_count and stats.stopped is None:
                # as a CARMEN log of no laser line: it read as no records, silently
                others = ", ".join(f"{c.topic} ({c.msgcount})" for c in reader.connections if c.msgcount)
                raise BagError(f"{self.path}: its LaserScan topic {stats.laser} holds no message: no scan (a recording "
                               f"stopped before its first scan?){'; other topics: ' + others if others else ''}")
        finally:
            reader.close()

    def last_stamp(self, largest: bool = False) -> float | None:
        """The latest header stamp (s) of the bag's scans on the topic read, read from the messages' bytes
        where the bag's definitions put it where ROS does (:meth:`_scan_stamps`), without reading its
        records; None where the bag cannot be read so or holds no scan. It is the largest already
        (``largest``, as the CARMEN reader's, changes nothing)."""
        try:
            reader = self._open()
            try:
                last = max(self._scan_stamps(reader, self._scan_connections(reader)), default=None)
            finally:
                reader.close()
        except Exception:  # noqa: BLE001 - a damaged bag: rosbags' own types; the pass that reads it reports it
            return None
        return None if last is None else _ns_stamp(last)

    @staticmethod
    def _scan_stamps(reader, scans: list) -> Iterator[int]:  # noqa: ANN001
        """The header stamps (ns) of the scans, read from their bytes where the bag's definitions
        put them where ROS does (:func:`_raw_stamp_reader`): this pass decoded every scan, so a
        bag's scans were decoded twice (20,000 scans: 80,000 decodes with odometry and truth, now
        60,000). Scans whose stamp cannot be read are left out (the pass that reads them reports
        them); with stamps read from the bytes, that is a message too short to hold one or, in ROS 2,
        one with no CDR encapsulation header."""
        raw_stamp = _raw_stamp_reader(reader)
        for conn, _, raw in _read_inside(reader.messages(connections=scans)):
            if raw_stamp is not None:
                ns = raw_stamp(raw)
                if ns is not None:
                    yield ns
                continue
            try:
                msg = reader.deserialize(raw, conn.msgtype)
                yield _header_ns(msg if reader.is2 else _unsigned_ros1_stamp(msg))
            except Exception:  # noqa: BLE001, S112 - rosbags' own types; reported by the reading pass
                continue

    def _records(self, matched: Iterable[tuple[int, Scan, dict[str, Pose2D | None]]]) -> Iterator[Record]:
        for index, scan, pose in matched:
            try:
                rec = Record(scan=scan, odom=pose.get(ODOM_TOPIC), truth=pose.get(TRUTH_TOPIC))
            except Exception as exc:  # noqa: BLE001 - was raised outside any try: no bag, topic or index
                self._fail(f"topic {self.stats.laser} message {index}", exc, index, fatal=False)
                continue
            yield rec


LOOKAHEAD_S = 1.0  # s of bag time a scan waits at most for the poses stamped at or before it
MAX_HELD = 256  # scans waiting at most (a bag whose scans all have one bag time held them all: 35 MB for 5,000)
#: beams those scans hold at most (256 of 361 beams are 92,416): 100 scans of 300,000 beams of one bag
#: time (a 120 MB bag) were all held, 528 MB resident (76 MB when stamped 1 s apart)
MAX_HELD_BEAMS = 1 << 20
MAX_POSES = 4096  # poses kept per topic at most


class _Held:
    """A scan waiting for its poses."""

    __slots__ = ("index", "stamp", "bag_ns", "scan", "pose")

    def __init__(self, index: int, stamp: int, bag_ns: int, scan: Scan) -> None:
        self.index, self.stamp, self.bag_ns, self.scan = index, stamp, bag_ns, scan
        self.pose: dict[str, Pose2D] = {}  # per topic, a pose stamped exactly like the scan, written before it


class _PoseMatcher:
    """Attaches to each scan, per pose topic, the pose for it by header stamps (integer ns):

    * a pose stamped exactly like the scan; several scans with one stamp take such poses in the
      order written (a pose before a scan is that scan's, as ``write_bag`` writes them; a pose that
      comes after every scan of its stamp belongs to the last ones of them);
    * else the latest pose stamped before the scan, at most ``tolerance_ns`` before it, whose stamp
      is no other scan's (that pose is the other scan's: a record written without odometry reads
      back without it);
    * else None.

    Scans are handed out in arrival order once every pose topic has shown a pose stamped after the
    scan, or ``LOOKAHEAD_S`` of bag time has passed, or more than ``MAX_HELD`` scans (or
    ``MAX_HELD_BEAMS`` beams) wait, so what
    is held stays bounded (poses: those stamped at most ``tolerance_ns`` plus ``LOOKAHEAD_S``
    before the oldest waiting or last handed-out scan, so a scan arriving after others stamped
    later still finds its pose; at most ``MAX_POSES`` a topic).
    """

    def __init__(self, topics: list[str], tolerance_ns: int) -> None:
        self.topics = topics
        self.tolerance = tolerance_ns
        self.held: deque[_Held] = deque()
        self.held_beams = 0  # beams of the held scans
        self.by_stamp: dict[str, dict[int, deque[Pose2D]]] = {t: {} for t in topics}  # unused poses, arrival order
        self.stamps: dict[str, list[int]] = {t: [] for t in topics}  # the keys of by_stamp, sorted
        self.count: dict[str, int] = {t: 0 for t in topics}
        self.newest: dict[str, int | None] = {t: None for t in topics}
        self.scan_stamps: dict[int, int] = {}  # stamps of recent scans -> how many
        self.scan_order: deque[int] = deque()
        #: per topic, the stamps of scans handed out without a pose of it (sorted; the latest MAX_POSES),
        #: and the poses that came after such a scan they would have been attached to (``late``)
        self.missed: dict[str, list[int]] = {t: [] for t in topics}
        self.late: dict[str, int] = {t: 0 for t in topics}

    def add_pose(self, topic: str, stamp: int, pose: Pose2D) -> None:
        missed = self.missed[topic]
        if missed:  # a pose for a scan handed out without it (written more than LOOKAHEAD_S of bag time late)
            i = bisect_left(missed, stamp)
            if i < len(missed) and missed[i] - stamp <= self.tolerance:
                self.late[topic] += 1
        newest = self.newest[topic]
        self.newest[topic] = stamp if newest is None else max(newest, stamp)
        same = self.by_stamp[topic].get(stamp)
        if same is None:
            same = self.by_stamp[topic][stamp] = deque()
            insort(self.stamps[topic], stamp)
        same.append(pose)
        self.count[topic] += 1
        while self.count[topic] > MAX_POSES:
            self._drop(topic, self.stamps[topic][0], 1)

    def add_scan(self, stamp: int, scan: Scan, index: int, bag_ns: int) -> None:
        h = _Held(index, stamp, bag_ns, scan)
        for topic in self.topics:  # the first unused pose of its stamp written before it
            same = self.by_stamp[topic].get(stamp)
            if same:
                h.pose[topic] = same.popleft()
                self._used(topic, stamp)
        self.held.append(h)
        self.held_beams += len(scan)
        self.scan_stamps[stamp] = self.scan_stamps.get(stamp, 0) + 1
        self.scan_order.append(stamp)

    def ready(self, bag_ns: int | None) -> Iterator[tuple[int, Scan, dict[str, Pose2D | None]]]:
        """The scans that need wait no longer (all at the end, ``bag_ns`` None) with their poses."""
        held = self.held
        while held:
            h = held[0]
            if (bag_ns is not None and len(held) <= MAX_HELD and self.held_beams <= MAX_HELD_BEAMS
                    and bag_ns - h.bag_ns <= LOOKAHEAD_S * 1e9
                    and not all(n is not None and n > h.stamp for n in self.newest.values())):
                return
            held.popleft()
            self.held_beams -= len(h.scan)
            poses = {topic: self._pose_for(topic, h) for topic in self.topics}
            for topic, pose in poses.items():
                if pose is None:  # remembered: a pose of its stamp coming later is said (see late)
                    insort(self.missed[topic], h.stamp)
                    if len(self.missed[topic]) > MAX_POSES:
                        del self.missed[topic][0]
            yield h.index, h.scan, poses
            # poses the held scans may use, and those of scans still to come stamped up to
            # LOOKAHEAD_S before them (scans that arrive out of stamp order)
            self._prune(min([h.stamp, *(g.stamp for g in held)]) - round(LOOKAHEAD_S * 1e9))

    def _pose_for(self, topic: str, h: _Held) -> Pose2D | None:
        if topic in h.pose:
            return h.pose[topic]
        same = self.by_stamp[topic].get(h.stamp)
        if same:  # poses of its stamp that came after it: the last ones go to the last scans
            k = 1 + sum(1 for g in self.held if g.stamp == h.stamp and topic not in g.pose)
            if len(same) >= k:
                pose = same[len(same) - k]
                del same[len(same) - k]
                self._used(topic, h.stamp)
                return pose
        stamps = self.stamps[topic]
        for j in range(bisect_left(stamps, h.stamp) - 1, -1, -1):
            p = stamps[j]
            if p < h.stamp - self.tolerance:
                break
            if p not in self.scan_stamps:  # a pose stamped like another scan is that scan's
                return self.by_stamp[topic][p][-1]
        return None

    def _used(self, topic: str, stamp: int) -> None:
        self.count[topic] -= 1
        if not self.by_stamp[topic][stamp]:
            del self.by_stamp[topic][stamp]
            stamps = self.stamps[topic]
            del stamps[bisect_left(stamps, stamp)]

    def _drop(self, topic: str, stamp: int, n: int | None = None) -> None:
        same = self.by_stamp[topic][stamp]
        for _ in range(len(same) if n is None else n):
            same.popleft()
            self.count[topic] -= 1
        if not same:
            del self.by_stamp[topic][stamp]
            del self.stamps[topic][bisect_left(self.stamps[topic], stamp)]

    def _prune(self, stamp: int) -> None:
        """Forget poses and scan stamps no scan stamped ``stamp`` or later can use."""
        oldest = stamp - self.tolerance
        for topic in self.topics:
            while self.stamps[topic] and self.stamps[topic][0] < oldest:
                self._drop(topic, self.stamps[topic][0])
        while self.scan_order and (self.scan_order[0] < oldest or len(self.scan_order) > MAX_POSES):
            s = self.scan_order.popleft()
            self.scan_stamps[s] -= 1
            if not self.scan_stamps[s]:
                del self.scan_stamps[s]
