"""Benchmark of the sensor-coordinate extractor: scans per second through the public
``features.extract(scan, method="sensor")`` call, one scan at a time, on 361-beam office scans
from the simulator (or, where ``sim`` is absent, analytic scans of a furnished rectangular room)."""

from __future__ import annotations

import time

import numpy as np

from features import extract
from lms200 import Scan

NAME = "features"


def office_scans(count: int, seed: int = 0) -> tuple[list[Scan], str]:
    """``count`` 361-beam scans of the simulated office (noise and quantisation on), with the
    source's name; analytic room scans when the simulator is not installed."""
    try:
        from sim import simulate_records
    except ImportError:
        return room_scans(count, seed), "analytic room"
    records = simulate_records(world="office", seed=seed, duration=count / 37.5 + 1.0)
    return [r.scan for r in records[:count]], "sim office"


def room_scans(count: int, seed: int = 0) -> list[Scan]:
    """Analytic scans of a 8 m x 5 m room with a 1 m box in it, from random poses (5 mm noise)."""
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
        b = th - np.pi / 2 + np.arange(361) * np.deg2rad(0.5)
        dx, dy = np.cos(b), np.sin(b)
        best = np.full(361, np.inf)
        for x1, y1, x2, y2 in walls:
            ex, ey = x2 - x1, y2 - y1
            den = dx * ey - dy * ex
            with np.errstate(divide="ignore", invalid="ignore"):
                t = ((x1 - x) * ey - (y1 - y) * ex) / den
                s = ((x1 - x) * dy - (y1 - y) * dx) / den
            hit = (np.abs(den) > 1e-12) & (t > 0) & (s >= 0) & (s <= 1)
            best = np.where(hit & (t < best), t, best)
        best = np.round(best + rng.normal(0, 0.005, 361), 3)
        best[best > 8.183] = np.inf
        scans.append(Scan.lms200(best))
    return scans


def run(quick: bool = False) -> list[dict]:
    """One row: scans/s and per-scan time of extract(scan, method="sensor")."""
    count = 200 if quick else 1500
    scans, source = office_scans(count)
    for s in scans[:50]:  # warm caches (templates, configs)
        extract(s, method="sensor")
    repeats = 1 if quick else 3
    times = np.empty((repeats, len(scans)))
    n_lines = n_corners = 0
    for rep in range(repeats):
        for i, s in enumerate(scans):
            t0 = time.perf_counter_ns()
            fs = extract(s, method="sensor")
            times[rep, i] = time.perf_counter_ns() - t0
            n_lines += len(fs.lines)
            n_corners += len(fs.corners)
    us = times.ravel() / 1e3
    return [
        {
            "benchmark": "extract_sensor",
            "source": source,
            "scans": len(scans),
            "scans_per_s": float(1e6 / us.mean()),
            "mean_us": float(us.mean()),
            "median_us": float(np.median(us)),
            "p95_us": float(np.percentile(us, 95)),
            "lines_per_scan": n_lines / (repeats * len(scans)),
            "corners_per_scan": n_corners / (repeats * len(scans)),
        }
    ]
