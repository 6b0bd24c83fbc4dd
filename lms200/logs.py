"""One entry point for every log format: ``read_log`` and ``write_log``.

CARMEN text logs (plain or ``.gz``) and ROS 1 / ROS 2 bags are told apart by their content and
name; both yield :class:`lms200.Record` objects.
"""

from __future__ import annotations

import bz2
import glob
import itertools
import lzma
import os
import shutil
import sqlite3
import stat
import time
import zlib
from pathlib import Path
from typing import Callable, Iterable, Iterator

from .bag import BagError, BagReader, is_bag, write_bag
from . import records
from .carmen import KNOWN_KINDS, CarmenReader, _first_line_end, archive_kind, compression, text_lines, write_carmen
from .errors import InputError, LmsbenchError, LogFormatError, LogNotFoundError
from .finite import is_one_of
from .laser_geometry import LaserGeometry
from .records import Record


def read_log(
    path: str | Path,
    skip_bad_lines: bool = False,
    topic: str | None = None,
    geometry: LaserGeometry | None = None,
) -> CarmenReader | BagReader:
    """Open a log for iteration: ``for rec in read_log(path): rec.scan, rec.odom, rec.truth``.

    Args:
        path: a CARMEN log (plain, or compressed with gzip, bzip2 or xz), a ROS 1 ``.bag`` file or a ROS 2 bag folder.
        skip_bad_lines: skip malformed lines (CARMEN) or unreadable messages (bags) instead of
            raising; what was skipped is in ``reader.stats.skipped`` as (line or message index,
            reason), and ``reader.stats.stopped`` says why a pass ended early, if it did.
        topic: the laser to read: a bag's LaserScan topic (needed when the bag has several), or a
            CARMEN laser message kind (FLASER, RLASER, ROBOTLASER1 / 2, RAWLASER1 .. 4; default: the
            first kind with poses in the log, else the first RAWLASER kind).
        geometry: CARMEN FLASER / RLASER only: beam geometry (rad, m) that overrides the log's
            PARAM lines and the convention from the beam count (see :mod:`lms200.laser_geometry`);
            its ``range_max`` alone also replaces a ROBOTLASER line's and a bag's LaserScan's (a
            driver's range_max of inf, which no scan takes, needs it).

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) naming the argument, for a path that
            is not a str / PathLike, ``skip_bad_lines`` that is not a bool, ``topic`` that is not a
            str, ``geometry`` that is not a LaserGeometry, a file of a ROS 2 bag folder (its metadata.yaml,
            a .db3 or .mcap), naming the folder to give instead (:func:`bag_member_message`), or of a
            ``lmsbench simulate`` folder beside its scans.clf (groundtruth.tum, world.json, config.yaml,
            map.png), naming its scans.clf (:func:`simulate_member_message`).
        LogNotFoundError: (an ``LmsbenchError`` and a ``FileNotFoundError``) when the path does not exist, or is a folder that is not a ROS 2 bag or
            not a regular file (a device, a pipe); for a ``lmsbench simulate`` folder the message names
            its scans.clf to read instead (:func:`folder_message`).
        LogFormatError: (while iterating) a CARMEN line that cannot be read, naming file and line; a
            CARMEN log of no laser line (an empty file, a compressed stream of nothing, only comments
            or only other messages), naming the file and what it holds.
        BagError: (while iterating) a bag that cannot be read, naming the topic and message index.
    """
    p = path_of(path)
    if not isinstance(skip_bad_lines, bool):
        raise InputError(f"skip_bad_lines: must be True or False, got {skip_bad_lines!r}")
    if topic is not None and not isinstance(topic, str):
        raise InputError(f"topic: must be a topic name (str) or None, got {topic!r}")
    if geometry is not None and not isinstance(geometry, LaserGeometry):
        raise InputError(f"geometry: must be an lms200.laser_geometry.LaserGeometry or None, got {geometry!r}")
    if not p.exists():
        raise LogNotFoundError(f"no such log: {p}")
    if is_bag(p):
        given = [name for name in ("fov", "resolution", "angle_min") if geometry is not None and getattr(geometry, name) is not None]
        if given:
            raise BagError(f"{p}: a bag's LaserScan messages carry their own beam geometry; the override of "
                           f"{', '.join(given)} (--laser-*-deg) applies to CARMEN FLASER / RLASER lines only "
                           "(range_max, --laser-range-max, applies to a bag's scans too)")
        return BagReader(p, topic=topic, skip_bad_lines=skip_bad_lines,
                         range_max=geometry.range_max if geometry is not None else None)
    if p.is_dir():
        raise LogNotFoundError(folder_message(p))
    member = bag_member_message(p) or simulate_member_message(p)
    if member is not None:
        raise InputError(member)
    return CarmenReader(p, skip_bad_lines=skip_bad_lines, topic=topic, geometry=geometry)


