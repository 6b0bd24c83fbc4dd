"""Every extractor on identical scans: timing interleaved per scan in one process, scores against
ground truth where the source has it, and a summary per source and method.

Sources: simulated worlds (``sim.simulate_records`` with the truth of ``sim.visible_truth`` at each
record's true pose) or a real log (``lms200.read_log``). Every source is also scored without ground
truth (``features.realdata``: explained fractions at 3 cm and at 3 sigma of the range noise, ray
RMSE, mean segment length, and repeatability between consecutive compared scans where the source
has poses to trust: the true poses of a simulation, the corrected poses of a Radish ``*-corrected``
log). The range noise is the sensor model's for simulated sources and estimated from the log itself
(``lms200.noise.estimate_range_noise``) for logs.
Timing wraps only the method's function (``time.perf_counter_ns``); on each scan the methods run
in an order rotated by one per scan, so no method always runs first (cold caches) or last.
"""

from __future__ import annotations

import dataclasses
import itertools
import os
from functools import partial
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np
import pandas as pd
import yaml

from features.baselines.checks import MIN_SIGMA_M as EXTRACTOR_MIN_SIGMA_M  # not this module's MIN_SIGMA_M (user's floor)
from features.errors import ConfigError
from features.registry import (available_methods, backend_of, check_beams, check_step, get_method, make_config,
                               returned_problem, warn_unread_fields)
from features.realdata import RealDataConfig, repeat_counts, scan_measures, truth_lines
from features.scoring import ScoreConfig, check_truth, explained_fraction, prf, score_scan
from lms200 import LmsbenchError, Pose2D, Record, read_log
from lms200.carmen import no_scan_read
from lms200.errors import InputError
from lms200.finite import check_integer, is_number, is_one_of, shown
from lms200.logs import SIMULATE_LOG
from lms200.noise import QUANTUM_CANDIDATES_M

from experiments.options import known_worlds, load_simulate_config, real_path  # sim.WORLD_NAMES, the simulator imported when first asked
from lms200.finite import printable


@dataclass
class Source:
    """Scans to compare on. ``truth_of(record)`` gives the visible truth, or is None (real logs)."""

    name: str
    kind: str  # "sim" or "log"
    seed: int | None
    records: Iterable[Record]
    truth_of: Callable[[Record], Any] | None = None
    total: int | None = None
    sigma_r: float | None = None  # range noise, 1 sigma (m): the sensor model's, or estimated (logs)
    pose_of: Callable[[Record], Pose2D | None] | None = None  # world pose to trust, for repeatability
    estimate_sigma: Callable[[], float] | None = None  # how to estimate sigma_r when it is not known
    extractor_sigma: float | None = None  # noise for the extractors' thresholds (m); None: as sigma_r
    estimate_extractor_sigma: Callable[[], float] | None = None  # its estimate (logs: neighbour scatter)
    fit_sigma: float | None = None  # scatter of beams about a fitted line (m), for split / merge tests; None: as extractor noise
    estimate_fit_sigma: Callable[[], float] | None = None  # its estimate (logs: features.noise_estimate.fit_sigma)
    bearing_sigma: float | None = None  # bearing noise (rad) for the sensor method's tests; None: its config's (0)
    estimate_bearing_sigma: Callable[[], float] | None = None  # its estimate (logs: features.noise_estimate.bearing_sigma)
    reader: Any = None  # the log reader (its ``stats`` say what was skipped)
    settings: dict[str, Any] = dataclasses.field(default_factory=dict)  # what produced the scans (saved beside results)
    # filled by compare(): the config each method ran with on this source (its noise fields set,
    # :func:`_with_noise`) and the range_max of its scans (m; which range-noise field applies)
    ran: dict[str, Any] = dataclasses.field(default_factory=dict)
    range_maxes: set[float] = dataclasses.field(default_factory=set)
    stride: int = 1  # records are every stride-th scan of the log: record k is the log's scan k * stride (messages)

    @classmethod
    def from_records(cls, records: Sequence[Record], truths: Sequence[Any] | None = None, name: str = "sim",
                     seed: int | None = None) -> "Source":
        """Records already in memory (a simulated run, a log read once), with their visible truths
        (one per record, sensor frame) when known: scored against them; else like a log, with the
        noise the extractors get on a log (``sigma_r="auto"``) estimated from these records as
        :func:`log_source` estimates it from its file, and repeatability measured through the
        records' corrected poses (``Record.corrected``, a Radish ``*-corrected`` log's) where they
        have them, as :func:`log_source` measures it (it was nan: a researcher's walkthrough,
        ``read_log`` of Intel into ``from_records``, against ``compare`` of the file's 0.82)."""
        records = list(records)
        if truths is None:
            return cls(name, "log", seed, records, None, len(records),
                       pose_of=partial(_corrected_pose, odometry_too=False), **log_noise_estimates(lambda: records))
        truths = list(truths)
        if len(truths) != len(records):
            raise LmsbenchError(f"{len(records)} records but {len(truths)} truths")
        by_index = {id(r): t for r, t in zip(records, truths)}
        return cls(name, "sim", seed, records, lambda rec: by_index[id(rec)], len(records),
                   pose_of=lambda rec: rec.truth)


def sim_source(world: str, seed: int = 0, duration: float = 30.0, rate_hz: float | None = 2.0,
               sensor: Any = None) -> Source:
    """Records of the simulated ``world`` (seeded) with their visible truth (sensor frame).

    The default sensor is the LMS200 model without interlaced timing: the truth is that of a single
    pose, so a scan whose beams come from poses up to 20 ms apart (1.2 deg of turn) would charge the
    robot's motion to the extractor. Pass ``sensor=sim.SensorConfig()`` for the moving-scan model.
    """
    import sim

    sensor = sensor if sensor is not None else sim.SensorConfig(interlaced=False)
    w = sim.make_world(world, seed=seed)
    records = sim.simulate_records(world=w, seed=seed, duration=duration, sensor=sensor, rate_hz=rate_hz)
    settings = dict(world=world, seed=seed, duration=duration, rate_hz=rate_hz, sensor=dataclasses.asdict(sensor))
    return Source(world, "sim", seed, records, _truth_in(w, sensor), len(records), sigma_r=sensor.noise_sigma,
                  pose_of=lambda rec: rec.truth, settings=settings)


def _truth_in(world: Any, sensor: Any) -> Callable[[Record], Any]:
    import sim

    def truth_of(rec: Record) -> Any:
        if rec.truth is None:
            raise LmsbenchError(f"simulated record at t={rec.scan.stamp} has no true pose")
        return sim.visible_truth(world, rec.truth, sensor)

    return truth_of


def is_simulation_folder(path: str | Path) -> bool:
    """A ``lmsbench simulate`` output folder (``options.simulate_log``) with its world.json, whose
    scans are scored against their truth (without it, its scans.clf is compared as a log). A
    world.json that is there but no regular file (a pipe, a link to /dev/zero) makes it one too, to
    be refused by ``World.from_json`` as slam refuses it: it was compared as a log, its truth
    dropped without a word, exit 0 (found by fuzzing)."""
    from experiments.options import simulate_log

    return simulate_log(path) is not None and (Path(path) / "world.json").exists()


