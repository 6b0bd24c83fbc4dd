"""The log-reading options every command that reads a log shares: one definition, one check.

``add_log_options(parser)`` adds ``--topic``, ``--skip-bad-lines`` and the FLASER geometry override
(``--laser-fov-deg``, ``--laser-resolution-deg``, ``--laser-angle-min-deg``, ``--laser-range-max``);
``read_log_options(args)`` turns them into ``lms200.read_log`` keywords, checked before any work;
``report_skipped(reader)`` says on stderr what a pass skipped.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import IO, Any

from lms200 import LaserGeometry, LmsbenchError
from lms200.bag import BagReadStats

_GEOMETRY_FLAGS = (("laser_fov_deg", "fov", True), ("laser_resolution_deg", "resolution", True),
                   ("laser_angle_min_deg", "angle_min", True), ("laser_range_max", "range_max", False))


#: the help of a command's LOG argument (it said "plain or .gz"; bzip2 and xz logs are read too)
LOG_HELP = "CARMEN log (plain, .gz, .bz2 or .xz), ROS 1 .bag, ROS 2 bag folder or lmsbench simulate folder"


def _float(text: str) -> float:
    """``float(text)`` of a number as a command line writes it (``options.plain_number``): "1_0" (read as
    10) and non-ASCII digits ("١٢" read as 12) are a ValueError, "invalid float value", as for any other
    word that is no number (the four geometry flags took them: `--laser-fov-deg 1_0` read a 10 deg field of
    view, exit 0; found by fuzzing). nan and inf pass here and are refused by LaserGeometry, naming the flag."""
    from experiments.options import Underflow, plain_number

    try:
        return plain_number(text)
    except Underflow as exc:  # --laser-angle-min-deg 1e-400 read 0 deg: argparse's "invalid float value" would hide why
        raise argparse.ArgumentTypeError(f"got {text!r}: {exc}") from None


_float.__name__ = "float"  # argparse's message: "invalid float value: '1_0'"


def add_log_options(parser: argparse.ArgumentParser) -> None:
    """Add the shared log-reading options to a command's parser."""
    g = parser.add_argument_group("reading logs")
    g.add_argument("--topic", help="the laser to read: a bag's LaserScan topic (needed when the bag has several) "
                                   "or a CARMEN laser message kind (FLASER, RLASER, ROBOTLASER1/2, RAWLASER1..4; "
                                   "default: the first with poses in the log, else the first RAWLASER)")
    g.add_argument("--skip-bad-lines", action="store_true",
                   help="skip malformed log lines / unreadable bag messages (reported on stderr) instead of stopping")
    g.add_argument("--laser-fov-deg", type=_float, metavar="DEG",
                   help="FLASER/RLASER field of view (deg), overriding PARAM lines and the 180 deg convention")
    g.add_argument("--laser-resolution-deg", type=_float, metavar="DEG",
                   help="FLASER/RLASER angle between beams (deg), overriding PARAM lines and the count convention")
    g.add_argument("--laser-angle-min-deg", type=_float, metavar="DEG",
                   help="FLASER/RLASER bearing of the first beam (deg; default: the scan is centred ahead)")
    g.add_argument("--laser-range-max", type=_float, metavar="M", help="largest valid range (m, 0.1 to 10000, above the log's range_min), overriding the log's own "
                        "(PARAM lines, ROBOTLASER's field, a bag's LaserScan range_max, else the unit's 8.183 / 81.83 m)")


def read_log_options(args: argparse.Namespace) -> dict[str, Any]:
    """``read_log`` keywords from the parsed options (topic, skip_bad_lines, geometry).

    Raises:
        LmsbenchError: for an option value that cannot be a geometry (naming the flag).
    """
    values: dict[str, float] = {}
    for flag, name, degrees in _GEOMETRY_FLAGS:
        value = getattr(args, flag, None)
        if value is None:
            continue
        values[name] = math.radians(value) if degrees else value
    try:
        geometry = LaserGeometry(**values) if values else None
    except ValueError as exc:
        name, _, reason = str(exc).partition(": ")
        flag = next(f for f, n, _ in _GEOMETRY_FLAGS if n == name)
        raise LmsbenchError(f"--{flag.replace('_', '-')}: {reason}") from None
    topic = getattr(args, "topic", None)
    if topic is not None and not topic.strip():
        raise LmsbenchError("--topic: must not be empty")
    return dict(topic=topic, skip_bad_lines=bool(getattr(args, "skip_bad_lines", False)), geometry=geometry)


def given_log_flags(args: argparse.Namespace) -> list[str]:
    """The log options (:func:`add_log_options`) given on the command line, as their flags: for a
    command to refuse them where it reads no log (they were ignored, silently)."""
    flags = ["--topic"] if getattr(args, "topic", None) is not None else []
    flags += ["--skip-bad-lines"] if getattr(args, "skip_bad_lines", False) else []
    return flags + [f"--{flag.replace('_', '-')}" for flag, _, _ in _GEOMETRY_FLAGS if getattr(args, flag, None) is not None]


def plain_log_options(options: dict[str, Any]) -> dict[str, Any]:
    """``read_log`` keywords as plain data (for a config saved beside results): geometry as a dict."""
    out = dict(options)
    geometry = out.get("geometry")
    out["geometry"] = {k: v for k, v in vars(geometry).items() if v is not None} if geometry is not None else None
    return out


def log_option_flags(plain: dict[str, Any] | None) -> list[str]:
    """The command-line flags that give these plain ``read_log`` options (:func:`plain_log_options`),
    none for the defaults: how a report names the run that read the log."""
    from experiments.options import number_text

    plain = plain or {}
    flags = ["--topic", str(plain["topic"])] if plain.get("topic") else []
    flags += ["--skip-bad-lines"] if plain.get("skip_bad_lines") else []
    geometry = plain.get("geometry") or {}
    for flag, name, degrees in _GEOMETRY_FLAGS:
        if geometry.get(name) is not None:
            value = math.degrees(geometry[name]) if degrees else geometry[name]
            flags += [f"--{flag.replace('_', '-')}", number_text(value)]
    return flags


def log_options_from_plain(plain: dict[str, Any] | None) -> dict[str, Any]:
    """The inverse of :func:`plain_log_options`: ``read_log`` keywords."""
    out = dict(plain or {})
    if out.get("geometry"):
        out["geometry"] = LaserGeometry(**out["geometry"])
    else:
        out.pop("geometry", None)
    return out


def report_skipped(reader: Any, stream: IO[str] | None = None, show: int = 3) -> int:
    """Print what the last pass over ``reader`` skipped (count, the first ``show`` reasons) and why it
    stopped early, if it did; returns the number of skipped lines / messages."""
    stream = stream or sys.stderr
    stats = getattr(reader, "stats", None)
    if stats is None:
        return 0
    path = getattr(reader, "path", "")
    skipped = list(getattr(stats, "skipped", []))
    count = getattr(stats, "skipped_count", len(skipped))  # skipped keeps the first MAX_SKIPPED_KEPT only
    bag = isinstance(stats, BagReadStats)  # bag reasons name topic and message index themselves
    if count:
        noun = ("message" if bag else "line") + ("" if count == 1 else "s")
        print(f"{path}: skipped {count} bad {noun}", file=stream)
        for where, reason in skipped[:show]:
            print(f"  {path}: {reason}" if bag else f"  {path}:{where}: {reason}", file=stream)
        if count > show:
            print(f"  ... and {count - show} more", file=stream)
    if getattr(stats, "stopped", None):
        print(f"{path}: reading stopped early at {stats.stopped}", file=stream)
    return count