#: name endings of packings the CARMEN writer does not make (it compresses .gz, .bz2 and .xz): a log
#: named so held plain text, which zstd, unzip or tar then refused
UNWRITTEN_PACKINGS = {".zst": "zstd-compressed file", ".lz4": "lz4-compressed file", ".zip": "zip archive",
                      ".7z": "7z archive", ".rar": "rar archive", ".tar": "tar archive", ".tgz": "tar archive",
                      ".z": "compress(1) file", ".bz": "bzip file"}


def write_log(path: str | Path, records: Iterable[Record], fmt: str | None = None) -> int:
    """Write Records to ``path``; returns the number of scans written.

    ``fmt``: "robotlaser1" (default for CARMEN) or "flaser" for CARMEN text (``.gz``, ``.bz2``, ``.xz`` compress),
    "bag" for a ROS 1 bag (default for ``*.bag``), "bag2" for a ROS 2 bag folder.

    A CARMEN log is written whole or not at all (:func:`write_whole`): an error part-way (an item that
    is not a Record, scans of mixed units, a full disk) leaves an existing file at ``path`` as it was,
    its permission bits are kept and a symbolic link's target is written; a bag, which is never
    written over, is removed again.

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) naming the argument: a path that is
            a folder, a device or in a missing folder, an unknown ``fmt``, a CARMEN ``fmt`` for a path
            ending in ``.bag`` (which read_log reads as a ROS 1 bag), an item of ``records``
            that is not an ``lms200.Record`` (naming its index), records that are not iterable,
            no record at all (nothing is written: ``read_log`` refuses a log of no scan; an empty
            CARMEN log or bag was written, exit 0, and the reader refused it), a write that fails
            (a full disk: "path: cannot write PATH: No space left on device"; a bag's was a raw
            ``OSError`` or ``sqlite3.OperationalError``).
    """
    p = path_of(path)
    if fmt is None:
        fmt = "bag" if p.suffix == ".bag" else "robotlaser1"
    if not is_one_of(fmt, ("robotlaser1", "flaser", "bag", "bag2")):
        raise InputError(f"fmt: must be 'robotlaser1', 'flaser', 'bag' or 'bag2', got {fmt!r}")
    if not p.parent.is_dir():
        raise InputError(f"path: the folder {p.parent} does not exist")
    try:
        items = iter(records)
    except TypeError:
        raise InputError(f"records: must be an iterable of lms200.Record, got {type(records).__name__}") from None
    if fmt == "bag" and p.suffix != ".bag":
        raise InputError(f"path: a ROS 1 bag must end in .bag, got {p.name}")
    if fmt == "bag2" and p.suffix == ".bag":
        raise InputError(f"path: a ROS 2 bag is a folder; do not name it {p.name}")
    if fmt in ("robotlaser1", "flaser") and p.suffix == ".bag":  # written, and read_log refused it: "File magic is invalid"
        raise InputError(f"path: a CARMEN log ({fmt}) named {p.name} is not read back: read_log reads a .bag as a ROS 1 "
                         "bag; name it .clf, .log or .gz, or give fmt='bag'")
    if fmt not in ("bag", "bag2"):
        if p.suffix.lower() in UNWRITTEN_PACKINGS:  # plain text was written under the name, silently
            raise InputError(f"path: {p.name} names a {UNWRITTEN_PACKINGS[p.suffix.lower()]}, which write_log does "
                             "not write (a CARMEN log is plain text, or compressed as .gz, .bz2 or .xz)")
        if p.exists() and not p.is_file():
            raise InputError(f"path: {p} exists and is not a regular file (a folder or a device); "
                             "name a file to write the log to")
    # the path and format checked, then the first record taken: a refused path left a live source
    # one record short; before anything is written, as a log of no scan is one read_log refuses
    checked = checked_records(_source_errors_marked(items))
    try:
        first = next(checked, None)
        if first is None:
            raise InputError(f"records: none to write to {p}: read_log refuses a log of no scan, so nothing was written")
        checked = itertools.chain([first], checked)
        if fmt in ("bag", "bag2"):
            return _bag_whole(p, checked)
        written: list[int] = []  # .NAME.PID.tmp.gz: the temporary name keeps the suffix write_carmen packs by
        write_whole(p, lambda tmp: written.append(write_carmen(tmp, checked, fmt=fmt)), suffix="".join(p.suffixes[-1:]))
        return written[0]
    except _SourceError as exc:  # the records' own error (a reader's, a generator's): as it is, not "cannot write"
        raise exc.error from exc.error.__cause__
    except LmsbenchError:  # the writers' own (a bag that exists is a FileExistsError too): as it is
        raise
    except (OSError, sqlite3.OperationalError) as exc:  # a full disk, an I/O error: one line, for either writer
        # (a bag's was a raw OSError, or sqlite3's "database or disk is full" for a ROS 2 one)
        raise InputError(f"path: cannot write {p}: {getattr(exc, 'strerror', None) or exc}") from None


