"""Corners where two line segments end next to each other (the paper's psi_i = theta_i -
theta_{i+k} confirms them), with the paper's remedy against false corners switchable."""

from __future__ import annotations

import math

import numpy as np

from ..types import Corner
from .config import SensorMethodConfig

SPACING_CAP = 1.0  # m: largest point spacing (grazing incidence) allowed for in the contact test


def neighbourhood_var(ranges: np.ndarray, valid: np.ndarray, lo: int, hi: int) -> float:
    """Variance (m^2) of the valid ranges of beams lo..hi: the paper's "variance in range between
    neighbouring points" around a corner (0 when fewer than 3 are valid)."""
    d = ranges[lo : hi + 1][valid[lo : hi + 1]]
    if d.size < 3:
        return 0.0
    return float(d.var())


def find_corners(
    rho: list[float],
    alpha: list[float],
    first: list[int],
    last: list[int],
    start: list[tuple[float, float]],
    end: list[tuple[float, float]],
    psi: np.ndarray,
    ranges: np.ndarray,
    bearings: np.ndarray,
    valid: np.ndarray,
    angle_min: float,
    increment: float,
    cfg: SensorMethodConfig,
) -> list[Corner]:
    """Corners between consecutive lines (indices into the line list, beam order)."""
    corners: list[Corner] = []
    n = ranges.size
    k = cfg.k
    min_turn = cfg.corner_min_turn
    for i in range(len(rho) - 1):
        j = i + 1
        if first[j] - last[i] - 1 > cfg.corner_max_gap:
            continue
        a1, a2 = alpha[i], alpha[j]
        s = math.sin(a2 - a1)
        turn = math.asin(min(1.0, abs(s))) if math.cos(a2 - a1) >= 0 else math.pi - math.asin(min(1.0, abs(s)))
        if turn < min_turn or turn > math.pi - min_turn:
            continue
        # intersection of x cos a + y sin a = rho for both lines
        x = (rho[i] * math.sin(a2) - rho[j] * math.sin(a1)) / s
        y = (rho[j] * math.cos(a1) - rho[i] * math.cos(a2)) / s
        # the intersection must lie near both facing ends: within corner_max_dist plus the point
        # spacing there (one beam step projected on each line, large at grazing incidence)
        b = math.atan2(y, x)
        spacing = math.hypot(x, y) * increment / max(min(math.cos(b - a1), math.cos(b - a2)), 0.1)
        reach = cfg.corner_max_dist + 1.5 * min(spacing, SPACING_CAP)
        if math.hypot(x - end[i][0], y - end[i][1]) > reach:
            continue
        if math.hypot(x - start[j][0], y - start[j][1]) > reach:
            continue
        # psi (the paper's corner signal) must show the turn between the two segments
        lo, hi = max(0, last[i] - k), min(n - 1, first[j])
        window = psi[lo : hi + 1]
        window = window[np.isfinite(window)]
        if window.size == 0 or float(np.abs(window).max()) < cfg.corner_psi * turn:
            continue
        index = int(round((b - angle_min) / increment))
        index = min(max(index, last[i]), first[j])
        if cfg.acute_check:
            var = neighbourhood_var(ranges, valid, max(0, index - k), min(n - 1, index + k))
            if var < cfg.acute_min_var * cfg.sigma_r**2:
                continue
        v1x, v1y = start[i][0] - x, start[i][1] - y
        v2x, v2y = end[j][0] - x, end[j][1] - y
        cos_angle = (v1x * v2x + v1y * v2y) / max(math.hypot(v1x, v1y) * math.hypot(v2x, v2y), 1e-300)
        angle = math.acos(min(1.0, max(-1.0, cos_angle)))
        if not (0.0 < angle < math.pi) or not (math.isfinite(x) and math.isfinite(y)):
            continue
        corners.append(Corner(x, y, angle, index, (i, j)))
    return corners
