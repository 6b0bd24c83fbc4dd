"""The SLAM evaluation behind docs/slam.md: simulated office runs per seed and rate (ATE), a long
run's consistency (NEES), and MIT CSAIL (relations error), paper preset against the default.

``python -m experiments.slameval --out results/slam-eval [--seeds 0-20] [--mit PATH|none]`` writes
slameval.yaml (its settings, first), sim.parquet, mit.parquet (where the log is), long.parquet (unless
``--long 0``) and tables.md (markdown), an earlier run's in the folder (told by its slameval.yaml) removed
first, a file of these names no earlier run wrote refused. Speeds are CPU time
(``time.process_time``) of ``run_slam`` (feature extraction included), one process, one core, the
best of 3 runs on the simulated runs and of 2 for the default preset on MIT CSAIL.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from experiments.options import (DURATION, MAX_DURATION_S, SEED, SLAMEVAL_OWNER, OneLineParser, OutTree, check_out,
                                 number, path_arg)
from experiments.provenance import versions, write_parquet, write_record
from lms200.yamlio import dump as dump_yaml

if TYPE_CHECKING:
    from experiments.slamrun import SlamInput

MIT_LOG = Path(__file__).resolve().parents[2] / "shared" / "data" / "carmen" / "mit-csail.clf.gz"


def _timed(records, config, repeats: int = 1):
    """The result of ``run_slam`` and its CPU time (s), the best of ``repeats`` runs (the runs are
    deterministic: the same result every time; the best time is the least disturbed by the other
    processes on a shared machine)."""
    from slam import run_slam

    best = np.inf
    for _ in range(repeats):
        start = time.process_time()
        result = run_slam(records, config)
        best = min(best, time.process_time() - start)
    return result, best


def sim_rows(seeds: list[int], rates: list[float], duration: float, presets: list[str]) -> pd.DataFrame:
    """One row per seed x rate x preset: ATE RMSE / max (m), loops, CPU scans/s."""
    from sim import simulate_records
    from slam import SlamConfig
    from slam.metrics import ate

    rows = []
    for seed in seeds:
        for rate in rates:
            records = simulate_records("office", seed=seed, duration=duration, rate_hz=rate)
            truth = np.array([(r.scan.stamp, *r.truth) for r in records])
            for preset in presets:
                result, cpu = _timed(records, SlamConfig(preset=preset), repeats=3)
                a = ate(result.trajectory, truth)
                d = result.diagnostics
                rows.append({"seed": seed, "rate_hz": rate, "preset": preset, "scans": len(records),
                             "ate_rmse_m": a.rmse, "ate_max_m": a.max, "loops": d.get("n_loops", 0),
                             "mean_nees": d["mean_nees"], "cpu_scans_per_s": len(records) / cpu})
                print(rows[-1], flush=True)
    return pd.DataFrame(rows)


def long_run(seed: int, duration: float, rate: float) -> pd.DataFrame:
    """Mean pose NEES of the default pipeline over a long run, against the chi-square band."""
    from scipy.stats import chi2
    from sim import simulate_records
    from slam import SlamConfig
    from slam.metrics import ate

    records = simulate_records("office", seed=seed, duration=duration, rate_hz=rate)
    truth = np.array([(r.scan.stamp, *r.truth) for r in records])
    result, cpu = _timed(records, SlamConfig())
    nees = result.diagnostics["nees"]
    later = nees[int(60 * rate):]
    later = later[np.isfinite(later)]
    return pd.DataFrame([{"seed": seed, "duration_s": duration, "rate_hz": rate, "scans": len(records),
                          "ate_rmse_m": ate(result.trajectory, truth).rmse, "mean_nees_after_60s": later.mean(),
                          "median_nees": float(np.median(later)), "band_lo": chi2.ppf(0.025, 3), "band_hi": chi2.ppf(0.975, 3),
                          "fraction_in_band": float(np.mean((later > chi2.ppf(0.025, 3)) & (later < chi2.ppf(0.975, 3)))),
                          "cpu_scans_per_s": len(records) / cpu}])


def read_mit(path: Path, log: Path | None = None) -> SlamInput:
    """The MIT CSAIL log at ``path``, read whole, with its relations (``NAME.relations`` beside it).
    ``log``: ``options.check_log(path)`` where the caller has it already (``--mit LOG``, checked as it
    is parsed: its head was read again here), else it is checked here (the default log).

    Raises:
        LmsbenchError: not a log (``options.check_log``, then the reader), or no relations beside it
            (:func:`mit_rows` scores against them: it failed after the runs, a TypeError traceback)."""
    from experiments.options import InputError, check_log
    from experiments.slamrun import load_input

    data = load_input(check_log(path) if log is None else log)
    if data.relations is None:
        raise InputError(f"--mit {path}: no relations file beside it (NAME.relations), which the relations error "
                         "is scored against")
    return data


def mit_rows(data: SlamInput, presets: list[str], inflations: tuple[float, ...] = (3.0, 10.0)) -> pd.DataFrame:
    """Relations error (mean, std, median, long > 200 s) per preset on MIT CSAIL (``data``, :func:`read_mit`),
    and of the default preset with other ``alignment.covariance_inflation`` values (robustness: the keyframe
    and closure factors both take their noise from their matches, so one global factor should not
    move the result)."""
    from slam import SlamConfig
    from slam.metrics import interpolate_poses, relative

    rel = data.relations
    if rel is None:  # read_mit refuses such a log
        raise ValueError("mit_rows: the log has no relations to score against")
    records = list(data.records)  # held, as the runs are timed: a pass over data.records reads the log again
    rows = []
    # the extractor at its defaults: sigma_r 0.02 was given here "for the cm-mode ranges", which read
    # sigma_r_cm ("auto") instead, so the runs were the defaults' bit for bit
    runs = [(preset, SlamConfig(preset=preset)) for preset in presets]
    if "default" in presets:
        runs += [(f"default, covariance_inflation {f:g}",
                  SlamConfig.from_dict({"alignment": {"covariance_inflation": f}}))
                 for f in inflations]
    for preset, cfg in runs:
        result, cpu = _timed(records, cfg, repeats=2 if preset == "default" else 1)
        p1, _ = interpolate_poses(result.trajectory, rel[:, 0])
        p2, _ = interpolate_poses(result.trajectory, rel[:, 1])
        err = relative(rel[:, 2:5], relative(p1, p2))
        te = np.hypot(err[:, 0], err[:, 1])
        long = rel[:, 1] - rel[:, 0] > 200
        rows.append({"preset": preset, "trans_mean_m": te.mean(), "trans_std_m": te.std(), "trans_median_m": float(np.median(te)),
                     "long_mean_m": te[long].mean(), "n_long": int(long.sum()), "loops": result.diagnostics.get("n_loops", 0),
                     "cpu_scans_per_s": len(data.records) / cpu})
        print(rows[-1], flush=True)
    return pd.DataFrame(rows)


def _md(df: pd.DataFrame) -> str:
    """A markdown table of a frame (floats to 3 decimals)."""
    cells = [[f"{v:.3f}" if isinstance(v, float) else str(v) for v in row] for row in df.itertuples(index=False)]
    head = [str(c) for c in df.columns]
    return "\n".join(["| " + " | ".join(head) + " |", "|" + "---|" * len(head)] + ["| " + " | ".join(c) + " |" for c in cells])


MAX_SEEDS = 1000  # seeds one evaluation runs at most (each runs a simulated run and its SLAM per rate)


def _seeds(text: str) -> list[int]:
    """An argparse type: a seed or a range LO-HI of seeds (whole numbers 0 .. 2**32 - 1, as ``options.SEED``,
    LO <= HI, at most ``MAX_SEEDS`` of them): `--seeds 0-99999999999` built the list of 1e11 seeds, a
    MemoryError traceback, and `--seeds 3-` ran seed 3."""
    lo, dash, hi = text.partition("-")
    if dash and not hi.strip():
        raise argparse.ArgumentTypeError(f"must be a seed or a range LO-HI of seeds (0-20), got {text!r}: no HI")
    try:
        first, last = (int(SEED(v)) for v in (lo, hi or lo))
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"must be a seed or a range LO-HI of seeds (0-20), got {text!r}: each {exc}") from None
    if first > last:
        raise argparse.ArgumentTypeError(f"must be a seed or a range LO-HI of seeds with LO <= HI, got {text!r}")
    if last - first + 1 > MAX_SEEDS:
        raise argparse.ArgumentTypeError(f"at most {MAX_SEEDS} seeds, got {text!r} ({last - first + 1:,})")
    return list(range(first, last + 1))


_seeds.__name__ = "seeds"  # argparse names the type in some messages


def _long(text: str) -> float:
    """An argparse type: the consistency run's duration (s), 0 for none, else as a simulated run's
    (``options.DURATION``: `--long 1e-3` failed inside the simulator, a traceback)."""
    value = number(0.0, MAX_DURATION_S, unit="s")(text)
    if value != 0.0:
        try:
            value = DURATION(text)
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentTypeError(f"{exc} (or 0: no consistency run)") from None
    return value


_long.__name__ = "number"


RATES_HZ = (37.5, 5.0)  # the simulated runs' rates: the LMS200's and decimated
#: what --out receives: slameval.yaml first, whole (it tells the folder as this script's: options.SLAMEVAL_OWNER)
RECORD = "slameval.yaml"
OUTPUTS = (RECORD, "sim.parquet", "mit.parquet", "long.parquet", "tables.md")
#: the simulated runs' sensor, ``sim.SensorConfig()``'s: 361 beams 0.5 deg apart (a test holds them to it:
#: importing the simulator to read them took 0.5 s of every parser build, ``--help`` and refusals included)
SIM_BEAMS, SIM_RESOLUTION_RAD = 361, math.radians(0.5)


def min_duration(rates: tuple[float, ...] = RATES_HZ) -> float:
    """The shortest simulated run (s, rounded up to 0.01 s) that keeps two scans at each of ``rates``, the
    fewest the ATE scores: `--duration 0.2` kept one at 5 scans/s and failed after the runs at 37.5 with
    a traceback ("ate: fewer than 2 estimated poses"). From the LMS200's timing (``lms200.timing``): a
    run's second scan kept at a rate is its every ``round(1 / (period * rate))``-th, as
    ``sim.records.scan_stamps`` keeps them, and it ends with that scan's last beam.

    Raises:
        LmsbenchError: a rate at which no run the simulator makes (``MAX_DURATION_S`` at most) keeps two
            scans (below one scan an hour: it keeps the first alone; the 3600.02 s given for it was
            longer than any run), or a rate that is not > 0."""
    from lms200 import LmsbenchError
    from lms200.timing import beam_time_offsets, scan_period

    period = scan_period(SIM_RESOLUTION_RAD)
    last_beam = float(beam_time_offsets(SIM_BEAMS, SIM_RESOLUTION_RAD).max())
    needs = []
    for rate in rates:
        need = max(1, round(1.0 / (period * rate))) * period + last_beam if rate > 0 else math.inf
        if not need <= MAX_DURATION_S:  # the simulator keeps one scan of any run at this rate
            raise LmsbenchError(f"min_duration: at {rate:g} scans/s no simulated run of at most {MAX_DURATION_S:g} s "
                                "keeps two scans (the simulator keeps its first alone)")
        needs.append(need)
    return math.ceil(max(needs) * 100 - 1e-6) / 100


def main(argv: list[str] | None = None) -> int:
    # the docstring's first paragraph (its first line alone stopped mid-sentence: "..., a long")
    # a bad value is one line, exit 2 (options.OneLineParser); the durations read as options.number reads them:
    # `--long 1e-400` read as 0, "no consistency run", and ran without it, exit 0 (lms200.finite.underflow_problem)
    from lms200 import LmsbenchError

    ap = OneLineParser(prog="python -m experiments.slameval", description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--out", type=path_arg, required=True, help="folder for slameval.yaml, sim.parquet, mit.parquet, long.parquet, tables.md")
    ap.add_argument("--seeds", type=_seeds, default="0-20",
                    help=f"simulated office runs, a seed or a range LO-HI, at most {MAX_SEEDS} (default 0-20)")
    shortest = min_duration()
    ap.add_argument("--duration", type=number(shortest, MAX_DURATION_S, unit="s"), default=90.0,
                    help=f"duration (s) of each simulated run, at least {shortest:g}: two scans at 5 scans/s (default 90)")
    ap.add_argument("--mit", type=_mit, default=MIT_LOG, action=_MitLog,
                    help="MIT CSAIL log, with its NAME.relations beside it, or 'none' for no MIT CSAIL run (default: "
                         "shared/data/carmen/mit-csail.clf.gz beside the checkout, none where absent)")
    ap.add_argument("--long", type=_long, default=900.0, help="duration (s) of the consistency run (default 900; 0: none)")
    ap.set_defaults(mit_log=None)
    args = ap.parse_args(argv)
    try:  # a user error is one line, exit 2, as the CLI's (an existing file as --out was a FileExistsError traceback)
        check_out(args.out, OUTPUTS, owner=SLAMEVAL_OWNER)  # only an earlier run's files are replaced
        return _run(args)
    except LmsbenchError as exc:
        ap.error(str(exc))
    return 2


class _MitLog(argparse.Action):
    """``--mit``: the log as given (``args.mit``, as slameval.yaml records it) and as ``check_log``
    returned it when parsed (``args.mit_log``, which :func:`read_mit` reads: it checked the log again)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        namespace.mit, namespace.mit_log = values if values is not None else (None, None)


