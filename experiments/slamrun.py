"""Driver of a SLAM run: load an input (simulator folder, CARMEN log, bag), run ``slam.run_slam``
with a progress bar and timing, score it against whatever reference the input has, write results.

Outputs in ``out``: trajectory.tum (one pose per input scan, the input's own stamps; with the
default preset the optimised pose graph's), keyframes.tum (default preset), map.json,
metrics.json (scores, timing, consistency, the loop closures), config.yaml, slam.png.
"""

from __future__ import annotations

import dataclasses
import functools
import io
import json
import time
import weakref
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Collection, Iterable, Iterator, Sequence, overload

import numpy as np
import yaml

from lms200 import LmsbenchError, read_log, read_tum, write_tum
from lms200.finite import fixed, shown
from lms200.records import Record
from lms200.yamlio import dump as dump_yaml
from experiments.options import SLAM_OUTPUTS, SLAM_OWNER, OutTree, check_simulate_finished, not_a_log_folder, simulate_log
from experiments.progress import say_on_terminal
from experiments.provenance import write_record
from lms200.finite import printable
from experiments.user_methods import scans_of
from slam import SlamConfig, SlamResult, run_slam
from slam.run import Column
from slam.metrics import Alignment2D, ate, interpolate_poses, map_error, read_relations, relations_error, rpe

#: Published mean absolute translational relation errors on MIT CSAIL (Kummerle et al. 2009) and
#: the raw odometry measured on the log (see ../shared/data/README.md), metres.
MIT_ANCHORS = {"scan matching": 0.106, "GMapping": 0.049, "graph SLAM": 0.004, "raw odometry": 1.70}


#: scans whose identity a pass of :class:`LogScans` keeps, weakly, while they live (:meth:`LogScans.index_of`): a
#: user extractor's failure names its scan by it; the paper preset extracts ``slam.run.EXTRACT_BATCH`` at once
RECENT_SCANS = 1024
_NO_POSE = (np.nan, np.nan, np.nan)


class _Poses:
    """One pose kind (odometry, true, corrected) of each scan kept, appended as the log is read: numpy
    blocks (:class:`slam.run.Column`) of (x, y, theta) rows, nan for none, made at the first pose seen."""

    def __init__(self) -> None:
        self.column: Column | None = None
        self.size = 0

    def append(self, pose: tuple[float, float, float] | None) -> None:
        if pose is not None and self.column is None:
            self.column = Column(np.float64, (3,))
            for _ in range(self.size):
                self.column.append(_NO_POSE)
        if self.column is not None:
            self.column.append(_NO_POSE if pose is None else pose)
        self.size += 1

    def taken(self) -> np.ndarray | None:
        """(n, 3) x m, y m, theta rad, nan rows where a scan has none; None where no scan has one."""
        return None if self.column is None else self.column.taken()


@dataclass
class ScanRows:
    """What :class:`LogScans` holds of each scan kept, appended one scan at a time as :func:`load_input`
    reads the log: its number in the log, stamp, a CRC-32 of its record (:func:`_crc`), its beam geometry's row in
    ``geometries`` (beams, angle_increment rad, range_max m) and its poses."""

    numbers: Column = field(default_factory=lambda: Column(np.int64))
    stamps: Column = field(default_factory=lambda: Column(np.float64))
    crcs: Column = field(default_factory=lambda: Column(np.uint32))
    shapes: Column = field(default_factory=lambda: Column(np.int32))
    geometries: dict[tuple[int, float, float], int] = field(default_factory=dict)
    odom: _Poses = field(default_factory=_Poses)
    truth: _Poses = field(default_factory=_Poses)
    corrected: _Poses = field(default_factory=_Poses)

    def append(self, number: int, rec: Record) -> None:
        scan = rec.scan
        self.numbers.append(number)
        self.stamps.append(scan.stamp)
        self.crcs.append(_crc(rec))
        self.shapes.append(self.geometries.setdefault((len(scan), float(scan.angle_increment), float(scan.range_max)),
                                                      len(self.geometries)))
        self.odom.append(rec.odom)
        self.truth.append(rec.truth)
        self.corrected.append(rec.corrected)

    def __len__(self) -> int:
        return self.numbers.size


def _crc(rec: Record) -> int:
    """A CRC-32 of all a record gives a run (float64 bytes): its scan's ranges, then its stamp, beam geometry
    (angle_min, angle_increment, range_min, range_max, beams) and poses (odometry, true, corrected; nan for
    none). A pass that reads the log again checks it read the same record: a log whose odometry alone changed
    between passes ran on, the raw odometry scored from the first read and the odometry baseline on the new."""
    scan = rec.scan
    crc = zlib.crc32(np.ascontiguousarray(scan.ranges, dtype=np.float64).tobytes())
    rest = [scan.stamp, scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max, len(scan)]
    for pose in (rec.odom, rec.truth, rec.corrected):
        rest.extend(_NO_POSE if pose is None else pose)
    return zlib.crc32(np.array(rest, dtype=np.float64).tobytes(), crc)


