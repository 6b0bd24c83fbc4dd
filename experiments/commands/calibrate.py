"""`lmsbench calibrate LOG`: fit the simulator's LMS200 model to a real log (sensor YAML)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from experiments.logargs import LOG_HELP, add_log_options, read_log_options
from experiments.calibrate import FIT_DURATION_S, MAX_FIT_DURATION_S, MIN_FIT_DURATION_S
from experiments.options import WORLDS, InputError, check_log, check_out_file, count, number, path_arg, real_path, world_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="measure a real log's noise, quantisation, no-return / invalid / "
                                         "max-range rates, mixed pixels and outliers; write a sensor YAML")
    p.add_argument("log", help=LOG_HELP)
    p.add_argument("--out", type=path_arg, help="write the sensor config here (default: print it)")
    p.add_argument("--world", default="office", type=world_name,
                   help="simulated world of the fits by simulation (spot width, outlier baseline, residual tail, the tail's "
                        "and the nans' clustering): " + WORLDS + " (default office)")
    p.add_argument("--stride", type=count(1), default=1, help="use every STRIDE-th scan (default 1)")
    p.add_argument("--max-scans", type=count(1), help="use at most this many scans")
    p.add_argument("--fit-duration", type=number(MIN_FIT_DURATION_S, MAX_FIT_DURATION_S, unit="s"), default=FIT_DURATION_S,
                   metavar="S", help=f"simulated seconds of each of the fit's runs of --world (default {FIT_DURATION_S:g}; "
                                     f"{MIN_FIT_DURATION_S:g}-{MAX_FIT_DURATION_S:g}: shorter is faster and its fitted "
                                     "fields noisier)")
    add_log_options(p)
    p.set_defaults(func=run, prints_without_out=True)  # without --out the YAML goes to stdout


def run(args: argparse.Namespace) -> int:
    import tempfile

    from experiments.calibrate import calibrate_log, format_calibration, write_sensor_yaml
    from experiments.progress import heartbeat_on_terminal

    read_options = read_log_options(args)
    args.log = check_log(args.log)  # a simulate folder: its scans.clf
    check_out_file(args.out)
    if args.out is not None:  # 'calibrate LOG --out LOG' wrote the YAML over the log it had just read
        if args.out.suffix.lower() not in (".yaml", ".yml"):
            raise InputError(f"--out {args.out}: calibrate writes a sensor YAML; give a file name ending in .yaml")
        if args.out.exists() and Path(args.log).exists() and real_path(args.out) == real_path(args.log):
            raise InputError(f"--out {args.out} is the log being calibrated")
        if args.out.is_file() and not os.access(args.out, os.R_OK):  # said "is not a sensor YAML that calibrate wrote"
            raise InputError(f"--out {args.out} cannot be read (permission denied), so calibrate cannot tell whether it "
                             "wrote it; make it readable, or give a new file name")
        if args.out.is_file() and not os.access(args.out, os.W_OK):  # a read-only earlier output was replaced, exit 0
            raise InputError(f"--out {args.out} is read-only; make it writable (chmod u+w), or give a new file name")
        if args.out.exists() and not _written_by_calibrate(args.out):  # a user's YAML was replaced silently
            raise InputError(f"--out {args.out} exists and is not a sensor YAML that calibrate wrote; give a new "
                             "file name (calibrate replaces only its own earlier output)")
    with heartbeat_on_terminal("calibrate", "calibrate: measuring the log and fitting by simulation ..."):
        result = calibrate_log(args.log, world=args.world, stride=args.stride, max_scans=args.max_scans,
                               fit_duration=args.fit_duration,
                               **read_options)
    if args.out is not None:  # before the summary: `calibrate LOG --out S.yaml | head -3` lost the YAML
        write_sensor_yaml(result, args.out, str(args.log))
        args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    if args.out is None:  # stdout is the sensor YAML: `calibrate LOG > S.yaml` wrote the summary above the YAML,
        # which `--sensor S.yaml` refused (not valid YAML); the summary is now its comments
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "sensor.yaml"
            write_sensor_yaml(result, path, str(args.log))
            text = path.read_text()
        first, _, rest = text.partition("\n")  # the YAML's own first line names calibrate and the log
        print(first)
        for line in format_calibration(result):
            print(f"# {line}".rstrip())
        print(rest, end="")
    else:
        for line in format_calibration(result):
            print(line)
        print(f"wrote {args.out}")
    return 0


def _written_by_calibrate(path: Path) -> bool:
    """Whether ``path`` is empty (nothing to lose) or starts with the header line calibrate writes
    (``write_sensor_yaml``)."""
    from experiments.calibrate import HEADER_START

    try:
        with open(path, "rb") as f:
            first = f.readline(200)
    except OSError:
        return False
    return first == b"" or first.startswith(HEADER_START.encode())