def _mit(text: str) -> tuple[Path, Path] | None:
    """An argparse type: ``--mit``'s log, which must exist, as given and as ``check_log`` returns it, or
    None for the word 'none' (a log given that did not exist was passed over in silence, and the run wrote
    no MIT CSAIL table)."""
    if text.strip().lower() == "none":
        return None
    from experiments.options import check_log, mid_sentence
    from lms200 import LmsbenchError

    path = path_arg(text)
    try:  # as `lmsbench slam` checks a log: what stands in its place, a name too long (a traceback here)
        log = check_log(path)
    except LmsbenchError as exc:
        raise argparse.ArgumentTypeError(f"{exc} (give 'none' for no MIT CSAIL run)") from None
    except OSError as exc:  # in the words of the CLI's: "NAME: file name too long"
        raise argparse.ArgumentTypeError(f"{exc.filename or text}: {mid_sentence(exc.strerror or str(exc))}") from None
    return path, log


def record(args: argparse.Namespace) -> str:
    """slameval.yaml: the run's settings and versions, which tell its folder as this script's."""
    seeds = f"{args.seeds[0]}-{args.seeds[-1]}" if len(args.seeds) > 1 else str(args.seeds[0])
    return ("# what wrote this folder; python -m experiments.slameval --out replaces its files only beside this record\n"
            + dump_yaml({"command": "python -m experiments.slameval", "seeds": seeds, "duration_s": args.duration,
                         "long_s": args.long, "mit": None if args.mit is None else str(args.mit),
                         "versions": versions()}, sort_keys=False))