class LogScans:
    """The scans :func:`load_input` kept of a log, read again from it at each pass (``for rec in
    scans``): a run holds one compact row a scan (its number in the log, stamp, beam geometry, poses
    and a CRC-32 of its record: 48 to 96 B), not the scans (3.5 KB a scan of MIT CSAIL, 361 beams), so
    that ``lmsbench slam`` keeps about what its SLAM runs keep (docs/slam.md, ``lmsbench slam``). A pass
    reads the whole log up to its last scan kept with a reader of its own (``open_log()``; MIT CSAIL's 1,988
    scans: 0.7 s at load 5 on 2 cores), the reader's warnings unsaid (the first read said them), and raises
    LmsbenchError where a record differs from the first read's (its stamp, ranges, beam geometry or poses)
    or the log ends before it: the file changed.

    Sized and re-iterable, as a list of the records was; ``scans[k]`` is a pass up to scan ``k``, ``scans[i:j]``
    (a step too) those scans as a LogScans; ``list(scans)`` holds them all in memory."""

    def __init__(self, open_log: Callable[[], Iterable[Record]], where: str, rows: ScanRows | None = None) -> None:
        rows = rows if rows is not None else ScanRows()
        self._hold(open_log, where, rows.numbers.taken(), rows.stamps.taken(), rows.crcs.taken(), rows.shapes.taken(),
                   list(rows.geometries), rows.odom.taken(), rows.truth.taken(), rows.corrected.taken())

    def _hold(self, open_log: Callable[[], Iterable[Record]], where: str, numbers: np.ndarray, stamps: np.ndarray,
              crcs: np.ndarray, shapes: np.ndarray, geometries: list[tuple[int, float, float]],
              odom: np.ndarray | None, truth: np.ndarray | None, corrected: np.ndarray | None) -> None:
        """Set the rows held (``__init__`` from a ScanRows, :meth:`taken` from another LogScans' arrays)."""
        self.open_log, self.where = open_log, where  # a new reader for each pass: two passes at once share nothing
        self.numbers: np.ndarray = numbers  # the log's own scan number of each (from 0)
        self.stamps: np.ndarray = stamps  # s
        self.crcs: np.ndarray = crcs
        self.shapes: np.ndarray = shapes  # rows of ``geometries``
        self.geometries: list[tuple[int, float, float]] = geometries  # (beams, angle_increment, range_max)
        self.odom, self.truth, self.corrected = odom, truth, corrected  # (n, 3) or None
        # id(scan) -> (a weak reference to it, its index) of the scans the last pass gave that live, the last
        # RECENT_SCANS at most: no scan is kept alive, and a new object at a freed scan's address is none of them
        self._recent: dict[int, tuple[weakref.ref, int]] = {}
        self.read_seconds = self.read_cpu_seconds = 0.0  # wall-clock and CPU time the passes spent reading the log

    def __len__(self) -> int:
        return int(self.numbers.size)

    def taken(self, keep: Sequence[int] | np.ndarray) -> "LogScans":
        """These scans at the indices ``keep`` (rising), read from the same log."""
        keep = np.asarray(keep, dtype=np.int64)
        if keep.size > 1 and not (np.diff(keep) > 0).all():  # a pass reads the log once, in order
            raise ValueError("LogScans.taken: the indices must rise (a pass reads the log in its order)")
        out = LogScans.__new__(LogScans)  # built from these arrays (an empty ScanRows was made, then written over)
        out._hold(self.open_log, self.where, self.numbers[keep], self.stamps[keep], self.crcs[keep], self.shapes[keep],
                  self.geometries, *(None if a is None else a[keep] for a in (self.odom, self.truth, self.corrected)))
        return out

    def __iter__(self) -> Iterator[Record]:
        return self._pass(len(self))

    @overload
    def __getitem__(self, k: int) -> Record: ...

    @overload
    def __getitem__(self, k: slice) -> "LogScans": ...

    def __getitem__(self, k: int | slice) -> "Record | LogScans":
        """Scan ``k`` (a pass up to it), or for a slice those scans as a LogScans (read again at each pass)."""
        if isinstance(k, slice):
            if k.step is not None and k.step < 0:
                raise ValueError("LogScans slices run forward (a pass reads the log in its order): "
                                 "list(records)[i:j:step] holds the records and takes any slice")
            return self.taken(np.arange(len(self))[k])
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
            raise TypeError(f"LogScans indices must be integers or slices, got {type(k).__name__}")
        k = int(k) + len(self) if k < 0 else int(k)
        if not 0 <= k < len(self):
            raise IndexError(f"scan index {k} out of range ({len(self)} scans)")
        for rec in self._pass(k + 1):
            last = rec
        return last

    def _pass(self, n: int) -> Iterator[Record]:
        """The first ``n`` scans kept, read again from the log; the time spent reading and checking them is
        added to ``read_seconds`` and ``read_cpu_seconds``."""
        if n <= 0:
            return
        import warnings

        recent: dict[int, tuple[weakref.ref, int]] = {}
        self._recent = recent
        wanted = self.numbers[:n].tolist()
        j = read = 0
        records = iter(self.open_log())
        try:
            while True:
                wall, cpu = time.perf_counter(), time.process_time()
                say = warnings.showwarning  # the reader's warnings unsaid: its first pass said them (_unsaid)
                warnings.showwarning = _unsaid
                try:
                    rec = next(records, None)
                finally:
                    warnings.showwarning = say
                if rec is not None and read == wanted[j] and (rec.scan.stamp != self.stamps[j]
                                                             or _crc(rec) != self.crcs[j]):
                    raise LmsbenchError(
                        f"{self.where}: scan {read} is not the one read before (its stamp {fixed(rec.scan.stamp)} s, "
                        f"first read {fixed(self.stamps[j])} s, or its ranges, beam geometry or poses differ): the "
                        "file changed while the run read it (a SLAM run reads its log again for each pass over the "
                        "scans); run again once no program writes it")
                self.read_seconds += time.perf_counter() - wall
                self.read_cpu_seconds += time.process_time() - cpu
                if rec is None:
                    break
                k, read = read, read + 1
                if k != wanted[j]:
                    continue
                key = id(rec.scan)
                recent.pop(key, None)
                recent[key] = (weakref.ref(rec.scan, functools.partial(_forget, recent, key)), j)
                if len(recent) > RECENT_SCANS:
                    del recent[next(iter(recent))]
                yield rec
                j += 1
                if j == n:
                    return
        finally:
            close = getattr(records, "close", None)
            if close is not None:
                close()
        raise LmsbenchError(f"{self.where}: ended after {read} records on reading it again, before its "
                            f"scan {wanted[j]} read before: the file changed while the run read it (a SLAM run reads its "
                            "log again for each pass over the scans); run again once no program writes it")

    def index_of(self, scan: Any) -> int | None:  # noqa: ANN401 - an lms200.Scan
        """The index of ``scan`` among these: by identity among the last RECENT_SCANS scans of the last
        pass still alive, else the first of its stamp (a driver's copy, e.g. a de-skewed one); None for neither."""
        hit = self._recent.get(id(scan))
        if hit is not None and hit[0]() is scan:
            return hit[1]
        stamp = getattr(scan, "stamp", None)
        if not isinstance(stamp, float):
            return None
        hits = np.flatnonzero(self.stamps == stamp)
        return int(hits[0]) if hits.size else None

    def range_maxes(self) -> set[float]:
        """The scans' range_max values (m)."""
        return {self.geometries[g][2] for g in np.unique(self.shapes).tolist()}

    def shapes_in_order(self) -> list[tuple[int, float]]:
        """The scans' (beams, angle_increment rad), each once, in the order met."""
        first = np.unique(self.shapes, return_index=True)[1]
        return list(dict.fromkeys(self.geometries[int(self.shapes[i])][:2] for i in np.sort(first)))

    def missing_odometry(self) -> int:
        """How many of the scans have no odometry."""
        return len(self) if self.odom is None else int(np.count_nonzero(np.isnan(self.odom[:, 0])))

    def light(self) -> Iterator[Any]:
        """Each scan as what :func:`slam.run.in_scale` reads of a record (``scan.stamp``, ``odom``, ``truth``,
        ``corrected``), from the rows held: the log is not read."""
        for i, stamp in enumerate(self.stamps.tolist()):
            yield _Light(_Stamped(stamp), *(None if a is None or np.isnan(a[i, 0]) else tuple(a[i].tolist())
                                            for a in (self.odom, self.truth, self.corrected)))


def _forget(recent: dict[int, tuple[weakref.ref, int]], key: int, ref: weakref.ref) -> None:
    """Drop ``recent[key]`` if it is still the entry of ``ref``, whose scan was freed (:meth:`LogScans.index_of`)."""
    if recent.get(key, (None,))[0] is ref:
        del recent[key]


@dataclass(frozen=True)
class _Stamped:
    stamp: float


@dataclass(frozen=True)
class _Light:
    scan: _Stamped
    odom: tuple[float, ...] | None
    truth: tuple[float, ...] | None
    corrected: tuple[float, ...] | None


