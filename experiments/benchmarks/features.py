"""Benchmark of the sensor-coordinate extractor: scans per second through the public
``features.extract(scan, method="sensor")`` call, one scan at a time, on 361-beam office scans
from the simulator (or, where ``sim`` is absent, analytic scans of a furnished rectangular room)."""

from __future__ import annotations

import time

import numpy as np

from experiments.synthetic import cast
from features import extract
from lms200 import Scan

NAME = "features"
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


def time_sensor(scans: list[Scan], repeats: int) -> dict:
    """Per-scan times of extract(scan, method="sensor") over ``repeats`` passes."""
    for s in scans[:50]:  # warm caches (templates) and load the compiled kernels
        extract(s, method="sensor")
    times = np.empty((repeats, len(scans)))
    cpu = np.empty(repeats)
    n_lines = n_corners = 0
    for rep in range(repeats):
        c0 = time.process_time_ns()
        for i, s in enumerate(scans):
            t0 = time.perf_counter_ns()
            fs = extract(s, method="sensor")
            times[rep, i] = time.perf_counter_ns() - t0
            n_lines += len(fs.lines)
            n_corners += len(fs.corners)
        cpu[rep] = (time.process_time_ns() - c0) / len(scans)
    us = times.ravel() / 1e3
    best_us = times.min(axis=0) / 1e3  # per scan, the least disturbed of the repeats
    return {
        "scans_per_s": float(1e6 / us.mean()),
        "mean_us": float(us.mean()),
        "cpu_us": float(cpu.min() / 1e3),
        "best_of_repeats_us": float(best_us.mean()),
        "scans_per_s_best": float(1e6 / best_us.mean()),
        "scans_per_s_cpu": float(1e9 / cpu.min()),
        "median_us": float(np.median(us)),
        "p95_us": float(np.percentile(us, 95)),
        "lines_per_scan": n_lines / (repeats * len(scans)),
        "corners_per_scan": n_corners / (repeats * len(scans)),
    }


def run(quick: bool = False) -> list[dict]:
    """One row: scans/s and per-scan time of extract(scan, method="sensor"), wall clock over all
    repeats (``scans_per_s``, ``mean_us``), the mean over scans of each scan's fastest repeat
    (``best_of_repeats_us``, ``scans_per_s_best``: on a shared machine the least disturbed
    figure), and the process CPU time per scan of the least disturbed pass (``cpu_us``,
    ``scans_per_s_cpu``)."""
    count = 200 if quick else 1500
    scans, source = office_scans(count)
    repeats = 2 if quick else 5
    row = {"benchmark": "extract_sensor", "backend": "numba", "source": source, "scans": len(scans)}
    row.update(time_sensor(scans, repeats))
    return [row]


def accuracy(world: str, duration: float = 300.0, rate_hz: float = 0.4, sensor=None, **params) -> dict:
    """Scores of the sensor method on a simulated tour of ``world`` (the README's accuracy table):
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


if __name__ == "__main__":  # python -m experiments.benchmarks.features: the README's accuracy table
    for name in ("office", "angles", "pillars"):
        print(", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in accuracy(name).items()))