def check_simulate_config(folder: Path) -> bool:
    """Whether a simulate folder has a config.yaml to read; LmsbenchError naming it for a pipe or a
    device in its place (regular_file) or a file beyond a config's size (refused unread: simulate
    writes 2 KB; 3 GB was read whole, MemoryError, 35 MB parsed for minutes: fuzzing)."""
    from experiments.options import simulate_config_size_problem

    cfg = folder / "config.yaml"
    if not cfg.exists():
        return False
    too_big = simulate_config_size_problem(cfg)
    if too_big:
        raise LmsbenchError(f"{cfg}: {too_big}")
    return True


def folder_source(path: str | Path, stride: int = 1, max_scans: int | None = None) -> Source:
    """The scans of a ``lmsbench simulate`` folder, scored against the visible truth of its
    world.json at each scan's true pose (its TRUEPOS lines), for the sensor of its config.yaml.

    The truth is that of the pose at the scan's stamp: a folder simulated with the default
    interlaced sensor charges the robot's motion within a scan (up to 1.2 deg) to the extractor."""
    stride, max_scans = check_counts(stride, max_scans)

    import sim
    from sim.sensor import upgrade_fields

    from experiments.options import check_simulate_finished

    p = Path(path)
    check_simulate_finished(p)
    world = sim.World.from_json(p / "world.json")
    settings: dict[str, Any] = {"folder": str(p)}
    sensor = sim.SensorConfig()
    seed = None
    if check_simulate_config(p):
        try:  # the simulate config the folder was made with: its sensor model scores the scans
            cfg = load_simulate_config(p / "config.yaml") or {}  # simulate's record, an earlier version's too
            if not isinstance(cfg, dict):
                raise TypeError("expected a mapping of world, seed, duration, sensor, ...")
            raw_sensor = cfg.get("sensor")
            if raw_sensor is None:  # an empty or cut file: the default sensor scored the scans, silently
                raise TypeError("it has no sensor: mapping (the sensor the scans were simulated with, which scores "
                                "them); restore it, or simulate the folder again")
            if isinstance(raw_sensor, dict):  # degrees in a folder simulated before the config held radians: read
                raw_sensor = upgrade_fields(raw_sensor, f"{p / 'config.yaml'}: sensor")  # converted, with a warning
            sensor = sim.SensorConfig(**raw_sensor)
            seed = cfg.get("seed")
            if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
                raise TypeError(f"seed: must be a whole number, got {seed!r}")
        except LmsbenchError as exc:
            raise LmsbenchError(f"{p / 'config.yaml'}: {exc}") from None
        except (yaml.YAMLError, TypeError, ValueError, UnicodeDecodeError) as exc:
            raise LmsbenchError(f"{p / 'config.yaml'}: not a simulate config ({' '.join(str(exc).split())})") from None
        settings.update({k: cfg.get(k) for k in ("world", "seed", "duration", "rate_hz")})
    settings["sensor"] = dataclasses.asdict(sensor)
    inner = log_source(p / SIMULATE_LOG, stride, max_scans, poses="none")
    return Source(printable(p.name), "sim", int(seed) if seed is not None else None, inner.records, _truth_in(world, sensor),
                  max_scans, sigma_r=sensor.noise_sigma, pose_of=lambda rec: rec.truth, reader=inner.reader,
                  settings=settings, stride=stride)


POSES = ("auto", "corrected", "none")
DATASHEET_SIGMA_M = 0.005  # LMS200 statistical error, 1 sigma (m): for a source whose noise cannot be had


def _plain(options: dict[str, Any]) -> dict[str, Any]:
    from experiments.logargs import plain_log_options

    return plain_log_options(options)


def check_counts(stride: object, max_scans: object) -> tuple[int, int | None]:
    """``stride`` a whole number >= 1 and ``max_scans`` None or one; InputError naming it. (A stride
    of 1.5 kept every third scan, ``k % 1.5 == 0``, True every one, "2" was a TypeError; max_scans 0
    or -1 read no scan and compared nothing, silently; a whole float, 2.0, is taken as the int it
    is, as it was before the check.)"""
    step = check_integer(stride, "stride", 1, what="(every stride-th scan)")
    most = None if max_scans is None else check_integer(max_scans, "max_scans", 1, what="(or None: every scan)")
    return step, most


def log_source(path: str | Path, stride: int = 1, max_scans: int | None = None,
               read_options: dict[str, Any] | None = None, poses: str = "auto") -> Source:
    """Every ``stride``-th scan of a real log (CARMEN or bag), at most ``max_scans`` of them; no ground truth.

    Args:
        read_options: keywords of ``lms200.read_log`` (topic, skip_bad_lines, geometry).
        poses: "corrected" when the log's poses are SLAM-corrected (repeatability is measured with
            them), "none" when they are raw odometry, "auto": corrected when the file name says
            so (Radish names its corrected logs ``*-corrected*``). The corrected poses a reader
            found (``Record.corrected``: the laser lines' pose fields of a log whose ODOM lines
            restart at each scan, :class:`lms200.carmen_odom.CorrectedChain`) are used unless
            "none"; the odometry then is the raw one the ODOM lines give, never trusted.
    """
    stride, max_scans = check_counts(stride, max_scans)
    if not is_one_of(poses, POSES):
        raise LmsbenchError(f"poses: must be one of {', '.join(POSES)}, got {poses!r}")
    options = dict(read_options or {})
    reader = read_log(path, **options)
    corrected = poses == "corrected" or (poses == "auto" and "corrected" in Path(path).name.lower())

    def records() -> Iterable[Record]:  # at most max_scans: it was the progress bar's total alone, and
        kept = 0  # log_source(path, max_scans=40) gave all 910 of Intel's scans (a library walkthrough)
        for k, rec in enumerate(reader):
            if max_scans is not None and kept >= max_scans:
                return
            if k % stride == 0:
                kept += 1
                check_beams(rec.scan, f"{path}: scan {k}")  # the log's own scan number, not the kept one's
                yield rec

    def estimate_sigma() -> float:
        from lms200.noise import estimate_range_noise

        noise = estimate_range_noise(read_log(path, **options))
        if not np.isfinite(noise.sigma_m):
            raise LmsbenchError(f"{path}: too few straight runs of beams to estimate the range noise; give --sigma")
        return float(noise.sigma_m)

    return Source(printable(Path(path).name), "log", None, records(), None, max_scans, sigma_r=None,
                  pose_of=None if poses == "none" else partial(_corrected_pose, odometry_too=corrected),
                  estimate_sigma=estimate_sigma,
                  reader=reader, **log_noise_estimates(lambda: read_log(path, **options)),
                  settings={"log": str(path), "stride": stride, "poses": poses, **_plain(options)}, stride=stride)


