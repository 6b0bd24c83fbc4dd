"""Speed of the SLAM filter (``lmsbench bench slam``).

Rows: the filter alone on analytic line observations of a convex room (no extraction), and end to
end (features.extract + filter) over the MIT CSAIL log where the shared data is present.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

NAME = "slam"
MIT_LOG = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "carmen" / "mit-csail.clf.gz"


def _filter_only(n: int) -> dict:
    from slam import SlamConfig, run_observations
    from slam.synthetic import CONVEX_ROOM, circle_path, observe_walls

    rng = np.random.default_rng(0)
    t, poses = circle_path(n, 10.0)
    obs = [observe_walls(CONVEX_ROOM, p, rng=rng) for p in poses]
    t0 = time.perf_counter_ns()
    run_observations(t, obs, SlamConfig(preset="paper"))
    s = (time.perf_counter_ns() - t0) / 1e9
    return {"case": "filter only, analytic room", "scans": n, "seconds": s, "scans_per_s": n / s}


def _mit(n: int | None, use_odometry: bool = False) -> dict | None:
    if not MIT_LOG.exists():
        return None
    from lms200 import read_log
    from slam import SlamConfig, run_slam

    records = list(read_log(MIT_LOG))[:n]
    t0 = time.perf_counter_ns()
    from slam.config import MotionConfig

    config = SlamConfig(preset="paper", motion=MotionConfig(use_odometry=True)) if use_odometry else SlamConfig()
    run_slam(records, config)
    s = (time.perf_counter_ns() - t0) / 1e9
    label = "end to end MIT CSAIL" + (" (paper preset, odometry)" if use_odometry else " (default preset)")
    return {"case": label, "scans": len(records), "seconds": s, "scans_per_s": len(records) / s}


def run(quick: bool = False) -> list[dict]:
    rows = [_filter_only(200 if quick else 1000)]
    mit = _mit(300 if quick else None)
    if mit:
        rows.append(mit)
    return rows
