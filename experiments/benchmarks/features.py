"""Benchmark of every extractor (``lmsbench bench features``): scans per second of single
``features.extract`` calls and of one ``features.extract_many`` call, on 361-beam office scans
from the simulator (or, where ``sim`` is absent, analytic scans of a furnished rectangular room)
and on MIT CSAIL scans where the shared data is present; process CPU time, best of repeats per
chunk of 50 scans, methods interleaved. ``accuracy`` scores the sensor method on simulated tours."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from experiments.synthetic import cast
from features import available_methods, extract, extract_many, make_config
from features.batch import available_cpus, threads_used
from features.noise_estimate import AUTO, neighbour_sigma
from features.registry import backend_of, get_method
from lms200 import Scan

NAME = "features"
NOISE_GIVEN = "sensor (noise given)"  # the sensor method with a cm-mode log's noise estimated once
ANGLES = -np.pi / 2 + np.arange(361) * np.deg2rad(0.5)  # LMS200 beam bearings (rad), sensor frame


def office_scans(count: int, seed: int = 0) -> tuple[list[Scan], str]:
    """``count`` 361-beam scans of the simulated office (noise and quantisation on), with the
    source's name; analytic room scans when the simulator is not installed."""
    try:
        from sim import simulate_records
    except ImportError:
        return room_scans(count, seed), "analytic room"
    records = simulate_records(world="office", seed=seed, duration=count / 37.5 + 1.0)  # every scan at 37.5/s
    return [r.scan for r in records[:count]], "sim office"


def room_scans(count: int, seed: int = 0) -> list[Scan]:
    """Analytic scans (``experiments.synthetic.cast``) of a 8 m x 5 m room with a 1 m box in it, from
    random poses (5 mm noise, 1 mm rounding)."""
    rng = np.random.default_rng(seed)
    room = [(0, 0, 8, 0), (8, 0, 8, 5), (8, 5, 0, 5), (0, 5, 0, 0)]
    box = [(4, 2, 5, 2), (5, 2, 5, 3), (5, 3, 4, 3), (4, 3, 4, 2)]
    walls = np.array(room + box, dtype=float)
    scans = []
    for _ in range(count):
        while True:
            x, y = rng.uniform(0.5, 7.5), rng.uniform(0.5, 4.5)
            if not (3.7 < x < 5.3 and 1.7 < y < 3.3):
                break
        th = rng.uniform(-np.pi, np.pi)
        best, _ = cast(walls, (x, y, th), ANGLES)
        best = np.round(best + rng.normal(0, 0.005, 361), 3)
        best[best > 8.183] = np.inf
        scans.append(Scan.lms200(best))
    return scans


MIT_LOG = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "carmen" / "mit-csail.clf.gz"


def mit_scans(count: int) -> list[Scan]:
    """Up to ``count`` scans of the MIT CSAIL log (every 4th), where the shared data is present."""
    if not MIT_LOG.exists():
        return []
    from lms200 import read_log

    out = []
    for k, rec in enumerate(read_log(MIT_LOG)):
        if k % 4 == 0:
            out.append(rec.scan)
            if len(out) == count:
                break
    return out


CHUNK = 50  # scans timed together; each chunk's best repeat counts (robust to bursts of load)


