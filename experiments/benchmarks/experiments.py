"""Benchmark of the sweep runner's own overhead: cells per second of a trivial cell kind
(scheduling, atomic per-cell Parquet writes, the final table), in process and on a local Dask
cluster of two worker processes (cluster start-up timed apart)."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

NAME = "experiments"


def noop_cell(params: dict) -> dict:
    """A cell that computes almost nothing, so the runner's cost is what is measured."""
    return {"y": float(params["x"]) * 2.0}


def _spec(n: int):
    from experiments.sweep import SweepSpec

    return SweepSpec.from_dict({"name": "overhead", "kind": f"{__name__}:noop_cell",
                                "grid": {"x": list(range(n))}, "seeds": [0]})


def run(quick: bool = False) -> list[dict]:
    """Rows: ``cells_per_s`` and ``ms_per_cell`` for each executor; ``startup_s`` for the cluster."""
    from experiments.sweep import run_sweep

    n = 50 if quick else 300
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        result = run_sweep(_spec(n), Path(tmp) / "inproc", "inprocess", progress=False)
        dt = time.perf_counter() - t0
        assert result.computed == n
        rows.append({"benchmark": "sweep_cells", "executor": "inprocess", "cells": n,
                     "cells_per_s": n / dt, "ms_per_cell": 1e3 * dt / n, "startup_s": 0.0})

        from experiments.sweep.runner import sweep_client

        t0 = time.perf_counter()
        # the sweep's own local cluster: its workers ignore Ctrl-C and it is closed however the run ends
        # (a cluster of its own here: Ctrl-C while it ran printed 79 lines of tracebacks after the one line)
        with sweep_client("local", 2) as client:
            startup = time.perf_counter() - t0
            t0 = time.perf_counter()
            result = run_sweep(_spec(n), Path(tmp) / "dask", client, progress=False)
            dt = time.perf_counter() - t0
        assert result.computed == n
        rows.append({"benchmark": "sweep_cells", "executor": "local cluster (2 processes)", "cells": n,
                     "cells_per_s": n / dt, "ms_per_cell": 1e3 * dt / n, "startup_s": startup})
    return rows