def _unsaid(*args: Any, **kwargs: Any) -> None:  # noqa: ANN401 - showwarning's arguments
    """``warnings.showwarning`` while a pass of :class:`LogScans` reads a record: the reader's warnings are
    not said again (a log's unknown PARAM line, its ranges in millimetres). The function is swapped for each
    record, not the filters: a change of the filters makes Python say again a run's own warnings that it
    says once."""


@dataclass
class SlamInput:
    """What a SLAM run reads: the scans kept of the input (read again from it at each pass:
    :class:`LogScans`) and the references found beside them."""

    name: str
    records: LogScans
    truth: np.ndarray | None = None  # (n, 4) t, x, y, theta of the reference poses (``reference``)
    walls: np.ndarray | None = None  # (k, 4) true wall segments, world frame
    relations: np.ndarray | None = None  # (m, 5) t1, t2, x, y, yaw
    sources: dict[str, str] = field(default_factory=dict)
    reference: str = "ground truth"  # what ``truth`` holds: "ground truth", or "corrected poses" of a log
    time_increment: float | None = None  # s between beams as a bag's LaserScans give it (BagReadStats)
    notes: list[str] = field(default_factory=list)  # one line each on what the input lacks, for the command to print

    @property
    def numbers(self) -> list[int]:
        """Each scan's own number in the log (from 0), a new list (``records.numbers`` is the array)."""
        return self.records.numbers.tolist()

    @property
    def stamps(self) -> np.ndarray:
        """(n,) each scan's stamp, s."""
        return self.records.stamps

    def number(self, k: int) -> int:
        """The log's own scan number of record ``k`` (messages name a scan by it, docs/commands.md), not
        its index among the scans kept (``--every`` / ``--rate-hz`` / ``--max-scans``)."""
        return int(self.records.numbers[k])

    @property
    def odometry(self) -> np.ndarray | None:
        """(n, 4) t, x, y, theta of the records' raw odometry, or None where any is missing."""
        odom = self.records.odom
        if not len(self.records) or odom is None or np.isnan(odom[:, 0]).any():
            return None
        return np.column_stack((self.records.stamps, odom))


def _relations_beside(path: Path) -> Path | None:
    stem = path.name
    for suffix in (".gz", ".clf", ".log", ".carmen"):
        if stem.endswith(suffix):
            stem = stem[: -len(suffix)]
    candidate = path.with_name(stem + ".relations")
    return candidate if candidate.is_file() else None


def deskew_for_sensor(config: SlamConfig, interlaced: bool) -> SlamConfig:
    """``config`` with ``alignment.deskew`` off when the scans were taken at one instant (a
    simulator sensor with ``interlaced=False``, e.g. ``--ideal``): de-skewing by the LMS200's beam
    times would add the motion it is meant to remove (60 s ideal office run: ATE 7.4 mm with it,
    3.9 mm without)."""
    if interlaced or not config.alignment.deskew:
        return config
    return dataclasses.replace(config, alignment=dataclasses.replace(config.alignment, deskew=False))


def simulated_interlaced(path: str | Path) -> bool | None:
    """The ``sensor.interlaced`` of a simulator output folder's config.yaml (None: not a simulator
    folder, or the file does not say). LmsbenchError naming the file for an ``interlaced`` that is
    no true / false (``"no"``, ``0``): it was read as "does not say", so a run simulated without
    interlacing was de-skewed as an interlaced LMS200's, silently (``compare`` refuses the file)."""
    from experiments.options import load_simulate_config, simulate_config_size_problem

    cfg = Path(path) / "config.yaml"
    if simulate_log(path) is None or not cfg.exists():
        return None
    # as compare refuses it: a pipe in its place, or a file beyond a config's size (unread: 3 GB took as much
    # memory, 35 MB minutes), was passed over, and a run simulated without interlacing was de-skewed, silently
    too_big = simulate_config_size_problem(cfg)
    if too_big:
        raise LmsbenchError(f"{cfg}: {too_big}")
    # a file that is no YAML mapping (not UTF-8, not YAML, a list, empty: a damaged or cut one) was passed over the
    # same way, the run de-skewed as the LMS200's whatever it had been simulated with (fuzzing; compare refuses it)
    try:
        raw = load_simulate_config(cfg)  # as compare reads it (YAML 1.1's words too)
    except (UnicodeDecodeError, yaml.YAMLError) as exc:
        raise LmsbenchError(f"{cfg}: not a simulate config ({' '.join(str(exc).split())}); its sensor.interlaced decides the scans' "
                            f"de-skew: restore it, or simulate the folder again") from None
    except OSError as exc:
        raise LmsbenchError(f"{cfg}: cannot be read ({exc.strerror or exc})") from None
    if not isinstance(raw, dict):
        raise LmsbenchError(f"{cfg}: not a simulate config (expected a mapping of world, seed, duration, sensor, ..., "
                            f"got {'an empty file' if raw is None else type(raw).__name__}); its sensor.interlaced decides "
                            f"the scans' de-skew: restore it, or simulate the folder again")
    sensor = raw.get("sensor")
    if not isinstance(sensor, dict) or "interlaced" not in sensor:
        return None
    value = sensor["interlaced"]
    if not isinstance(value, bool):
        raise LmsbenchError(f"{cfg}: sensor.interlaced: must be true or false (whether the scans were simulated with "
                            f"the LMS200's interlaced sweeps, which decides their de-skew), got {shown(value)}")
    return value


def _check_cut_boxes(path: Path, content: dict) -> None:
    """Refuse a world.json whose walls list is empty although some box spans the scan plane: simulate
    writes the faces of those boxes (sim.world.spans_plane, the rule World uses) as the walls, so an
    empty list beside them would score the map against no wall. Boxes all off the plane give no walls:
    simulate wrote that file itself (they were scanned as nothing)."""
    from sim.world import SCAN_HEIGHT_M, json_rows, spans_plane

    try:  # json_rows: a ragged box was numpy's "inhomogeneous shape", a 400-digit number an OverflowError
        boxes = json_rows(content["boxes"], "boxes", "box", 7, "cx, cy, yaw, hx, hy, z0, z1")
        h = float(content.get("scan_height", SCAN_HEIGHT_M))
    except (TypeError, ValueError, OverflowError) as exc:
        raise LmsbenchError(f"{path}: not a world.json ({exc})") from None
    cut = int(spans_plane(boxes[:, 5], boxes[:, 6], h).sum())
    if cut:
        raise LmsbenchError(f"{path}: not a world.json: its walls list is empty beside {cut} of its {len(boxes)} "
                            f"boxes that span the scan plane (at {h:g} m), so the map would be scored against no "
                            "wall (simulate writes those boxes' faces there)")


#: --every and --rate-hz given together: each chooses the scans kept, and load_input kept them by the rate alone
#: (`slam RUN --every 2 --rate-hz 5` ran 5 scans/s, exit 0)
EVERY_AND_RATE = ("--every {every} and --rate-hz {rate_hz:g} both choose the scans kept (every N-th scan, or about "
                  "that many a second by the stamps); give one of them")