def _bag_whole(p: Path, records: Iterable[Record]) -> int:
    """``write_bag`` to ``p``; a bag that did not exist before is removed again when the write fails."""
    existed = p.exists()
    try:
        return write_bag(p, records)
    except BaseException:
        if not existed and p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        elif not existed and p.exists():
            p.unlink()
        raise


class _SourceError(Exception):
    """An exception raised by the records given to ``write_log`` while they were read, carried past the
    writers' handling of their own errors (an ``OSError`` of the source, a reader's missing file, said
    "path: cannot write OUT: No such file or directory", blaming the output)."""

    def __init__(self, error: BaseException) -> None:
        super().__init__(str(error))
        self.error = error


def _source_errors_marked(items: Iterator[object]) -> Iterator[object]:
    """``items``, with an ``Exception`` raised while taking one wrapped as ``_SourceError``."""
    while True:
        try:
            item = next(items)
        except StopIteration:
            return
        except Exception as exc:
            raise _SourceError(exc) from exc
        yield item


SIMULATE_LOG = "scans.clf"
"""The CARMEN log a ``lmsbench simulate`` output folder holds (beside its ground truth and world)."""
#: the other files a ``lmsbench simulate`` output folder holds, each said as what it is (none is a log)
SIMULATE_OTHER_FILES = {"groundtruth.tum": "its ground-truth trajectory", "world.json": "its world",
                        "config.yaml": "its settings", "map.png": "its map figure"}


def hidden_stem(path: Path, tail_bytes: int) -> str:
    """The start of a hidden file's name beside ``path`` (its lock, its temporary file), to which a
    tail of ``tail_bytes`` bytes is added: ``.NAME``, or, where that would pass the file system's
    longest name (NAME_MAX, 255 bytes on Linux's), ``.PREFIX.HASH``: NAME's first bytes and 16 hex
    digits of its SHA-256, the same for every run. A file named near 255 bytes made names no file
    system takes: its lock went unguarded, and ``calibrate --out`` failed after its work,
    "...: file name too long", naming the temporary file."""
    import hashlib

    name = os.fsencode(path.name)
    try:
        most = os.pathconf(path.parent if path.parent.is_dir() else ".", "PC_NAME_MAX")
    except (OSError, ValueError):
        most = 255
    most = most if most and most > 0 else 255
    if 1 + len(name) + tail_bytes <= most:
        return f".{path.name}"
    digest = hashlib.sha256(name).hexdigest()[:16].encode()
    keep = max(most - tail_bytes - 2 - len(digest), 0)
    head = name[:keep]
    try:  # not cut within a UTF-8 character: its first bytes alone were a name no UTF-8 decoder reads
        name.decode("utf-8")
        head = head.decode("utf-8", "ignore").encode("utf-8")  # drops only the cut character's bytes
    except UnicodeDecodeError:  # a name that is no UTF-8 (os.fsencode's escapes): cut as bytes
        pass
    return os.fsdecode(b"." + head + b"." + digest)


def temporary_stem(path: Path, suffix: str = "") -> str:
    """``.NAME`` of :func:`write_whole`'s ``.NAME.PID.tmp`` (``.NAME.PID.tmpSUFFIX``), shortened for a
    name near the file system's longest (:func:`hidden_stem`; room kept for a PID of 10 digits, so one
    stem for every run: "...: file name too long" was ``calibrate --out``'s error after its work)."""
    return hidden_stem(path, len(".0123456789.tmp") + len(os.fsencode(suffix)))