def _corrected_pose(rec: Record, odometry_too: bool) -> Pose2D | None:
    """The pose of ``rec`` to measure repeatability with: its corrected pose, or (``odometry_too``:
    the user or the file name says the log's poses are corrected) its odometry pose."""
    return rec.corrected if rec.corrected is not None else (rec.odom if odometry_too else None)


def log_noise_estimates(scans: Callable[[], Iterable[Any]]) -> dict[str, Callable[[], float]]:
    """The ``estimate_*`` fields of a log-like Source (what ``sigma_r="auto"`` gives the extractors
    on a log), each from a fresh pass over ``scans()`` (the whole log, not its stride): the
    neighbour scatter for every method's range noise, the scatter about fitted lines for the split
    / merge tests of split_merge and iepf, the bearing noise for the sensor method's line tests."""
    from features.noise_estimate import bearing_sigma, fit_sigma, neighbour_sigma

    return dict(estimate_extractor_sigma=lambda: neighbour_sigma(scans()),
                estimate_fit_sigma=lambda: fit_sigma(scans()),
                estimate_bearing_sigma=lambda: bearing_sigma(scans()))


def world_words(specs: Sequence[str]) -> list[str]:
    """The source words that name a simulated world (``office``, ``office:1``), told by name as
    ``parse_sources`` reads them (a folder named ``office`` does not make ``office`` a file)."""
    return [s for s in specs if s.partition(":")[0] in known_worlds()]


def _check_seed(spec: str, seed: str) -> None:
    """The seed after a world's colon (``office:3``): ASCII digits below 2**32 ("٣" read as 3)."""
    if not (seed.isascii() and seed.isdigit() and int(seed) < 2**32):
        raise LmsbenchError(f"{spec}: the seed after the colon must be a whole number >= 0, got {seed!r}")


def parse_sources(specs: Sequence[str], seeds: Sequence[int] = (0,), duration: float = 30.0,
                  rate_hz: float | None = 2.0, stride: int = 1, max_scans: int | None = None,
                  read_options: dict[str, Any] | None = None, poses: str = "auto",
                  sensor: Any = None) -> list[Source]:
    """Sources from command-line words: a world name (one source per seed), ``world:seed``, a
    ``lmsbench simulate`` folder, or the path of a log (read with ``read_options``, see
    :func:`log_source`). ``sensor`` (a ``sim.SensorConfig``) is the simulated worlds' sensor model
    (a simulate folder has its own, in its config.yaml).

    Raises:
        LmsbenchError: a word that is none of these, a bad seed, or a log of the wrong kind.
    """
    stride, max_scans = check_counts(stride, max_scans)
    out: list[Source] = []
    for spec in specs:
        name, colon, seed = spec.partition(":")
        if name in known_worlds():
            if colon:
                _check_seed(spec, seed)
            for s in ([int(seed)] if colon else seeds):
                out.append(sim_source(name, s, duration, rate_hz, sensor))
        elif is_simulation_folder(spec):
            out.append(folder_source(spec, stride, max_scans))
        else:
            if not Path(spec).exists():
                raise LmsbenchError(f"{spec!r} is neither a world ({', '.join(known_worlds())}), a simulate folder "
                                    "nor an existing log")
            from experiments.options import simulate_log

            out.append(log_source(simulate_log(spec) or spec, stride, max_scans, read_options, poses))
    return out


def check_sources(specs: Sequence[str], read_options: dict[str, Any] | None = None,
                  seeds: Sequence[int] = (0,), configs: dict[str, Any] | None = None) -> None:
    """Check command-line source words before any work: world names and seeds, simulate folders
    (world.json loads), logs (their kind, and at least one laser scan), and that no two words give
    the same source or sources of one name (the tables group by name: ``compare a.clf a.clf``
    counted each scan twice, ``compare x/a.clf y/a.clf`` reported two logs as one); ``seeds``:
    the seeds of a world given without one; ``configs`` (method -> its config, as it will run):
    each log's first beam step is one they segment (``features.registry.check_step``)."""
    from experiments.options import check_log

    seen: dict[tuple[str, int | None], str] = {}  # (source name, seed or None) -> the word that gave it
    kinds: dict[str, tuple[str, str]] = {}  # source name -> (a word that gave it, its path or "world")
    stems: dict[str, str] = {}  # a log's figure name (realdata_STEM) -> the word that gave it
    files: dict[tuple[int, int], tuple[str, Path]] = {}  # the file read (st_dev, st_ino) -> the word that gave it, its path
    for spec in specs:
        word = spec
        name, colon, seed = spec.partition(":")
        world = name in known_worlds()  # as parse_sources reads it
        if world and colon:
            _check_seed(spec, seed)
        label = name if world else printable(Path(spec).name)  # as the tables name it (parse_sources)
        where = "world" if world else str(real_path(spec))
        first = kinds.setdefault(label, (spec, where))
        if first[1] != where:
            escaped = "" if world or label == Path(spec).name else ", a name that is not UTF-8, shown escaped"
            raise LmsbenchError(f"{first[0]} and {spec} would both be reported as '{label}'{escaped} (compare names a "
                                "source by its world, folder or file name): give one of them another name, "
                                "e.g. a link")
        for s in (([int(seed)] if colon else list(seeds)) if world else [None]):
            if (label, s) in seen:
                again = f"{label}:{s}" if world else spec
                raise LmsbenchError(f"{again} is given twice ({seen[(label, s)]} and {spec}): each source once "
                                    "(the tables would count its scans twice)")
            seen[(label, s)] = spec
        if world:
            continue
        if is_simulation_folder(spec):
            import sim

            try:
                sim.World.from_json(Path(spec) / "world.json")
            except LmsbenchError:
                raise
            except (ValueError, KeyError, TypeError) as exc:
                raise LmsbenchError(f"{spec}/world.json: not a world ({type(exc).__name__}: {exc})") from None
            check_simulate_config(Path(spec))  # before any work: it was refused after the kernels' warm-up (a review)
            spec = str(Path(spec) / SIMULATE_LOG)
        elif not Path(spec).exists() and not Path(spec).is_symlink():  # a link to nothing: check_log says so
            close = [w for w in known_worlds() if _close(w, name)]
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise LmsbenchError(f"{spec!r} is neither a world ({', '.join(known_worlds())}){hint}, a simulate folder "
                                "nor an existing log")
        spec = str(check_log(spec))  # a simulate folder without world.json: its scans.clf, as a log
        # one input under two spellings (a simulate folder and its scans.clf, a path and a link to it, a hard
        # link): the names differ, so the checks above pass, and its scans were counted twice
        st = os.stat(spec)
        other, read = files.setdefault((st.st_dev, st.st_ino), (word, real_path(spec)))
        if other != word:
            raise LmsbenchError(f"{other} and {word} are the same input ({read}), given twice: "
                                "each source once (the tables would count its scans twice)")
        # each log's figure is named by its file name made safe (figures.realdata.figure_stem): "a b.clf" and
        # "a_b.clf" both wrote realdata_a_b_clf.*, the second over the first ("ä.clf" and "ö.clf": realdata__clf)
        from experiments.figures.realdata import figure_stem

        stem = figure_stem(Path(), label).name
        other = stems.setdefault(stem, spec)
        if other != spec:
            raise LmsbenchError(f"{other} and {spec} would both write their figure as {stem}.png (a figure's "
                                "name keeps only letters, digits, _ and - of the file name): give one of them another "
                                "name, e.g. a link")
        reader = read_log(spec, **(read_options or {}))
        first = next(iter(reader), None)
        if first is None:
            if reader.stats.stopped:  # damage before the first scan (read under --skip-bad-lines)
                raise LmsbenchError(f"{spec}: {no_scan_read(reader.stats.stopped)}")
            raise LmsbenchError(f"{spec}: no laser messages found (not a CARMEN log with FLASER / ROBOTLASER / RAWLASER "
                                "lines, nor a bag with LaserScan messages)")
        check_beams(first.scan, f"{spec}: scan 0")  # its scans go to the extractors' run, which extract's limit does not guard
        for method, cfg in (configs or {}).items():  # a breakpoint_lambda not above the step: no line, silently
            check_step(cfg, first.scan.angle_increment, method, f"{spec}: scan 0")


