"""Speed of every extractor on identical scans, interleaved per scan (``lmsbench bench baselines``).

Scans: noisy synthetic rooms (exact L-shaped room, 5 mm noise, seeded poses) and, where the shared
data is present, every 10th scan of the MIT CSAIL log. Rows: one per method x scan set, with the
median wall and CPU microseconds per scan, scans/s and the speed ratios to the sensor method, with
the implementation each runs on (numba: compiled, numpy: vectorised).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from experiments.synthetic import L_ROOM, room_scan
from features.registry import available_methods, backend_of, check_beams, get_method, make_config

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


def variants(methods: list[str]) -> list[tuple[str, str, dict]]:
    """(label, method, params) of every timed variant: each method with its default config."""
    return [(m, m, {}) for m in methods]


def time_methods(scans: list, methods: list, repeats: int) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Wall and CPU microseconds per scan of each method (medians of ``repeats``), interleaved.
    ``methods``: names, or (label, method, params) tuples as from :func:`variants`."""
    specs = [(m, m, {}) if isinstance(m, str) else m for m in methods]
    runs = [(label, get_method(m).run, make_config(m, **params)) for label, m, params in specs]
    for k, scan in enumerate(scans):  # extract's beam limit, which the methods' run (timed alone) does not check
        check_beams(scan, f"scan {k}")
    for _, fn, cfg in runs:  # first calls load compiled kernels and fill caches: not timed
        fn(scans[0], cfg)
    wall = {label: np.empty(len(scans)) for label, _, _ in runs}
    cpu = {label: np.empty(len(scans)) for label, _, _ in runs}
    for k, scan in enumerate(scans):
        shift = k % len(runs)
        for name, fn, cfg in runs[shift:] + runs[:shift]:
            t, c = [], []
            for _ in range(repeats):
                t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
                fn(scan, cfg)
                c.append(time.thread_time_ns() - c0)
                t.append(time.perf_counter_ns() - t0)
            wall[name][k] = np.median(t) / 1e3
            cpu[name][k] = np.median(c) / 1e3
    return wall, cpu


def run(quick: bool = False) -> list[dict]:
    """One row per method variant x scan set; ``backend`` says which implementation ran (speed
    ratios are like for like only between equal backends; the ratios are to the sensor method on
    its default backend)."""
    specs = variants(available_methods())
    n, repeats = (20, 1) if quick else (100, 3)
    rows = []
    for label, scans in (("synthetic_room", _room_scans(n)), ("mit_csail", _log_scans(n))):
        if not scans:
            continue
        wall, cpu = time_methods(scans, specs, repeats)
        ref = np.median(wall["sensor"]) if "sensor" in wall else float("nan")
        ref_cpu = np.median(cpu["sensor"]) if "sensor" in cpu else float("nan")
        for name, m, params in specs:
            us, cu = np.median(wall[name]), np.median(cpu[name])
            rows.append(dict(case=f"{name}/{label}", method=m, backend=backend_of(m, make_config(m, **params)),
                             scans=len(scans), us_median=float(us), cpu_us_median=float(cu),
                             scans_per_s=float(1e6 / us), speed_vs_sensor=float(ref / us),
                             cpu_speed_vs_sensor=float(ref_cpu / cu)))
    return rows
