"""Parameter sweeps: YAML spec -> cells -> Dask (or in-process) -> one tidy Parquet table.

    from experiments.sweep import load_sweep, run_sweep
    result = run_sweep(load_sweep("sweeps/k_vs_noise.yaml"), "results/sweeps/k_vs_noise")
    result.table    # one row per cell: every parameter, the metrics, status, error, elapsed_s, cell
"""

from .cells import available_kinds, register_cell, resolve_kind, run_cell
from .runner import SweepResult, load_results, run_sweep
from .spec import SweepSpec, SweepSpecError, cell_key, load_sweep

__all__ = [
    "SweepSpec", "SweepSpecError", "SweepResult", "load_sweep", "run_sweep", "load_results",
    "cell_key", "register_cell", "resolve_kind", "run_cell", "available_kinds",
]
