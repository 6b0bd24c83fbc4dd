"""``run_slam(records, config)``: the filter over a scan source, and its result."""

from __future__ import annotations

import itertools
import sys
import warnings
from dataclasses import dataclass, field
from typing import Any, Iterable, Iterator, Sequence, Sized

import numpy as np

from lms200.errors import LmsbenchWarning
from lms200.finite import fixed, shown
from lms200.logs import MAX_COORD_M, checked_records
from lms200.records import Record, pose_problem
from lms200.units import reader_watches, units_watched

from .config import MIN_MATCH_POINTS, SlamConfig
from .filter import SlamFilter, SlamInputError, checked_step
from .models import wrap
from .observations import Observations, from_features


@dataclass
class SlamResult:
    """Output of a SLAM run. World frame = the frame of the first scan's estimated pose.

    Attributes:
        trajectory: (n, 4) t s, x m, y m, theta rad: one pose per input scan, the input's stamps.
        covariances: (n, 3, 3) covariance of (x, y, theta).
        map_lines: (k, 7) confirmed line landmarks: R, theta, x0, y0, x1, y1, hits.
        map_corners: (c, 3) confirmed corner landmarks: x, y, hits.
        diagnostics: per-scan arrays ``nis``, ``nis_dof``, ``nees`` (nan without truth),
            ``n_landmarks``, ``n_matched``, ``n_lines``, ``prealign_used``, ``point_score``
            (paper preset; the default pipeline: ``inliers``, ``matched``, ``keyframe``, the
            ``keyframes`` (t, x, y, theta) and the ``loops`` closed); scalars ``diverged``,
            ``diverged_at`` (stamp or None: NIS too high, or the scan's points off the map at
            the estimate for ``consistency.point_window`` scans), ``mean_nis_per_dof``,
            ``mean_nees``, ``healthy``, ``matched_fraction`` (the share of steps after the first
            matched to the map: paper preset, a line paired with a landmark).
    """

    trajectory: np.ndarray
    covariances: np.ndarray
    map_lines: np.ndarray
    map_corners: np.ndarray
    diagnostics: dict[str, Any] = field(default_factory=dict)

    def map_dict(self) -> dict[str, Any]:
        """The map as plain lists (for map.json)."""
        return {
            "frame": "world frame of the first scan (x m, y m, angles rad)",
            "lines": [
                {"R": r[0], "theta": r[1], "start": [r[2], r[3]], "end": [r[4], r[5]], "hits": int(r[6])}
                for r in self.map_lines.tolist()
            ],
            "corners": [{"x": c[0], "y": c[1], "hits": int(c[2])} for c in self.map_corners.tolist()],
        }


def _compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2])])


def run_observations(
    stamps: Iterable[float],
    observations: Iterable[Observations],
    config: SlamConfig = SlamConfig(),
    odometry: Iterable[tuple[float, float, float] | None] | None = None,
    truths: Iterable[tuple[float, float, float] | None] | None = None,
) -> SlamResult:
    """Run the filter over ready observations (one per scan); see :func:`run_steps`.

    Raises:
        SlamInputError: an argument that is not iterable, or ``observations``, ``odometry`` or
            ``truths`` of another length than ``stamps`` (zip cut them to the shortest, silently:
            11 stamps and 10 observations gave 10 poses, ``odometry="abc"`` 3).
    """
    lists: dict[str, list[Any]] = {}
    n = 0
    for name, value in (("stamps", stamps), ("observations", observations), ("odometry", odometry), ("truths", truths)):
        if value is None and name in ("odometry", "truths"):
            lists[name] = [None] * n
            continue
        if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
            raise SlamInputError(f"{name}: must be an iterable (one item a scan), got {type(value).__name__}")
        lists[name] = list(listed(value, name))
        if name == "stamps":
            n = len(lists[name])
        elif len(lists[name]) != n:
            raise SlamInputError(f"{name}: {len(lists[name])} items for {n} stamps (one a scan)")
    return _run_steps(zip(lists["stamps"], lists["observations"], lists["odometry"], lists["truths"]), config)


