"""Line segments from the fitted lines: overlaps between neighbours resolved, collinear neighbours
merged (and refitted), endpoints projected, short segments dropped."""

from __future__ import annotations

import math

import numpy as np

from .config import SensorMethodConfig
from .lines import LineTable
from .signals import wrap

MERGE_FLOOR_VAR = np.array([0.005**2, 0.005**2])  # model-error floor on (rho m^2, alpha rad^2)


def merge_neighbours(table: LineTable, invalid_cum: np.ndarray, cfg: SensorMethodConfig) -> LineTable:
    """Merge neighbouring lines that are one line: close in beams, at most ``bridge_invalid``
    invalid beams between (none by default: +inf and nan beams break segments), and
    (rho, alpha) equal within ``merge_tau`` std. The merged line is the information-weighted
    combination of the pieces (independent fits of one line), so no refit is needed."""
    n = table.rho.size
    if n < 2:
        return table
    rho, alpha = table.rho.tolist(), table.alpha.tolist()
    first, last, npts = table.first.tolist(), table.last.tolist(), table.n_points.tolist()
    c = table.cov.reshape(n, 4).tolist()
    tau2 = cfg.merge_tau**2
    f00, f11 = MERGE_FLOOR_VAR
    out: list[int] = [0]  # index of the current line of each output row
    cur = 0
    for i in range(1, n):
        gap = first[i] - last[cur] - 1
        if gap > cfg.merge_gap or (gap > 0 and invalid_cum[first[i]] - invalid_cum[last[cur] + 1] > cfg.bridge_invalid):
            out.append(i)
            cur = i
            continue
        dr = rho[i] - rho[cur]
        da = (alpha[i] - alpha[cur] + math.pi) % (2 * math.pi) - math.pi
        a00, a01, _, a11 = c[cur]
        b00, b01, _, b11 = c[i]
        s00, s01, s11 = a00 + b00 + f00, a01 + b01, a11 + b11 + f11
        det = s00 * s11 - s01 * s01
        if not det > 0 or (s11 * dr * dr - 2 * s01 * dr * da + s00 * da * da) > tau2 * det:
            out.append(i)
            cur = i
            continue
        # information-weighted fusion of the two estimates (alpha of i unwrapped next to cur's)
        pa = _inv2(a00, a01, a11)
        pb = _inv2(b00, b01, b11)
        p00, p01, p11 = pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]
        va0 = pa[0] * rho[cur] + pa[1] * alpha[cur] + pb[0] * rho[i] + pb[1] * (alpha[cur] + da)
        va1 = pa[1] * rho[cur] + pa[2] * alpha[cur] + pb[1] * rho[i] + pb[2] * (alpha[cur] + da)
        q00, q01, q11 = _inv2(p00, p01, p11)
        rho[cur] = q00 * va0 + q01 * va1
        alpha[cur] = q01 * va0 + q11 * va1
        c[cur] = [q00, q01, q01, q11]
        last[cur] = max(last[cur], last[i])
        npts[cur] += npts[i]
    if len(out) == n:
        return table
    idx = np.array(out)
    cov = np.array([c[i] for i in out]).reshape(-1, 2, 2)
    rho_a = np.array([rho[i] for i in out])
    alpha_a = wrap(np.array([alpha[i] for i in out]))
    return LineTable(
        rho_a, alpha_a, cov, table.first[idx], np.array([last[i] for i in out]), np.array([npts[i] for i in out])
    )


def _inv2(a: float, b: float, d: float) -> tuple[float, float, float]:
    """Inverse of the symmetric 2x2 matrix [[a, b], [b, d]] as (00, 01, 11)."""
    det = a * d - b * b
    return d / det, -b / det, a / det


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