def _run(args: argparse.Namespace) -> int:
    """The evaluation of the parsed options: the tables, written into ``args.out``, whose earlier run's
    outputs (all ``check_out`` let it hold: beside that run's slameval.yaml) are removed first: one this run
    does not write (long.parquet under `--long 0`, mit.parquet without the log) stayed beside the new tables
    as if it were this run's."""
    # the log read (and so checked) whole before anything is removed: a --mit file that was no log was
    # refused after the earlier run's outputs (hours of runs) were gone
    if args.mit == MIT_LOG and not MIT_LOG.exists():  # the default (a --mit given is checked when parsed)
        print(f"no MIT CSAIL log at {MIT_LOG}: no MIT CSAIL run (give --mit LOG, or --mit none to say so)",
              file=sys.stderr)
        args.mit = None
    data = None if args.mit is None else read_mit(args.mit, getattr(args, "mit_log", None))
    args.out.mkdir(parents=True, exist_ok=True)
    # before any is written: a stopped run leaves no mix; only the files an earlier run's record tells as its own
    # (check_out refused any other: a user's long.parquet in the folder was removed by its name alone)
    SLAMEVAL_OWNER.remove_earlier(args.out, OutTree(OUTPUTS), keep=(RECORD,))
    write_record(args.out / RECORD, record(args))
    md = []
    if data is not None:
        mit = mit_rows(data, ["paper", "default"])
        write_parquet(mit, args.out / "mit.parquet")
        md += [_md(mit), ""]
    if args.long > 0:
        lg = long_run(0, args.long, RATES_HZ[0])
        write_parquet(lg, args.out / "long.parquet")
        md += [_md(lg), ""]
    sim = sim_rows(args.seeds, list(RATES_HZ), args.duration, ["default"])
    write_parquet(sim, args.out / "sim.parquet")
    wide = sim.pivot_table(index="seed", columns="rate_hz", values=["ate_rmse_m", "cpu_scans_per_s"])
    wide.columns = [f"{v} @ {r:g} Hz" for v, r in wide.columns]
    md += [_md(wide.reset_index()), ""]
    (args.out / "tables.md").write_text("\n".join(md))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