def time_methods(scans: list[Scan], methods: list[str], repeats: int,
                 variants: dict[str, tuple[str, Any]] | None = None, threads: int = 1) -> dict[str, dict[str, float]]:
    """CPU seconds per scan of each method over ``scans``: ``single`` (one ``extract`` call per
    scan) and ``batch`` (one one-thread ``extract_many`` call per chunk of CHUNK scans), each
    chunk's best (least disturbed) of ``repeats`` passes, summed over the chunks; the methods and
    the two modes interleaved within every repeat, so that load on a shared machine falls on all
    alike. ``threaded`` and ``one_thread``: wall seconds per scan of one ``extract_many`` call over
    all the scans on ``threads`` threads and on one, best of the repeats (on a loaded machine their
    ratio shows the load, not the threads; nan for the methods that run in one thread, hough and
    ransac). Also the lines and corners per scan. ``variants``: more rows, label -> (method, config)."""
    runs = {m: (m, make_config(m)) for m in methods}
    runs.update(variants or {})
    methods = list(runs)
    configs = {label: cfg for label, (_, cfg) in runs.items()}
    names = {label: m for label, (m, _) in runs.items()}
    for m in methods:  # load the compiled kernels (and compile them in a fresh checkout): not timed
        extract_many(scans[:2], names[m], configs[m])
        extract(scans[0], names[m], configs[m])
    chunks = [scans[i : i + CHUNK] for i in range(0, len(scans), CHUNK)]
    best = {m: {"single": np.full(len(chunks), np.inf), "batch": np.full(len(chunks), np.inf)} for m in methods}
    counts = {}
    threaded: dict[tuple[str, int], float] = {}
    for rep in range(repeats):
        order = methods[rep % len(methods):] + methods[: rep % len(methods)]
        for m in order:
            cfg, name = configs[m], names[m]
            n_lines = n_corners = 0
            for c, chunk in enumerate(chunks):
                c0 = time.process_time()
                for s in chunk:
                    extract(s, name, cfg)
                c1 = time.process_time()
                many = extract_many(chunk, name, cfg, threads=1)
                c2 = time.process_time()
                best[m]["single"][c] = min(best[m]["single"][c], c1 - c0)
                best[m]["batch"][c] = min(best[m]["batch"][c], c2 - c1)
                n_lines += sum(len(f.lines) for f in many)
                n_corners += sum(len(f.corners) for f in many)
            counts[m] = (n_lines / len(scans), n_corners / len(scans))
            if get_method(name).thread_safe and threads > 1:  # (the others run scan by scan in one thread: nan)
                for t in (1, threads):  # all the scans in one call: wall time (CPU time adds the threads up)
                    w0 = time.perf_counter()
                    extract_many(scans, name, cfg, threads=t)
                    threaded[(m, t)] = min(threaded.get((m, t), np.inf), time.perf_counter() - w0)
    return {m: {"single": float(best[m]["single"].sum()) / len(scans), "batch": float(best[m]["batch"].sum()) / len(scans),
                "threaded": threaded.get((m, threads), np.nan) / len(scans),
                "one_thread": threaded.get((m, 1), np.nan) / len(scans), "lines": counts[m][0], "corners": counts[m][1]}
            for m in methods}


def run(quick: bool = False) -> list[dict]:
    """One row per method x scan set (simulated office, 361 beams; MIT CSAIL, where present):
    scans/s of single ``extract`` calls and of one-thread ``extract_many`` batches (process CPU
    time, each chunk's best of the repeats, methods interleaved), per-scan microseconds, the
    ratios to the sensor method (> 1: faster than sensor), and the wall-clock scans/s of
    ``extract_many`` on as many threads as the process has CPUs (at most one a MIN_SCANS_PER_THREAD
    scans; none measured on one CPU) with its ratio to one thread. Where the sensor method estimates the noise from
    the scans (``sigma_r_cm="auto"``, SICK cm mode: MIT CSAIL), a row "sensor (noise given)" runs
    it with that noise estimated once from all the scans, as ``lmsbench compare`` does per log."""
    count = 100 if quick else 600
    repeats = 2 if quick else 7
    threads = threads_used(available_cpus(), count)  # the threads extract_many can use on count scans
    office, source = office_scans(count)
    methods = available_methods()
    rows = []
    for name, scans in ((source, office), ("mit csail", mit_scans(count))):
        if not scans:
            continue
        variants = {}
        if "sensor" in methods and make_config("sensor").sigma_for(scans[0].range_max) == AUTO:
            variants[NOISE_GIVEN] = ("sensor", make_config("sensor", sigma_r_cm=neighbour_sigma(scans)))
        t = time_methods(scans, methods, repeats, variants, threads)
        ref = t.get("sensor", t[methods[0]])
        for m in t:
            rows.append({
                "benchmark": "extract", "method": m, "backend": backend_of(m if m != NOISE_GIVEN else "sensor"),
                "source": name, "scans": len(scans),
                "single_scans_per_s": 1.0 / t[m]["single"], "batch_scans_per_s": 1.0 / t[m]["batch"],
                "single_us": 1e6 * t[m]["single"], "batch_us": 1e6 * t[m]["batch"],
                "single_vs_sensor": ref["single"] / t[m]["single"], "batch_vs_sensor": ref["batch"] / t[m]["batch"],
                "threads": threads, "threaded_scans_per_s": 1.0 / t[m]["threaded"],
                "threaded_vs_one_thread": t[m]["one_thread"] / t[m]["threaded"],
                "lines_per_scan": t[m]["lines"], "corners_per_scan": t[m]["corners"],
            })
    return rows