def load_input(path: str | Path, relations: str | Path | None = None, every: int = 1,
               max_scans: int | None = None, rate_hz: float | None = None,
               read_options: dict[str, Any] | None = None, config: SlamConfig | None = None) -> SlamInput:
    """Read a simulator output folder (scans.clf, groundtruth.tum, world.json), a CARMEN log or a
    bag; keep every ``every``-th scan (or, with ``rate_hz``, the first scan at least 1/rate_hz s
    after the last one kept), at most ``max_scans``. Relations come from ``relations`` or a
    ``NAME.relations`` file beside a log. ``read_options``: keywords of ``lms200.read_log``
    (topic, skip_bad_lines, geometry). ``config``: the SLAM config the scans are for, checked
    against the first scan kept as it is read (``slam.run.check_first_scan``: a stride, a
    min_line_points or an extractor's breakpoint_lambda that cannot work on these scans), not
    after the whole log.

    Raises:
        FileNotFoundError: the input does not exist.
        LmsbenchError: a folder without scans.clf, a simulate folder whose run did not finish
            (options.check_simulate_finished), an input without scans, or none with a valid beam, or
            more than one scan read, or kept, and all of one stamp (no time between scans for the motion model), or
            one scan to run on (an input of one scan, ``max_scans`` below 2, ``rate_hz`` / ``every`` that
            keep one scan of several), or ``every`` other than 1 beside ``rate_hz`` (give one).
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such input: {p}")
    if every < 1:
        raise LmsbenchError(f"--every must be >= 1, got {every}")
    if every != 1 and rate_hz is not None:  # both choose the scans kept: --every was ignored, config.yaml saying it
        raise LmsbenchError(EVERY_AND_RATE.format(every=every, rate_hz=rate_hz))
    if max_scans is not None and max_scans < 2:
        raise LmsbenchError(f"--max-scans must be >= 2 (SLAM needs two or more scans), got {max_scans}")
    sources: dict[str, str] = {}
    truth = walls = rel = None
    notes: list[str] = []
    check_simulate_finished(p)
    sim_log = simulate_log(p)
    if sim_log is not None:
        log = sim_log
        # a folder (or a pipe) of these names is an error (read_tum, regular_file), not no truth / no
        # world: a groundtruth.tum that was a folder ran without the truth's scores, exit 0
        if (p / "groundtruth.tum").exists():
            stamps, poses = read_tum(p / "groundtruth.tum")
            truth = np.column_stack((stamps, poses))
            sources["truth"] = str(p / "groundtruth.tum")
        if (p / "world.json").exists():
            try:
                from sim.world import json_rows, read_world_json, world_json_content, world_json_text

                data = read_world_json(p / "world.json")  # bounded, a regular file
                try:  # a key given twice or misspelt: as World.from_json refuses it (simulate, compare)
                    content = world_json_content(world_json_text(data))
                except (TypeError, ValueError) as exc:
                    raise LmsbenchError(f"{p / 'world.json'}: not a world.json ({exc})") from None
                if isinstance(content, dict) and not any(content.get(k) for k in ("walls", "circles", "boxes")):
                    raise LmsbenchError(f"{p / 'world.json'}: not a world.json: it holds no walls, circles or boxes, "
                                        "nothing to scan or score against")  # as World.from_json (compare): the
                # (the map was scored against nothing, exit 0); a wall of 3 numbers: numpy's "inhomogeneous shape"
                try:
                    walls = json_rows(content["walls"], "walls", "wall", 4, "x1, y1, x2, y2 (m)")
                except ValueError as exc:  # as World.from_json words it (simulate, compare)
                    raise LmsbenchError(f"{p / 'world.json'}: not a world.json ({exc})") from None
                if not walls.size and content.get("boxes"):  # the boxes simulated the scans, the walls score the map:
                    _check_cut_boxes(p / "world.json", content)  # with none, 0 matched, exit 0
                if walls.size:
                    sources["walls"] = str(p / "world.json")
            except (KeyError, TypeError, ValueError) as exc:  # TypeError: a JSON list, null or a dict of walls
                raise LmsbenchError(f"{p / 'world.json'}: no wall list ({exc})") from None
            from sim.world import MAX_COORD_M

            if not np.isfinite(walls).all() or (walls.size and np.abs(walls).max() > MAX_COORD_M):
                # as World.from_json refuses them (simulate, compare); here a NaN wall was map_error's error
                # after the whole run, its outputs but metrics.json written, and 1e308 overflowed the figure
                raise LmsbenchError(f"{p / 'world.json'}: not a world.json (walls: must be finite numbers within "
                                    f"+-{MAX_COORD_M:g} m)")
            if walls.size and not np.all(np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1]) > 0):
                # map_error's "walls: every wall must have two distinct ends", after the whole run, naming no file
                k = int(np.argmin(np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])))
                raise LmsbenchError(f"{p / 'world.json'}: not a world.json (walls: wall {k}, {walls[k].tolist()}, has "
                                    "two equal ends: a wall of zero length has no direction to score the map against)")
            if not walls.size:  # boxes all off the scan plane: scored "matched 0, wall_coverage 0.0", exit 0
                notes.append(f"{p / 'world.json'}: the world has no wall in the scan plane to score the map against "
                             "(no map score)")
                walls = None
    elif p.is_dir() and not (p / "metadata.yaml").is_file():
        raise LmsbenchError(not_a_log_folder(p))
    else:
        log = p
    sources["scans"] = str(log)
    rel_path = Path(relations) if relations else (_relations_beside(p) if p.is_file() else None)
    if rel_path is not None:
        rel = read_relations(rel_path)
        sources["relations"] = str(rel_path)
    # > 0, no floor: a log may last a day (--rate-hz 0.0002 keeps 13 of a 24 h log's 25 hourly scans, docs/slam.md);
    # a rate that keeps one scan alone (1e-308 did, exit 0) is refused below, after the read, with the count it kept
    if rate_hz is not None and not rate_hz > 0:
        raise LmsbenchError(f"--rate-hz must be > 0 scans/s, got {rate_hz}")
    from features.registry import check_beams
    from slam.run import check_first_scan

    rows = ScanRows()  # one compact row a scan kept: the scans are read again at each pass (LogScans)
    reader = read_log(log, **(read_options or {}))
    first_stamp, last_stamp, n_read, timed, rows_first_stamp = None, None, 0, False, 0.0  # timed: some scan read has another stamp than the first
    kept_stamp = None  # the stamp of the last scan kept
    kept_timed = False  # some scan kept has another stamp than the first kept
    from lms200.units import UnitsTally

    tally, valid = UnitsTally(), False  # the scans kept: their units (all of them), a valid beam in some
    for k, rec in enumerate(reader):
        n_read += 1
        if first_stamp is None:
            first_stamp = rec.scan.stamp
        timed = timed or rec.scan.stamp != first_stamp
        last_stamp = rec.scan.stamp
        if rate_hz is not None:
            keep = kept_stamp is None or rec.scan.stamp >= kept_stamp + 1.0 / rate_hz - 1e-9
        else:
            keep = k % every == 0
        if keep:
            # the extractors' limit (extract refuses it at that scan, after the notes on the input), named
            # by the log's own scan number (counted from 0), not the kept scan's
            check_beams(rec.scan, f"{log}: scan {k}")
            if config is not None and not len(rows):
                check_first_scan(rec.scan, config, f"{log}: scan {k}")
            if len(rows):
                kept_timed = kept_timed or rec.scan.stamp != rows_first_stamp
            else:
                rows_first_stamp = rec.scan.stamp
            rows.append(k, rec)
            kept_stamp = rec.scan.stamp
            if not valid:
                valid = bool(rec.scan.valid.any())
                tally.add(rec.scan)
            if max_scans is not None and len(rows) >= max_scans:
                break
    if getattr(reader, "stats", None) is not None and (reader.stats.skipped or reader.stats.stopped):
        from experiments.logargs import report_skipped

        skips = io.StringIO()  # a note each line: the command says them once its checks pass (a refused
        report_skipped(reader, stream=skips)  # run is its error alone)
        notes.extend(skips.getvalue().splitlines())
    records = LogScans(lambda: read_log(log, **(read_options or {})), str(log), rows)
    del rows
    if not len(records):
        raise LmsbenchError(f"{log}: no laser scans found")
    if n_read > 1 and not timed:  # it ran: every step predicted no motion and searched no turn
        from slam.run import same_stamp_problem

        raise LmsbenchError(f"{log}: {same_stamp_problem(n_read, first_stamp)}")
    if len(records) == 1 and n_read > 1 and (rate_hz is not None or every > 1):  # it ran: a "SLAM" of one scan
        flag = f"--rate-hz {rate_hz:g}" if rate_hz is not None else f"--every {every}"
        raise LmsbenchError(f"{log}: {flag} keeps 1 of the {n_read} scans read (stamps {fixed(first_stamp)} to "
                            f"{fixed(last_stamp)} s); SLAM needs two or more")
    if len(records) > 1 and not kept_timed:  # the scans read had stamps, those kept one: it ran, then run_slam refused
        flags = " and ".join(([f"--every {every}"] if every > 1 else [])  # it as "all 5 scans read have the same
                             + ([f"--max-scans {max_scans}"] if max_scans is not None else []))  # stamp", of 10 read
        raise LmsbenchError(f"{log}: {flags or 'the selection'} keeps {len(records)} of the {n_read} scans read, all "
                            f"stamped {fixed(rows_first_stamp)} s; SLAM's motion model needs the time between scans")
    if len(records) == 1:  # it ran and reported a healthy run of no step (matched fraction 1 of 0 steps)
        raise LmsbenchError(f"{log}: holds one scan (stamp {fixed(first_stamp)} s); SLAM needs two or more")
    if not valid:
        # ranges in millimetres: the error says so (the reader's units warning is held by the command's checks:
        # it said that warning, then this error, two lines for a user error); the tally holds every scan kept
        mm = tally.evidence()
        if mm is not None:
            raise LmsbenchError(f"{log}: none of its {len(records)} scans has a valid beam, nothing to localise "
                                f"against: {mm}")
        raise LmsbenchError(f"{log}: none of its {len(records)} scans has a valid beam (every reading +inf, -inf, nan, 0 "
                            "or outside the scan's range limits): "
                            "nothing to localise against")
    # which scans ran, recorded beside the files (config.yaml and metrics.json's input: --every, --rate-hz and
    # --max-scans were in neither, so a run's record did not say which of the log's scans it ran on)
    chosen = (f"the first at least 1/{rate_hz:g} s after the last kept (--rate-hz)" if rate_hz is not None
              else "every scan" if every == 1 else f"one in {every} (--every)")
    sources["scans_kept"] = (f"{len(records)} of the {n_read} read: {chosen}"
                             + (f", at most {max_scans} (--max-scans)" if max_scans is not None else ""))
    if truth is not None:  # groundtruth.tum: its scores need it beside the scans (see _check_truth_span)
        _check_truth_span(truth, records.stamps, sources["truth"])
    if rel is not None:
        try:
            _check_relations_span(rel, records.stamps, sources["relations"],
                                  max_scans if len(records) == max_scans else None, reader.last_stamp)
        except LmsbenchError as exc:
            if relations:  # given: the user's mistake, said before the run
                raise
            # found beside the log, not given: a stale file must not stop the run (there is no option to
            # leave it out); it scores nothing, so the run goes on without it and says so
            notes.append(f"{exc} -- found beside the log, not given: the run goes on without it")
            rel = None
            del sources["relations"]
    if truth is None and records.truth is not None and not np.isnan(records.truth[:, 0]).any():
        truth = np.column_stack((records.stamps, records.truth))
        sources["truth"] = f"{log} (TRUEPOS)"
    reference = "ground truth"
    if truth is None and records.corrected is not None and not np.isnan(records.corrected[:, 0]).any():
        # a Radish corrected log: its odometry is the ODOM lines' (raw)
        truth = np.column_stack((records.stamps, records.corrected))
        sources["truth"] = f"{log} (corrected poses: the log's own SLAM solution, not ground truth)"
        reference = "corrected poses"
    time_increment = getattr(getattr(reader, "stats", None), "time_increment", None)  # bags only
    return SlamInput(p.name, records, truth, walls, rel, sources, reference,
                     time_increment if isinstance(time_increment, float) else None, notes)


def _stamps_of(records: np.ndarray | Iterable[Record]) -> np.ndarray:
    """The stamps (s) of ``records`` (records, or their stamps already)."""
    return records if isinstance(records, np.ndarray) else np.array([r.scan.stamp for r in records])


def _check_truth_span(truth: np.ndarray, records: np.ndarray | Iterable[Record], where: str) -> None:
    """LmsbenchError naming the truth file, before any work, when fewer than two of the scans kept
    lie within its time span (the ATE interpolates the truth at the scans' stamps and leaves the
    others out). A groundtruth.tum of another run, or shifted by 100 s, ran the whole SLAM, wrote
    its trajectory and map, then failed: "ate: fewer than 2 estimated poses fall inside the ground
    truth's time span", exit 2, no file named, no metrics.json (the wrong-input hunt)."""
    # (a groundtruth.tum of comments or of nothing, "internal error: IndexError" here once: read_tum refuses it)
    stamps = _stamps_of(records)
    t0, t1 = float(truth[0, 0]), float(truth[-1, 0])
    inside = int(np.count_nonzero((stamps >= t0) & (stamps <= t1)))
    if inside < 2:
        raise LmsbenchError(f"{where}: its stamps ({fixed(t0)} to {fixed(t1)} s) cover {inside} of the {len(stamps)} scans "
                            f"to run on ({fixed(stamps[0])} to {fixed(stamps[-1])} s); scoring against it needs two or more "
                            "(the ground truth of another run, or stamps of another clock?)")