def listed(items: Iterable[Any], name: str) -> Iterable[Any]:
    """``items`` for :func:`run_observations`, which lists them all before the run: an iterator of
    more than ``MAX_SLAM_SCANS`` items is refused (SlamInputError naming ``name``) as a list is."""
    if isinstance(items, Sized):
        check_size(items, name)
        return items
    out = list(itertools.islice(items, MAX_SLAM_SCANS + 1))
    if len(out) > MAX_SLAM_SCANS:
        raise SlamInputError(f"{name}: an iterator or generator that yielded more than {MAX_SLAM_SCANS:,} items "
                             "(slam.run.MAX_SLAM_SCANS, one a scan: 24 h at 75 Hz) without ending (itertools.count?); "
                             "pass a finite piece of it (itertools.islice), or run_steps, which ends the run there")
    return out


#: most scans one run reads (run_slam, run_steps, run_observations): 24 h of an LMS200 at its 75 Hz.
#: A run keeps a few hundred bytes a scan whatever the scan (its pose, 3x3 covariance and per-scan
#: diagnostics: the paper preset's result 185 B a scan, 1.2 GB at the bound; its peak while it runs
#: 267 B a scan, 1.7 GB, its numpy blocks (:class:`Column`) and the result they are joined into; its
#: Python lists were ~730 B, 4.7 GB. The default preset's result 163 B a scan, its peak 356 B, 2.3 GB,
#: its per-scan values in Columns too (its ScanStep records, stamps, truths and anchor tuples in lists were
#: ~990 B, 6.4 GB); tracemalloc, 20,000 vs 40,000 steps, 2,000 vs 4,000 scans and 300 vs 1,300 scans); past
#: it a source is most likely one that never ends
#: (``run_slam(itertools.repeat(record))`` ran for ever, its trajectory growing). An iterator is read
#: up to it and the run ends there, with a SlamLimitWarning (its result kept: a live source, a day's
#: bag); a list, a tuple (any sized collection) or ``run_observations``' inputs (listed first) longer
#: than it are refused before any work (SlamInputError).
MAX_SLAM_SCANS = 24 * 3600 * 75


def check_size(items: Sized, name: str) -> None:
    """SlamInputError naming ``name`` when the sized ``items`` hold more than ``MAX_SLAM_SCANS``."""
    if len(items) > MAX_SLAM_SCANS:
        raise SlamInputError(f"{name}: {len(items):,} scans, more than a run reads (slam.run.MAX_SLAM_SCANS, "
                             f"{MAX_SLAM_SCANS:,}: 24 h at 75 Hz); pass a piece of it")


class SlamLimitWarning(LmsbenchWarning):
    """A run met one of its bounds: the paper preset's filter left observations out
    (``observations.max_lines`` a scan, ``landmarks.max_landmarks`` in the map: a
    :class:`SlamBoundWarning`), or an iterator of scans was read up to ``MAX_SLAM_SCANS`` and the run
    ended there."""


class SlamBoundWarning(SlamLimitWarning):
    """The paper preset's filter left observations out (``observations.max_lines``,
    ``landmarks.max_landmarks``): once a run, what :func:`bounds_met` finds in its diagnostics. A driver
    of several runs (``lmsbench slam``'s baselines) may silence these and say the runs' in one line."""


@dataclass(frozen=True)
class BoundMet:
    """A bound of the filter a run met: ``count`` observations left out in ``scans`` of its ``n_scans``
    scans, beyond the config field ``name`` of value ``value``."""

    name: str
    value: int
    what: str  # what was left out, e.g. "lines or corners were not observed"
    count: int
    scans: int
    n_scans: int

    def counted(self) -> str:
        """``"830 lines or corners were not observed in 150 of 150 scans"``."""
        return f"{self.count:,} {self.what} in {self.scans:,} of {self.n_scans:,} scans"

    def beyond(self) -> str:
        """``"beyond observations.max_lines (2, a bound of the filter's time and memory)"``."""
        return f"beyond {self.name} ({self.value:,}, a bound of the filter's time and memory)"