def _check_types(method: str, overrides: dict[str, Any]) -> None:
    """An override has the kind of its field's default: a number for a number, true/false for a
    flag, text for text (configs check ranges, not types)."""
    config = make_config(method)
    default = dataclasses.asdict(config)
    annotations = {f.name: str(f.type) for f in dataclasses.fields(config)}
    for name, value in overrides.items():
        if name not in default:
            continue  # make_config names unknown fields
        d = default[name]
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if "|" in annotations[name] and (number or isinstance(value, str)):
            continue  # a field that takes a number or a word (sigma_r: metres or "auto"): the config checks it
        if isinstance(d, bool):
            ok = isinstance(value, bool)
            kind = "true or false"
        elif isinstance(d, (int, float)):
            ok = number and (isinstance(d, float) or float(value).is_integer())
            kind = "a whole number" if isinstance(d, int) else "a number"
        elif isinstance(d, str):
            ok = isinstance(value, str)
            kind = "text"
        else:
            continue
        if not ok:
            raise LmsbenchError(f"{method}: {name} must be {kind} (default {d!r}), got {value!r}")


def _close(a: str, b: str) -> bool:
    import difflib

    return difflib.SequenceMatcher(None, a, b).ratio() >= 0.75


def _errors(values: np.ndarray) -> tuple[float, float]:
    if values.size == 0:
        return float("nan"), float("nan")
    return float(np.mean(values)), float(np.sqrt(np.mean(values**2)))