def _check_relations_span(relations: np.ndarray, records: np.ndarray | Iterable[Record], where: str, cut: int | None,
                          log_end: Callable[..., float | None] | None = None) -> None:
    """LmsbenchError naming the relations file, before any work, when none of its relations lies within
    the time span of the scans to run on (both stamps: the relations error scores no other), as
    ``_check_truth_span`` does for ground truth: another log's relations (MIT CSAIL's given with the
    Intel log) ran the whole SLAM, warned "the relations error covers 0 of the file's 1172 relations"
    and wrote metrics.json without a relations score, exit 0. ``cut``: the --max-scans that stopped
    the read early; then the span is the whole log's, from its first scan read to its last stamp
    (``log_end``: the reader's ``last_stamp``, asked only here; before refusing, ``log_end(largest=True)``,
    as the last line's stamp is not the largest where the stamps go back at the log's end), so that
    relations past the cut but within the log are left to the run's note and warning, and relations
    outside the whole log are refused as without the cut (they passed whenever they lay after the cut: another log's relations
    ran the whole SLAM under --max-scans, exit 0). Where the log's last stamp cannot be told
    (``log_end`` None or giving None), relations after the last scan read pass as the log's own, perhaps.
    ``records``: the scans to run on, or their stamps (s)."""
    stamps = _stamps_of(records)
    lo, hi = float(stamps.min()), float(stamps.max())
    t1, t2 = relations[:, 0], relations[:, 1]

    def within(end: float) -> bool:
        return bool(np.any((np.minimum(t1, t2) >= lo - 1e-9) & (np.maximum(t1, t2) <= end + 1e-9)))

    if within(hi):
        return
    first, last = float(relations[:, :2].min()), float(relations[:, :2].max())
    end = log_end() if cut is not None and log_end is not None and last > hi else None
    if end is not None and not within(max(end, hi)):
        # the last line's stamp is no bound of the log's stamps where they go back at its end (a 61st line stamped
        # before the 60 above it, which --skip-bad-lines drops, refused the log's own relations as outside
        # "10.000000 to 10.400000 s"): refused only against the largest stamp, one pass over the log
        end = log_end(largest=True)
    if cut is not None and last > hi and (end is None or within(max(end, hi))):  # past the cut: the log's own (the run warns)
        return
    if cut is None:
        scans = f"the log's {len(stamps)} scans to run on {fixed(lo)} to {fixed(hi)} s"
    elif end is not None:
        scans = f"the whole log's scans {fixed(lo)} to {fixed(max(end, hi))} s ({len(stamps)} of them read, --max-scans)"
    else:
        scans = f"the {len(stamps)} scans read (at most {cut}, --max-scans) {fixed(lo)} to {fixed(hi)} s"
    raise LmsbenchError(f"{where}: none of its {len(relations)} relations lies within the scans' time span: the relations "
                        f"span {fixed(first)} to {fixed(last)} s, {scans}; the relations "
                        "error would score nothing (the relations of another log, or stamps of another clock?)")


