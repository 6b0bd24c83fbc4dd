"""`lmsbench compare`: every extractor on the same scans (simulated worlds or a real log), timed
interleaved in one process; a tidy table, a summary (printed and saved) and the resolved configs."""

from __future__ import annotations

import argparse
import sys
import dataclasses
from pathlib import Path
from typing import Any

import yaml

from lms200 import LmsbenchError
from lms200.timing import check_scan_rate
from lms200.yamlio import dump as dump_yaml

from experiments.overrides import check_set_once, set_option
from experiments.logargs import add_log_options, given_log_flags, plain_log_options, read_log_options, report_skipped
from experiments.options import (WORLDS, COMPARE_FIGURES, COMPARE_OUTPUTS, COMPARE_OWNER, DURATION, FIGURE_ENDS, OutTree, recorded_names, warnings_after_checks, check_sim2real_finished, SIMULATE_OUTPUTS, listed_seed, InputError, check_methods, check_out,
                                 Underflow, check_out_spares, check_seeds, count, plain_number, path_arg, scan_rate, text)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("compare", help="every extractor on identical scans: accuracy, corners and speed")
    p.add_argument("sources", nargs="+",
                   help="world names (" + WORLDS + "; WORLD:SEED for one seed), "
                        "`lmsbench simulate` folders, or paths of real logs")
    p.add_argument("--methods", nargs="+", type=text("an extractor's name"),
                   help="extractors: built-in names or a user's MODULE:FUNCTION, apart or comma-separated (default: every "
                        "built-in one)")
    p.add_argument("--method", dest="methods", nargs="+", type=text("an extractor's name"),
                   help="the same as --methods (`--method MODULE:FUNCTION` runs a user's extractor)")
    p.add_argument("--seeds", nargs="+", type=listed_seed, help="seeds of each world named without one, listed (default 0 1 2; "
                                                         "`--seeds 3` is the one seed 3)")
    p.add_argument("--duration", type=DURATION, help="simulated seconds per world and seed (default 30)")
    p.add_argument("--rate", "--rate-hz", dest="rate", type=scan_rate,
                   help="simulated scans per second kept (default 2; --rate-hz as in simulate, demo, figures)")
    p.add_argument("--stride", type=count(1), help="logs and simulate folders: use every STRIDE-th scan (default 1)")
    p.add_argument("--max-scans", type=count(1), help="at most this many scans per source")
    p.add_argument("--sigma", type=_sigma, default="auto",
                   help="range noise, 1 sigma (m, 0.0001 to 1000), for the 3-sigma explained fraction; 'auto' (default): the "
                        "sensor model's for worlds, estimated from the data for logs")
    p.add_argument("--poses", choices=("auto", "corrected", "none"), default=None,
                   help="logs: are the log's poses SLAM-corrected (then repeatability is measured)? "
                        "auto (default): when the file name says 'corrected' or the reader found a Radish "
                        "corrected log's anchors; corrected: always (a log without such anchors: its "
                        "odometry taken as corrected poses); none: never")
    p.add_argument("--sensor", type=path_arg, metavar="FILE.yaml",
                   help="sensor model of the simulated sources, as written (e.g. from `lmsbench calibrate`); "
                   "needs a world among the sources (logs and simulate folders carry their own)")
    p.add_argument("--set", dest="params", action="append", type=set_option, default=[], metavar="extractor.[METHOD.]FIELD=VALUE",
                   help="override a config field of every extractor that has it, or of METHOD only (repeatable)")
    p.add_argument("--out", type=path_arg, help="output folder (default: a new results/compare/DATE_TIME, "
                                            "linked as results/compare/latest)")
    p.add_argument("--format", choices=("parquet", "csv"), default="parquet", help="format of the tidy table (default parquet)")
    p.add_argument("--no-progress", "--quiet", dest="no_progress", action="store_true", help="no progress bar")
    add_log_options(p)
    p.set_defaults(func=run)


DEFAULT_SEEDS, DEFAULT_DURATION_S, DEFAULT_RATE_HZ = (0, 1, 2), 30.0, 2.0  # of the worlds compare simulates


