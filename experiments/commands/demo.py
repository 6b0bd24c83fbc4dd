"""`lmsbench demo`: the main job, end to end, with nothing outside the repository."""

from __future__ import annotations

import argparse
from pathlib import Path

from experiments.logargs import add_log_options, plain_log_options, read_log_options
from experiments.options import WORLDS, DEMO_OUTPUTS, DEMO_OWNER, DURATION, SEED, InputError, check_log, check_out, path_arg, scan_rate, world_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="simulate an office run, compare every extractor, run SLAM, a sweep, "
                                    "sim2real of the MIT CSAIL log where present, figures and results/demo/report.md")
    p.add_argument("--out", type=path_arg, help="output folder (default: a new results/demo/DATE_TIME, "
                                            "linked as results/demo/latest)")
    p.add_argument("--seed", type=SEED, default=0, help="world and run seed (default 0)")
    p.add_argument("--world", type=world_name, default="office", help="simulated world: " + WORLDS + " (default office)")
    p.add_argument("--duration", type=DURATION, default=40.0, help="simulated run, s (default 40)")
    p.add_argument("--rate-hz", type=scan_rate, default=10.0, help="scans kept per second of the run (default 10)")
    p.add_argument("--log", type=path_arg, help="real CARMEN log, bag or lmsbench simulate folder for Fig. 9 (default: shared/data/carmen/"
                   "intel-corrected.log.gz beside the checkout, where present)")
    p.add_argument("--no-sweep", action="store_true", help="skip the small Dask sweep")
    p.add_argument("--inprocess", action="store_true", help="run the sweep in this process instead of on Dask")
    add_log_options(p)  # for the real log of Fig. 9
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from experiments.demo import run_demo
    from experiments.figures.study import StudyConfig, check_panel_log, check_study

    if args.inprocess and args.no_sweep:  # it was ignored: there is no sweep to run in this process
        raise InputError("--inprocess runs the demo's sweep in this process; --no-sweep skips it: give one of them")
    check_out(args.out, writes=DEMO_OUTPUTS, owner=DEMO_OWNER, default=DEMO_BASE)
    cfg = StudyConfig(world=args.world, seed=args.seed, duration=args.duration, rate_hz=args.rate_hz)
    if args.log is not None:
        cfg.intel_log = str(check_log(args.log))
    cfg.log_options = plain_log_options(read_log_options(args))
    check_study(cfg)
    check_panel_log(cfg)  # before the run folder and results/demo/latest are made
    executor = None if args.no_sweep else ("inprocess" if args.inprocess else "local")
    from experiments.provenance import link_latest, new_run_folder

    if args.out is not None:
        run_demo(args.out, cfg, sweep_executor=executor)
        return 0
    args.out = new_run_folder(DEMO_BASE)  # named if a reader of stdout that goes away stops it
    report = run_demo(args.out, cfg, sweep_executor=executor)
    link_latest(args.out)  # only now: a demo stopped or failed midway left latest naming its partial folder
    copy_report_up(report)
    return 0


#: where the demo's runs go without --out, each in its own DATE_TIME folder, the newest linked as latest
DEMO_BASE = "results/demo"


def copy_report_up(report: Path) -> None:
    """Copy the newest run's report to its base folder (``results/demo/report.md`` and
    ``report.html``, the paths issue #8 names), the Markdown's relative links pointing into the run's
    folder; the HTML embeds its figures already. Each run without --out replaces both."""
    import re

    from experiments.provenance import write_record

    run = report.parent
    text = re.sub(r"\]\((?![a-z]+:|/|#)([^)]+)\)", lambda m: f"]({run.name}/{m.group(1)})", report.read_text())
    # and the run's files named in code spans ("settings in `tables/study.yaml`")
    text = re.sub(r"`((?:tables|figures|sim2real|sweeps)/[^`]*)`", lambda m: f"`{run.name}/{m.group(1)}`", text)
    write_record(run.parent / "report.md", text)
    write_record(run.parent / "report.html", (run / "report.html").read_text())
    print(f"== copied the report to {run.parent / 'report.md'} and {run.parent / 'report.html'}")