def write_whole(path: str | os.PathLike, write: Callable[[Path], object], suffix: str = "") -> Path:
    """Write the file ``path`` whole or not at all: ``write`` writes a hidden temporary file beside it
    (``.NAME.PID.tmp``, the path it is given), renamed over ``path`` once whole (``os.replace``, atomic
    on POSIX); on any error the temporary file is removed and ``path`` is as it was. As a write in
    place did: a file that exists keeps its permission bits (a 0600 one became 0644 / 0664, the
    umask's), and a symbolic link is followed, its target replaced (the link was replaced by a
    regular file, its target left as it was). ``suffix`` ends the temporary name (``.NAME.PID.tmp.gz``)
    for a ``write`` that packs by the name's suffix. First, the temporary files of ``path`` that a
    process which no longer runs left (killed between write and rename) are removed
    (:func:`remove_dead_temporaries`). Returns ``path``. Every whole-file output goes
    through here (``write_log``'s CARMEN logs, ``write_tum``, ``experiments.provenance.write_record``)."""
    given = Path(path)
    target = Path(os.path.realpath(given)) if os.path.islink(given) else given
    stem = temporary_stem(target, suffix)
    tmp = target.with_name(f"{stem}.{os.getpid()}.tmp{suffix}")
    remove_dead_temporaries(target, stem, suffix)
    try:
        write(tmp)
        try:
            mode = os.stat(target).st_mode
        except FileNotFoundError:
            mode = None
        if mode is not None and stat.S_ISREG(mode):
            os.chmod(tmp, mode & 0o777)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return given


#: age (s, by mtime) past which a dead writer's ``.NAME.PID.tmp`` is removed: a write_whole writes
#: and renames within seconds; a younger one may be a live writer's on another host (NFS) or in
#: another container, whose PID means nothing here
STALE_TEMPORARY_S = 600.0

#: the kernel's pid_max where /proc/sys/kernel/pid_max cannot be read (its largest, 2^22)
DEFAULT_PID_MAX = 4194304


def pid_max() -> int:
    """The PIDs this host gives are below this (/proc/sys/kernel/pid_max, else ``DEFAULT_PID_MAX``)."""
    try:
        return int(Path("/proc/sys/kernel/pid_max").read_text().strip())
    except (OSError, ValueError):
        return DEFAULT_PID_MAX


def process_alive(pid: int) -> bool:
    """Whether a process ``pid`` runs on this machine (one of another user's counts: it may be writing)."""
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):  # none; a pid beyond any the kernel gives
        return False
    except PermissionError:  # another user's process
        return True
    return pid > 0


def temporaries(path: Path, stem: str | None = None, suffix: str = "") -> list[tuple[Path, int]]:
    """The ``STEM.PID.tmpSUFFIX`` files :func:`write_whole` writes ``path`` through that lie beside
    it (``stem`` :func:`temporary_stem` of it by default), each with its PID: a name whose PID part
    is no number (a user's ``.NAME.notes.tmp``) is none. In name order."""
    stem = temporary_stem(path, suffix) if stem is None else stem
    end = f".tmp{suffix}"
    out = []
    for tmp in sorted(path.parent.glob(f"{glob.escape(stem)}.*{glob.escape(end)}")):
        pid = tmp.name[len(stem) + 1 : len(tmp.name) - len(end)]
        if pid.isascii() and pid.isdigit():
            out.append((tmp, int(pid)))
    return out


def remove_dead_temporaries(target: Path, stem: str, suffix: str) -> None:
    """Remove the ``STEM.PID.tmpSUFFIX`` files beside ``target`` that a :func:`write_whole` killed
    (SIGKILL, a power cut) between its write and its rename left (they stayed for ever). One is
    removed only when (a) its PID is one this host gives (1 to :func:`pid_max` - 1: a 10-digit one
    is another host's), (b) no process of that PID runs here, and (c) it was last written more than
    ``STALE_TEMPORARY_S`` (10 min) ago: a PID dead here may be a live writer's on another host
    sharing the folder (NFS) or in another container, and a write_whole writes and renames within
    seconds. A user's ``.NAME.notes.tmp`` is kept. Best effort: a file that cannot be removed is left."""
    if not target.parent.is_dir():
        return
    most, now = pid_max(), time.time()
    for old, pid in temporaries(target, stem, suffix):
        if not 0 < pid < most or pid == os.getpid() or process_alive(pid):
            continue
        try:
            st = old.lstat()
            if stat.S_ISREG(st.st_mode) and now - st.st_mtime > STALE_TEMPORARY_S:
                old.unlink()
        except OSError:
            pass


