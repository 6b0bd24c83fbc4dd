"""`lmsbench sim2real LOG`: a real log against the calibrated simulation of a matching world."""

from __future__ import annotations

import argparse
import math
import sys

from lms200 import read_log
from lms200.timing import check_scan_rate

from experiments.logargs import LOG_HELP, add_log_options, read_log_options
from experiments.options import (
    DURATION,
    listed_seed,
    SIM2REAL_OUTPUTS,
    SIM2REAL_OWNER,
    WORLDS,
    InputError,
    warnings_after_checks,
    check_log,
    check_out,
    check_out_spares,
    check_seeds,
    check_sim2real_finished,
    check_yaml,
    count,
    scan_rate,
    number,
    path_arg,
    world_name,
)
from experiments.calibrate import FIT_DURATION_S, MAX_FIT_DURATION_S, MIN_FIT_DURATION_S
from experiments.sim2real import (DEFAULT_DURATION_S, DEFAULT_RATE_HZ, DEFAULT_SEEDS, PROBE_DURATION_S, PROBE_RATE_HZ,
                                  PROBE_SEEDS, resolve_probe_seeds)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sim2real", help="a real log against its calibrated simulation: explained fraction, ray RMSE, "
                                        "lines per scan, range / residual / segment histograms (table and figure)")
    p.add_argument("log", help=LOG_HELP)
    p.add_argument("--world", default="mit", type=world_name, help="simulated world: " + WORLDS + " (default mit, the MIT-CSAIL-like preset)")
    p.add_argument("--sensor", type=path_arg, metavar="FILE.yaml",
                   help="use this sensor model instead of calibrating on the log")
    p.add_argument("--seeds", nargs="+", type=listed_seed, default=list(DEFAULT_SEEDS),
                   help=f"simulated runs, one world each, listed (default {DEFAULT_SEEDS[0]}-{DEFAULT_SEEDS[-1]}; `--seeds 3` is the "
                        "one world 3)")
    p.add_argument("--duration", type=DURATION, default=DEFAULT_DURATION_S,
                   help=f"simulated seconds per seed (default {DEFAULT_DURATION_S:g}, as the fits' probe runs)")
    p.add_argument("--probe-duration", type=DURATION,
                   help=f"simulated seconds of each probe run of the mit world's fits (default {PROBE_DURATION_S:g})")
    p.add_argument("--probe-seeds", nargs="+", type=listed_seed, metavar="SEED",
                   help=f"worlds of the mit world's fits' probe runs, none of them in --seeds (default "
                        f"{PROBE_SEEDS[0]}-{PROBE_SEEDS[-1]}, the first as many as --seeds gives)")
    p.add_argument("--rate-hz", type=scan_rate, default=DEFAULT_RATE_HZ,
                   help=f"simulated scans kept per second (default {DEFAULT_RATE_HZ:g}; the probe runs keep {PROBE_RATE_HZ:g})")
    p.add_argument("--stride", type=count(1), default=5, help="use every STRIDE-th real scan (default 5)")
    p.add_argument("--max-scans", type=count(1), default=400, help="at most this many real scans (default 400)")
    p.add_argument("--fit-duration", type=number(MIN_FIT_DURATION_S, MAX_FIT_DURATION_S, unit="s"), metavar="S",
                   help=f"simulated seconds of each run of the sensor calibration's fit (default {FIT_DURATION_S:g}, as "
                        f"`lmsbench calibrate`; {MIN_FIT_DURATION_S:g}-{MAX_FIT_DURATION_S:g}; not with --sensor)")
    p.add_argument("--fit-rooms", action="store_true",
                   help="mit world: also fit the rooms' size to the log's share of readings at 2-8 m that reach 4 m "
                        "(off by default: docs/simulator.md)")
    p.add_argument("--out", type=path_arg, help="output folder (default: a new results/sim2real/DATE_TIME, linked as "
                                            "results/sim2real/latest)")
    add_log_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import datetime

    from sim import SensorConfig

    started = datetime.datetime.now()  # what names the run's folder (2-3 min at the defaults)

    from experiments.progress import heartbeat_on_terminal
    from experiments.provenance import link_latest, new_run_folder, versions
    from experiments.sim2real import format_report, sim2real, write_outputs

    read_options = read_log_options(args)
    given, args.log = args.log, check_log(args.log)  # a simulate folder: its scans.clf
    check_out_spares(args.out, SIM2REAL_OUTPUTS, [given, args.log] + ([args.sensor] if args.sensor else []))
    check_out(args.out, writes=SIM2REAL_OUTPUTS, owner=SIM2REAL_OWNER, default="results/sim2real")  # after: an input in --out is the sharper message
    check_seeds(args.seeds)
    if args.fit_duration is not None and args.sensor is not None:  # it would be ignored: nothing is calibrated
        raise InputError("--fit-duration sets the calibration's fit; with --sensor the log is not calibrated")
    if args.fit_rooms and args.world != "mit":
        raise InputError(f"--fit-rooms fits the mit world's room size; it does nothing for --world {args.world}")
    if args.probe_duration is not None and args.world != "mit":
        raise InputError(f"--probe-duration sets the mit world's fits; it does nothing for --world {args.world}")
    if args.probe_seeds is not None:
        if args.world != "mit":
            raise InputError(f"--probe-seeds sets the mit world's fits; it does nothing for --world {args.world}")
        check_seeds(args.probe_seeds, "--probe-seeds")
    if args.world == "mit":  # before any work: given or default, the probe worlds are not the report's
        resolve_probe_seeds(args.seeds, args.probe_seeds, ("--seeds", "--probe-seeds"))
    args.probe_duration = PROBE_DURATION_S if args.probe_duration is None else args.probe_duration
    with warnings_after_checks():  # a refused run is its error alone, without a warning of what it read
        sensor = None
        if args.sensor is not None:
            check_yaml(args.sensor, "a sensor YAML")
            check_sim2real_finished(args.sensor, "--sensor")
            sensor = SensorConfig.from_yaml(args.sensor)
        first = next(iter(read_log(args.log, **read_options)), None)  # the log's geometry, before any work
        if first is not None:
            from features.registry import check_beams

            check_beams(first.scan, f"{args.log}: scan 0")  # the extractors' limit, as extract's
        if sensor is not None:
            check_scan_rate(args.rate_hz, sensor.angle_increment, "--rate-hz")
            if first is not None and (len(first.scan) != sensor.n_beams
                                      or not math.isclose(first.scan.angle_increment, sensor.angle_increment, rel_tol=1e-6)):
                # it ran: 181-beam worlds against 361-beam real scans, lines per scan compared across resolutions
                raise InputError(f"--sensor {args.sensor}: {sensor.n_beams} beams at {sensor.resolution_deg:g} deg, but "
                                 f"{args.log} has {len(first.scan)} at {math.degrees(first.scan.angle_increment):g} deg; "
                                 "sim2real compares like with like (calibrate the log, or give a sensor of its geometry)")
        elif first is not None:  # the sensor is calibrated to the log: its resolution
            check_scan_rate(args.rate_hz, first.scan.angle_increment, "--rate-hz")
    first = (f"sim2real: calibrating, fitting the world to the log and simulating {len(args.seeds)} world(s) "
             "(minutes at the defaults; Ctrl-C stops) ...")
    with heartbeat_on_terminal("sim2real", first):
        result = sim2real(args.log, world=args.world, seeds=args.seeds, duration=args.duration, rate_hz=args.rate_hz,
                          stride=args.stride, max_scans=args.max_scans, sensor=sensor, read_options=read_options,
                          fit_rooms=args.fit_rooms, probe_duration=args.probe_duration, probe_seeds=args.probe_seeds,
                          fit_duration=args.fit_duration)
    config = dict(log=str(args.log), duration=args.duration, probe_duration=args.probe_duration, rate_hz=args.rate_hz,
                  stride=args.stride,
                  max_scans=args.max_scans, sensor_file=None if args.sensor is None else str(args.sensor),
                  world=args.world, glass_per_10m=result.glass, fit_rooms=args.fit_rooms,
                  fit_duration=None if args.sensor is not None else args.fit_duration or FIT_DURATION_S,
                  versions=versions())
    run_folder = args.out is None  # results/sim2real/DATE_TIME, linked as latest once its files are written
    args.out = args.out or new_run_folder("results/sim2real", now=started)  # named by the run's start, as the demo's
    paths = write_outputs(result, args.out, str(args.log), config)
    args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    if run_folder:
        link_latest(args.out)
    print(format_report(result, str(args.log)), end="")
    for warning in result.warnings:
        if warning not in result.warned_early:  # said before the work (too few real scans)
            print(f"lmsbench sim2real: warning: {warning}", file=sys.stderr)
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0