class Capped:
    """An iterable's items for one run: a sized one (a list, a tuple) whole, SlamInputError naming
    ``name`` when it holds more than ``MAX_SLAM_SCANS``; an iterator's first ``MAX_SLAM_SCANS``
    (``ended`` is then True: :meth:`warn` says so)."""

    def __init__(self, items: Iterable[Any], name: str) -> None:
        self.items, self.name, self.read, self.ended = items, name, 0, False
        if isinstance(items, Sized):
            check_size(items, name)

    def __iter__(self) -> Iterator[Any]:
        if isinstance(self.items, Sized):
            yield from self.items
            return
        for item in itertools.islice(self.items, MAX_SLAM_SCANS):
            self.read += 1
            yield item
        self.ended = self.read >= MAX_SLAM_SCANS

    def warn(self, stacklevel: int) -> None:
        """A one-line SlamLimitWarning when the iterator was cut at ``MAX_SLAM_SCANS``."""
        if self.ended:
            warnings.warn(f"{self.name}: the run ended after {self.read:,} scans (slam.run.MAX_SLAM_SCANS, 24 h at "
                          "75 Hz); the iterator's scans after them, if any, were not read", SlamLimitWarning,
                          stacklevel=stacklevel + 1)


class Column:
    """Per-scan values of one dtype and row shape, appended one at a time into numpy blocks of
    ``BLOCK_ROWS`` rows (a scan's pose, covariance or diagnostic): 8 B a float where a list of
    Python floats held 32 B (a pointer and the float) and a list of 3x3 covariance arrays ~190 B a
    scan for 72 B of numbers. :meth:`taken` joins the blocks into one array and lets them go."""

    BLOCK_ROWS = 4096

    def __init__(self, dtype: type | np.dtype, shape: tuple[int, ...] = ()) -> None:
        self.dtype, self.shape = np.dtype(dtype), shape
        self.full: list[np.ndarray] = []  # the blocks filled
        self.block = np.empty((0, *shape), self.dtype)
        self.fill = 0  # rows of self.block in use
        self.size = 0  # rows in all

    def append(self, value: Any) -> None:
        if self.fill == len(self.block):
            if self.fill:
                self.full.append(self.block)
            self.block, self.fill = np.empty((self.BLOCK_ROWS, *self.shape), self.dtype), 0
        self.block[self.fill] = value
        self.fill += 1
        self.size += 1

    def last(self, k: int) -> np.ndarray:
        """The last ``k`` rows (all of them when there are fewer), oldest first, one contiguous array."""
        if k <= self.fill:
            return self.block[self.fill - k:self.fill]
        parts, need = [self.block[:self.fill]], k - self.fill
        for block in reversed(self.full):
            if need <= 0:
                break
            parts.append(block[max(len(block) - need, 0):])
            need -= len(block)
        return np.concatenate(parts[::-1])

    def blocks(self) -> list[np.ndarray]:
        """The rows as the blocks that hold them (views of their filled rows, oldest first; the column is kept)."""
        return self.full + [self.block[:self.fill]]

    def taken(self) -> np.ndarray:
        """All rows as one array; the column is empty after (its blocks released)."""
        blocks, self.full = self.full + [self.block[:self.fill]], []
        self.block, self.fill, self.size = np.empty((0, *self.shape), self.dtype), 0, 0
        out = blocks[0].copy() if len(blocks) == 1 else np.concatenate(blocks)
        del blocks
        return out


def run_steps(steps: Iterable[tuple[float, Observations, Any, Any]], config: SlamConfig = SlamConfig()) -> SlamResult:
    """Run the filter over (stamp s, observations, odometry pose or None, true pose or None).

    The filter starts at the origin; with true poses, the pose NEES is computed in the truth frame
    anchored at the first true pose. An iterator of steps is read up to ``MAX_SLAM_SCANS``
    (6,480,000) steps and the run ends there (a SlamLimitWarning); a list or tuple longer than that
    is refused (SlamInputError).
    """
    if isinstance(steps, (str, bytes)) or not isinstance(steps, Iterable):
        raise SlamInputError(f"steps: must be an iterable (one item a scan), got {type(steps).__name__}")
    capped = Capped(steps, "steps")
    result = _run_steps(capped, config)
    capped.warn(stacklevel=2)
    return result