def folder_message(p: Path) -> str:
    """Why ``read_log`` refuses the folder ``p`` (not a ROS 2 bag), and, for a ``lmsbench simulate``
    folder, which file to read instead. The folder is not read as its scans.clf: this package knows
    log formats, not the layout of the command line's output folders, and the command line checks
    such a folder before it reads its log (a run that was killed left a cut scans.clf, refused
    there, ``experiments.options.check_log``); ``read_log(p)`` said "not a ROS 2 bag" and no more."""
    log = p / SIMULATE_LOG
    if log.is_file():
        return (f"{p} is a folder, not a log: it holds {SIMULATE_LOG}, as a lmsbench simulate output folder does; "
                f"read_log({str(log)!r}) reads its scans (`lmsbench info {p}` also checks that its run finished)")
    return f"{p} is a folder but not a ROS 2 bag ({missing_file_reason(p / 'metadata.yaml')})"


def bag_member_message(p: Path) -> str | None:
    """Why the file ``p``, one of a ROS 2 bag folder's own (its metadata.yaml, a .db3 or .mcap storage
    file), is no log by itself, naming the folder to give instead; None for any other file. Given one,
    ``read_log`` said "not a CARMEN log: none of its 38 lines ... starts with a message name" and the
    command line "a binary file, not a CARMEN log, ROS 1 .bag or ROS 2 bag folder" (round 7)."""
    folder = p.parent
    if not (p.is_file() and (p.name == "metadata.yaml" or p.suffix in (".db3", ".mcap"))
            and (folder / "metadata.yaml").is_file()):
        return None
    return (f"{p}: a file of the ROS 2 bag {folder} (its {'metadata' if p.name == 'metadata.yaml' else 'storage file'}), "
            f"not a log by itself: a ROS 2 bag is read as its folder; give {folder}")


def simulate_member_message(p: Path, give_folder: bool = False) -> str | None:
    """Why the file ``p``, one of a ``lmsbench simulate`` output folder's own beside its scans.clf (its
    groundtruth.tum, world.json, config.yaml or map.png: SIMULATE_OTHER_FILES), is no log, naming what
    to give instead: the folder (``give_folder``: the command line, which checks the run finished) or
    its scans.clf (``read_log``); None for any other file. Given one, both said "not a CARMEN log: none
    of its 37 lines ... starts with a message name" (map.png "a binary file"), with no hint (round 9)."""
    folder = p.parent
    what = SIMULATE_OTHER_FILES.get(p.name)
    if what is None or not p.is_file() or not (folder / SIMULATE_LOG).is_file():
        return None
    return (f"{p}: a file of the lmsbench simulate output folder {folder} ({what}), not a log: the run's scans "
            f"are its {SIMULATE_LOG}; give {folder if give_folder else folder / SIMULATE_LOG}")


def missing_file_reason(path: Path) -> str:
    """Why a folder's file ``path`` (a ROS 2 bag's metadata.yaml, a simulate folder's scans.clf) is not
    there as a regular file, in a few words: ``no NAME``, or what stands in its place (a folder, a pipe
    or a device, a link to nothing): "no metadata.yaml" was said of a metadata.yaml that was a pipe."""
    name = path.name
    if path.is_dir():
        return f"its {name} is a folder"
    if path.exists():
        return f"its {name} is not a regular file but a pipe, a device or a socket"
    if path.is_symlink():
        return f"its {name} is a link to {os.readlink(path)}, which does not exist (or a loop of links)"
    return f"no {name}"


def path_of(path: object) -> Path:
    """``path`` as a Path; InputError naming it when it is not a str or os.PathLike, an empty or blank
    str (an unset ``$LOG``: pathlib reads "" as the current folder), or when a name
    in it is longer than the file system takes (NAME_MAX, 255 bytes on Linux's: the readers and
    writers raised a raw OSError, "File name too long", from their first look at it)."""
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: must be a str or os.PathLike, got {type(path).__name__}")
    if isinstance(path, str) and not path.strip():  # Path("") is ".": read_log("") said ". is a folder but not a ROS 2 bag"
        raise InputError(f"path: empty ({path!r}); give a file or folder name")
    p = Path(path)
    for part in p.parts:
        size = len(os.fsencode(part))
        if size > 255:  # no file system takes it (NAME_MAX: 255 on Linux's, less on none of the usual ones)
            raise InputError(f"path: a name of {size} bytes ({part[:40]}...), longer than a file system takes (255); "
                             "give a shorter one")
    return p


