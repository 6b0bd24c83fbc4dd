"""`lmsbench bench`: run the benchmarks of every area (or the named ones) and save a table."""

from __future__ import annotations

import argparse
import datetime
import importlib
import pkgutil

from lms200 import LmsbenchError
from lms200.yamlio import dump as dump_yaml

from experiments import benchmarks
from experiments.options import BENCH_OUTPUTS, BENCH_OWNER, OutTree, check_out, path_arg


def discover() -> dict[str, object]:
    """Benchmark modules by NAME."""
    found = {}
    for info in sorted(pkgutil.iter_modules(benchmarks.__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{benchmarks.__name__}.{info.name}")
        if hasattr(module, "run"):
            found[getattr(module, "NAME", info.name)] = module
    return found


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run the speed benchmarks and save a table of rates")
    areas = ", ".join(sorted(m.name for m in pkgutil.iter_modules(benchmarks.__path__)))  # each module's NAME
    p.add_argument("names", nargs="*", metavar="NAME", help=f"benchmark areas to run: {areas} (default: all)")
    p.add_argument("--quick", action="store_true", help="fewer repetitions, for a smoke run")
    p.add_argument("--out", type=path_arg, help="output folder (default: a new results/bench/DATE_TIME, "
                                            "linked as results/bench/latest)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    found = discover()
    names = args.names or list(found)
    missing = [n for n in names if n not in found]
    if missing:
        # '' would be invisible, and ' sim' read as the known sim
        shown_missing = ", ".join(n if n.strip() == n and n else repr(n) for n in missing)
        raise LmsbenchError(f"unknown benchmark(s) {shown_missing}; known: {', '.join(found)}")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise LmsbenchError(f"benchmark(s) {', '.join(twice)} named more than once")
    check_out(args.out, writes=BENCH_OUTPUTS, owner=BENCH_OWNER, default="results/bench")
    from experiments.progress import heartbeat_on_terminal

    # the run's folder is named by its start, as the demo's: a run started 10:34:23 wrote 2026-12-05_10-38-00
    started = datetime.datetime.now()
    rows = []
    for number, name in enumerate(names, 1):
        print(f"== {name}", flush=True)
        # an area's rows come when it ends: `bench features` was 106 s of silence on a terminal, `make bench`
        # 159 s; a line every few seconds there says it runs
        first = f"bench: measuring {name} (area {number} of {len(names)}; its rows follow when it ends) ..."
        with heartbeat_on_terminal(f"bench {name}", first):
            area = found[name].run(quick=args.quick)
        for row in area:
            row = {"area": name, **row}
            rows.append(row)
            print("   " + ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()), flush=True)
    import pandas as pd  # here, not at import: every `lmsbench` start (even --help) loads this module

    from experiments.provenance import link_latest, new_run_folder, versions, write_record

    run_folder = args.out is None  # results/bench/DATE_TIME, linked as latest once its files are written
    args.out = args.out or new_run_folder("results/bench", now=started)
    # versions.yaml first, whole: it tells the folder as bench's (options.BENCH_OWNER); a run stopped
    # while writing bench.csv left a folder the next run into it refused (a cut bench.csv too)
    BENCH_OWNER.remove_earlier(args.out, OutTree(BENCH_OUTPUTS), keep=("versions.yaml",))  # a stop after it left
    # the earlier run's bench.csv beside this run's versions.yaml, rows of other areas than it names
    write_record(args.out / "versions.yaml", dump_yaml(dict(benchmarks=names, quick=args.quick, versions=versions()),
                                                            sort_keys=False))
    write_record(args.out / "bench.csv", lambda p: pd.DataFrame(rows).to_csv(p, index=False))  # a record too
    args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    if run_folder:
        link_latest(args.out)
    print(f"wrote {args.out / 'bench.csv'}, {args.out / 'versions.yaml'}")
    return 0
