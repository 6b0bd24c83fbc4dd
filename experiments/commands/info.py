"""`lmsbench info LOG`: summary of a CARMEN log or ROS bag."""

from __future__ import annotations

import argparse
import json
import math

from lms200 import LogFormatError, read_log
from lms200.carmen import no_scan_read
from lms200.finite import fixed

from experiments.logargs import LOG_HELP, add_log_options, read_log_options, report_skipped
from experiments.loginfo import summarise
from experiments.options import check_log, warnings_after_checks


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("info", help="summarise a CARMEN log, ROS bag or lmsbench simulate folder (scans, geometry, rate, validity)")
    p.add_argument("log", help=LOG_HELP)
    add_log_options(p)
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    # the reader's warnings are said once the log is read whole: a log refused (a malformed line after scan 50 of
    # a log in millimetres) is its error alone (it said the units warning, then the error)
    with warnings_after_checks():
        args.log = check_log(args.log)  # a simulate folder: its scans.clf
        reader = read_log(args.log, **read_log_options(args))
        summary = summarise(reader)
        stats = reader.stats
        if summary.scans == 0:
            if stats.stopped:  # damage before the first scan (read under --skip-bad-lines)
                raise LogFormatError(args.log, None, no_scan_read(stats.stopped))
            met = getattr(stats, "messages", {})
            seen = f" (other lines: {sum(met.values())})" if met else ""
            raise LogFormatError(args.log, None, "no laser messages found: not a CARMEN log (FLASER/RLASER/ROBOTLASER/RAWLASER "
                                              f"lines) nor a bag with LaserScan messages{seen}")
    others = stats.other_lasers() if hasattr(stats, "other_lasers") else {}
    mount = getattr(stats, "mount", None)  # a CARMEN laser off the robot's centre: its poses are the laser's
    changes = getattr(stats, "mount_changes", 0)  # a mounting PARAM line after laser lines: frames differ
    changed = ({"count": changes, "first_line": stats.mount_changed_at, "before": stats.mount_before}
               if changes else None)
    report_skipped(reader)
    if args.json:
        print(json.dumps({**summary.as_dict(), "laser": stats.laser, "laser_mount": mount, "laser_mount_changes": changed,
                          "skipped_lines": stats.skipped_count,
                          "skipped": [{"at": at, "reason": reason} for at, reason in stats.skipped],
                          "stopped": stats.stopped, "other_lasers": others}, indent=2))
        return 0
    print(f"{args.log}")
    for line in summary.lines():
        print("  " + line)
    print(f"  laser           {stats.laser}")
    if mount is not None:
        print(f"  laser mount     x {fixed(mount[0], 3)} m, y {fixed(mount[1], 3)} m, {fixed(math.degrees(mount[2]), 2)} deg "
              f"on the robot ({stats.mounted} scans): their poses are the laser's (docs/data.md, \"Laser mounting\")")
    if changed is not None:
        before = stats.mount_before or (0.0, 0.0, 0.0)
        print(f"  laser mount     changed mid-log {changes} time{'s' * (changes != 1)}, first by the PARAM line "
              f"{stats.mount_changed_at} (before it x {fixed(before[0], 3)} m, y {fixed(before[1], 3)} m, "
              f"{fixed(math.degrees(before[2]), 2)} deg): each scan is placed by the mounting of the lines before it")
    for kind, count in others.items():
        print(f"  also in the log {kind} ({count} lines, not read: --topic {kind})")
    return 0