def score(traj: np.ndarray, data: SlamInput, result: SlamResult | None = None) -> dict[str, Any]:
    """Every score the input's references allow, as plain numbers."""
    out: dict[str, Any] = {}
    if data.truth is not None:
        a = ate(traj, data.truth)
        out["ate"] = a.as_dict()
        out["rpe_1m"] = rpe(traj, data.truth, 1.0).as_dict()  # every pose paired (docs/slam.md)
        out["rpe_1m_evo"] = rpe(traj, data.truth, 1.0, pairs="evo").as_dict()  # evo_rpe's pairing
        if result is not None and data.walls is not None:
            out["map"] = map_error(result.map_lines[:, 2:6], data.walls, Alignment2D(a.rotation, a.translation)).as_dict()
    if data.relations is not None:
        out["relations"] = _relations_score(traj, data.relations)
    return out


def _relations_score(traj: np.ndarray, relations: np.ndarray) -> dict[str, Any]:
    """The relations error, or ``{"n": 0, "note": ...}`` where no relation lies inside the run
    (a run cut short by --max-scans ends before the first relation's second stamp)."""
    _, in1 = interpolate_poses(traj, relations[:, 0])
    _, in2 = interpolate_poses(traj, relations[:, 1])
    if not np.any(in1 & in2):
        return {"n": 0, "n_skipped": int(relations.shape[0]),
                "note": f"none of the {relations.shape[0]} relations falls inside the run's time span "
                        f"({fixed(traj[0, 0], 3)} to {fixed(traj[-1, 0], 3)} s)"}
    return relations_error(traj, relations).as_dict()


@dataclass
class SlamRun:
    """A finished run: the result, its scores, the baselines' scores, timing."""

    result: SlamResult
    metrics: dict[str, Any]
    seconds: float


def _quiet_bounds(records: Iterable[Record], config: SlamConfig) -> SlamResult:
    """``run_slam`` without its SlamBoundWarnings (:func:`say_bounds` says them naming the run), nor its
    RangeUnitsWarning: the records are a log reader's (:func:`load_input`), whose pass said it, naming the log."""
    import warnings

    from lms200.units import RangeUnitsWarning
    from slam.run import SlamBoundWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SlamBoundWarning)
        warnings.simplefilter("ignore", RangeUnitsWarning)
        return run_slam(records, config)


def say_bounds(label: str, result: SlamResult, config: SlamConfig) -> None:
    """One SlamBoundWarning for each bound of the filter (``observations.max_lines``,
    ``landmarks.max_landmarks``) the run ``label`` met, naming it with its counts: said as each run of
    the command ends (the run's own after its files are written), so that a stop during a later
    baseline loses none. The run and its paper-preset baselines each said the same line, naming
    neither: `slam --preset paper` with an extractor of more lines a scan than observations.max_lines."""
    import warnings

    from slam.run import SlamBoundWarning, bounds_met

    for bound in bounds_met(result.diagnostics, config):
        warnings.warn(f"{bound.counted()} of {label}: {bound.beyond()}", SlamBoundWarning, stacklevel=3)


def _source_name(config: SlamConfig) -> str:
    if config.preset == "paper":
        return "paper preset (odometry)" if config.motion.use_odometry else "paper preset"
    return "slam (odometry)" if config.motion.use_odometry else "slam"


