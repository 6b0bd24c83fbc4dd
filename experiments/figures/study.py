"""The study behind the figures and the demo: simulate, extract, score, SLAM -> tidy tables.

:func:`run_study` computes every table (see :mod:`experiments.figures.tables` for schemas) and
:func:`save_tables` writes them as Parquet with the resolved settings as YAML beside them; the
figures are then drawn from those files alone (:mod:`experiments.figures.make`).
"""

from __future__ import annotations

from lms200.angles import wrap
from lms200.yamlio import load as load_yaml, dump as dump_yaml

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd
import yaml

from experiments.sweep.kinds import align, slam_metrics, true_trajectory
from experiments.compare import Source, compare, summarise
from experiments.evaluate import ALL_METHODS, extract_timed, sensor_config, simulate_run, truths_for
from experiments.user_methods import scans_of
from experiments.provenance import read_parquet
from lms200.finite import printable

from .tables import feature_panels, map_table, pick_evenly, signals_table, trajectory_table

INTEL_LOG = Path(__file__).resolve().parents[3] / "shared" / "data" / "carmen" / "intel-corrected.log.gz"


@dataclass
class StudyConfig:
    """Settings of one study. Times in s of simulated time, rates in scans/s."""

    world: str = "office"
    seed: int = 0
    duration: float = 40.0  # simulated run for the comparison and the SLAM
    rate_hz: float = 10.0  # scans kept per second of the run (the LMS200 gives 37.5)
    methods: tuple[str, ...] = ALL_METHODS
    signals_k: int = 10  # the paper's AD_i10
    panels: int = 4  # scans shown in Fig. 9, per source
    slam: bool = True
    intel_log: str | None = str(INTEL_LOG)  # skipped with a note where absent
    # the paper's extractor on the Intel log: cm-mode ranges (1 cm codes), so a larger range noise
    intel_sensor_params: dict = field(default_factory=dict)  # extractor overrides for the Intel panels (default: none)
    sensor: dict = field(default_factory=dict)  # SensorConfig overrides
    log_options: dict = field(default_factory=dict)  # read_log keywords for intel_log (plain data, see logargs)

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["methods"] = list(self.methods)
        return d


Log = Callable[[str], None]


def check_study(cfg: StudyConfig, flags: tuple[str, str] = ("--duration", "--rate-hz"), hint: str = "") -> None:
    """Refuse, before any work, a rate above the sensor's scan rate, and a study whose simulated run
    keeps fewer than the two scans the SLAM (Fig. 10) needs: ``figures --duration 0.5 --rate-hz 2`` (one scan) and the demo ran the whole
    comparison first, then stopped with "internal error: ValueError: ate: fewer than 2 estimated
    poses". ``flags``: the options that set the duration and the rate, for the message; ``hint``:
    another way out (``, or --no-slam``).

    Raises:
        InputError: naming the options and the scans kept.
    """
    from lms200.errors import InputError
    from lms200.timing import check_scan_rate
    from sim.records import scan_stamps

    sensor = sensor_config(cfg.sensor)
    # a rate above the sensor's (--rate-hz 1e9) was refused only once the simulation began, after the
    # Intel log's panels, with or without the SLAM; the demo left its --out folder behind, empty
    check_scan_rate(cfg.rate_hz, sensor.angle_increment, flags[1])
    if not cfg.slam:
        return
    kept = len(scan_stamps(sensor, cfg.duration, cfg.rate_hz))
    if kept < 2:
        raise InputError(f"{flags[0]} {cfg.duration:g} at {flags[1]} {cfg.rate_hz:g} keeps {kept} scan(s) of the simulated "
                         f"run; the SLAM (Fig. 10) needs two or more (a longer run or a higher rate{hint})")


