"""`lmsbench simulate`: a robot tour through a simulated office, scanned by an emulated LMS200."""

from __future__ import annotations

from lms200.timing import check_scan_rate
from lms200.yamlio import load as load_yaml

import argparse
import math

from experiments.options import (WORLDS, DURATION, MAX_DURATION_S, MIN_DURATION_S, SEED, SIMULATE_OUTPUTS, SIMULATE_OWNER, InputError, plain, check_file, warnings_after_checks, check_sim2real_finished,
                                 check_world_file,
                                 check_out, check_out_spares, check_yaml, known_worlds, number, path_arg, scan_rate, world_hint)


CLUTTER_MAX = 10.0  # sim.worlds.MAX_CLUTTER (tests/test_cli_bad_input.py checks they agree)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="simulate an LMS200 run through an office world (scans.clf, "
                                        "groundtruth.tum, world.json, config.yaml, map.png)")
    p.add_argument("--world", default=None,
                   help="a built-in world (" + WORLDS + "; cluttered is the office with clutter 1, mit the "
                        "MIT-CSAIL-like preset) or a world.json (default office)")
    # the interval in one message: -1 said ">= 0" while 1e300 said "at most 10" (sim.worlds.MAX_CLUTTER, not
    # imported here: sim loads pybullet)
    p.add_argument("--clutter", type=number(0.0, CLUTTER_MAX, unit="(10x a furnished office at most)"), default=None,
                   help="clutter level of a named world: 0 none, 1 a furnished office, 2-3 busy "
                        "(chair and table legs, people, plants, bins, glass, doors at any angle; at most 10; default: the world's own)")
    p.add_argument("--seed", type=SEED, default=None, help="seed of the world, tour and sensor noise (>= 0; default 0)")
    p.add_argument("--duration", type=DURATION, default=None,
                   help=f"simulated time, s (default 120, at most {MAX_DURATION_S:g})")
    p.add_argument("--out", type=path_arg, required=True, help="output folder")
    p.add_argument("--rate-hz", type=scan_rate, default=None, help="keep about this many scans/s (default all)")
    p.add_argument("--resolution-deg", "--resolution", dest="resolution_deg", type=plain(), choices=(0.25, 0.5, 1.0),
                   default=None, help="angular resolution, deg: 0.5 (361 beams), 1 (181), 0.25 (401 over 100 deg); "
                   "default 0.5; --resolution is the old spelling")
    p.add_argument("--units", choices=("mm", "cm"), default=None, help="range unit mode (default mm)")
    p.add_argument("--ideal", action="store_true", help="exact ranges: no noise, quantisation, dropouts, ...")
    p.add_argument("--sensor", type=path_arg, metavar="FILE.yaml",
                   help="sensor model from a YAML (e.g. from `lmsbench calibrate`), which sets the resolution and units: "
                   "not to be combined with --resolution-deg, --units or --ideal")
    p.add_argument("--odometry", action="store_true", help="add noisy wheel odometry to the scans")
    p.add_argument("--config", type=path_arg, help="rerun a config.yaml written by an earlier run (it holds the whole "
                                               "run: no other option of the run may be given with it)")
    p.add_argument("--quiet", "--no-progress", dest="quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


RUN_FLAGS = (("--world", "world"), ("--clutter", "clutter"), ("--seed", "seed"), ("--duration", "duration"),
             ("--rate-hz", "rate_hz"), ("--resolution-deg", "resolution_deg"), ("--units", "units"),
             ("--ideal", "ideal"), ("--sensor", "sensor"), ("--odometry", "odometry"))
DEFAULTS = {"world": "office", "seed": 0, "duration": 120.0, "resolution_deg": 0.5, "units": "mm"}


def _config(args: argparse.Namespace):
    import yaml

    from lms200 import LmsbenchError
    from sim import SensorConfig
    from sim.records import OdometryConfig

    from experiments.simulation import SimulationConfig

    if args.config:
        given = [flag for flag, dest in RUN_FLAGS if getattr(args, dest) is not None and getattr(args, dest) is not False]
        if given:
            raise InputError(f"--config holds the whole run; {', '.join(given)} cannot be given with it "
                             "(edit the file, or leave out --config)")
        check_yaml(args.config, "a simulate config.yaml")
        try:
            raw = load_yaml(args.config.read_text())
        except yaml.YAMLError as exc:
            raise InputError(f"{args.config}: not valid YAML ({exc})") from None
        try:
            if not isinstance(raw, dict):
                raise TypeError("expected a mapping of world, seed, duration, sensor, ...")
            cfg = SimulationConfig.from_dict(raw, where=str(args.config))
        except (TypeError, ValueError) as exc:
            raise InputError(f"{args.config}: not a simulate config ({' '.join(str(exc).split())})") from None
        if cfg.world not in known_worlds() and not cfg.world.endswith(".json"):
            raise InputError(f"{args.config}: unknown world {cfg.world!r}; known worlds: {', '.join(known_worlds())}")
        if not MIN_DURATION_S <= cfg.duration <= MAX_DURATION_S:  # the value given was not said (nor which field)
            why = " (shorter holds no scan)" if cfg.duration < MIN_DURATION_S else ""  # said of a value too long too
            raise InputError(f"{args.config}: duration: must be in [{MIN_DURATION_S:g}, {MAX_DURATION_S:g}] s{why}, "
                             f"got {cfg.duration:g}")  # (rate_hz: check_scan_rate below, naming it)
        from sim.worlds import MAX_CLUTTER, check_seed

        try:
            check_seed(cfg.seed)
        except ValueError as exc:
            raise InputError(f"{args.config}: {exc}") from None
        if cfg.clutter is not None and not 0 <= cfg.clutter <= MAX_CLUTTER:
            raise InputError(f"{args.config}: clutter must be in [0, {MAX_CLUTTER:g}], got {cfg.clutter}")
        check_scan_rate(cfg.rate_hz, cfg.sensor.angle_increment, f"{args.config}: rate_hz")
        return cfg
    geometry = [flag for flag, dest in (("--resolution-deg", "resolution_deg"), ("--units", "units"))
                if getattr(args, dest) is not None]
    if args.sensor is not None and geometry:  # they were ignored: the file's n_beams / resolution / units ran
        raise InputError(f"--sensor holds the whole sensor model; {', '.join(geometry)} cannot be given with it "
                         "(edit the file, or leave out --sensor)")
    for dest, default in DEFAULTS.items():
        if getattr(args, dest) is None:
            setattr(args, dest, default)
    worlds = known_worlds()
    if args.world not in worlds and not args.world.endswith(".json"):
        raise InputError(f"--world: unknown world {args.world!r}{world_hint(args.world)}; known worlds: "
                         f"{', '.join(worlds)} or a world.json")
    if args.world.endswith(".json"):
        check_file(args.world, "a world.json")
    if args.clutter is not None and args.world.endswith(".json"):
        raise InputError("--clutter applies to named worlds; a world.json holds its own solids")
    beams = {0.5: 361, 1.0: 181, 0.25: 401}[args.resolution_deg]
    base = SensorConfig.ideal if args.ideal else SensorConfig
    if args.sensor is not None:
        if args.ideal:
            raise InputError("--sensor and --ideal exclude each other (the file holds the whole sensor model)")
        check_sim2real_finished(args.sensor, "--sensor")
        try:
            sensor = SensorConfig.from_yaml(args.sensor)
        except LmsbenchError:
            raise
        except (yaml.YAMLError, TypeError, ValueError, KeyError) as exc:
            raise InputError(f"{args.sensor}: not a sensor model ({' '.join(str(exc).split())})") from None
    else:
        sensor = base(n_beams=beams, resolution=math.radians(args.resolution_deg), units=args.units,
                      **({} if args.ideal or args.units == "mm" else {"noise_sigma": 0.01}))
    check_scan_rate(args.rate_hz, sensor.angle_increment, "--rate-hz")
    return SimulationConfig(world=args.world, seed=args.seed, duration=args.duration, rate_hz=args.rate_hz,
                            sensor=sensor, odometry=OdometryConfig() if args.odometry else None,
                            clutter=args.clutter)


def run(args: argparse.Namespace) -> int:
    from experiments.simulation import run_simulation

    with warnings_after_checks():  # a refused run is its error alone, without a warning of what it read
        cfg = _config(args)  # reads and checks the inputs (the config, the sensor YAML), writes nothing
        # every input against --out at once, the config's world.json too (it was a second check after the
        # config was read): a world.json read is an input too, `simulate --world DIR/world.json --out DIR`
        # wrote world.json over it
        world = cfg.world if cfg.world.endswith(".json") else None
        check_out_spares(args.out, SIMULATE_OUTPUTS, [f for f in (args.config, args.sensor, world) if f is not None])
        check_out(args.out, writes=SIMULATE_OUTPUTS, owner=SIMULATE_OWNER)  # after: an input in --out is the sharper message
        check_world_file(cfg.world)
    records = run_simulation(cfg, args.out, progress=not args.quiet)
    args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    print(f"simulated {len(records)} scans of world {cfg.world} (seed {cfg.seed}, {cfg.duration:g} s) into {args.out}")
    return 0