def run(data: SlamInput, config: SlamConfig, progress: bool = True, odometry_baseline: bool = True,
        out: Path | None = None, paper_baseline: bool = True, replace_earlier: bool = False) -> SlamRun:
    """Run SLAM over ``data`` (timed: feature extraction + SLAM; wall clock ``seconds`` and CPU
    time ``cpu_seconds``), score it, and score the baselines: the raw odometry, with
    ``odometry_baseline`` the paper's filter driven by odometry, and with ``paper_baseline`` (for
    the default preset) the paper preset. With ``out``, config.yaml (first), trajectory.tum, map.json and
    keyframes.tum (default preset) are written there before any scoring and the baselines, so a
    scoring error or a Ctrl-C loses no result; no other file in ``out`` is touched (write_scores
    writes metrics.json and slam.png at the end). With ``replace_earlier`` (``lmsbench slam``, after
    :func:`foreign_outputs` found none) an earlier run's metrics.json and slam.png in ``out``, and its
    trajectory.tum, keyframes.tum and map.json, are removed before this run's config.yaml is
    written, so a run stopped while writing its files leaves none of them beside its own as if they
    were its trajectory, map or scores; only files
    :func:`earlier_run_files` tells an earlier lmsbench slam run wrote (a user's own metrics.json
    and slam.png in --out were deleted).
    """
    scans = data.records
    t0, c0 = _clocks(scans)  # the SLAM's own time: the passes' reading of the log is taken out (_since)
    with scans_of(data.name, data.records, data.records.numbers):  # a user's --extractor MODULE:FUNCTION that fails names its scan
        result = _quiet_bounds(_bar(data.records, "slam", progress), config)
    seconds, cpu = _since(scans, t0, c0)
    if out is not None:
        # an earlier run's outputs, all but the config.yaml written over whole next, so that no stop leaves one of
        # them beside this run's files; records (map.json, metrics.json) last (options.Owner.remove_earlier)
        earlier = SLAM_OWNER.remove_earlier(out, OutTree(OUTPUTS), keep=("config.yaml",)) if replace_earlier else []
        write_config(out, data, config)  # first: a stop after it leaves a folder told as slam's (SLAM_OWNER)
        write_result(out, result, earlier)
    say_bounds(f"this run ({_source_name(config)})", result, config)  # after its files: -W error loses none
    d = result.diagnostics
    scores = score(result.trajectory, data, result)
    # "seconds": each SLAM's wall-clock time (extraction + SLAM), so that a summary can say what took the time
    table = [{"source": _source_name(config), **_flat(scores), "cpu_scans_per_s": len(data.records) / max(cpu, 1e-9),
              "seconds": seconds}]
    # the baselines ran silent after the run's own bar had gone (MIT CSAIL: 78.6 s of a dead terminal after a
    # 6 s run): each is announced, with a bar of its own, on a terminal
    if paper_baseline and config.preset == "default":
        if progress:
            say_on_terminal(f"slam: baseline: the paper preset (EKF) over the same {len(data.records)} scans, for the "
                            "comparison table (--no-paper-baseline leaves it out) ...")
        t1, c1 = _clocks(scans)
        paper_config = dataclasses.replace(config, preset="paper")  # the same motion input as the run
        with scans_of(data.name, data.records, data.records.numbers):
            paper = _quiet_bounds(_bar(data.records, "paper preset", progress), paper_config)
        say_bounds("the paper preset baseline", paper, paper_config)
        table.append({"source": _source_name(paper_config), **_flat(score(paper.trajectory, data, paper)),
                      "cpu_scans_per_s": len(data.records) / max(_since(scans, t1, c1)[1], 1e-9),
                      "seconds": _since(scans, t1, c1)[0]})
    odo = data.odometry
    if odo is not None:
        raw = _flat(score(odo, data))
        if raw:  # without a reference (no truth, no relations) it has no score: it was an empty row
            table.append({"source": "raw odometry", **raw})
        if odometry_baseline and not config.motion.use_odometry:
            if progress:
                say_on_terminal(f"slam: baseline: the paper preset driven by the input's odometry over the same "
                                f"{len(data.records)} scans, for the comparison table (--no-odometry-baseline leaves "
                                "it out) ...")
            t1, c1 = _clocks(scans)
            odo_config = dataclasses.replace(config, preset="paper", motion=dataclasses.replace(config.motion, use_odometry=True))
            with scans_of(data.name, data.records, data.records.numbers):
                with_odo = _quiet_bounds(_bar(data.records, "paper preset (odometry)", progress), odo_config)
            say_bounds("the paper preset (odometry) baseline", with_odo, odo_config)
            table.append({"source": "paper preset (odometry)", **_flat(score(with_odo.trajectory, data, with_odo)),
                          "seconds": _since(scans, t1, c1)[0]})
    consistency = {
        "diverged": bool(d["diverged"]),
        "diverged_at": d["diverged_at"],
        "healthy": bool(d["healthy"]),
        "mean_nis_per_dof": d["mean_nis_per_dof"],
        "mean_nees": d["mean_nees"],
    }
    if "prealign_used" in d:
        consistency["prealign_fraction"] = float(np.mean(d["prealign_used"]))
    for key in ("matched_fraction", "searched_fraction", "ambiguous_fraction", "odometry_fraction",
                "odometry_doubt_fraction", "degenerate_fraction", "degenerate_drift", "degenerate_drift_at"):
        if key in d:
            consistency[key] = d[key]
    metrics = {
        "input": data.sources,
        **({"reference": data.reference} if data.truth is not None else {}),  # what ate / rpe are against
        "preset": config.preset,
        "n_scans": len(data.records),
        "seconds": seconds,
        "cpu_seconds": cpu,
        "scans_per_s": len(data.records) / seconds if seconds > 0 else float("nan"),
        "cpu_scans_per_s": len(data.records) / cpu if cpu > 0 else float("nan"),
        "consistency": consistency,
        "landmarks": {"lines": int(result.map_lines.shape[0]), "corners": int(result.map_corners.shape[0])},
        **scores,
        "table": table,
    }
    if "loops" in d:
        metrics["loop_closures"] = {"n": d["n_loops"], "n_keyframes": d["n_keyframes"], "closed": d["loops"]}
    if data.relations is not None and "mit" in data.name.lower():
        metrics["anchors_relations_trans_mean_m"] = MIT_ANCHORS
    return SlamRun(result, metrics, seconds)


def _clocks(scans: LogScans) -> tuple[float, float]:
    """The wall clock and the process's CPU time (s), less the time ``scans``' passes spent reading the log:
    a run's time is its extraction's and SLAM's (:func:`_since`), as when the scans were held in memory."""
    return time.perf_counter() - scans.read_seconds, time.process_time() - scans.read_cpu_seconds


def _since(scans: LogScans, wall: float, cpu: float) -> tuple[float, float]:
    """Wall-clock and CPU seconds since :func:`_clocks` gave ``wall`` and ``cpu``, the reading of the log left out."""
    now_wall, now_cpu = _clocks(scans)
    return now_wall - wall, now_cpu - cpu


def _bar(records: LogScans, desc: str, progress: bool) -> Iterable[Record]:
    """``records`` behind a progress bar named ``desc`` on a terminal (with ``progress``), gone
    when done (the summary says the times)."""
    if not progress:
        return records
    from tqdm import tqdm

    return tqdm(records, desc=desc, unit="scan", leave=False, disable=None)  # None: on a terminal only


def _flat(scores: dict[str, Any]) -> dict[str, float]:
    keep = {"ate": ("rmse", "mean", "max"), "rpe_1m": ("trans_rmse", "rot_rmse"), "map": ("distance_mean", "matched"),
            "relations": ("trans_mean", "trans_std", "rot_mean_deg", "rot_std_deg", "trans_median", "trans_mean_far")}
    return {f"{k}_{f}": scores[k][f] for k, fields in keep.items() if k in scores for f in fields if f in scores[k]}