def run_study(cfg: StudyConfig, log: Log = print) -> tuple[dict[str, pd.DataFrame], list[str]]:
    """Every table of the figures and the report; and notes on anything skipped."""
    check_study(cfg, ("duration", "rate_hz"))
    t0 = time.perf_counter()
    say = lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")  # noqa: E731
    tables: dict[str, pd.DataFrame] = {}
    notes: list[str] = []
    from experiments.progress import warm_up_kernels

    # the SLAM's kernels too: the demo's first report timed the default pipeline with their compile
    # (5.9 s for 375 scans, 7x the paper preset's, where warm it is 0.3 s, 3x faster)
    warm_up_kernels(log=say, slam=cfg.slam)
    panel_method = panel_method_of(cfg)
    # the real log first: one it cannot draw is refused before the simulation and comparison
    intel = Path(cfg.intel_log) if cfg.intel_log else None
    if intel is not None and intel.exists():
        tables.update(_intel_panels(intel, cfg.panels, panel_method,
                                    cfg.intel_sensor_params if panel_method == "sensor" else None, cfg.log_options))
        say(f"{log_name(intel)} log: {cfg.panels} scans with features")
    else:
        notes.append(f"{INTEL_SKIPPED} {intel} is not present on this machine.")
        say(notes[-1])
    sensor = sensor_config(cfg.sensor)
    world, records = simulate_run(cfg.world, cfg.seed, cfg.duration, sensor, cfg.rate_hz)
    say(f"simulated {cfg.world} (seed {cfg.seed}): {len(records)} scans over {cfg.duration:g} s at {cfg.rate_hz:g} Hz")
    truths = truths_for(world, records, sensor)
    say(f"ground truth of {len(records)} scans")

    tables["signals"] = signals_table(records[len(records) // 2].scan, k=cfg.signals_k, sigma_r=sensor.noise_sigma or 0.005)
    noise = max(float(sensor.noise_sigma), 0.001)
    run_name = f"{cfg.world}:{cfg.seed}"  # how an error of a user's MODULE:FUNCTION extractor names the run
    with scans_of(run_name, records):
        tables["timing"] = compare([Source.from_records(records, truths, seed=cfg.seed)], cfg.methods, sigma=noise)
    tables["summary"] = summarise(tables["timing"])
    for row in tables["summary"].itertuples():
        say(f"{row.method:12s} median {row.time_ms_median:7.2f} ms/scan, line F1 {row.f1:.3f}, "
            f"{row.lines_per_scan:.1f} lines/scan")

    picks = pick_evenly(len(records), cfg.panels)
    with scans_of(run_name, records):
        fsets, _ = extract_timed([records[i].scan for i in picks], panel_method)
    pts, lns, crs = feature_panels([records[i].scan for i in picks], [f"{cfg.world} scan {i}" for i in picks], fsets)
    tables.update(office_points=pts, office_lines=lns.assign(method=panel_method), office_corners=crs)

    if cfg.slam:
        from slam import SlamConfig, run_slam

        rows, trajs, maps = [], {}, {}
        for name, preset in (("default", "default"), ("paper preset", "paper")):
            start = time.process_time()
            result = run_slam(records, SlamConfig(preset=preset))
            slam_s = time.process_time() - start
            metrics = slam_metrics(result, records)
            trajs[name], maps[name] = _slam_in_world(result, records)
            rows.append({
                "preset": name, "scans": len(records), "ate_rms_m": metrics["ate_rms"], "ate_max_m": metrics["ate_max"],
                "heading_rms_deg": float(np.degrees(metrics["heading_rms"])), "final_error_m": metrics["final_error_m"],
                "map_lines": int(metrics["n_map_lines"]), "diverged": bool(metrics["diverged"]), "cpu_time_s": slam_s,
                "time_per_scan_ms": 1e3 * slam_s / max(1, len(records))})
            say(f"SLAM ({name}): {len(records)} scans in {slam_s:.1f} s of CPU time, ATE {metrics['ate_rms']:.3f} m, "
                f"{int(metrics['n_map_lines'])} map lines")
        tables["trajectory"] = trajectory_table(trajs["default"], records, {"paper preset": trajs["paper preset"]})
        tables["map"] = map_table(maps["default"], world.walls, {"paper preset": maps["paper preset"]})
        tables["slam_metrics"] = pd.DataFrame(rows)
    return tables, notes


def save_tables(tables: dict[str, pd.DataFrame], cfg: StudyConfig, notes: list[str], folder: Path) -> None:
    """The settings (study.yaml), Parquet per table and the notes (notes.txt). The settings first,
    whole: they tell the demo's folder as its own (options.DEMO_OWNER), and a demo stopped among
    its tables left Parquet files without them, which the next demo into the folder refused."""
    from experiments.compare import resolved_configs
    from experiments.provenance import versions, write_parquet, write_record

    settings = cfg.to_dict()
    settings["resolved"] = {"sensor": dataclasses.asdict(sensor_config(cfg.sensor)),
                            "extractors": resolved_configs(cfg.methods), "versions": versions()}
    if cfg.slam:
        from slam import SlamConfig

        settings["resolved"]["slam"] = dataclasses.asdict(SlamConfig())
    write_record(folder / "study.yaml", dump_yaml(settings, sort_keys=False))
    for name, table in tables.items():  # each whole: a full disk left a cut table or notes.txt
        write_record(folder / f"{name}.parquet", lambda p, table=table: write_parquet(table, p))
    write_record(folder / "notes.txt", "\n".join(notes) + ("\n" if notes else ""))  # UTF-8, read back by --tables


#: how a study's note says the Intel panels were not made (run_study; figures --tables reads it back)
INTEL_SKIPPED = "Fig. 9 (Intel log) skipped:"


#: the tables a study saves (run_study): a CSV of one of these names in a tables folder is refused, not left out
STUDY_TABLE_NAMES = ("signals", "timing", "summary", "office_points", "office_lines", "office_corners", "intel_points",
                     "intel_lines", "intel_corners", "trajectory", "map", "slam_metrics")


def load_tables(folder: Path) -> tuple[dict[str, pd.DataFrame], list[str]]:
    """The tables and notes saved by :func:`save_tables`."""
    from lms200 import LmsbenchError

    for p in sorted(folder.glob("*.parquet")):  # pyarrow reads a folder as a dataset: an empty one was no table
        if not p.is_file():  # and its figures were left out, exit 0 (a damaged-input fuzz round)
            raise LmsbenchError(f"{p}: {'a folder' if p.is_dir() else 'not a regular file'} where a table of the study "
                                "goes; a table is a Parquet file")
    for p in sorted(folder.glob("*.csv")):  # a table saved as CSV was left out, its figures not drawn, exit 0
        if (folder / f"{p.stem}.parquet").exists() or p.stem not in STUDY_TABLE_NAMES:
            continue
        raise LmsbenchError(f"{p}: the study's tables are read as Parquet ({p.stem}.parquet, as `lmsbench figures` and "
                            "`lmsbench demo` save them), not CSV")
    tables = {p.stem: read_table(p) for p in sorted(folder.glob("*.parquet"))}
    notes_file = folder / "notes.txt"
    if notes_file.exists() and not notes_file.is_file():  # a named pipe was waited on for ever (the wrong-input hunt)
        raise LmsbenchError(f"{notes_file}: not a regular file (a pipe, a device or a socket); a study's notes are "
                            "a text file")
    try:
        notes = notes_file.read_text(encoding="utf-8").splitlines() if notes_file.exists() else []
    except UnicodeDecodeError as exc:  # was "internal error: UnicodeDecodeError"
        raise LmsbenchError(f"{notes_file}: not UTF-8 text (byte {exc.start}); a study's notes are a text file") from None
    return tables, notes


def read_table(path: Path) -> pd.DataFrame:
    """One saved table; a damaged or foreign file is an LmsbenchError naming it (pyarrow raises
    ArrowInvalid, an OSError or a ValueError)."""
    from lms200 import LmsbenchError

    try:
        table = read_parquet(path)
    except (OSError, ValueError) as exc:
        raise LmsbenchError(f"{path}: not a readable parquet table ({' '.join(str(exc).split())[:200]})") from None
    return check_table(table, path)


def check_table(table: pd.DataFrame, path: Path) -> pd.DataFrame:
    """``table``, read from ``path``, when the figures can draw it (plain column names, magnitudes within
    MAX_TABLE_VALUE), else an LmsbenchError naming ``path``: :func:`read_table`'s checks, for a table
    read already (a sweep's, by ``options.read_sweep_results``)."""
    from lms200 import LmsbenchError

    odd = [c for c in table.columns if not isinstance(c, str)]
    if odd:  # levels of columns (a MultiIndex) were "internal error: AttributeError: 'DataFrame' object has no attribute 'dtype'"
        raise LmsbenchError(f"{path}: its column {odd[0]!r} is no plain name (a table of named columns, one level, "
                            "as `lmsbench figures` saves them)")
    for column in table.columns:
        values = table[column]
        if not pd.api.types.is_float_dtype(values):  # int64 stays below 1e19; text and booleans are no magnitudes
            continue
        numbers = values.to_numpy(dtype=float, na_value=np.nan)
        big = np.isfinite(numbers) & (np.abs(numbers) > MAX_TABLE_VALUE)  # nan and inf: said where a figure needs them
        if big.any():  # +-1e308 was "internal error: ValueError: Axis limits cannot be NaN or Inf", 1e308 alone a figure
            row = int(np.argmax(big))  # drawn under matplotlib's overflow warnings, exit 0 (a damaged-input round)
            raise LmsbenchError(f"{path}: its column {column} holds {float(values.iloc[row]):g} (row {row}), beyond "
                                f"+-{MAX_TABLE_VALUE:g}, where its plot's axis arithmetic would overflow: the figures "
                                "cannot draw it (lmsbench's own tables hold stamps below 2^32 s and coordinates within "
                                "1e9 m: a damaged or edited table, or a sweep's parameter or metric that large)")
    return table


#: largest magnitude of a finite number in a table the figures are drawn from (:func:`read_table`): no
#: quantity lmsbench writes comes near it, and squared (a std over seeds) or scaled to degrees it stays finite
MAX_TABLE_VALUE = 1e100


def panel_method_of(cfg: StudyConfig) -> str:
    """The method whose features Fig. 9 draws: the sensor method when the study runs it, else its first."""
    return "sensor" if "sensor" in cfg.methods else cfg.methods[0]


def check_panel_log(cfg: StudyConfig) -> None:
    """Refuse, before any output, a Fig. 9 log that does not read, or holds no scan with a valid
    beam: it is read with the study's log options up to its first scan with one (a file that is not
    a log fails on its first lines). ``demo --log run/groundtruth.tum`` made the run folder and
    moved ``results/demo/latest`` to it, empty, before the study refused the file; a log of only
    +inf / nan readings still left the run folder (or ``--out``) behind, empty (the wrong-input hunt).
    Its first scan's beam step is one the panels' method segments (``features.registry.check_step``,
    compare's message): ``figures --methods split_merge --log`` a 12-deg log drew Fig. 9's real-log
    panels with no line, exit 0. The read's warnings are the study's to say, as it reads the log again: a
    log refused here is its error alone (a log in millimetres said the units warning, then this error; the
    error says the units)."""
    import warnings

    from lms200 import LmsbenchError, read_log
    from lms200.units import UnitsTally

    from features.registry import check_step, make_config

    from experiments.logargs import log_options_from_plain

    if cfg.intel_log is None or not Path(cfg.intel_log).exists():
        return
    path = Path(cfg.intel_log)
    records = iter(read_log(path, **log_options_from_plain(cfg.log_options)))
    method = panel_method_of(cfg)
    n = 0
    units = UnitsTally()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # every category: the study reads the log again and says them
            for record in records:  # the first scan of a log has a valid beam but for a damaged one: no second pass
                if n == 0:
                    check_step(make_config(method, **(cfg.intel_sensor_params if method == "sensor" else {})),
                               record.scan.angle_increment, method, f"{path}: scan 0")
                n += 1
                if record.scan.valid.any():
                    return
                units.add(record.scan)  # every scan read, none held
    finally:
        close = getattr(records, "close", None)  # a generator's: its file is closed now, not when collected
        if close is not None:
            close()
    if n == 0:
        raise LmsbenchError(f"{path}: no laser scans found")
    mm = units.evidence()  # the reader's units warning, ignored above: the error says it
    if mm is not None:
        raise LmsbenchError(f"{path}: none of its {n} scans has a valid beam, no scan to draw for Fig. 9: {mm}")
    raise LmsbenchError(f"{path}: none of its {n} scans has a valid beam (all +inf, nan or 0): no scan to draw for "
                        "Fig. 9")


def _intel_panels(path: Path, n: int, method: str, params: dict | None,
                  log_options: dict | None = None) -> dict[str, pd.DataFrame]:
    from lms200 import read_log

    from experiments.logargs import log_options_from_plain, report_skipped

    reader = read_log(path, **log_options_from_plain(log_options))
    records = list(reader)
    report_skipped(reader)
    from lms200 import LmsbenchError

    if not records:
        raise LmsbenchError(f"{path}: no laser scans found")
    valid = [i for i, r in enumerate(records) if r.scan.valid.any()]  # an empty panel drew nothing
    if not valid:  # was "internal error: ZeroDivisionError" when drawing, after the whole study
        raise LmsbenchError(f"{path}: none of its {len(records)} scans has a valid beam (all +inf, nan or 0): "
                            "no scan to draw for Fig. 9")
    picks = [valid[i] for i in pick_evenly(len(valid), n)]
    scans = [records[i].scan for i in picks]
    with scans_of(str(path), records):
        fsets, _ = extract_timed(scans, method, params)
    pts, lns, crs = feature_panels(scans, [f"{log_name(path)} scan {i}" for i in picks], fsets)
    return {"intel_points": pts, "intel_lines": lns.assign(method=method), "intel_corners": crs}


def log_name(path: Path) -> str:
    """How Fig. 9's real-log panels name their log: "Intel" for the Intel log (the default),
    else the file's name (`demo --log` / `figures --intel` take any log; every label said Intel)."""
    return "Intel" if Path(path).name == INTEL_LOG.name else printable(Path(path).name)


def _slam_in_world(result, records) -> tuple[np.ndarray, np.ndarray]:
    """The SLAM trajectory (n, 4) and map segments (k, 4) moved into the world frame by the same
    2-D alignment the ATE uses (the SLAM's frame is that of its first pose)."""
    from slam import metrics

    est = np.asarray(result.trajectory, float)
    ate = metrics.ate(est, true_trajectory(records))
    traj = est.copy()
    traj[:, 1:3] = align(est[:, 1:3], ate.rotation, ate.translation)
    traj[:, 3] = wrap(est[:, 3] + ate.rotation)
    lines = np.asarray(result.map_lines, float).reshape(-1, 7)
    segs = np.column_stack((align(lines[:, 2:4], ate.rotation, ate.translation),
                            align(lines[:, 4:6], ate.rotation, ate.translation)))
    return traj, segs


#: largest AD window of a study's signals (Figs. 4-6): half a scan of the extractors' most beams
MAX_SIGNALS_K = 1 << 13


def load_config(folder: Path) -> StudyConfig:
    """The settings saved beside the tables (defaults where there is no study.yaml)."""
    from lms200 import LmsbenchError

    from lms200.yamlio import size_problem

    path = folder / "study.yaml"
    too_big = size_problem(path.stat().st_size, "a study.yaml", "lmsbench figures writes a few KB") if path.is_file() else None
    if too_big:  # read whole and parsed, a 30 MB one took 10 s before its error
        raise LmsbenchError(f"{path}: {too_big}")
    try:
        raw = load_yaml(path.read_text()) if path.exists() else {}
        if not isinstance(raw or {}, dict):
            raise TypeError("expected a mapping of the study's settings")
        known = {f.name for f in dataclasses.fields(StudyConfig)}
        cfg = StudyConfig(**{k: v for k, v in (raw or {}).items() if k in known})
        _check_settings(cfg, raw or {})
        cfg.methods = tuple(cfg.methods)
        # what the figures draw with: a text signals_k or world was "internal error: TypeError", a huge k a
        # MemoryError, a negative one drew Fig. 4's reference line and labels of AD_i-5, exit 0
        if isinstance(cfg.signals_k, bool) or not isinstance(cfg.signals_k, int) or not 1 <= cfg.signals_k <= MAX_SIGNALS_K:
            raise ValueError(f"signals_k: must be a whole number from 1 to {MAX_SIGNALS_K}, the AD window of Figs. 4-6 "
                             f"(got {cfg.signals_k!r})")
        if not isinstance(cfg.world, str):
            raise ValueError(f"world: must be the name of the simulated world (got {cfg.world!r})")
    except (yaml.YAMLError, TypeError, ValueError, UnicodeDecodeError) as exc:
        raise LmsbenchError(f"{path}: not the study.yaml of lmsbench figures / demo ({' '.join(str(exc).split())[:200]})") from None
    return cfg


def _check_settings(cfg: StudyConfig, raw: dict) -> None:
    """Refuse (ValueError naming the field) a study.yaml field that is not what a study writes: a text
    seed, a negative duration, a ``slam: "no"`` (taken as true: Fig. 10's table said missing) or a list
    for a mapping was taken without a word, exit 0. The bounds are what ``run_study`` itself takes
    (a world by name or world.json path, any seed from 0, a positive duration and rate), not the
    command line's narrower ones: a study run from Python with ``seed=2**40`` draws (review)."""
    import math

    from sim.worlds import WORLD_NAMES

    from experiments.figures.make import MAX_PANELS

    def whole(value: object) -> bool:
        return isinstance(value, int) and not isinstance(value, bool)

    def real(value: object) -> bool:
        return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)

    if not isinstance(cfg.world, str):
        return  # said as before, below
    problems = [
        ("world", bool(cfg.world.strip()), f"a built-in world's name ({', '.join(WORLD_NAMES)}) or a world.json path"),
        ("seed", whole(cfg.seed) and cfg.seed >= 0, "a whole number from 0"),
        ("duration", real(cfg.duration) and cfg.duration > 0, "a positive number of seconds"),
        ("rate_hz", real(cfg.rate_hz) and cfg.rate_hz > 0, "a positive number of scans/s"),
        ("methods", isinstance(cfg.methods, (list, tuple)) and len(cfg.methods) > 0
         and all(isinstance(m, str) and m.strip() for m in cfg.methods), "a list of extractor names"),
        ("panels", whole(cfg.panels) and 1 <= cfg.panels <= MAX_PANELS, f"a whole number from 1 to {MAX_PANELS}"),
        ("slam", isinstance(cfg.slam, bool), "true or false"),
        ("intel_log", cfg.intel_log is None or isinstance(cfg.intel_log, str), "a log's path or null"),
    ]
    problems += [(name, isinstance(raw.get(name, {}), dict), "a mapping")
                 for name in ("intel_sensor_params", "sensor", "log_options", "resolved")]
    for name, ok, what in problems:
        if not ok:
            raise ValueError(f"{name}: must be {what} (got {raw.get(name)!r:.80})")