def _run_steps(steps: Iterable[tuple[float, Observations, Any, Any]], config: SlamConfig) -> SlamResult:
    """:func:`run_steps` without its bound (its callers bound their input: :class:`Capped`)."""
    if not isinstance(config, SlamConfig):
        raise SlamInputError(f"config: must be a slam.SlamConfig, got {type(config).__name__}")
    slam = SlamFilter(config)
    traj, covs = Column(np.float64, (4,)), Column(np.float64, (3, 3))  # numpy blocks, not lists: see MAX_SLAM_SCANS
    kinds = {"nis": np.float64, "nis_dof": np.int64, "nees": np.float64, "n_landmarks": np.int64,
             "n_matched": np.int64, "n_lines": np.int64, "prealign_used": np.bool_, "prealign_shift": np.float64,
             "point_score": np.float64, "n_unobserved": np.int64, "n_unadded": np.int64, "n_dropped": np.int64}
    diag = {k: Column(kind) for k, kind in kinds.items()}
    diverged_at = None
    anchor = None
    healthy = True
    for k, step in enumerate(steps):
        t, obs, odom, truth = _step_items(k, step)
        t, odom, truth = checked_step(k, t, obs, odom, truth)  # the filter's step checks the time order
        info = slam.step(t, obs, odom if config.motion.use_odometry else None)
        pose = slam.pose
        P = slam.ekf.P[:3, :3].copy()
        if not np.all(np.abs(pose[:2]) <= MAX_COORD_M):  # diverged beyond every reader's bound (the TUM reader's):
            pose = np.full(3, np.nan)  # a lost pose (written as nan), not x = 1e18 m in a file no reader takes
            healthy = False
            diverged_at = t if diverged_at is None else diverged_at
        traj.append((t, *pose))
        covs.append(P)
        nees = np.nan
        if truth is not None:
            if anchor is None:
                anchor = np.asarray(truth, float)
            est = _compose(anchor, pose)
            e = np.asarray(truth, float) - est
            e[2] = wrap(e[2])
            c, s = np.cos(anchor[2]), np.sin(anchor[2])
            Rw = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
            Pw = Rw @ P @ Rw.T
            if k > 0:
                try:
                    nees = float(e @ np.linalg.solve(Pw, e))
                except np.linalg.LinAlgError:
                    nees = np.inf
        for key, value in (("nis", info.nis), ("nis_dof", info.nis_dof), ("nees", nees),
                           ("n_landmarks", len(slam.landmarks)), ("n_matched", info.n_matched),
                           ("n_lines", info.n_lines), ("prealign_used", info.prealign_used),
                           ("prealign_shift", info.prealign_shift), ("point_score", info.point_score),
                           ("n_unobserved", info.n_unobserved), ("n_unadded", info.n_unadded),
                           ("n_dropped", info.n_dropped)):
            diag[key].append(value)
        ok = slam.healthy(full=(k % 50 == 0))
        healthy &= ok
        window = config.consistency.nis_window
        nis_w = np.sum(diag["nis"].last(window))
        dof_w = np.sum(diag["nis_dof"].last(window))
        if diverged_at is None and (not ok or (diag["nis"].size >= window and dof_w > 0 and nis_w / dof_w > config.consistency.nis_divergence)
                                    or lost_against_scan(diag["point_score"].last(config.consistency.point_window),
                                                         config.consistency)):
            diverged_at = t
    if not traj.size:
        raise SlamInputError("no scans in the input")
    out: dict[str, Any] = {k: column.taken() for k, column in diag.items()}  # one at a time: blocks let go
    warn_limits(out, config)
    dof = out["nis_dof"].sum()
    finite_nees = out["nees"][np.isfinite(out["nees"])]
    out.update(
        diverged=diverged_at is not None,
        diverged_at=diverged_at,
        healthy=bool(healthy and slam.healthy(full=True)),
        # the steps whose scan had a line paired with a landmark (the rest are the motion model's
        # guess): a run of scans without a line (every beam nan, 3-beam scans) was said nothing of
        matched_fraction=float(np.mean(out["n_matched"][1:] > 0)) if out["n_matched"].size > 1 else 1.0,
        mean_nis_per_dof=float(out["nis"].sum() / dof) if dof else float("nan"),
        mean_nees=float(finite_nees.mean()) if finite_nees.size else float("nan"),
    )
    return SlamResult(traj.taken(), covs.taken(), slam.map_lines(), slam.map_corners(), out)


