"""`lmsbench figures`: the paper's figures (PNG + PDF + the data behind each) from tidy tables."""

from __future__ import annotations

import argparse
import datetime
from pathlib import Path
from typing import Any

from lms200.yamlio import dump as dump_yaml

from experiments.logargs import add_log_options, given_log_flags, plain_log_options, read_log_options
from experiments.options import (WORLDS, DEMO_OWNER, DURATION, FIGURE_ENDS, FIGURE_PART_FILES, FIGURES_OUTPUTS, FIGURES_OWNER, SEED, STUDY_TABLES, InputError, OutTree, check_log, real_path,
                                 check_methods, check_out, check_study_tables, read_sweep_results, SweepResults, path_arg, scan_rate, world_name,
                                 text, check_link, recorded_names)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("figures", help="draw the paper's figures (3-7, 9, 10), accuracy vs speed, sweep plots")
    p.add_argument("--out", type=path_arg, help="output folder (default: a new results/figures/DATE_TIME, "
                                            "linked as results/figures/latest)")
    p.add_argument("--tables", type=path_arg,
                   help="redraw from the tables in this folder (from an earlier run) instead of computing them")
    p.add_argument("--sweep", type=path_arg, action="append", default=[], metavar="DIR",
                   help="also plot this sweep folder (with results.parquet); repeatable")
    p.add_argument("--duration", type=DURATION, help="simulated run, s (default 40)")
    p.add_argument("--rate-hz", type=scan_rate, help="scans kept per second of the run (default 10)")
    p.add_argument("--seed", type=SEED, help="world and run seed (default 0)")
    p.add_argument("--world", type=world_name, help="simulated world: " + WORLDS + " (default office)")
    p.add_argument("--methods", nargs="+", type=text("an extractor's name"), help="extractors to compare, apart or comma-separated (default: all five)")
    p.add_argument("--intel", "--log", dest="intel", type=path_arg,
                   help="CARMEN log, bag or lmsbench simulate folder for Fig. 9 (--log as in demo; default: shared/data/carmen/"
                   "intel-corrected.log.gz beside the checkout, where present)")
    p.add_argument("--no-slam", action="store_true", help="skip the SLAM run and Fig. 10")
    add_log_options(p)  # for the real log of Fig. 9
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from experiments.figures.make import DRIVING_TABLES, accuracy_speed_problem, check_tables, draw_figures, draw_sweep
    from experiments.provenance import link_latest, new_run_folder, write_record
    from experiments.figures.study import (STUDY_TABLE_NAMES, StudyConfig, check_panel_log, check_study, load_config,
                                           load_tables, run_study, save_tables)

    started = datetime.datetime.now()
    writes = FIGURES_OUTPUTS
    for path in (args.out, args.tables):  # a loop of links: Path.resolve below raised RuntimeError
        if path is not None:
            check_link(path, "--out" if path is args.out else "--tables")
    if args.out is not None:
        _check_not_a_demos_figures(args.out, args.tables)
    if args.out is not None and args.tables is not None and real_path(args.out) == real_path(args.tables):
        writes = OutTree(FIGURES_OUTPUTS.files + STUDY_TABLES.files, FIGURES_OUTPUTS.folders)  # the tables it reads
    # a file of its names is replaced only beside its own record (options.FIGURES_OWNER): by names
    # alone a user's fig3_scan.png or accuracy_speed.csv in --out was written over; --tables: no table is
    replaces = FIGURES_OUTPUTS if args.tables is None else OutTree(FIGURES_OUTPUTS.files)
    check_out(args.out, writes=writes, owner=FIGURES_OWNER, replaces=replaces, default="results/figures")
    # each sweep's table and sweep.yaml read once, by its checks, and drawn from (each was read four times: the checks, the plots'
    # names, the record and the drawing)
    sweeps = [read_sweep_results(folder) for folder in args.sweep]
    _check_sweeps_apart(sweeps)
    study = (("--duration", args.duration), ("--rate-hz", args.rate_hz), ("--seed", args.seed), ("--world", args.world),
             ("--methods", args.methods), ("--intel", args.intel), ("--no-slam", args.no_slam or None))
    ignored = [flag for flag, value in study if value is not None]
    if args.tables and ignored:  # they were ignored: the figures were redrawn from the tables as they were
        raise InputError(f"{', '.join(ignored)} set the study that --tables replaces; redrawing from {args.tables} "
                         "computes nothing (leave them out, or leave out --tables)")
    unread = given_log_flags(args)
    if args.tables and unread:  # they were ignored: the tables hold what the study read of the log
        raise InputError(f"{', '.join(unread)} {'do' if len(unread) > 1 else 'does'} not apply to --tables: they say how to read the study's log (Fig. 9's "
                         f"Intel log), and redrawing from {args.tables} reads no log (leave them out, or leave out --tables)")
    defaults = {"duration": 40.0, "rate_hz": 10.0, "seed": 0, "world": "office"}
    for name, value in defaults.items():
        setattr(args, name, value if getattr(args, name) is None else getattr(args, name))
    if args.tables:
        check_study_tables(args.tables)
        tables, notes = load_tables(args.tables)
        check_tables(tables, f"--tables {args.tables}")  # before any output: a foreign table failed part-way
        if not any(len(t) for n, t in tables.items() if n in DRIVING_TABLES) and not args.sweep:  # "wrote 0 files", exit 0
            raise InputError(f"--tables {args.tables}: every table a figure is drawn from is empty (no rows); nothing to draw")
        cfg = load_config(args.tables)
    else:
        cfg = StudyConfig(world=args.world, seed=args.seed, duration=args.duration, rate_hz=args.rate_hz, slam=not args.no_slam)
        if args.methods:
            cfg.methods = tuple(check_methods(args.methods))
        if args.intel is not None:
            cfg.intel_log = str(check_log(args.intel))
        cfg.log_options = plain_log_options(read_log_options(args))
        check_study(cfg, hint=", or --no-slam")
        check_panel_log(cfg)  # before any work: a log the panels cannot draw (as the demo checks it)
        tables, notes = run_study(cfg)
    run_folder = args.out is None  # results/figures/DATE_TIME, linked as latest once its figures are drawn
    args.out = args.out or new_run_folder("results/figures", now=started)  # named by the run's start
    if not run_folder and not _demos_figures(args.out):  # the earlier run's files this run may not write again (a
        FIGURES_OWNER.remove_earlier(args.out, replaces, keep=("figures.yaml",), also=(  # demo's: its sweep plots, kept)
            *FIGURE_PART_FILES, *(f"tables/{name}.parquet" for name in STUDY_TABLE_NAMES),
            # the sweep plots its figures.yaml lists (a --sweep run's stayed beside a run without --sweep)
            *recorded_names(args.out / "figures.yaml", "sweep_plots")))
    elif not run_folder:  # a demo's figures/: the demo's own files stay, an earlier figures run's sweep plots go (they
        _remove_earlier_sweep_plots(args.out)  # stayed, and its figures.yaml, the one list of them, was written over)
    write_record(args.out / "figures.yaml", _record(args, sweeps))  # first, whole: a run stopped after it is told as ours
    if not args.tables:
        save_tables(tables, cfg, notes, args.out / "tables")
    from experiments.progress import heartbeat_on_terminal

    # drawing took ~27 s without a word (12 s from --tables) before the listing: each figure is said on a
    # terminal as it starts, and a slow one beats
    with heartbeat_on_terminal("figures", None) as beat:
        say = lambda msg: beat.say(f"figures: {msg}")  # noqa: E731
        try:
            written = draw_figures(tables, args.out, signals_k=cfg.signals_k, world=cfg.world, log=say)
        except (KeyError, AttributeError) as exc:  # a column or field a figure reads is missing
            if not args.tables:
                raise
            from lms200 import LmsbenchError  # tables from the user's folder lack what a figure reads

            raise LmsbenchError(f"--tables {args.tables}: the tables do not hold what the figures read "
                                f"({type(exc).__name__}: {' '.join(str(exc).split())[:160]}); redraw from a "
                                "complete tables/ folder of `lmsbench figures` or `lmsbench demo`") from None
        for folder, table, spec in sweeps:
            written.update(draw_sweep(folder, args.out, log=say, table=table, spec=spec))
    args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    if run_folder:
        link_latest(args.out)
    for name, paths in written.items():
        print(f"{name:32s} " + " ".join(p.name for p in paths))
    for note in notes:
        print(f"note: {note}")
    for name in sorted(n for n, t in tables.items() if not len(t) and n in DRIVING_TABLES):
        print(f"note: table {name} is empty: the figures drawn from it are not drawn")
    if (problem := accuracy_speed_problem(tables)) is not None:
        print(f"note: {problem}")
    if args.tables:
        for name, figures in _missing_tables(tables, cfg, notes):
            print(f"note: table {name} is missing ({name}.parquet, which the study saved): {figures} not drawn")
    print(f"wrote {sum(len(p) for p in written.values())} files in {args.out}")
    return 0