def compare(
    sources: Sequence[Source | str],
    methods: Sequence[str] | None = None,
    *,
    params: dict[str, dict[str, Any]] | None = None,
    score_config: ScoreConfig | None = None,
    sigma: float | str = "auto",
    max_scans: int | None = None,
    progress: bool = False,
    matches: list[dict[str, Any]] | None = None,
    realdata_config: RealDataConfig | None = None,
) -> pd.DataFrame:
    """Run ``methods`` (default: every available one) on every scan of ``sources``.

    Args:
        sources: Source objects, or strings as for :func:`parse_sources` (seed 0).
        methods: extractor names; the order does not matter (it is rotated per scan).
        params: per-method overrides of config fields, ``{"hough": {"rho_step": 0.01}}``; only for
            methods in ``methods`` (another method's entry is an InputError, before any source is read).
        score_config: line / corner matching tolerances.
        sigma: range noise, 1 sigma (m, in [MIN_SIGMA_M, MAX_SIGMA_M]: 0.1 mm to 1000 m), for the
            noise-scaled explained fractions, or "auto": the sensor model's for simulated sources,
            estimated from the data for logs.
        max_scans: at most this many scans per source.
        progress: show a tqdm progress bar.
        matches: if a list, one dict per matched line is appended to it (method, source, seed,
            scan, face, rho_err, alpha_err): see :func:`common_errors`.
        realdata_config: tolerances of the measures without ground truth (``features.realdata``).

    Returns:
        A tidy table, one row per method x scan: method, backend ("numba" or "numpy", see
        ``features.registry.backend_of``: speed ratios are fair only between equal backends), source, kind, seed, scan, stamp, n_valid,
        n_lines, n_corners, microseconds (wall, ``perf_counter_ns``), time_ms (the same in ms), cpu_microseconds (this
        thread's CPU time, ``thread_time_ns``: what a pre-empted call really used), explained,
        range_rms (m) (3 sigma band), sigma_r (m, the noise used), explained_3cm,
        explained_3sigma, n_explained_3cm, ray_rmse (m, of the beams explained at 3 cm),
        mean_segment_m, repeat_found / repeat_in_view (lines of the previous compared scan found
        again / still in view; nan without trusted poses) and, for simulated sources,
        n_truth, tp, fp, fn, precision, recall, f1, rho_err_mean / rho_err_rms (m),
        alpha_err_mean / alpha_err_rms (rad), endpoint_err_mean (m), n_truth_corners, corner_tp,
        corner_fp, corner_fn, corner_err_mean (m).
    """
    from experiments.user_methods import UserMethodFailed, ensure_method, is_user_method

    if isinstance(methods, (str, bytes)):  # its letters were taken as names: "unknown extraction method 's'"
        raise InputError(f"methods: must be a list of method names, got the text {methods!r} (give [{methods!r}])")
    methods = available_methods() if methods is None else list(methods)
    if not methods:  # [] ran every method, as None does
        raise InputError("methods: no method given (None runs every available one)")
    for m in methods:
        ensure_method(m)
    twice = next((m for i, m in enumerate(methods) if m in methods[:i]), None)
    if twice is not None:  # each of its scans was measured and counted twice
        raise InputError(f"methods: {twice!r} is given twice")
    fixed_sigma = checked_sigma(sigma)
    if matches is not None and not isinstance(matches, list):  # appended to after every scan was run: 'dict' object
        raise InputError(f"matches: must be a list (one dict is appended per matched line) or None, "  # has no attribute
                         f"got {type(matches).__name__}")  # 'append', at the end
    params = {} if params is None else params
    if not isinstance(params, dict) or not all(isinstance(v, dict) for v in params.values()):  # 'int' object has no attribute 'get'
        raise InputError(f"params: must be a mapping of method name to its fields, {{'hough': {{'rho_step': 0.01}}}}, "
                         f"got {shown(params)}")
    idle = next((m for m in params if m not in methods), None)
    if idle is not None:  # its fields were dropped without a word: a typo'd or left-out method ran on its defaults
        raise InputError(f"params: {shown(idle)} is not among the methods run ({', '.join(methods)}); "
                         f"give parameters only for a method in methods")
    if isinstance(sources, (str, bytes)):
        raise InputError(f"sources: must be a list of sources, got the text {sources!r} (give [{sources!r}])")
    try:
        sources = list(sources)  # a generator of sources too
    except TypeError:
        raise InputError(f"sources: must be a list of sources, got {shown(sources)}") from None
    if not sources:  # an empty table, silently
        raise InputError("sources: no source given")
    if max_scans is not None:
        max_scans = check_integer(max_scans, "max_scans", 1, what="(or None: every scan)", strict=True)
    registered = {m: get_method(m) for m in methods}
    runs = [(m, registered[m].run, make_config(m, **params.get(m, {}))) for m in methods]
    backends = {name: backend_of(name, cfg) for name, _, cfg in runs}
    srcs = [s for spec in sources for s in ([spec] if isinstance(spec, Source) else parse_sources([spec]))]
    total = sum(min(s.total or 0, max_scans or s.total or 0) for s in srcs) or None
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="scan", desc="compare", disable=None)  # None: on a terminal only
    rows: list[dict[str, Any]] = []
    warmed = False
    rd_cfg = realdata_config or RealDataConfig()
    for src in srcs:
        # the source's first scan is checked before its range noise is estimated: a log of too wide scans was
        # read whole for its noise (sigma "auto") before compare() refused its scan 0 (the CLI checks it while
        # parsing); checked here, source by source, so that one log is open at a time (first scans taken for
        # every source before the loop kept every log's reader open: 60 logs, "too many open files")
        src_records = _first_checked(src, max_scans)
        sigma_r = _source_sigma(src, fixed_sigma)
        src_runs = _with_noise(runs, params, _extractor_noise(src, sigma_r), _fit_noise(src), _bearing_noise(src))
        src.ran = {name: cfg for name, _, cfg in src_runs}
        previous: dict[str, tuple[np.ndarray, Pose2D]] = {}  # method -> lines and pose of the last scan
        for k, rec in enumerate(src_records):
            if max_scans is not None and k >= max_scans:
                break
            scan = rec.scan
            number = k * src.stride  # the log's own scan number (record k of every stride-th), as in messages
            check_beams(scan, f"{source_label(src)}: scan {number}")  # as extract refuses it, before any method runs on it
            for name, _, cfg in src_runs:  # as extract refuses a breakpoint_lambda not above the step (no line found)
                check_step(cfg, scan.angle_increment, name, f"{source_label(src)}: scan {number}")
            src.range_maxes.add(float(scan.range_max))
            truth = check_truth(src.truth_of(rec)) if src.truth_of else None  # checked once, scored per method
            n_valid = int(np.count_nonzero(scan.valid))
            exact = _truth_row(truth, scan, sigma_r, rd_cfg) if truth is not None else {}
            shift = k % len(runs)
            try:  # a user's MODULE:FUNCTION that fails, warming up or timed, is said with its scan
                if not warmed:  # first calls load compiled kernels and fill caches: not timed
                    for _, fn, cfg in src_runs:
                        fn(scan, cfg)
                    warmed = True
                for name, fn, cfg in src_runs[shift:] + src_runs[:shift]:
                    t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
                    fs = fn(scan, cfg)
                    c1, t1 = time.thread_time_ns(), time.perf_counter_ns()
                    elapsed, cpu = t1 - t0, c1 - c0
                    problem = returned_problem(registered[name], fs, len(scan))  # a user method's rows, outside the timed span
                    if problem:
                        if is_user_method(name):
                            raise UserMethodFailed(name, f"returned {problem}", scan, False)
                        raise ConfigError(f"method {name!r}: its run returned {problem} on {source_label(src)} scan {number}")
                    explained, range_rms = explained_fraction(fs, scan, sigma_r)
                    row = dict(method=name, backend=backends[name], source=src.name, kind=src.kind, seed=src.seed, scan=number,
                               stamp=scan.stamp, n_valid=n_valid, n_lines=len(fs.lines),
                               n_corners=len(fs.corners), microseconds=elapsed / 1e3, cpu_microseconds=cpu / 1e3,
                               explained=explained, range_rms=range_rms)
                    row.update(_realdata_row(fs, rec, src, sigma_r, rd_cfg, previous, name))
                    row.update(exact)
                    if truth is not None:
                        score = score_scan(fs, truth, score_config)
                        row.update(_score_row(score))
                        if matches is not None:
                            for face, dr, da in zip(score.matches[:, 1].tolist(), score.rho_errors.tolist(),
                                                    score.alpha_errors.tolist()):
                                matches.append(dict(method=name, source=src.name, seed=src.seed, scan=number,
                                                    face=face, rho_err=dr, alpha_err=da))
                    rows.append(row)
            except UserMethodFailed as exc:
                raise exc.at(source_label(src), number)  # the log's own scan number, as docs/commands.md
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    # a --set / params field no scan of the run read (sigma_r on cm-mode logs): said once, as extract says it per call
    warn_unread_fields(params, {name: cfg for src in srcs for name, cfg in src.ran.items()},
                       sorted({r for src in srcs for r in src.range_maxes}),
                       f"the scans of {', '.join(source_label(src) for src in srcs)}")
    table = pd.DataFrame(rows)
    if not table.empty:
        table.insert(table.columns.get_loc("microseconds") + 1, "time_ms", table["microseconds"] / 1e3)
    return table


def _first_checked(src: Source, max_scans: int | None = None) -> Iterable[Record]:
    """``src``'s records, its first scan's beams checked (:func:`check_beams`) now, before its range
    noise is estimated; a list of records is left as it is (re-iterable, for that estimate). The
    first scans of a source not read by a log reader (records of the user's, which the readers'
    check does not see) are checked for ranges in millimetres (``lms200.units``: a warning), no more of
    them than the run takes (``max_scans``, compare's): a user's live stream is not read further for it."""
    from lms200.units import UNITS_SCANS, warn_units

    if isinstance(src.records, Sequence):
        if len(src.records):
            check_beams(src.records[0].scan, f"{source_label(src)}: scan 0")
            if src.reader is None:
                warn_units((rec.scan for rec in itertools.islice(src.records, UNITS_SCANS)), source_label(src))
        return src.records
    it = iter(src.records)
    first = next(it, None)  # a log's records check their beams as read (log_source), naming the log's path
    if first is None:
        return ()
    check_beams(first.scan, f"{source_label(src)}: scan 0")
    if src.reader is not None:
        return itertools.chain([first], it)
    most = UNITS_SCANS if max_scans is None else min(UNITS_SCANS, max_scans)
    head = [first, *itertools.islice(it, most - 1)]
    warn_units((rec.scan for rec in head), source_label(src))
    return itertools.chain(head, it)


def source_label(src: Source) -> str:
    """How a message names ``src``: a world with its seed as on the command line (``office:3``),
    else its name (a simulate folder's or a log's)."""
    return f"{src.name}:{src.seed}" if src.name in known_worlds() and src.seed is not None else src.name


#: the range noise std (m) ``compare``'s ``sigma`` (``--sigma``) takes, given as a number: at least
#: 0.1 mm, below any rangefinder's (the LMS200 codes ranges in 1 mm or 1 cm, the finest quantum
#: ``lms200.noise`` looks for is 0.1 mm): --sigma 1e-300 ran, the sensor method found no line (F1 0),
#: every 3-sigma explained fraction was 0 and sigma_r_mm read 1e-297, exit 0; at most the
#: extractors' cap (``features.baselines.checks.MAX_SIGMA_M``; 1e308 overflowed in the summary)
MIN_SIGMA_M = min(QUANTUM_CANDIDATES_M)


