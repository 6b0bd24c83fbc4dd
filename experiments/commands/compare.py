"""`lmsbench compare`: every extractor on the same scans (simulated worlds or a real log), timed
interleaved in one process; a tidy table, a summary (printed and saved) and the resolved configs."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

import yaml

from lms200 import LmsbenchError

from experiments.options import DURATION, SEED, check_methods, check_out, check_yaml, count, positive


def _param(text: str) -> tuple[str, Any]:
    key, eq, value = text.partition("=")
    if not eq or not key.startswith("extractor.") or len(key) <= len("extractor."):
        hint = f" (write extractor.{key})" if eq and "." in key and not key.startswith("extractor.") else ""
        raise argparse.ArgumentTypeError(f"--set takes extractor.FIELD=VALUE or extractor.METHOD.FIELD=VALUE, "
                                         f"got {text!r}{hint}")
    try:
        return key, yaml.safe_load(value)
    except yaml.YAMLError:
        raise argparse.ArgumentTypeError(f"--set {key}: {value!r} is not a value") from None


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("compare", help="every extractor on identical scans: accuracy, corners and speed")
    p.add_argument("sources", nargs="+",
                   help="world names (office, corridor, angles, pillars, random; WORLD:SEED for one seed), "
                        "`lmsbench simulate` folders, or paths of real logs")
    p.add_argument("--methods", nargs="+", help="extractors (default: every available one)")
    p.add_argument("--seeds", nargs="+", type=SEED, default=[0, 1, 2], help="seeds of each world (default 0 1 2)")
    p.add_argument("--duration", type=DURATION, default=30.0, help="simulated seconds per world and seed (default 30)")
    p.add_argument("--rate", type=positive("scans/s"), default=2.0, help="simulated scans per second kept (default 2)")
    p.add_argument("--stride", type=count(1), default=1, help="logs: use every STRIDE-th scan (default 1)")
    p.add_argument("--max-scans", type=count(1), help="at most this many scans per source")
    p.add_argument("--sigma", type=positive("m"), default=0.005, help="range noise (m) for the explained fraction")
    p.add_argument("--sensor", type=Path, metavar="FILE.yaml",
                   help="sensor model of the simulated sources, as written (e.g. from `lmsbench calibrate`)")
    p.add_argument("--set", dest="params", action="append", type=_param, default=[], metavar="extractor.[METHOD.]FIELD=VALUE",
                   help="override a config field of every extractor that has it, or of METHOD only (repeatable)")
    p.add_argument("--out", type=Path, default=Path("results/compare"), help="output folder")
    p.add_argument("--format", choices=("parquet", "csv"), default="parquet", help="format of the tidy table")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from experiments.compare import (check_sources, common_errors, compare, format_summary, parse_sources,
                                     resolved_configs, summarise)
    from experiments.overrides import extractor_overrides
    from features.scoring import ScoreConfig

    methods = check_methods(args.methods)
    params = extractor_overrides(dict(args.params), methods)
    configs = resolved_configs(methods, params)  # raises on unknown methods / fields before any work
    check_out(args.out)
    check_sources(args.sources)
    sensor = None
    if args.sensor is not None:
        import sim

        check_yaml(args.sensor, "a sensor YAML")
        try:
            sensor = sim.SensorConfig.from_yaml(args.sensor)
        except LmsbenchError:
            raise
        except (yaml.YAMLError, TypeError, ValueError, KeyError) as exc:
            raise LmsbenchError(f"{args.sensor}: not a sensor model ({' '.join(str(exc).split())})") from None
    from experiments.progress import warm_up_kernels

    warm_up_kernels()
    sources = parse_sources(args.sources, args.seeds, args.duration, args.rate, args.stride, args.max_scans,
                            sensor=sensor)
    score_config = ScoreConfig()
    matches: list = []
    table = compare(sources, methods, params=params, score_config=score_config, sigma=args.sigma,
                    max_scans=args.max_scans, progress=not args.no_progress, matches=matches)
    if table.empty:
        raise LmsbenchError("no scans in the given sources")
    summary = summarise(table)
    if matches:
        summary = summary.merge(common_errors(pd.DataFrame(matches)), on=["source", "method"], how="left")
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"compare.{args.format}"
    if args.format == "parquet":
        table.to_parquet(path, index=False)
    else:
        table.to_csv(path, index=False)
    summary.to_csv(args.out / "summary.csv", index=False)
    text = format_summary(summary)
    (args.out / "summary.txt").write_text(text + "\n")
    resolved = dict(
        sources=args.sources, seeds=args.seeds, duration=args.duration, rate_hz=args.rate, stride=args.stride,
        max_scans=args.max_scans, sigma=args.sigma, methods=configs, scoring=dataclasses.asdict(score_config),
    )
    resolved["scans_from"] = [dict(name=src.name, kind=src.kind, **src.settings) for src in sources]
    (args.out / "config.yaml").write_text(yaml.safe_dump(resolved, sort_keys=False))
    print(text)
    print(f"wrote {path}, {args.out / 'summary.csv'}, {args.out / 'summary.txt'}, {args.out / 'config.yaml'}")
    return 0
