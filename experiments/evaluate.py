"""Run extractors over a source of scans, time them, score them against ground truth: tidy tables.

This is driver code (timing, loops); the algorithms it calls stay pure. Tables:

- per scan (:func:`evaluate_extractor`): method, scan, stamp, time_ms, n_lines, n_corners, and
  every scalar field of ``features.scoring.ScanScore`` (array fields as ``NAME_rms`` and
  ``NAME_n``) when ground truth is given;
- per method (:func:`summarise_methods`): pooled counts, precision / recall / F1 recomputed from
  the pooled counts, pooled RMS errors, and time per scan (median, 5 %, 95 %, mean).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Iterable, Sequence

import numpy as np
import pandas as pd

from lms200 import Record, Scan

#: The extractors compared by default: the paper's method and the four baselines.
ALL_METHODS = ("sensor", "split_merge", "iepf", "hough", "ransac")


def split_params(params: dict[str, Any], prefix: str) -> dict[str, Any]:
    """The ``prefix.NAME`` entries of a flat parameter dict, as ``{NAME: value}``."""
    head = prefix + "."
    return {k[len(head):]: v for k, v in params.items() if k.startswith(head)}


def sensor_config(overrides: dict[str, Any] | None = None, ideal: bool = False):
    """A ``sim.SensorConfig`` with the given fields changed (``SensorConfig.ideal()`` as base if asked)."""
    from sim import SensorConfig

    base = SensorConfig.ideal() if ideal else SensorConfig()
    return dataclasses.replace(base, **(overrides or {}))


def simulate_run(world: str = "office", seed: int = 0, duration: float = 10.0, sensor=None,
                 rate_hz: float | None = None) -> tuple[Any, list[Record]]:
    """The world object and the records of a simulated run (truth pose on every record)."""
    from sim import make_world, simulate_records

    records = simulate_records(world=world, seed=seed, duration=duration, sensor=sensor, rate_hz=rate_hz)
    return make_world(world, seed=seed), records


def truths_for(world, records: Sequence[Record], sensor=None) -> list[Any]:
    """The visible ground truth (sensor frame) of every record, from its true pose."""
    from sim import SensorConfig, visible_truth

    sensor = sensor if sensor is not None else SensorConfig()
    return [visible_truth(world, r.truth, sensor) for r in records]


def extract_timed(scans: Iterable[Scan], method: str, params: dict[str, Any] | None = None
                  ) -> tuple[list[Any], np.ndarray]:
    """Feature sets of every scan and the time each extraction took (ms, perf_counter_ns)."""
    from features import registry

    config = registry.make_config(method, **(params or {}))
    run = registry.get_method(method).run  # time the algorithm alone, not the registry look-up
    results, times = [], []
    for scan in scans:
        start = time.perf_counter_ns()
        fs = run(scan, config)
        times.append((time.perf_counter_ns() - start) / 1e6)
        results.append(fs)
    return results, np.asarray(times)


def evaluate_extractor(records: Sequence[Record], method: str, params: dict[str, Any] | None = None,
                       truths: Sequence[Any] | None = None, keep_features: bool = False
                       ) -> pd.DataFrame | tuple[pd.DataFrame, list[Any]]:
    """Per-scan table of one extractor over ``records``; scored when ``truths`` are given."""
    feature_sets, times = extract_timed((r.scan for r in records), method, params)
    rows = []
    for i, (record, fs, ms) in enumerate(zip(records, feature_sets, times)):
        row: dict[str, Any] = {"method": method, "scan": i, "stamp": float(record.scan.stamp),
                               "time_ms": float(ms), "n_lines": len(fs.lines), "n_corners": len(fs.corners)}
        if truths is not None:
            row.update(score_row(fs, truths[i]))
        rows.append(row)
    table = pd.DataFrame(rows)
    return (table, feature_sets) if keep_features else table


def score_row(fs, truth) -> dict[str, float]:
    """The scalar fields of ``score_scan(fs, truth)``; array fields as NAME_rms and NAME_n."""
    from features.scoring import score_scan

    score = score_scan(fs, truth)
    row: dict[str, float] = {}
    for name, value in dataclasses.asdict(score).items():
        if name in ("matches", "extra"):  # indices and free-form extras are not metrics
            continue
        if np.ndim(value) == 0:
            if isinstance(value, (bool, int, float, np.integer, np.floating)):
                row[name] = value
        else:
            arr = np.asarray(value, dtype=float).ravel()
            arr = arr[np.isfinite(arr)]
            row[f"{name}_n"] = int(arr.size)
            row[f"{name}_rms"] = float(np.sqrt(np.mean(arr**2))) if arr.size else np.nan
    return row


def summarise_methods(per_scan: pd.DataFrame) -> pd.DataFrame:
    """One row per method: pooled accuracy and time per scan."""
    rows = [{"method": m, **summarise_scans(g).to_dict()} for m, g in per_scan.groupby("method", sort=False)]
    return pd.DataFrame(rows)


def summarise_scans(table: pd.DataFrame) -> pd.Series:
    """Pooled metrics of the scans of one run of one method (see module docstring)."""
    out: dict[str, float] = {"scans": float(len(table))}
    t = table["time_ms"].to_numpy()
    out.update(time_ms_median=float(np.median(t)), time_ms_mean=float(np.mean(t)),
               time_ms_p05=float(np.percentile(t, 5)), time_ms_p95=float(np.percentile(t, 95)),
               n_lines_mean=float(table["n_lines"].mean()), n_corners_mean=float(table["n_corners"].mean()))
    cols = set(table.columns)
    for prefix in sorted({c[:-2] for c in cols if c.endswith("tp")}):
        if {prefix + "fp", prefix + "fn"} <= cols:
            tp, fp, fn = (float(table[prefix + s].sum()) for s in ("tp", "fp", "fn"))
            precision = tp / (tp + fp) if tp + fp else np.nan
            recall = tp / (tp + fn) if tp + fn else np.nan
            f1 = 2 * tp / (2 * tp + fp + fn) if tp + fp + fn else np.nan
            out.update({prefix + "tp": tp, prefix + "fp": fp, prefix + "fn": fn, prefix + "precision": precision,
                        prefix + "recall": recall, prefix + "f1": f1})
    for name in sorted(c[:-4] for c in cols if c.endswith("_rms")):
        n = table[name + "_n"].to_numpy(dtype=float)
        rms = table[name + "_rms"].to_numpy(dtype=float)
        keep = n > 0
        out[name + "_rms"] = float(np.sqrt(np.sum(rms[keep] ** 2 * n[keep]) / n[keep].sum())) if keep.any() else np.nan
    return pd.Series(out)
