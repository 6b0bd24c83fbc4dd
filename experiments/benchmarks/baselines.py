"""Speed of every extractor on identical scans, interleaved per scan (``lmsbench bench baselines``).

Scans: noisy synthetic rooms (exact L-shaped room, 5 mm noise, seeded poses) and, where the shared
data is present, every 10th scan of the MIT CSAIL log. Rows: one per method x scan set, with the
mean and median microseconds per scan, scans/s and the speed ratio to the sensor method.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from experiments.synthetic import L_ROOM, room_scan
from features.registry import available_methods, get_method, make_config

NAME = "baselines"
MIT_LOG = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "carmen" / "mit-csail.clf.gz"


def _room_scans(n: int) -> list:
    rng = np.random.default_rng(0)
    scans = []
    while len(scans) < n:
        x, y = rng.uniform(-1.5, 4.5), rng.uniform(-2.5, 3.5)
        if x > 3.0 and y > 0.5 + (5.0 - x):  # outside the room's cut corner
            continue
        scans.append(room_scan(L_ROOM, (x, y, rng.uniform(-np.pi, np.pi)), sigma=0.005, seed=len(scans))[0])
    return scans


def _log_scans(n: int) -> list:
    if not MIT_LOG.exists():
        return []
    from lms200 import read_log

    return [rec.scan for k, rec in enumerate(read_log(MIT_LOG)) if k % 10 == 0][:n]


def time_methods(scans: list, methods: list[str], repeats: int) -> dict[str, np.ndarray]:
    """Microseconds per scan of each method (median of ``repeats``), interleaved per scan."""
    runs = [(m, get_method(m).run, make_config(m)) for m in methods]
    out = {m: np.empty(len(scans)) for m in methods}
    for k, scan in enumerate(scans):
        shift = k % len(runs)
        for name, fn, cfg in runs[shift:] + runs[:shift]:
            t = []
            for _ in range(repeats):
                t0 = time.perf_counter_ns()
                fn(scan, cfg)
                t.append(time.perf_counter_ns() - t0)
            out[name][k] = np.median(t) / 1e3
    return out


def run(quick: bool = False) -> list[dict]:
    methods = available_methods()
    n, repeats = (20, 1) if quick else (100, 3)
    rows = []
    for label, scans in (("synthetic_room", _room_scans(n)), ("mit_csail", _log_scans(n))):
        if not scans:
            continue
        times = time_methods(scans, methods, repeats)
        ref = times["sensor"].mean() if "sensor" in times else float("nan")
        for m in methods:
            us = times[m]
            rows.append(dict(case=f"{m}/{label}", method=m, scans=len(scans), us_mean=float(us.mean()),
                             us_median=float(np.median(us)), scans_per_s=float(1e6 / us.mean()),
                             speed_vs_sensor=float(ref / us.mean())))
    return rows
