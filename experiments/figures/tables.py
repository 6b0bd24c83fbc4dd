"""The tidy tables behind the figures, computed from scans, runs and SLAM results.

Schemas (one table per figure input; figures are drawn from these alone):

- ``signals``: beam, bearing_deg, range_m, ad, theta_deg, psi_deg (Figs. 4-6; k = 10 as in the paper).
- ``timing``: the per-scan table of ``experiments.compare.compare`` plus ``time_ms`` (Fig. 7);
  ``summary``: its ``summarise`` plus time_ms_median / _p05 / _p95 (accuracy versus speed).
- ``panels_points`` / ``panels_lines`` / ``panels_corners``: panel, label, x, y / panel, x1, y1,
  x2, y2 / panel, x, y, in each scan's sensor frame (m) (Fig. 9).
- ``trajectory``: source, t, x, y, theta; ``map``: source, x1, y1, x2, y2 (world frame, m) (Fig. 10).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from lms200 import Record, Scan


def signals_table(scan: Scan, k: int = 10, sigma_r: float = 0.005) -> pd.DataFrame:
    """AD_ik, theta_i and psi_i of every beam (``features.sensor.signals``); angles in degrees.

    ``ad_band`` is the half-width of the extractor's straight-line test around the line value,
    ``ad_tau * sigma(AD_ik)`` with the extractor's default ``ad_tau`` (nan where not given).
    """
    from features.sensor import SensorMethodConfig, signals

    sig = signals(scan, k=k, sigma_r=sigma_r)
    n = len(scan.ranges)
    ad_sigma = np.asarray(sig.get("ad_sigma", np.full(n, np.nan)), dtype=float)
    return pd.DataFrame({
        "beam": np.arange(n),
        "bearing_deg": np.degrees(scan.angles),
        "range_m": scan.ranges,
        "ad": np.asarray(sig["ad"], dtype=float),
        "ad_band": SensorMethodConfig().ad_tau * ad_sigma,
        "theta_deg": np.degrees(np.asarray(sig["theta"], dtype=float)),
        "psi_deg": np.degrees(np.asarray(sig["psi"], dtype=float)),
    })


def ad_reference(k: int, angle_increment: float) -> float:
    """The value of AD_ik on any straight line: 1 + 2 sum_{j=1..k} cos(j D) (eq. 4)."""
    return float(1.0 + 2.0 * np.cos(np.arange(1, k + 1) * angle_increment).sum())


def feature_panels(scans: Sequence[Scan], labels: Sequence[str], feature_sets: Sequence[Any]
                   ) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Points, line segments and corners of each scan (sensor frame), one panel per scan."""
    points, lines, corners = [], [], []
    for panel, (scan, label, fs) in enumerate(zip(scans, labels, feature_sets)):
        p = scan.points[scan.valid] if hasattr(scan, "valid") else scan.points
        p = p[np.all(np.isfinite(p), axis=1)]
        points.append(pd.DataFrame({"panel": panel, "label": label, "x": p[:, 0], "y": p[:, 1]}))
        seg = np.array([[*np.asarray(ln.start, float)[:2], *np.asarray(ln.end, float)[:2]] for ln in fs.lines])
        seg = seg.reshape(-1, 4)
        lines.append(pd.DataFrame({"panel": panel, "x1": seg[:, 0], "y1": seg[:, 1], "x2": seg[:, 2], "y2": seg[:, 3]}))
        c = np.array([[cr.x, cr.y] for cr in fs.corners], dtype=float).reshape(-1, 2)
        corners.append(pd.DataFrame({"panel": panel, "x": c[:, 0], "y": c[:, 1]}))
    return (pd.concat(points, ignore_index=True), pd.concat(lines, ignore_index=True),
            pd.concat(corners, ignore_index=True))


def panels_log_name(points: pd.DataFrame) -> str:
    """The log of Fig. 9's real-log panels, from their labels ("NAME scan I"): "Intel" for tables
    written before the labels named other logs."""
    labels = points["label"] if "label" in points else pd.Series(dtype=object)
    return str(labels.iloc[0]).rsplit(" scan ", 1)[0] if len(labels) else "Intel"


def trajectory_table(result_trajectory: np.ndarray, records: Sequence[Record],
                     extra: dict[str, np.ndarray] | None = None) -> pd.DataFrame:
    """SLAM (t, x, y, theta) rows and the true poses of the records, as one table by source;
    ``extra`` adds more estimates by source name (e.g. ``{"paper preset": trajectory}``)."""
    est = np.asarray(result_trajectory, dtype=float).reshape(-1, 4)
    truth = np.array([[r.scan.stamp, *r.truth] for r in records if r.truth is not None], dtype=float).reshape(-1, 4)
    frames = [pd.DataFrame(est, columns=["t", "x", "y", "theta"]).assign(source="slam"),
              *(pd.DataFrame(np.asarray(tr, float).reshape(-1, 4), columns=["t", "x", "y", "theta"]).assign(source=name)
                for name, tr in (extra or {}).items()),
              pd.DataFrame(truth, columns=["t", "x", "y", "theta"]).assign(source="truth")]
    odom = [[r.scan.stamp, *r.odom] for r in records if r.odom is not None]
    if odom:
        frames.append(pd.DataFrame(np.array(odom, float), columns=["t", "x", "y", "theta"]).assign(source="odometry"))
    table = pd.concat(frames, ignore_index=True)
    return table[["source", "t", "x", "y", "theta"]]


def map_table(slam_segments: np.ndarray, true_walls: np.ndarray, extra: dict[str, np.ndarray] | None = None) -> pd.DataFrame:
    """Estimated map segments and the true walls (x1, y1, x2, y2, world frame) by source;
    ``extra`` adds more maps by source name."""
    cols = ["x1", "y1", "x2", "y2"]
    est = pd.DataFrame(np.asarray(slam_segments, float).reshape(-1, 4), columns=cols).assign(source="slam")
    more = [pd.DataFrame(np.asarray(seg, float).reshape(-1, 4), columns=cols).assign(source=name)
            for name, seg in (extra or {}).items()]
    true = pd.DataFrame(np.asarray(true_walls, float).reshape(-1, 4), columns=cols).assign(source="truth")
    return pd.concat([est, *more, true], ignore_index=True)[["source", *cols]]


def pick_evenly(n_items: int, n_pick: int, skip_ends: bool = True) -> list[int]:
    """``n_pick`` indices spread evenly over ``range(n_items)`` (away from the ends if asked)."""
    if n_items <= 0:
        return []
    if skip_ends:
        return sorted({int(i) for i in np.linspace(0, n_items - 1, n_pick + 2)[1:-1].round()})
    return sorted({int(i) for i in np.linspace(0, n_items - 1, n_pick).round()})