def sigma_problem(value: float) -> str | None:
    """What is wrong with ``value`` (m) as the range noise std of ``compare``'s ``sigma``, or None."""
    from features.baselines.checks import MAX_SIGMA_M, finite

    if not (finite(value) and MIN_SIGMA_M <= value <= MAX_SIGMA_M):  # nan fails every comparison
        return f"must be a range noise std in [{MIN_SIGMA_M:g}, {MAX_SIGMA_M:g}] m, or 'auto'"
    return None


def checked_sigma(sigma: object) -> float | None:
    """``compare``'s ``sigma`` (m) as a float, None for "auto"; LmsbenchError naming it otherwise, before any
    source is read: a bool was taken as 1 m (``float(True)``), and an array was numpy's "truth value of an array
    ... is ambiguous" ValueError (fuzz round 10)."""
    if is_one_of(sigma, ("auto",)):
        return None
    value = float(sigma) if is_number(sigma) else float("nan")  # type: ignore[arg-type]  # a real number
    problem = sigma_problem(value)
    if problem:
        raise LmsbenchError(f"sigma: {problem}, got {shown(sigma)}")
    return value


def _source_sigma(src: Source, sigma: float | None) -> float:
    """The range noise (m) a source is scored with: ``sigma`` if a number (:func:`checked_sigma`), else the
    source's own."""
    if sigma is not None:
        return sigma
    if src.sigma_r is None and src.estimate_sigma is not None:
        src.sigma_r = src.estimate_sigma()
    if src.sigma_r is None and isinstance(src.records, Sequence):  # re-iterable: estimate from it
        from lms200.noise import estimate_range_noise

        estimate = estimate_range_noise(src.records).sigma_m
        src.sigma_r = float(estimate) if np.isfinite(estimate) else None
    if src.sigma_r is None:
        src.sigma_r = DATASHEET_SIGMA_M
    return max(float(src.sigma_r), EXTRACTOR_MIN_SIGMA_M)  # the extractors' noise floor: they cannot drift apart


NOISE_FIELDS = ("sigma_r", "sigma_r_cm", "sigma")  # extractor config fields holding the range noise (m)
FIT_NOISE_FIELDS = ("sigma_fit",)  # fields holding the scatter of beams about a fitted line (m; split_merge, iepf)
BEARING_NOISE_FIELDS = ("sigma_bearing",)  # fields holding the bearing noise (rad; sensor)


def _extractor_noise(src: Source, sigma_r: float) -> float:
    """The range noise (m) the extractors are given on ``src``: the simulator's known noise, or for
    a log the scatter of neighbouring beams estimated from the log (``features.noise_estimate``,
    what ``sigma_r="auto"`` means), resolved once per source."""
    if src.extractor_sigma is None and src.estimate_extractor_sigma is not None:
        src.extractor_sigma = src.estimate_extractor_sigma()
    return float(src.extractor_sigma) if src.extractor_sigma is not None else sigma_r


def _fit_noise(src: Source) -> float | None:
    """The scatter of beams about a fitted line (m) the split / merge tests of ``src``'s extractors
    allow for: a log's ``features.noise_estimate.fit_sigma`` (below its neighbour scatter where
    interlaced sweeps are offset), resolved once per source; None (the extractor noise) for
    simulated sources."""
    if src.fit_sigma is None and src.estimate_fit_sigma is not None:
        src.fit_sigma = src.estimate_fit_sigma()
    return src.fit_sigma


def _bearing_noise(src: Source) -> float | None:
    """The bearing noise (rad) the sensor method's line tests allow for on ``src``: a log's
    ``features.noise_estimate.bearing_sigma`` (the turn between the interlaced sweeps of 0.5 deg
    logs), resolved once per source; None (the config's 0) for simulated sources."""
    if src.bearing_sigma is None and src.estimate_bearing_sigma is not None:
        src.bearing_sigma = src.estimate_bearing_sigma()
    return src.bearing_sigma


def _with_noise(runs: list, params: dict[str, dict[str, Any]], noise: float, fit_noise: float | None = None,
                bearing_noise: float | None = None) -> list:
    """``runs`` with every extractor's noise fields set to ``noise`` (m), its fit-scatter fields
    to ``fit_noise`` (m) and its bearing-noise fields to ``bearing_noise`` (rad; each when given),
    except those the caller set in ``params``: a field the caller set replaces that field alone
    (``--set extractor.sensor.sigma_r=X`` once dropped the log's bearing noise as well, and on a
    cm-mode log, where sigma_r is not read, that was its only effect)."""
    out = []
    for name, fn, cfg in runs:
        fields = {f.name for f in dataclasses.fields(cfg)}
        given = params.get(name, {})
        noise_params: dict[str, Any] = {f: noise for f in NOISE_FIELDS if f in fields and f not in given}
        if fit_noise is not None:
            noise_params.update({f: fit_noise for f in FIT_NOISE_FIELDS if f in fields and f not in given})
        if bearing_noise is not None:
            noise_params.update({f: bearing_noise for f in BEARING_NOISE_FIELDS if f in fields and f not in given})
        out.append((name, fn, dataclasses.replace(cfg, **noise_params) if noise_params else cfg))
    return out


def source_noise(src: Source) -> dict[str, dict[str, Any]]:
    """The noise each method ran with on ``src`` (after :func:`compare`): ``{method: {field:
    value}}`` of its noise fields (range noise, fit scatter, bearing noise), those it read alone:
    the sensor method's range noise of the mode of the source's scans (``sigma_r_cm`` for cm-mode
    scans, ``sigma_r`` for mm-mode ones), and a ``sigma_fit`` of None (as ``sigma``) as the value
    it stood for. What compare's config.yaml records per source (``ran_with``)."""
    out: dict[str, dict[str, Any]] = {}
    for method, cfg in src.ran.items():
        values = {f.name: getattr(cfg, f.name) for f in dataclasses.fields(cfg)
                  if f.name in NOISE_FIELDS + FIT_NOISE_FIELDS + BEARING_NOISE_FIELDS}
        if hasattr(cfg, "noise_field") and src.range_maxes:  # sigma_r / sigma_r_cm: the one each scan reads
            read = {cfg.noise_field(r) for r in src.range_maxes}
            values = {f: v for f, v in values.items() if f not in ("sigma_r", "sigma_r_cm") or f in read}
        if values.get("sigma_fit", 0.0) is None and "sigma" in values:
            values["sigma_fit"] = values["sigma"]
        out[method] = {f: plain_data(v) for f, v in values.items()}
    return out