def regular_file(path: object, what: str) -> Path:
    """``path`` (:func:`path_of`) of an existing regular file, ``what`` naming its kind in the
    message; LogNotFoundError otherwise. A device or a pipe is refused unread: read_tum and
    read_relations read /dev/zero line by line until the memory ran out (found by fuzzing)."""
    p = path_of(path)
    if not p.exists():
        raise LogNotFoundError(f"no such {what}: {p}")
    if p.is_dir():
        raise LogNotFoundError(f"{p} is a folder, not a {what}")
    if not p.is_file():
        raise LogNotFoundError(f"{p}: a {what} must be a regular file, not a device or pipe")
    return p


MAX_ROW_CHARS = 1 << 20
"""Longest line of a text file of rows (TUM, relations) read (characters, as ``carmen.MAX_LINE_CHARS``):
a row is 8 numbers, under 200 characters. A file of zeros or of binary data with no line break
was read as one line, whole: a 3 GB one ended in MemoryError ("internal error", exit 1)."""
MAX_COORD_M = records.MAX_COORD_M
"""Largest |x|, |y| (m) a TUM or relations row (or a CARMEN line's pose) may hold: far beyond any
trajectory on Earth (UTM northings are below 1e7 m); 1e300 m overflowed the squares of the metrics
(RuntimeWarnings on stderr and an error of inf, exit 0)."""
MAX_HEADING_RAD = records.MAX_HEADING_RAD
"""Largest |heading| (rad) a CARMEN pose, a relations row's roll, pitch or yaw, or a trajectory given to
``slam.metrics`` may hold (160,000 turns): a float of 1e300 holds no angle, and it was read as one."""


#: decompressed bytes :func:`head_problem` reads from a compressed head to tell a CARMEN log (bounded: the
#: head alone is decompressed, never the file)
PEEK_BYTES = 8192


def carmen_message(head: bytes, whole: bool = False) -> tuple[int, str] | None:
    """(line number, message name) when the first line of text ``head`` that is no comment starts with a
    CARMEN message name (as :func:`row_lines` tells a log given as a row file), else None. A last line
    without its end counts only when ``whole`` (the head is the whole text)."""
    text = head.removeprefix(b"\xef\xbb\xbf").decode("ascii", "replace")  # a UTF-8 byte-order mark skipped
    lines = text.split("\n") if "\n" in text or "\r" not in text else text.split("\r")  # classic Mac ends
    for no, line in enumerate(lines if whole else lines[:-1], 1):
        words = line.split(maxsplit=1)
        if words and not words[0].startswith("#"):
            return (no, words[0]) if words[0] in KNOWN_KINDS else None
    return None


def _unpacked_head(head: bytes, kind: str) -> tuple[bytes, bool]:
    """The first decompressed bytes (at most PEEK_BYTES) of the gzip, xz or bzip2 stream that starts
    with ``head``, and whether they are the whole text; (b"", False) where none can be had from the
    head (a bzip2 block of 100-900 KB of text that the head does not hold whole; a broken stream)."""
    try:
        if kind == "gzip":
            gz = zlib.decompressobj(wbits=16 + zlib.MAX_WBITS)  # the gzip format, as the gzip module reads it
            return gz.decompress(head, PEEK_BYTES), gz.eof
        if kind in ("xz", "bzip2"):  # a bzip2 block decompresses only once whole: in the head, a small file's alone
            unpack = lzma.LZMADecompressor(format=lzma.FORMAT_XZ) if kind == "xz" else bz2.BZ2Decompressor()
            return unpack.decompress(head, PEEK_BYTES), unpack.eof
    except (zlib.error, lzma.LZMAError, OSError, EOFError):
        pass
    return b"", False