#: a study's driving tables (make.DRIVING_TABLES) but summary (accuracy_speed says its own) and the figures of each
_FIGURES_OF = {"signals": "fig3_scan to fig6_psi are", "timing": "fig7_timing is", "office_points": "fig9_office is",
               "intel_points": "fig9_intel is", "trajectory": "fig10_slam is"}


def _missing_tables(tables: dict, cfg: Any, notes: list[str]) -> list[tuple[str, str]]:  # noqa: ANN401 - a StudyConfig
    """(table, its figures) of each driving table the study of ``cfg`` saved (Intel's where its notes do
    not say it was skipped; the trajectory where it ran the SLAM) that a --tables folder lacks: its
    figures were left out without a word, exit 0."""
    made = ["signals", "timing", "office_points"]
    from experiments.figures.study import INTEL_SKIPPED

    made += [] if any(n.startswith(INTEL_SKIPPED) for n in notes) else ["intel_points"]
    made += ["trajectory"] if cfg.slam else []
    return [(name, _FIGURES_OF[name]) for name in made if name not in tables]


def _check_not_a_demos_figures(out: Path, tables: Path | None) -> None:
    """Refuse, before any work, ``figures --out DEMO/figures`` unless it redraws the demo's figures
    from the demo's own tables (``--tables DEMO/tables``). Without --tables it computed a study of
    its own, drew its figures over some of the demo's (those of the demo's report.md and tables/)
    and saved its tables in DEMO/figures/tables/, so the next ``demo --out DEMO`` refused DEMO
    ("holds figures/tables/, which this command does not write"); with another study's tables
    (``--tables X/tables``) it drew X's figures over the demo's, exit 0, beside the demo's
    fig10_slam and under its report.md, which still described its own study."""
    if not _demos_figures(out):
        return
    real = real_path(out)
    demo = out.parent if out.name == "figures" else real.parent
    if tables is None:
        raise InputError(f"--out {out}: the figures of the lmsbench demo in {demo}, drawn from its tables/ and shown in its "
                         "report.md; without --tables this run computes a study of its own, whose figures and tables "
                         f"would not match them: give --tables {demo / 'tables'} to redraw the demo's figures, or another --out")
    if real_path(tables) != real.parent / "tables":
        raise InputError(f"--out {out}: the figures of the lmsbench demo in {demo}, drawn from its tables/ and shown in its "
                         f"report.md; figures drawn from --tables {tables}, not the demo's tables, would not match them: "
                         f"give a new folder as --out, or --tables {demo / 'tables'} to redraw the demo's figures")