def write_result(out: Path, res: SlamResult, earlier: Collection[str] = ()) -> None:
    """trajectory.tum and map.json in ``out`` (the run's own outputs, no scores); with the default
    preset also keyframes.tum, the optimised keyframe poses. Without them (the paper preset) an
    earlier default-preset run's keyframes.tum is removed when ``earlier`` (:func:`earlier_run_files`)
    names it."""
    out.mkdir(parents=True, exist_ok=True)
    write_tum(out / "trajectory.tum", res.trajectory[:, 0], res.trajectory[:, 1:])
    kf = res.diagnostics.get("keyframes")
    if kf is not None:
        write_tum(out / "keyframes.tum", kf[:, 0], kf[:, 1:])
    elif "keyframes.tum" in earlier:
        (out / "keyframes.tum").unlink(missing_ok=True)
    write_record(out / "map.json", json.dumps(res.map_dict(), indent=1) + "\n")  # a record (SLAM_OWNER): whole


#: What lmsbench slam writes in its --out folder.
OUTPUTS = SLAM_OUTPUTS


def earlier_run_files(out: Path) -> set[str]:
    """The files of ``out`` (of :data:`OUTPUTS`) an earlier ``lmsbench slam`` run wrote, as far as
    what it left tells (options.SLAM_OWNER, the rule every command with an --out folder follows):
    config.yaml, metrics.json and map.json by their content, trajectory.tum, keyframes.tum and
    slam.png by one of those beside them. A file it does not tell is the user's: never removed or
    written over (a metrics.json of notes and a slam.png in an --out folder were deleted as an
    earlier run's)."""
    return SLAM_OWNER.earlier(out, OutTree(OUTPUTS))


def foreign_outputs(out: Path) -> list[str]:
    """The files of ``out`` named as lmsbench slam's outputs that no earlier run of it wrote
    (:func:`earlier_run_files`), which a run into ``out`` would write over or remove."""
    if not out.is_dir():
        return []
    return sorted(SLAM_OWNER.foreign(out, OutTree(OUTPUTS)), key=OUTPUTS.index)


def write_outputs(out: Path, data: SlamInput, config: SlamConfig, slam_run: SlamRun) -> None:
    """trajectory.tum, map.json, metrics.json, config.yaml, slam.png in ``out`` (and keyframes.tum
    with the default preset; an earlier run's, told by :func:`earlier_run_files`, is removed with the
    paper preset)."""
    earlier = earlier_run_files(out) if out.is_dir() else set()
    write_config(out, data, config)
    write_result(out, slam_run.result, earlier)
    write_scores(out, data, slam_run)


def write_scores(out: Path, data: SlamInput, slam_run: SlamRun) -> None:
    """metrics.json and slam.png in ``out``: what :func:`run` with ``out`` leaves to write once
    the run is scored (it wrote config.yaml, the trajectory and the map before the scores)."""
    write_record(out / "metrics.json", json.dumps(_jsonable(slam_run.metrics), indent=2) + "\n")
    # whole (a hidden temporary file renamed into place): a full disk left a cut slam.png beside whole files
    write_record(out / "slam.png", lambda tmp: plot(tmp, data, slam_run.result))


def write_config(out: Path, data: SlamInput, config: SlamConfig) -> None:
    """config.yaml in ``out``: the input, the SLAM config of the run, the extractor's resolved
    config (every field of ``config.extractor``'s config, its defaults included: the SLAM config
    holds only the overrides, ``extractor_params: {}`` for none) and the versions of the code and
    libraries; written first and whole (provenance.write_record), as it tells ``out`` as an lmsbench
    slam folder: a run stopped after its trajectory.tum, before config.yaml, left a folder the next
    run into it refused. ``slam --config`` reads the slam: section back; the other two are records."""

    from experiments.compare import resolved_configs
    from experiments.options import SLAM_RECORD_KEYS
    from experiments.provenance import versions

    from experiments.overrides import unread_marked
    from features.registry import make_config

    extractor = resolved_configs([config.extractor], {config.extractor: config.extractor_params})[config.extractor]
    # sigma_r given for cm-mode scans (or sigma_r_cm for mm-mode ones) was recorded as if it ran
    extractor = unread_marked(extractor, make_config(config.extractor, **config.extractor_params),
                              data.records.range_maxes(), config.extractor_params)
    records = {"extractor_config": extractor, "versions": versions()}
    assert tuple(records) == SLAM_RECORD_KEYS  # what slam --config reads past and --out tells the folder by
    write_record(out / "config.yaml", dump_yaml({"input": data.sources, "slam": config.to_dict(), **records},
                                                     sort_keys=False))


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return None if not np.isfinite(value) else float(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def plot(path: Path, data: SlamInput, res: SlamResult) -> None:
    """Trajectory and map lines, over the ground truth or corrected poses (aligned into their frame)
    where there are some."""
    try:
        from experiments.style import apply_style, equal_axes
    except ImportError:  # pragma: no cover - the style module is part of the project
        apply_style = equal_axes = None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    if apply_style:
        apply_style()
    fig, ax = plt.subplots(figsize=(7, 6))
    al = Alignment2D(0.0, (0.0, 0.0))
    if data.truth is not None:
        a = ate(res.trajectory, data.truth)
        al = Alignment2D(a.rotation, a.translation)
        if data.walls is not None and len(data.walls):  # one artist: a plot per wall took 118 s for 20,000 walls
            ax.add_collection(LineCollection(data.walls.reshape(-1, 2, 2), colors="0.75", linewidths=1.0))
        ax.plot(data.truth[:, 1], data.truth[:, 2], color="k", lw=1.0, label=data.reference)
    xy = al.apply(res.trajectory[:, 1:3])
    if len(res.map_lines):  # one artist, as the walls
        ends = al.apply(res.map_lines[:, 2:6].reshape(-1, 2)).reshape(-1, 2, 2)
        ax.add_collection(LineCollection(ends, colors="#1f77b4", linewidths=1.5))
    ax.plot(xy[:, 0], xy[:, 1], color="#8c564b", lw=1.0, label="slam trajectory")
    if res.map_corners.size:
        c = al.apply(res.map_corners[:, :2])
        ax.plot(c[:, 0], c[:, 1], "o", color="#2ca02c", ms=3, label="map corners" if "keyframes" in res.diagnostics
                else "corner landmarks")
    # the paper preset's EKF keeps line landmarks; the default pipeline's lines are its keyframes' merged map
    default_pipeline = "keyframes" in res.diagnostics
    ax.plot([], [], color="#1f77b4", lw=1.5, label="map lines" if default_pipeline else "line landmarks")
    ax.autoscale_view()  # the collections' extent, as the plots of each line set it
    ax.set_title(f"{printable(data.name)}: {len(data.records)} scans, {res.map_lines.shape[0]} lines")
    ax.legend(loc="best")
    if equal_axes:
        equal_axes(ax)
    else:
        ax.set_aspect("equal")
    from experiments.style import savefig  # a full disk its OSError, not matplotlib's cleanup error

    savefig(fig, path, format="png", dpi=120)  # path may be a temporary name (write_scores)
    plt.close(fig)
