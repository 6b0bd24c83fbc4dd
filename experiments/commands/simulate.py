"""`lmsbench simulate`: a robot tour through a simulated office, scanned by an emulated LMS200."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="simulate an LMS200 run through an office world (scans.clf, "
                                        "groundtruth.tum, world.json, config.yaml, map.png)")
    p.add_argument("--world", default="office",
                   help="office, corridor, angles, pillars, random, cluttered (office with clutter 1), "
                        "mit (the MIT-CSAIL-like preset), or a world.json (default office)")
    p.add_argument("--clutter", type=float, default=None,
                   help="clutter level of a named world: 0 none, 1 a furnished office, 2-3 busy "
                        "(chair and table legs, people, plants, bins, glass, doors at any angle; default: the world's own)")
    p.add_argument("--seed", type=int, default=0, help="seed of the world, tour and sensor noise")
    p.add_argument("--duration", type=float, default=120.0, help="simulated time, s (default 120)")
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--rate-hz", type=float, default=None, help="keep about this many scans/s (default all)")
    p.add_argument("--resolution", type=float, choices=(0.25, 0.5, 1.0), default=0.5,
                   help="angular resolution, deg: 0.5 (361 beams), 1 (181), 0.25 (401 over 100 deg)")
    p.add_argument("--units", choices=("mm", "cm"), default="mm", help="range unit mode (default mm)")
    p.add_argument("--ideal", action="store_true", help="exact ranges: no noise, quantisation, dropouts, ...")
    p.add_argument("--sensor", type=Path, metavar="FILE.yaml",
                   help="sensor model from a YAML (e.g. from `lmsbench calibrate`); replaces --resolution and --units")
    p.add_argument("--odometry", action="store_true", help="add noisy wheel odometry to the scans")
    p.add_argument("--config", type=Path, help="rerun a config.yaml written by an earlier run")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import yaml

    from lms200 import LmsbenchError
    from sim import WORLD_NAMES, SensorConfig
    from sim.records import OdometryConfig

    from experiments.simulation import SimulationConfig, run_simulation

    if args.config:
        try:
            cfg = SimulationConfig.from_dict(yaml.safe_load(args.config.read_text()))
        except (yaml.YAMLError, TypeError, ValueError) as exc:
            raise LmsbenchError(f"{args.config}: not a simulate config ({exc})") from None
    else:
        if args.world not in WORLD_NAMES and not args.world.endswith(".json"):
            raise LmsbenchError(f"unknown world {args.world!r}; known worlds: {', '.join(WORLD_NAMES)} or a world.json")
        if args.world.endswith(".json") and not Path(args.world).is_file():
            raise FileNotFoundError(f"no such world file: {args.world}")
        if args.clutter is not None and not args.clutter >= 0:
            raise LmsbenchError(f"--clutter must be >= 0, got {args.clutter}")
        if args.clutter is not None and args.world.endswith(".json"):
            raise LmsbenchError("--clutter applies to named worlds; a world.json holds its own solids")
        if args.duration <= 0:
            raise LmsbenchError(f"--duration must be > 0, got {args.duration}")
        beams = {0.5: 361, 1.0: 181, 0.25: 401}[args.resolution]
        base = SensorConfig.ideal if args.ideal else SensorConfig
        if args.sensor is not None:
            if args.ideal:
                raise LmsbenchError("--sensor and --ideal exclude each other (the file holds the whole sensor model)")
            sensor = SensorConfig.from_yaml(args.sensor)
        else:
            sensor = base(n_beams=beams, resolution_deg=args.resolution, units=args.units,
                          **({} if args.ideal or args.units == "mm" else {"noise_sigma": 0.01}))
        cfg = SimulationConfig(world=args.world, seed=args.seed, duration=args.duration, rate_hz=args.rate_hz,
                               sensor=sensor, odometry=OdometryConfig() if args.odometry else None,
                               clutter=args.clutter)
    records = run_simulation(cfg, args.out)
    print(f"simulated {len(records)} scans of world {cfg.world} (seed {cfg.seed}, {cfg.duration:g} s) into {args.out}")
    return 0