def _remove_earlier_sweep_plots(out: Path) -> None:
    """In a demo's figures/ folder ``out``, remove the sweep plots an earlier figures run there lists in its
    figures.yaml, but the demo's own (of its sweep, by name): each a plain file name, no pattern."""
    from experiments.options import demo_sweep_files

    own = {name.removeprefix("figures/") for name in demo_sweep_files(real_path(out).parent)}
    plots = tuple(n for n in recorded_names(out / "figures.yaml", "sweep_plots")
                  if n not in own and "/" not in n and not any(c in n for c in "*?["))
    if plots:
        FIGURES_OWNER.remove_earlier(out, OutTree(plots), keep=("figures.yaml",))


def _demos_figures(out: Path) -> bool:
    """Whether ``out`` is the figures/ folder of an lmsbench demo's folder."""
    real = real_path(out)
    return real.name == "figures" and DEMO_OWNER.wrote_in(real.parent)


def _check_sweeps_apart(sweeps: list[SweepResults]) -> None:
    """Refuse, before any work, two ``--sweep`` folders whose plots would have one name: a sweep's
    plots are ``sweep_<name>_<metric>.*`` by the ``name:`` of its sweep.yaml, so one sweep file run
    into two folders (``sweep s.yaml --out a``, ``--out b``) drew b's plots over a's, exit 0
    ("sweep_k_vs_noise_f1 ... wrote 31 files"); the same folder twice is refused as such, as
    ``compare`` refuses a source given twice (and, like it, two logs of one figure name). ``sweeps``: each
    folder with its table and sweep.yaml (``options.read_sweep_results``)."""
    from experiments.figures.make import sweep_stems

    seen: dict[str, Path] = {}  # a plot's name -> the --sweep folder that draws it
    folders_seen: dict[Path, Path] = {}  # a folder's real path -> the --sweep word that gave it
    for folder, table, spec in sweeps:
        first = folders_seen.setdefault(real_path(folder), folder)
        if first is not folder:
            raise InputError(f"--sweep {folder} is given twice ({first} and {folder}): each sweep folder once")
        stems = sweep_stems(folder, table, spec)
        if not stems:  # nothing of it was drawn, and the run said nothing of it
            raise InputError(f"--sweep {folder}: {_nothing_to_plot(folder, table, spec)}")
        for stem in stems:
            other = seen.setdefault(stem, folder)
            if other is not folder:
                raise InputError(f"--sweep {other} and --sweep {folder} would both write their plot {stem}.png (a sweep's "
                                 "plots are named by the name: of its sweep.yaml, else by its folder's name): draw them with two runs of figures "
                                 "(another --out), or give one of them another name: in its sweep.yaml")