def _step_items(k: int, step: object) -> tuple[Any, Any, Any, Any]:
    """Step ``k`` of :func:`run_steps` as its four items; SlamInputError naming it when it is no
    (stamp, observations, odometry, truth) tuple: a (stamp, observations) pair was "ValueError: not
    enough values to unpack", a bare stamp "TypeError: cannot unpack non-iterable float"."""
    items = (isinstance(step, Sequence) and not isinstance(step, (str, bytes))) or (isinstance(step, np.ndarray) and step.ndim == 1)
    if items and len(step) == 4:  # type: ignore[arg-type]  # a Sequence or an array: sized
        return step[0], step[1], step[2], step[3]  # type: ignore[index]
    what = f"{len(step)} items" if items else type(step).__name__  # type: ignore[arg-type]
    raise SlamInputError(f"steps[{k}]: must be a tuple (stamp s, slam.Observations, odometry pose or None, true pose "
                         f"or None), got {what}")


def bounds_met(diag: dict[str, Any], config: SlamConfig) -> list[BoundMet]:
    """The bounds of the filter a run met, from its diagnostics (``n_unobserved``, ``n_unadded`` a
    scan; a run without them, the default preset's, met none)."""
    met = []
    for key, what, name, value in (
            ("n_unobserved", "lines or corners were not observed", "observations.max_lines", config.observations.max_lines),
            ("n_unadded", "observations started no landmark", "landmarks.max_landmarks", config.landmarks.max_landmarks)):
        counts = diag.get(key)
        if counts is not None and counts.sum():
            met.append(BoundMet(name, value, what, int(counts.sum()), int(np.count_nonzero(counts)), int(counts.size)))
    return met


def warn_limits(diag: dict[str, Any], config: SlamConfig) -> None:
    """A SlamBoundWarning for each bound of the filter a run met (once a run: its scans and counts)."""
    for bound in bounds_met(diag, config):
        warnings.warn(f"{bound.counted()}: {bound.beyond()}", SlamBoundWarning, stacklevel=4)


def lost_against_scan(scores: Sequence[float] | np.ndarray, cfg) -> bool:
    """The NEES-like check against the scan itself: the last ``cfg.point_window`` scans all put
    fewer than ``cfg.point_min_score`` of their points on the map (nan scores, no reference, are
    not counted as bad)."""
    if len(scores) < cfg.point_window:
        return False
    last = np.asarray(scores[-cfg.point_window:], float)
    return bool(np.all(last < cfg.point_min_score))


def pose_nees(traj: np.ndarray, covs: np.ndarray, truths: Iterable[Any]) -> np.ndarray:
    """Per-scan pose NEES ``e^T P^-1 e`` (3 dof) of an (n, 4) trajectory with (n, 3, 3) world-frame
    covariances against true poses (None where unknown: nan), in the truth frame anchored at the
    first true pose (the estimate's frame is that of its first pose)."""
    out = np.full(traj.shape[0], np.nan)
    anchor = None
    for k, truth in enumerate(truths):
        if truth is None:
            continue
        if anchor is None:
            anchor = np.asarray(truth, float)
            continue
        e = np.asarray(truth, float) - _compose(anchor, traj[k, 1:])
        e[2] = wrap(e[2])
        c, s = np.cos(anchor[2]), np.sin(anchor[2])
        Rw = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
        Pw = Rw @ covs[k] @ Rw.T
        try:
            out[k] = float(e @ np.linalg.solve(Pw, e))
        except np.linalg.LinAlgError:
            out[k] = np.inf
    return out


