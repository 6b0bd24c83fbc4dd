"""Helpers of ``features.extract_many``: the one geometry of a batch of scans, the stacked ranges,
the per-scan FeatureSets cut from a batch kernel's concatenated rows, and the threads a batch runs on."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterable, Sequence, Sized
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from lms200 import Scan
from lms200.finite import shown

from .errors import BatchSizeError, ConfigError, ScanGeometryError, not_a_scan
from .types import BatchFeatureSet, FeatureSet

THREADS_ENV = "LMSBENCH_THREADS"  # the default thread count of extract_many (else 1)
MAX_THREADS = 1024
#: fewest scans a thread is given (~1 ms of work): starting a thread costs ~0.1 ms, four 361-beam scans
MIN_SCANS_PER_THREAD = 32


#: most beams ``extract_many`` reads from an iterator or generator of scans (a list or tuple is taken
#: whole): 2^27 ranges, 1 GiB of float64, 371,794 scans of 361 beams (2.75 h of an LMS200 at 37.5
#: scans/s). ``extract_many`` returns a list of one FeatureSet a scan, so it needs the whole batch:
#: ``itertools.repeat(scan)`` or a generator that never ends ran until memory ran out (a MemoryError
#: under a 3 GB limit). 2^25 refused a finite generator of a 45 min log that a list of the same
#: scans passed (a review): the bound stops an endless iterator, not a long log.
MAX_ITERATOR_BEAMS = 1 << 27


def scan_list(scans: Iterable[Any]) -> list[Any]:
    """``scans`` as a list: a sized collection (a list, a tuple) whole, as it is already held; an
    iterator or generator read scan by scan, each checked to be a Scan (``ScanTypeError`` naming
    the first that is not), up to MAX_ITERATOR_BEAMS beams: one that yields more (or never ends)
    raises ``BatchSizeError`` saying to pass a list or pieces of it. A TypeError where ``scans``
    is not iterable (the caller says so)."""
    if isinstance(scans, Sized):
        return list(scans)
    out: list[Any] = []
    beams = 0
    for i, scan in enumerate(scans):
        if not isinstance(scan, Scan):  # an endless iterator of something else stops at its first item
            raise not_a_scan(scan, f"scans[{i}]")
        beams += scan.ranges.size
        if beams > MAX_ITERATOR_BEAMS:
            raise BatchSizeError(
                f"scans: an iterator or generator ({type(scans).__name__}) that yielded more than {MAX_ITERATOR_BEAMS:,} "
                f"beams ({i + 1:,} scans) without ending: extract_many returns one FeatureSet a scan, so it takes a "
                "finite batch; pass a list or tuple of scans, or call it on pieces of the iterator "
                "(itertools.islice(scans, 4096))")
        out.append(scan)
    return out


def default_threads() -> int:
    """The threads ``extract_many`` uses when not told: ``$LMSBENCH_THREADS``, else 1. Not every
    CPU: on a 2-vCPU machine under load two threads ran 0.75-1.01x as fast as one (a second vCPU
    gave a compute-only loop 1.10-1.23x), so threads are asked for, not assumed."""
    env = os.environ.get(THREADS_ENV)
    if env is not None and env.strip():
        text = env.strip()  # ASCII digits, as every option takes: int() also read "1_0" as 10 and "２" as 2
        value = int(text) if text.isascii() and text.isdigit() and len(text) <= 9 else 0  # 5,000 digits: int()'s limit
        if not 1 <= value <= MAX_THREADS:
            raise ConfigError(f"{THREADS_ENV}: must be a whole number from 1 to {MAX_THREADS}, got {shown(env)}")
        return value
    return 1


def available_cpus() -> int:
    """The CPUs this process may run on (its affinity mask: ``taskset`` or a container's cpuset lowers it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def check_threads(threads: Any) -> int:
    """``threads`` as ``extract_many`` takes it: None (``default_threads()``) or a whole number >= 1."""
    if threads is None:
        return default_threads()
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or not 1 <= threads <= MAX_THREADS:
        raise ConfigError(f"threads: must be a whole number from 1 to {MAX_THREADS} or None (the default: "
                          f"${THREADS_ENV}, else 1), got {threads!r}")
    return int(threads)


def threads_used(threads: int, n: int) -> int:
    """The threads ``run_pieces`` starts for ``n`` scans when ``threads`` are allowed: at least
    MIN_SCANS_PER_THREAD scans each, at least one thread."""
    return max(1, min(threads, n // MIN_SCANS_PER_THREAD))


def run_pieces(run_many: Callable[[Sequence[Scan], Any], list[FeatureSet]], scans: Sequence[Scan], cfg: Any,
               threads: int, chunk: int) -> list[FeatureSet]:
    """``run_many(piece, cfg)`` over contiguous pieces of ``scans`` of at most ``chunk`` scans, on
    ``threads`` threads of this call's own (never more at once; none when one is used), the
    FeatureSets in the scans' order. Each thread takes one contiguous share of the scans (at
    least MIN_SCANS_PER_THREAD) and runs it piece by piece; after an error or Ctrl-C the others
    stop at their next piece and the error is raised. Each scan is extracted by itself, so the
    result does not depend on the pieces or the threads."""
    n = len(scans)
    use = threads_used(threads, n)
    share = -(-n // use) if n else 0
    shares = [(i, min(i + share, n)) for i in range(0, n, share)] if n else []
    stop = threading.Event()

    def run_share(lo: int, hi: int) -> list[FeatureSet]:
        out: list[FeatureSet] = []
        for start in range(lo, hi, chunk):
            if stop.is_set():
                break
            out += run_many(scans[start:min(start + chunk, hi)], cfg)
        return out

    if len(shares) <= 1:
        return [fs for lo, hi in shares for fs in run_share(lo, hi)]
    with ThreadPoolExecutor(max_workers=len(shares), thread_name_prefix="lmsbench-extract") as pool:
        futures = [pool.submit(run_share, lo, hi) for lo, hi in shares]
        try:
            return [fs for f in futures for fs in f.result()]
        except BaseException:
            stop.set()  # the other threads end at their next piece; the pool's exit waits for them
            raise


def common_geometry(scans: Sequence[Scan]) -> Scan:
    """The first scan, after checking that every scan has its geometry: beam count, angle_min,
    angle_increment, range_min and range_max. Raises ValueError naming the first that differs,
    and ``ScanTypeError`` naming the first item that is not a Scan."""
    first = scans[0]
    if not isinstance(first, Scan):
        raise not_a_scan(first, "scans[0]")
    key = (first.ranges.size, first.angle_min, first.angle_increment, first.range_min, first.range_max)
    for i, s in enumerate(scans):  # ranges.size, not len(s): a Python call a scan fewer
        if not isinstance(s, Scan):
            raise not_a_scan(s, f"scans[{i}]")
        if (s.ranges.size, s.angle_min, s.angle_increment, s.range_min, s.range_max) != key:
            raise ScanGeometryError(
                f"scans[{i}]: geometry (beams, angle_min, angle_increment, range_min, range_max) = "
                f"{(len(s), s.angle_min, s.angle_increment, s.range_min, s.range_max)} differs from scans[0]'s {key}; "
                "extract_many needs scans of one geometry (group them first)"
            )
    return first


def stacked_ranges(scans: Sequence[Scan]) -> np.ndarray:
    """(S, n) C-contiguous ranges of the scans (m), which have n beams each; read-only, like a Scan's
    ranges, so that the batch kernels' per-scan rows have the types of a single call's ranges and
    reuse its compiled code instead of compiling the whole extractor a second time."""
    out = np.concatenate([s.ranges for s in scans]).reshape(len(scans), -1)
    out.flags.writeable = False
    return out


def split_rows(lv: np.ndarray, lb: np.ndarray, cv: np.ndarray, cb: np.ndarray, line_off: np.ndarray,
               corner_off: np.ndarray, method: str) -> list[FeatureSet]:
    """One FeatureSet per scan from a batch's concatenated line and corner rows and their offsets
    (``BatchFeatureSet``: each scan's rows are cut from the batch's when first read)."""
    rows = (lv, lb, cv, cb, line_off.tolist(), corner_off.tolist())
    cut = BatchFeatureSet.cut
    return [cut(rows, s, method) for s in range(len(line_off) - 1)]