def _realdata_row(fs: Any, rec: Record, src: Source, sigma_r: float, cfg: RealDataConfig,
                  previous: dict[str, tuple[np.ndarray, Pose2D]], method: str) -> dict[str, Any]:
    """The measures without ground truth of one method on one scan (see :func:`compare`)."""
    lines = fs.line_array()
    m = scan_measures(lines, rec.scan, sigma_r, cfg)
    found = in_view = float("nan")
    pose = src.pose_of(rec) if src.pose_of is not None else None
    if pose is not None:
        if method in previous:
            prev_lines, prev_pose = previous[method]
            found, in_view = repeat_counts(prev_lines, prev_pose, lines, pose, rec.scan, cfg)
        previous[method] = (lines, pose)
    return dict(sigma_r=sigma_r, explained_3cm=m.explained_tol, explained_3sigma=m.explained_sigma,
                n_explained_3cm=m.n_explained_tol, ray_rmse=m.ray_rmse_m, mean_segment_m=m.mean_segment_m,
                repeat_found=found, repeat_in_view=in_view)


def _truth_row(truth: Any, scan: Any, sigma_r: float, cfg: RealDataConfig) -> dict[str, Any]:
    """The measures without ground truth of the exact lines of a simulated scan (its visible
    faces, :func:`features.realdata.truth_lines`): what an extractor that found every face exactly
    would score, the reference for the methods' explained fraction and ray RMSE."""
    m = scan_measures(truth_lines(truth), scan, sigma_r, cfg)
    return dict(truth_explained_3cm=m.explained_tol, n_truth_explained_3cm=m.n_explained_tol,
                truth_ray_rmse=m.ray_rmse_m)


def _score_row(s) -> dict[str, Any]:
    rho_mean, rho_rms = _errors(s.rho_errors)
    alpha_mean, alpha_rms = _errors(s.alpha_errors)
    return dict(
        n_truth=s.n_truth, tp=s.tp, fp=s.fp, fn=s.fn, precision=s.precision, recall=s.recall, f1=s.f1,
        rho_err_mean=rho_mean, rho_err_rms=rho_rms, alpha_err_mean=alpha_mean, alpha_err_rms=alpha_rms,
        endpoint_err_mean=float(np.mean(s.endpoint_errors)) if s.tp else float("nan"),
        n_truth_corners=s.corner_tp + s.corner_fn, corner_tp=s.corner_tp, corner_fp=s.corner_fp,
        corner_fn=s.corner_fn,
        corner_err_mean=float(np.mean(s.corner_errors)) if s.corner_tp else float("nan"),
    )


def _weighted(values: pd.Series, weights: pd.Series) -> float:
    ok = values.notna() & (weights > 0)
    return float((values[ok] * weights[ok]).sum() / weights[ok].sum()) if ok.any() else float("nan")


#: the columns of compare's table that summarise reads from every one it is given
SUMMARISED = ("source", "method", "kind", "seed", "n_lines", "explained", "range_rms", "microseconds")


def summarise(table: pd.DataFrame, reference: str = "sensor") -> pd.DataFrame:
    """One row per source x method: counts pooled over scans and seeds (micro-averaged precision,
    recall, F1), error bias and RMS pooled over matched lines (rho in mm, alpha in deg), corner
    scores, mean explained fraction, time per scan (mean and median, microseconds), scans per
    second and ``speed_vs_sensor`` = the reference method's time / this method's (above 1 =
    faster than the reference; nan when the reference did not run). Both rates use the median
    time: on a shared machine a pre-empted call can take 100 times the usual, which swamps a mean.
    ``cpu_us_median`` and ``cpu_speed_vs_sensor`` are the same from CPU time: under load a call
    longer than the scheduler's slice is pre-empted more often, which wall time penalises.
    ``time_ms_p05`` / ``_p25`` / ``_median`` / ``_p75`` / ``_p95``: quantiles of the wall time per
    scan in ms (the figures' error bars).

    Raises:
        InputError: a ``table`` that is no DataFrame with :data:`SUMMARISED`, the columns of :func:`compare` it
            reads (a list was an AttributeError, another table a KeyError naming one column).
    """
    if not isinstance(table, pd.DataFrame):
        raise InputError(f"table: must be compare()'s table (a pandas DataFrame), got {type(table).__name__}")
    missing = [c for c in SUMMARISED if c not in table.columns]
    if missing:
        raise InputError(f"table: lacks compare()'s column(s) {', '.join(missing)}: summarise reads the table compare() "
                         "returns")
    out = []
    for (source, method), g in table.groupby(["source", "method"], sort=False):
        row: dict[str, Any] = dict(source=source, method=method, kind=g["kind"].iloc[0], scans=len(g),
                                   backend=g["backend"].iloc[0] if "backend" in g else "numpy",
                                   seeds=g["seed"].nunique(), lines_per_scan=g["n_lines"].mean())
        if "tp" in g and g["tp"].notna().any():
            tp, fp, fn = (int(g[c].sum()) for c in ("tp", "fp", "fn"))
            p, r, f = prf(tp, fp, fn)
            ctp, cfp, cfn = (int(g[c].sum()) for c in ("corner_tp", "corner_fp", "corner_fn"))
            cp, cr, cf = prf(ctp, cfp, cfn)
            w = g["tp"]
            row.update(
                tp=tp, fp=fp, fn=fn, precision=p, recall=r, f1=f,
                rho_bias_mm=1e3 * _weighted(g["rho_err_mean"], w),
                rho_rms_mm=1e3 * np.sqrt(_weighted(g["rho_err_rms"] ** 2, w)),
                alpha_bias_deg=np.rad2deg(_weighted(g["alpha_err_mean"], w)),
                alpha_rms_deg=np.rad2deg(np.sqrt(_weighted(g["alpha_err_rms"] ** 2, w))),
                endpoint_err_mm=1e3 * _weighted(g["endpoint_err_mean"], w),
                corner_precision=cp, corner_recall=cr, corner_f1=cf,
                corner_err_mm=1e3 * _weighted(g["corner_err_mean"], g["corner_tp"]),
            )
        row.update(explained=g["explained"].mean(), range_rms_mm=1e3 * g["range_rms"].mean(),
                   us_mean=g["microseconds"].mean(), us_median=g["microseconds"].median())
        if "explained_3cm" in g:
            row.update(_realdata_summary(g))
        if "cpu_microseconds" in g:
            row["cpu_us_median"] = g["cpu_microseconds"].median()
        row["scans_per_s"] = 1e6 / row["us_median"]
        ms = g["microseconds"] / 1e3
        for q, label in ((0.05, "p05"), (0.25, "p25"), (0.5, "median"), (0.75, "p75"), (0.95, "p95")):
            row[f"time_ms_{label}"] = float(ms.quantile(q))
        out.append(row)
    summary = pd.DataFrame(out)
    if summary.empty:
        return summary
    ref = summary[summary["method"] == reference].set_index("source")["us_median"]
    summary["speed_vs_sensor"] = summary["source"].map(ref) / summary["us_median"]
    if "cpu_us_median" in summary:
        ref = summary[summary["method"] == reference].set_index("source")["cpu_us_median"]
        summary["cpu_speed_vs_sensor"] = summary["source"].map(ref) / summary["cpu_us_median"]
    return summary