def run_slam(records: Iterable[Record], config: SlamConfig = SlamConfig(), max_scans: int | None = None) -> SlamResult:
    """Odometry-free SLAM over a scan source (a log reader, the simulator's records...).

    ``config.preset == "default"``: motion measured by scan matching, keyframe pose graph with
    loop closures (:func:`slam.scanslam.run_scan_slam`); the trajectory is the optimised graph's.
    ``"paper"``: the paper's EKF (section 4.1) with line (and, with ``config.observations.use_corners``,
    corner) observations from ``features.extract_many(scans, method=config.extractor,
    **config.extractor_params)`` in batches of ``EXTRACT_BATCH`` scans. The records' odometry is used only with
    ``config.motion.use_odometry`` (either preset; a record without it is predicted by the
    motion model); true poses only for the NEES diagnostic.

    ``max_scans``: at most this many records are read (the rest are not: a live source may stop
    there), silently. Without it, an iterator or generator of records is read up to
    ``MAX_SLAM_SCANS`` (6,480,000: 24 h at the LMS200's 75 Hz) and the run ends there, its result
    returned with a one-line SlamLimitWarning (how many scans were read; the rest were not); a
    list, a tuple or another sized collection is taken whole, and refused before any work when it
    holds more than ``MAX_SLAM_SCANS``.

    The first ``lms200.units.UNITS_SCANS`` (50) scans are looked at for ranges in millimetres as
    they come (none read ahead): one ``lms200.units.RangeUnitsWarning`` where they look so (every
    beam a no return). A log reader given as ``records`` itself (``read_log(...)``) looks at them in
    its own pass, and this check is left out; a list or slice of a reader's records is looked at
    here as well, so a log in millimetres is then said twice (the reader's text, naming the log,
    and this one, naming ``records``).

    Returns:
        SlamResult with one pose per record, stamped with the record's ``scan.stamp``.

    Raises:
        SlamInputError: an item that is no Record (naming its index), scans out of time order, two
            or more scans all of one stamp (``same_stamp_problem``, as ``lmsbench slam`` says it: a list
            or tuple before any work, another source at its end), a
            ``max_scans`` that is no integer >= 1, a sized ``records`` of more than ``MAX_SLAM_SCANS``
            with no ``max_scans``.
    """
    if not isinstance(config, SlamConfig):
        raise SlamInputError(f"config: must be a slam.SlamConfig, got {type(config).__name__}")
    if max_scans is not None and (isinstance(max_scans, bool) or not isinstance(max_scans, (int, np.integer))
                                  or max_scans < 1):
        raise SlamInputError(f"max_scans: must be an integer >= 1 (or None), got {shown(max_scans)}")
    try:
        iter(records)
    except TypeError:
        raise SlamInputError(f"records: must be an iterable of lms200.Record, got {type(records).__name__}") from None
    given = records
    watched = reader_watches(records)  # a bare log reader's pass looks at its first scans' units itself
    # an int past sys.maxsize is no count islice takes (a raw ValueError); no source holds that many
    capped: Iterable[Any] = (Capped(records, "records") if max_scans is None
                             else itertools.islice(records, min(int(max_scans), sys.maxsize)))
    records = in_scale(checked_records(iter(capped), SlamInputError))
    if not watched:
        # the first UNITS_SCANS scans looked at as they come for ranges in millimetres (lms200.units), none read
        # ahead: a hand-built Scan in millimetres ran with every beam a no return, and nothing said why (a log
        # reader's pass says it itself)
        records = units_watched(records, "records")
    range_maxes: set[float] = set()
    _check_one_stamp_given(given, max_scans)

    def seen(records: Iterable[Record]) -> Iterator[Record]:
        """The records, the first scan checked against the config before any matching or extraction
        (:func:`check_first_scan`), each scan's range_max noted; after the last, SlamInputError where
        there were two or more and all of one stamp (an iterator's, known only at its end)."""
        n, first, timed = 0, 0.0, False
        for i, rec in enumerate(records):
            if i == 0:
                check_first_scan(rec.scan, config, "records[0]")
                first = float(rec.scan.stamp)
            timed = timed or float(rec.scan.stamp) != first
            range_maxes.add(float(rec.scan.range_max))
            n = i + 1
            yield rec
        if n > 1 and not timed:
            raise SlamInputError(f"records: {same_stamp_problem(n, first)}")

    records = seen(records)
    if config.preset == "default":
        from .scanslam import run_scan_slam

        result = run_scan_slam(((rec.scan.stamp, rec.scan, rec.odom, rec.truth) for rec in records), config)
        _warn_unread(config, range_maxes)
        if isinstance(capped, Capped):
            capped.warn(stacklevel=2)
        return result

    def steps():
        batch: list[Record] = []
        for rec in records:
            batch.append(rec)
            if len(batch) == EXTRACT_BATCH:
                yield from _observed(batch, config)
                batch = []
        yield from _observed(batch, config)

    result = _run_steps(steps(), config)
    _warn_unread(config, range_maxes)
    if isinstance(capped, Capped):
        capped.warn(stacklevel=2)
    return result


