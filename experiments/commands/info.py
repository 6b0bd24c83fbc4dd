"""`lmsbench info LOG`: summary of a CARMEN log or ROS bag."""

from __future__ import annotations

import argparse
import json

from lms200 import LogFormatError, read_log

from experiments.loginfo import summarise


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("info", help="summarise a CARMEN log or ROS bag (scans, geometry, rate, validity)")
    p.add_argument("log", help="CARMEN log (plain or .gz), ROS 1 .bag or ROS 2 bag folder")
    p.add_argument("--skip-bad-lines", action="store_true", help="skip malformed CARMEN lines and count them")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    reader = read_log(args.log, skip_bad_lines=args.skip_bad_lines)
    summary = summarise(reader)
    if summary.scans == 0:
        met = getattr(getattr(reader, "stats", None), "messages", {})
        seen = f" (other lines: {sum(met.values())})" if met else ""
        raise LogFormatError(args.log, 1, "no laser messages found: not a CARMEN log (FLASER/RLASER/ROBOTLASER "
                                          f"lines) nor a bag with LaserScan messages{seen}")
    skipped = len(getattr(getattr(reader, "stats", None), "skipped", []))
    if args.json:
        print(json.dumps({**summary.as_dict(), "skipped_lines": skipped}, indent=2))
        return 0
    print(f"{args.log}")
    for line in summary.lines():
        print("  " + line)
    if skipped:
        print(f"  skipped lines   {skipped} (malformed)")
    return 0