def accuracy(world: str, duration: float = 300.0, rate_hz: float = 0.4, sensor=None, **params) -> dict:
    """Scores of the sensor method on a simulated tour of ``world`` (docs/features.md's accuracy table):
    line precision/recall/F1, rho/alpha errors (RMS and median), errors over the reported std,
    corner precision/recall, false corners, corner position RMS. Needs ``sim``."""
    import warnings

    from features.scoring import score_scan
    from sim import SensorConfig, make_world, simulate_records, visible_truth

    sensor = sensor if sensor is not None else SensorConfig(interlaced=False)  # exact truth per scan
    w = make_world(world, 0)
    scores, z = [], []
    for rec in simulate_records(world=w, seed=0, duration=duration, sensor=sensor, rate_hz=rate_hz):
        with warnings.catch_warnings(), np.errstate(invalid="ignore"):
            warnings.simplefilter("ignore")
            truth = visible_truth(w, rec.truth, sensor)
        fs = extract(rec.scan, method="sensor", **params)
        sc = score_scan(fs, truth)
        scores.append(sc)
        for (e, _), dr, da in zip(sc.matches, sc.rho_errors, sc.alpha_errors):
            cov = fs.lines[e].cov
            z.append((dr / np.sqrt(cov[0, 0]), da / np.sqrt(cov[1, 1])))
    tp, fp, fn = (sum(getattr(s, f) for s in scores) for f in ("tp", "fp", "fn"))
    ctp, cfp, cfn = (sum(getattr(s, f) for s in scores) for f in ("corner_tp", "corner_fp", "corner_fn"))
    rho = np.concatenate([s.rho_errors for s in scores])
    alpha = np.concatenate([s.alpha_errors for s in scores])
    cerr = np.concatenate([s.corner_errors for s in scores])
    z = np.array(z).reshape(-1, 2)
    p, r = tp / max(tp + fp, 1), tp / max(tp + fn, 1)
    return {
        "world": world, "scans": len(scores), "precision": p, "recall": r, "f1": 2 * p * r / max(p + r, 1e-12),
        "rho_rms_mm": 1e3 * float(np.sqrt(np.mean(rho**2))), "rho_median_mm": 1e3 * float(np.median(np.abs(rho))),
        "alpha_rms_mrad": 1e3 * float(np.sqrt(np.mean(alpha**2))),
        "alpha_median_mrad": 1e3 * float(np.median(np.abs(alpha))),
        "z_std_rho": float(z[:, 0].std()), "z_std_alpha": float(z[:, 1].std()),
        "corner_precision": ctp / max(ctp + cfp, 1), "corner_recall": ctp / max(ctp + cfn, 1),
        "false_corners": cfp, "corner_rms_mm": 1e3 * float(np.sqrt(np.mean(cerr**2))) if cerr.size else float("nan"),
    }


if __name__ == "__main__":  # python -m experiments.benchmarks.features: docs/features.md's accuracy table
    import argparse

    argparse.ArgumentParser(prog="python -m experiments.benchmarks.features",  # --help ran the whole table
                            description="the sensor method's accuracy on 120 scans of office, angles and pillars "
                                        "(docs/features.md); takes no options").parse_args()
    for name in ("office", "angles", "pillars"):
        print(", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in accuracy(name).items()))