def _check_applies(args: argparse.Namespace) -> None:
    """An option given for sources none of which it applies to was ignored: ``compare office:1
    --seeds 4 5`` ran seed 1 alone, ``compare LOG --duration 60`` read the log as before."""
    from experiments.compare import world_words
    from experiments.options import known_worlds

    bare = [s for s in args.sources if s in known_worlds()]
    worlds = world_words(args.sources)
    files = [s for s in args.sources if s not in worlds]
    if args.seeds is not None and not bare:
        raise InputError(f"--seeds sets the seeds of the worlds named without one (office); none of "
                         f"{' '.join(args.sources)} is one (WORLD:SEED names its seed; logs and simulate folders have none)")
    for flag, value in (("--duration", args.duration), ("--rate", args.rate)):
        if value is not None and not worlds:
            raise InputError(f"{flag} sets the worlds compare simulates (office, office:1, ...); none of "
                             f"{' '.join(args.sources)} is one (a log or a simulate folder has its own scans)")
    if args.stride is not None and not files:
        raise InputError(f"--stride thins logs and simulate folders; none of {' '.join(args.sources)} is one "
                         "(the worlds' scans are set by --rate)")
    if args.poses is not None and not files:
        raise InputError(f"--poses says whether a log's poses are SLAM-corrected; none of {' '.join(args.sources)} "
                         "is a log (a world's poses are its ground truth)")
    unread = given_log_flags(args)
    if unread and not files:  # they were ignored: `compare office:0 --topic FLASER --skip-bad-lines` ran, exit 0
        raise InputError(f"{', '.join(unread)} {'say' if len(unread) > 1 else 'says'} how to read a log; none of "
                         f"{' '.join(args.sources)} is one (the worlds are simulated)")
    if args.sensor is not None and not worlds:  # it was ignored: logs and simulate folders carry their own
        raise InputError("--sensor sets the sensor of the worlds compare simulates (office, office:1, ...); "
                         f"none of {' '.join(args.sources)} is one (a log or a simulate folder has its own)")


def _sigma(text: str) -> float | str:
    if text == "auto":
        return text
    try:
        value = plain_number(text)
    except Underflow as exc:
        raise argparse.ArgumentTypeError(f"--sigma takes metres or 'auto', got {text!r}: {exc}") from None
    except ValueError:
        raise argparse.ArgumentTypeError(f"--sigma takes metres or 'auto', got {text!r}") from None
    from experiments.compare import sigma_problem

    problem = sigma_problem(value)  # 1e308 overflowed in the summary; 1e-300 found no line and explained nothing, exit 0
    if problem:
        raise argparse.ArgumentTypeError(f"--sigma {problem}, got {text!r}")
    return value