def same_stamp_problem(n: int, stamp: float) -> str:
    """Why ``n`` (> 1) scans all stamped ``stamp`` (s) are no SLAM input, one line: every step would
    predict no motion and search no turn (``lmsbench slam`` refused such a log, ``run_slam`` ran it)."""
    return (f"all {n} scans read have the same stamp ({fixed(stamp)} s); SLAM's motion model needs the "
            "time between scans (a log written without a clock?)")


def _check_one_stamp_given(records: object, max_scans: int | None) -> None:
    """SlamInputError before any work where ``records`` is a list or tuple of two or more Records
    (of the first ``max_scans``) all of one stamp; other sources are checked at their end (``seen``)."""
    if not isinstance(records, (list, tuple)):
        return
    taken = records if max_scans is None else records[: int(max_scans)]
    if len(taken) < 2 or not all(isinstance(r, Record) for r in taken):
        return  # an item that is no Record is checked_records' error, naming its index
    try:
        first = float(taken[0].scan.stamp)
        one_stamp = all(float(r.scan.stamp) == first for r in taken)
    except (TypeError, ValueError, AttributeError):
        return  # a stamp that is no number is checked_records' error
    if one_stamp:
        raise SlamInputError(f"records: {same_stamp_problem(len(taken), first)}")


def check_first_scan(scan: Any, config: SlamConfig, where: str = "records[0]") -> None:
    """SlamInputError (or ``features.ConfigError``, as ``extract`` raises it) when the run's first
    scan shows that the config cannot work on these scans, each checked once, at the first scan, as
    the scans come (``lmsbench slam`` as it reads the log: it refused them after reading the whole
    log, or, for the extractor's step, after the whole default run):

    - the default preset's ``alignment.stride`` keeps fewer of its beams than the ICP needs
      (``MIN_MATCH_POINTS``; a scan with fewer beams is too short at any stride, and runs to its "not
      healthy" warning): the stride is bounded by the most beams a scan may have (16,384, where 60-150
      keeps as many points as 3 on an LMS200), so a 361-beam scan's limit is checked here;
    - ``observations.min_line_points`` is more than its beams (bounded alike, by 16,384): no line of
      the scan can have that many points, so none was observed (the paper preset ran on odometry
      alone, the default preset's map held no line), silently; as for the stride, a scan of fewer
      than ``MIN_MATCH_POINTS`` beams is left to its "not healthy" warning (the default 8 refused a
      7-beam log the user had set nothing for);
    - a baseline extractor's ``breakpoint_lambda`` (or its corners') is not below its beam step
      (``features.registry.check_step``, compare's message, naming ``where``)."""
    beams = int(np.size(scan.ranges))
    if config.preset == "default":
        stride = config.alignment.stride
        need = MIN_MATCH_POINTS  # a scan with fewer beams is short whatever the stride (it runs, "not healthy")
        if beams >= need and -(-beams // stride) < need:  # ceil: beams 0, stride, 2 stride, ...
            largest = (beams - 1) // (need - 1)
            raise SlamInputError(f"alignment.stride: {stride:,} keeps {-(-beams // stride)} of the first scan's "
                                 f"{beams:,} beams, fewer than the {need} points the scan matcher needs; "
                                 f"at most {largest:,} for these scans")
    least = config.observations.min_line_points
    if least > beams and beams >= MIN_MATCH_POINTS:  # a scan shorter than that runs to its "not healthy" warning
        found = "the map would hold no line" if config.preset == "default" else "the filter would observe no line"
        raise SlamInputError(f"observations.min_line_points: {least:,} is more than the first scan's {beams:,} beams: "
                             f"no line of these scans has that many points, so {found}; at most {beams:,} for these "
                             "scans")
    from features.registry import check_step, make_config

    check_step(make_config(config.extractor, **config.extractor_params), float(scan.angle_increment),
               config.extractor, where)


def _warn_unread(config: SlamConfig, range_maxes: set[float]) -> None:
    """An ``UnreadNoiseWarning`` (``features.registry``) per field of ``config.extractor_params`` that
    none of the run's scans read (``sigma_r`` on cm-mode scans): once per run, as ``features.extract``
    says it per call (``extract_all`` passes the config, not its fields, so it did not, and the run
    was silent)."""
    if not config.extractor_params:
        return
    from features.registry import make_config, warn_unread_fields

    warn_unread_fields({config.extractor: config.extractor_params},
                       {config.extractor: make_config(config.extractor, **config.extractor_params)},
                       sorted(range_maxes), "the scans", stacklevel=4)


#: s: the longest step between consecutive scans' stamps SLAM takes (31,700 years; a 1e9 s gap runs):
#: the motion model's variance grows with its square, and a log stamped 1e200 s apart was
#: 'internal error: OverflowError: (34, 'Numerical result out of range')' after the run had started
MAX_STAMP_STEP_S = 1e12
#: m: the largest odometry, true or corrected pose coordinate SLAM takes (an odometry of 1e300 m
#: overflowed the odometry model's variance the same way); the TUM and relations readers' bound too
MAX_POSE_M = MAX_COORD_M


def in_scale(records: Iterable[Record], label: str = "records[{k}]",
             numbers: Sequence[int] | None = None) -> Iterator[Record]:
    """The records, raising SlamInputError (naming the record by ``label``, formatted with its index
    ``k``, or with ``numbers[k]``: the log's own scan number of each record) at the first whose stamp lies
    more than MAX_STAMP_STEP_S after the one before or whose odometry, true or corrected pose has a
    coordinate beyond +-MAX_POSE_M or a heading beyond +-MAX_HEADING_RAD (lazily, as they are used)."""
    before = None
    for i, rec in enumerate(records):
        k = numbers[i] if numbers else i
        stamp = rec.scan.stamp
        if before is not None and stamp - before > MAX_STAMP_STEP_S:
            raise SlamInputError(f"{label.format(k=k)}: stamp {stamp:.6g} s lies {stamp - before:.3g} s after the "
                                 f"scan before's, more than {MAX_STAMP_STEP_S:g} s (stamps of another unit, or damaged?): "
                                 "SLAM's motion model cannot step that far")
        before = stamp
        for name in ("odom", "truth", "corrected"):
            pose = getattr(rec, name)  # a Record's poses are finite (1e300 rad: each step's turn was noise)
            problem = None if pose is None else pose_problem(pose[0], pose[1], pose[2], f"its {name} pose")
            if problem is not None:
                raise SlamInputError(f"{label.format(k=k)}: {problem}: SLAM's models cannot take it")
        yield rec


#: scans extracted in one ``features.extract_many`` call (bounds the memory of a long log)
EXTRACT_BATCH = 256


def extract_all(scans: list, config: SlamConfig) -> list:
    """``features.extract_many`` over scans of one geometry (one compiled call), or
    ``features.extract`` scan by scan where the geometry changes within the batch."""
    from features import extract, extract_many
    from features.errors import ScanGeometryError
    from features.registry import make_config

    if not scans:
        return []
    # the config, not its fields as keywords: a noise field no scan reads is said once by the
    # drivers (``lmsbench slam``), not by extract_many in every batch; the same config either way
    cfg = make_config(config.extractor, **config.extractor_params)
    try:
        return extract_many(scans, method=config.extractor, config=cfg)
    except ScanGeometryError:  # scans of different geometries: one call each
        return [extract(s, method=config.extractor, config=cfg) for s in scans]


def _observed(batch: list, config: SlamConfig):
    for rec, fs in zip(batch, extract_all([r.scan for r in batch], config)):
        yield rec.scan.stamp, from_features(fs, config, rec.scan), rec.odom, rec.truth
