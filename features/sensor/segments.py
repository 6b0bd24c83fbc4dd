"""Line segments from the fitted lines: overlaps between neighbours resolved, collinear neighbours
merged (and refitted), endpoints projected, short segments dropped."""

from __future__ import annotations

import numpy as np

from .config import SensorMethodConfig
from .lines import LineTable, fit_spans
from .signals import wrap

MERGE_FLOOR_VAR = np.array([0.005**2, 0.005**2])  # model-error floor on (rho m^2, alpha rad^2)


def merge_neighbours(
    table: LineTable,
    ranges: np.ndarray,
    bearings: np.ndarray,
    invalid_cum: np.ndarray,
    cfg: SensorMethodConfig,
) -> LineTable:
    """Merge neighbouring lines that are one line (close in beams, no invalid beam between, and
    (rho, alpha) equal within ``merge_tau`` std) and refit the merged spans."""
    n = table.rho.size
    if n < 2:
        return table
    rho, alpha, cov = table.rho.tolist(), table.alpha.tolist(), table.cov
    first, last = table.first.tolist(), table.last.tolist()
    groups: list[list[int]] = [[0]]
    tau2 = cfg.merge_tau**2
    for i in range(1, n):
        j = groups[-1][-1]
        gap = first[i] - last[j] - 1
        if gap > cfg.merge_gap:
            groups.append([i])
            continue
        if gap > 0 and invalid_cum[first[i]] - invalid_cum[last[j] + 1] > 0:  # invalid beam between
            groups.append([i])
            continue
        dr = rho[i] - rho[j]
        da = float(wrap(alpha[i] - alpha[j]))
        s = cov[i] + cov[j]
        s00, s01, s11 = s[0, 0] + MERGE_FLOOR_VAR[0], s[0, 1], s[1, 1] + MERGE_FLOOR_VAR[1]
        det = s00 * s11 - s01 * s01
        m2 = (s11 * dr * dr - 2 * s01 * dr * da + s00 * da * da) / det
        if m2 <= tau2:
            groups[-1].append(i)
        else:
            groups.append([i])
    if len(groups) == n:
        return table
    merged = [g for g in groups if len(g) > 1]
    g_first = np.array([first[g[0]] for g in merged])
    g_last = np.array([max(last[i] for i in g) for g in merged])
    seed = [max(g, key=lambda i: table.n_points[i]) for g in merged]
    valid = invalid_cum[1:] == invalid_cum[:-1]
    fit, good = fit_spans(
        g_first, g_last, table.rho[seed], table.alpha[seed], None, ranges, bearings, valid, cfg
    )
    rows: list[tuple] = []
    m = 0
    for g in groups:
        if len(g) > 1:
            if good[m]:
                rows.append(tuple(a[m] for a in fit))
            else:
                rows.extend(tuple(a[i] for a in table) for i in g)
            m += 1
        else:
            rows.append(tuple(a[g[0]] for a in table))
    return LineTable(
        np.array([r[0] for r in rows]),
        np.array([r[1] for r in rows]),
        np.array([r[2] for r in rows]).reshape(-1, 2, 2),
        np.array([r[3] for r in rows], dtype=np.int64),
        np.array([r[4] for r in rows], dtype=np.int64),
        np.array([r[5] for r in rows], dtype=np.int64),
    )


def resolve_overlaps(first: np.ndarray, last: np.ndarray) -> None:
    """Neighbouring lines claiming the same beams (around a corner) split them at the middle."""
    over = np.flatnonzero(last[:-1] >= first[1:])
    for i in over.tolist():
        mid = (first[i + 1] + last[i]) // 2
        last[i] = max(mid, first[i])
        first[i + 1] = min(mid + 1, last[i + 1])


def endpoints(
    rho: np.ndarray, alpha: np.ndarray, ranges: np.ndarray, bearings: np.ndarray, beams: np.ndarray
) -> np.ndarray:
    """(L, 2) projections of the points of the given beams onto their lines (m, sensor frame)."""
    c, s = np.cos(alpha), np.sin(alpha)
    d = ranges[beams]
    b = bearings[beams]
    x, y = d * np.cos(b), d * np.sin(b)
    off = x * c + y * s - rho
    return np.column_stack((x - off * c, y - off * s))