def run(args: argparse.Namespace) -> int:
    import datetime

    import pandas as pd

    started = datetime.datetime.now()  # what names the run's folder (a real log's compare takes minutes)

    from experiments.compare import (check_sources, common_errors, compare, format_ran_with, format_summary,
                                     parse_sources, resolved_configs, source_label, source_noise, summarise, world_words)
    from experiments.overrides import extractor_overrides
    from experiments.progress import warm_up_kernels
    from features.scoring import ScoreConfig

    methods = check_methods(args.methods)
    check_set_once(args.params)
    params = extractor_overrides(dict(args.params), methods)
    configs = resolved_configs(methods, params)  # raises on unknown methods / fields before any work
    reads = [Path(s) / name for s in args.sources if Path(s).is_dir() for name in SIMULATE_OUTPUTS]
    reads += [Path(s) for s in args.sources if Path(s).is_file()] + ([args.sensor] if args.sensor else [])
    check_out_spares(args.out, COMPARE_OUTPUTS, reads)
    check_out(args.out, writes=COMPARE_OUTPUTS, patterns=COMPARE_FIGURES, owner=COMPARE_OWNER, default="results/compare")  # after: an input in --out is the sharper message
    _check_applies(args)
    args.seeds = args.seeds or list(DEFAULT_SEEDS)
    args.duration = args.duration or DEFAULT_DURATION_S
    args.rate = args.rate or DEFAULT_RATE_HZ
    args.stride = args.stride or 1
    args.poses = args.poses or "auto"
    check_seeds(args.seeds)
    from features.registry import check_step, make_config

    runs = {m: make_config(m, **params.get(m, {})) for m in methods}  # as compare makes them (checked above)
    check_sources(args.sources, read_log_options(args), args.seeds, runs)
    with warnings_after_checks():  # a refused run is its error alone, without a warning of what it read
        sensor = None
        if args.sensor is not None:
            import sim

            check_sim2real_finished(args.sensor, "--sensor")
            try:
                sensor = sim.SensorConfig.from_yaml(args.sensor)
            except LmsbenchError:
                raise
            except (yaml.YAMLError, TypeError, ValueError, KeyError) as exc:
                raise LmsbenchError(f"{args.sensor}: not a sensor model ({' '.join(str(exc).split())})") from None
        if world_words(args.sources):  # simulated here, at --rate
            import sim

            step = (sensor or sim.SensorConfig()).angle_increment
            check_scan_rate(args.rate, step, "--rate")
            for m, cfg in runs.items():  # the simulated scans' step, before any is simulated
                check_step(cfg, step, m, f"the simulated scans ({args.sensor or 'the default sensor'})")
    warm_up_kernels()
    sources = parse_sources(args.sources, args.seeds, args.duration, args.rate, args.stride, args.max_scans,
                            read_options=read_log_options(args), poses=args.poses, sensor=sensor)
    score_config = ScoreConfig()
    matches: list = []
    table = compare(sources, methods, params=params, score_config=score_config, sigma=args.sigma,
                    max_scans=args.max_scans, progress=not args.no_progress, matches=matches)
    for src in sources:
        if src.reader is not None:
            report_skipped(src.reader)
    if table.empty:
        raise LmsbenchError("no scans in the given sources")
    summary = summarise(table)
    if matches:
        summary = summary.merge(common_errors(pd.DataFrame(matches)), on=["source", "method"], how="left")
    from experiments.provenance import link_latest, new_run_folder, versions, write_parquet, write_record

    resolved = dict(
        sources=args.sources, seeds=args.seeds, duration=args.duration, rate_hz=args.rate, stride=args.stride,
        max_scans=args.max_scans, sigma=args.sigma, poses=args.poses,
        log_options=plain_log_options(read_log_options(args)),
        sigma_r={src.name: src.sigma_r for src in sources},
        methods=_per_source_marked(configs, params, sources), scoring=dataclasses.asdict(score_config),
        # the noise each method ran with on each source (m; sigma_bearing rad): the fields compare sets
        # per source (the log's estimates, the simulator's noise) and those set with --set, each as it
        # was read (the sensor method's sigma_r_cm on cm-mode scans, sigma_r on mm-mode ones)
        ran_with={source_label(src): source_noise(src) for src in sources},  # office:0, office:1, a log's name
    )
    # what produced each source's scans: the sensor that was simulated (interlaced or not), the log read
    resolved["scans_from"] = [dict(name=src.name, kind=src.kind, **src.settings) for src in sources]
    resolved["versions"] = versions()
    from experiments.figures.realdata import fig_explained_vs_lines, figure_stem

    drawn = [src for src in sources if src.kind == "log" and src.name in set(summary["source"])]  # a figure each
    # the files of the logs' figures, named by the log (realdata_*), listed before they are written: the next run
    # into the folder removes exactly these (options.recorded_names), not a user's realdata_notes.csv beside them
    resolved["figures"] = [figure_stem(Path(), src.name).name + end for src in drawn for end in FIGURE_ENDS]
    run_folder = args.out is None  # results/compare/DATE_TIME, linked as latest once its files are written
    args.out = args.out or new_run_folder("results/compare", now=started)  # named by the run's start, as the demo's
    # the earlier run's outputs first (options.Owner.remove_earlier): those it may not write again stayed beside
    # this run's as if they were its own (`compare a.clf` then `compare b.clf` into D left a.clf's realdata_*
    # figure beside a summary of b.clf alone; a --format csv run the parquet table of the run before)
    COMPARE_OWNER.remove_earlier(args.out, OutTree(COMPARE_OUTPUTS + COMPARE_FIGURES), keep=("config.yaml",),
                                 also=recorded_names(args.out / "config.yaml", "figures"))  # a log's figure, as listed
    # config.yaml first, whole: it tells the folder as compare's (options.COMPARE_OWNER); a run stopped
    # after compare.parquet left a folder the next run into it refused
    write_record(args.out / "config.yaml", dump_yaml(resolved, sort_keys=False))
    path = args.out / f"compare.{args.format}"
    if args.format == "parquet":  # whole, as every output: a full disk left a cut one beside whole files
        write_record(path, lambda p: write_parquet(table, p))
    else:  # compare.csv and summary.csv are records too: whole, or a cut one refused the next run
        write_record(path, lambda p: table.to_csv(p, index=False))
    write_record(args.out / "summary.csv", lambda p: summary.to_csv(p, index=False))
    text = format_summary(summary) + "\n" + format_ran_with(resolved["ran_with"])  # the noise, as read: config.yaml
    write_record(args.out / "summary.txt", text + "\n")
    figures = []
    for src in drawn:
        figures += [str(p) for p in fig_explained_vs_lines(summary, src.name, figure_stem(args.out, src.name))]
    args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    if run_folder:
        link_latest(args.out)
    print(text)
    print(f"wrote {path}, {args.out / 'summary.csv'}, {args.out / 'summary.txt'}, {args.out / 'config.yaml'}"
          + "".join(f", {f}" for f in figures))
    if args.poses == "corrected" and "repeat_in_view" in table:
        for src in sources:  # asked for, and nothing to measure it with: it was "-" in the table, nothing said
            rows = table[table["source"] == src.name]
            if src.kind == "log" and len(rows) and rows["repeat_in_view"].isna().all():
                print(f"lmsbench compare: warning: {src.name}: --poses corrected, but no two scans in a row have a "
                      "pose (a corrected pose or odometry): its repeatability is not measured", file=sys.stderr)
    moving = [src.name for src in sources if src.kind == "sim" and (src.settings.get("sensor") or {}).get("interlaced")]
    if moving:  # a simulate folder of simulate's default sensor was scored as if its scans were still, silently
        print(f"lmsbench compare: warning: {', '.join(dict.fromkeys(moving))}: simulated with the interlaced LMS200 "
              "(simulate's default), each beam from the pose at its own time, but scored against the visible truth "
              "of the pose at the scan's stamp: the robot's motion within a scan (up to 1.2 deg, 1 cm) counts as "
              "the extractors' error (the sensor method's most); a world named as a source (office:0) is simulated "
              "without it, as is a simulate --sensor YAML with interlaced: false", file=sys.stderr)
    return 0


