"""`lmsbench demo`: the main job, end to end, with nothing outside the repository."""

from __future__ import annotations

import argparse
from pathlib import Path

from lms200 import read_log

from experiments.demo import plot_scan, room_scan
from experiments.loginfo import summarise


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="run the main job end to end and write results/demo/")
    p.add_argument("--log", help="use this CARMEN log or bag instead of a simulated scan")
    p.add_argument("--out", type=Path, default=Path("results/demo"), help="output folder")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    args.out.mkdir(parents=True, exist_ok=True)
    if args.log:
        records = read_log(args.log)
        summary = summarise(records)
        scan = next(iter(records)).scan
        source = str(args.log)
    else:
        scan = room_scan(seed=args.seed)
        source = "analytic 6 m x 4 m room"
        from lms200 import Record

        summary = summarise([Record(scan)])
    print(source)
    for line in summary.lines():
        print("  " + line)
    plot_scan(scan, args.out / "scan.png", title=source)
    print(f"wrote {args.out / 'scan.png'}")
    return 0