def _realdata_summary(g: pd.DataFrame) -> dict[str, Any]:
    """Pooled measures without ground truth of one source x method: mean explained fractions over
    scans, ray RMSE pooled over the explained beams (mm), mean segment length over all lines (m),
    repeatability = lines found again / lines still in view (nan without trusted poses); on
    simulated sources also the exact lines' explained fraction and ray RMSE (``truth_explained_3cm``,
    ``truth_ray_rmse_mm``, the same for every method of a source)."""
    ray = _pooled_rms(g["ray_rmse"], g["n_explained_3cm"])
    lines = g["n_lines"].astype(float)
    seg_ok = g["mean_segment_m"].notna() & (lines > 0)
    seg = float((g["mean_segment_m"][seg_ok] * lines[seg_ok]).sum() / lines[seg_ok].sum()) if seg_ok.any() else float("nan")
    in_view = g["repeat_in_view"].sum(min_count=1)
    repeat = float(g["repeat_found"].sum() / in_view) if pd.notna(in_view) and in_view > 0 else float("nan")
    out = dict(sigma_r_mm=1e3 * g["sigma_r"].iloc[0], explained_3cm=g["explained_3cm"].mean(),
               explained_3sigma=g["explained_3sigma"].mean(), ray_rmse_mm=1e3 * ray, mean_segment_m=seg,
               repeatability=repeat)
    if "truth_ray_rmse" in g and g["truth_ray_rmse"].notna().any():  # simulated: the exact lines' scores
        out.update(truth_explained_3cm=g["truth_explained_3cm"].mean(),
                   truth_ray_rmse_mm=1e3 * _pooled_rms(g["truth_ray_rmse"], g["n_truth_explained_3cm"]))
    return out


def _pooled_rms(rms: pd.Series, weights: pd.Series) -> float:
    """The RMS of the pooled values whose per-scan RMS and counts are given (nan when none)."""
    w = weights.astype(float)
    ok = rms.notna() & (w > 0)
    return float(np.sqrt((rms[ok] ** 2 * w[ok]).sum() / w[ok].sum())) if ok.any() else float("nan")


def common_errors(matches: pd.DataFrame) -> pd.DataFrame:
    """Errors on the faces every method matched (per source): the like-for-like accuracy, since a
    method that finds more (harder: far, short, grazing) faces pools larger errors. One row per
    source x method: n_common, rho_rms_common_mm, alpha_rms_common_deg."""
    cols = ["source", "method", "n_common", "rho_rms_common_mm", "alpha_rms_common_deg"]
    if matches.empty:
        return pd.DataFrame(columns=cols)
    out = []
    key = ["seed", "scan", "face"]
    for source, g in matches.groupby("source", sort=False):
        n_methods = g["method"].nunique()
        seen = g.groupby(key)["method"].nunique()
        common = seen[seen == n_methods].index
        c = g.set_index(key).loc[lambda d: d.index.isin(common)]
        for method, h in c.groupby("method", sort=False):
            out.append(dict(source=source, method=method, n_common=len(h),
                            rho_rms_common_mm=1e3 * float(np.sqrt(np.mean(h["rho_err"] ** 2))),
                            alpha_rms_common_deg=float(np.rad2deg(np.sqrt(np.mean(h["alpha_err"] ** 2))))))
    return pd.DataFrame(out, columns=cols)


def format_summary(summary: pd.DataFrame) -> str:
    """The summary as a fixed-width text table (the columns that exist)."""
    cols = ["source", "method", "backend", "scans", "f1", "precision", "recall", "rho_bias_mm", "rho_rms_mm",
            "alpha_bias_deg", "alpha_rms_deg", "rho_rms_common_mm", "alpha_rms_common_deg", "corner_precision", "corner_recall", "corner_err_mm",
            "explained", "range_rms_mm", "sigma_r_mm", "explained_3cm", "explained_3sigma", "ray_rmse_mm",
            "truth_explained_3cm", "truth_ray_rmse_mm",
            "lines_per_scan", "mean_segment_m", "repeatability", "us_median", "scans_per_s", "speed_vs_sensor", "cpu_us_median",
            "cpu_speed_vs_sensor"]
    cols = [c for c in cols if c in summary]
    text = summary[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}", na_rep="-")
    if "backend" in summary and summary["backend"].nunique() > 1:
        mixed = ", ".join(f"{m}={b}" for m, b in summary.drop_duplicates("method")[["method", "backend"]].values)
        text += (f"\nnote: the methods ran on different backends ({mixed}; numba = compiled kernels, numpy = "
                 "vectorised numpy): speed ratios between different backends are not like for like")
    return text


#: the range noise fields of a method's config, as format_ran_with shows them
RANGE_NOISE_FIELDS = ("sigma", "sigma_r", "sigma_r_cm")


def format_ran_with(ran_with: dict[str, dict[str, dict[str, Any]]]) -> str:
    """The range noise each method ran with on each source (config.yaml's ``ran_with``), for
    summary.txt: a line per source, each method's range noise field and value in mm (``sensor
    sigma_r_cm=9.47`` on cm-mode scans, ``split_merge sigma=9.47``), ``-`` for a method with no such
    field (a user's extractor without a config_type). A value that is not a number (``auto``) as it is."""
    def mm(value: Any) -> str:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return f"{value * 1000:.3g}"
        return str(value)

    width = max((len(source) for source in ran_with), default=0)
    lines = ["range noise each method ran with (mm; config.yaml's ran_with has every noise field):"]
    for source, methods in ran_with.items():
        said = []
        for method, fields in methods.items():
            noise = [f"{f}={mm(fields[f])}" for f in RANGE_NOISE_FIELDS if f in fields]
            said.append(f"{method} {' '.join(noise) if noise else '-'}")
        lines.append(f"  {source:{width}s}  {', '.join(said)}")
    return "\n".join(lines)

def plain_data(value: Any) -> Any:
    """``value`` as data ``yaml.safe_dump`` writes: mappings, lists, str, int, float (inf and nan
    kept), bool and None; numpy scalars and arrays as Python's, any other object as its repr."""
    if isinstance(value, dict):
        return {str(k): plain_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain_data(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain_data(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    return repr(value)


def resolved_configs(methods: Sequence[str], params: dict[str, dict[str, Any]] | None = None) -> dict[str, Any]:
    """Each method's full config as plain data (saved beside the results as YAML: numpy values as
    Python's, other objects as their repr).

    Raises:
        LmsbenchError: an override of a value that cannot work (``rho_step=0``, ``k="abc"``)."""
    params = params or {}
    out = {}
    for m in methods:
        _check_types(m, params.get(m, {}))
        try:
            # a user's config with np.deg2rad(20) as a default failed yaml.safe_dump: internal error, exit 1
            out[m] = plain_data(dataclasses.asdict(make_config(m, **params.get(m, {}))))
        except ConfigError as exc:  # "min_points: ..." named no method: extractor.min_points goes to several
            raise ConfigError(f"{m}: {exc}") from None
        except LmsbenchError:
            raise
        except (ValueError, TypeError) as exc:
            raise LmsbenchError(f"{m}: {' '.join(str(exc).split())}") from None
    return out