PER_SOURCE = "set per source (ran_with)"  # config.yaml's methods: entry of a field compare sets per source


def _per_source_marked(configs: dict[str, Any], params: dict[str, dict[str, Any]], sources: list) -> dict[str, Any]:
    """``configs`` (each method's config as plain data) with every field compare set per source
    (not by --set) written as PER_SOURCE: it listed the defaults there (``sigma: 0.005, sigma_fit:
    null``) for methods that ran with each log's noise, and config.yaml's ran_with has the values."""
    from experiments.compare import BEARING_NOISE_FIELDS, FIT_NOISE_FIELDS, NOISE_FIELDS
    from experiments.overrides import unread_marked

    fit = any(src.fit_sigma is not None for src in sources)
    bearing = any(src.bearing_sigma is not None for src in sources)
    filled = NOISE_FIELDS + (FIT_NOISE_FIELDS if fit else ()) + (BEARING_NOISE_FIELDS if bearing else ())
    range_maxes = {r for src in sources for r in src.range_maxes}
    out = {}
    for method, cfg in configs.items():
        if not isinstance(cfg, dict):
            out[method] = cfg
            continue
        given = params.get(method, {})
        ran = next((src.ran[method] for src in sources if method in src.ran), None)
        marked = unread_marked(cfg, ran, range_maxes, given)  # a field set with --set that no scan read
        out[method] = {f: PER_SOURCE if f in filled and f not in given else v for f, v in marked.items()}
    return out