def head_problem(head: bytes, what: str, packed: bool = True, carmen: bool = True) -> str | None:
    """Why a file whose first bytes are ``head`` is not ``what``, a text file: compressed (unless ``packed``
    is False: the caller reads through it), a compressed CARMEN log (its head's first PEEK_BYTES
    decompressed bytes say so), an archive, binary, a CARMEN log (unless ``carmen`` is False: ``what``
    is a log); or None. The one wording of the row files'
    readers and of the command line's check of every text file (``experiments.options``)."""
    kind, archive = compression(head) if packed else None, archive_kind(head)
    if kind:
        message = carmen_message(*_unpacked_head(head, kind))
        if message:  # a gzip-compressed MIT CSAIL log given as --relations was told to be decompressed
            return carmen_log_problem(*message, what, kind)
        return f"{kind}-compressed, not {what} (read as plain text); decompress it first"
    if archive:
        return f"{archive}, not {what}; extract it first"
    if b"\x00" in head:
        return f"a binary file, not {what}"
    message = carmen_message(head) if carmen else None  # a log given as a config or sweep file: it was "not a
    return carmen_log_problem(*message, what) if message else None  # simulate config (expected a mapping ...)"


def carmen_log_problem(line: int, message: str, what: str, packed: str | None = None) -> str:
    """The one wording of a CARMEN log given where ``what`` is read (``packed``: its compression)."""
    log = f"{'an' if packed == 'xz' else 'a'} {packed}-compressed CARMEN log" if packed else "a CARMEN log"
    return f"{log} (its line {line} is a {message} message), not {what}"


def row_lines(path: str | Path, p: Path, what: str = "a text file of rows") -> Iterator[tuple[int, str]]:
    """(line number, line) of the text file ``p`` (named ``path`` in messages, ``what`` its kind: a
    compressed, archived or binary file is a LogFormatError saying so), each line read at most
    :data:`MAX_ROW_CHARS` characters at a time: a longer one is a LogFormatError naming it. A UTF-8
    byte-order mark before the first line (a file saved by a Windows editor) is skipped, as the CARMEN
    reader skips it: it read as three replacement characters, so a TUM file's header comment was a
    row of 9 entries and a first row a non-number. Lines end as in a CARMEN log
    (:func:`lms200.carmen.open_text`): at "\\n" ("\\r\\n" too), a lone "\\r" being whitespace within its
    line, or at "\\r" in a file of classic Mac line ends; a line's number is the one an editor or
    ``sed -n Np`` gives it (a lone "\\r" ended a line, so every error after one named the wrong line)."""
    with open(p, "rb") as raw:
        head = raw.read(4096)
        problem = head_problem(head, what)
        if problem:  # read as text: "line 1: relation rows need 8 numbers, got 16" of a gzip-compressed file
            raise LogFormatError(path, None, problem)
        ends = _first_line_end(head, raw)
        raw.seek(0)
        f = text_lines(raw, head, ends)
        first = True  # the first row yet to come: a CARMEN log's message there says what the file is
        for no, line in enumerate(iter(lambda: f.readline(MAX_ROW_CHARS + 1), ""), 1):
            if len(line) > MAX_ROW_CHARS:
                raise LogFormatError(path, no, f"longer than {MAX_ROW_CHARS:,} characters: not a text file of rows "
                                               "(binary data, or no line breaks)")
            words = line.split(maxsplit=1) if first else None
            if words and not words[0].startswith("#"):
                first = False
                if words[0] in KNOWN_KINDS:  # past the head's lines (a long comment block before it): head_problem's
                    raise LogFormatError(path, None, carmen_log_problem(no, words[0], what))
            yield no, line


def row_numbers(path: str | Path, no: int, words: list[str], what: str) -> list[float]:
    """The numbers of a TUM or relations row, as a float parser of the format reads them: Python's
    float() also takes ``1_000`` (a stamp 1_000 read as 1000 s), which neither evo nor numpy does:
    a LogFormatError naming the line, as a word that is no number is."""
    try:
        if any("_" in w for w in words):
            raise ValueError
        return [float(w) for w in words]
    except ValueError:
        raise LogFormatError(path, no, f"{what} has a non-number: {' '.join(words)[:60]!r}") from None


def checked_records(records: Iterable[object], error: type[Exception] = InputError) -> Iterator[Record]:
    """The records, raising ``error`` naming the index of the first item that is not a Record (lazily:
    a log's records are checked as they are written or used)."""
    for i, rec in enumerate(records):
        if not isinstance(rec, Record):
            hint = " (wrap a Scan as lms200.Record(scan=scan))" if type(rec).__name__ == "Scan" else ""
            raise error(f"records[{i}]: expected an lms200.Record, got {type(rec).__name__}{hint}")
        yield rec