def _nothing_to_plot(folder: Path, table: Any, spec: dict) -> str:  # noqa: ANN401 - a pandas DataFrame
    """Why a sweep folder gives no plot: no metric with a value (its cells failed), or no grid
    parameter that varies and no sampled one (nothing to plot against)."""
    from experiments.figures.make import sweep_plan

    table, _, varied, sampled, metrics = sweep_plan(folder, table, spec)
    if not metrics:
        failed = int((table["status"] != "ok").sum()) if "status" in table else 0
        # "the others gave nan for every metric" was said of a kind's text, inf or boolean metrics too
        return (f"no metric has a value in its results.parquet ({failed} of its {len(table)} cells failed, the others "
                "gave no finite number for any metric (nan, inf, text or a bool); the error column of its results.csv "
                "holds the failures' reasons), so there is nothing to plot")
    return ("no grid parameter takes two values and none is sampled, so there is nothing to plot the metrics "
            "against (its results.csv holds them)")


def _record(args: argparse.Namespace, sweeps: list[SweepResults]) -> str:
    """figures.yaml: what drew the figures of its folder (options.FIGURES_OWNER tells the folder by
    it): a figure and its CSV say nothing of lmsbench, and ``--tables T --out DIR`` writes no table."""

    from experiments.figures.make import sweep_stems
    from experiments.provenance import versions

    # sweep_plots: the files of the --sweep plots, named by a pattern (sweep_*), listed before they are drawn: the
    # next figures run into the folder removes exactly these (options.recorded_names), not a user's sweep_notes.csv
    plots = [f"{stem}{end}" for sweep in sweeps for stem in sweep_stems(*sweep) for end in FIGURE_ENDS]
    record = {"command": "lmsbench figures", "tables": str(args.tables) if args.tables else "tables (computed by this run)",
              "sweeps": [str(folder) for folder in args.sweep], "sweep_plots": plots, "versions": versions()}
    return ("# what drew the figures in this folder; lmsbench figures --out replaces its files only beside this record\n"
            + dump_yaml(record, sort_keys=False))
