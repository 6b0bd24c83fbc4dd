"""A line map from many world-frame segments: near-collinear overlapping segments are merged."""

from __future__ import annotations

import numpy as np

from features.jit import wrap_one

from .icpkernel import kernel
from .models import wrap


def normal_form(seg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R m >= 0, theta rad) of the infinite lines through segments (k, 4)."""
    d = seg[:, 2:] - seg[:, :2]
    theta = np.arctan2(d[:, 0], -d[:, 1])  # normal (cos, sin) is perpendicular to the direction
    R = seg[:, 0] * np.cos(theta) + seg[:, 1] * np.sin(theta)
    theta = np.where(R < 0, wrap(theta + np.pi), theta)
    return np.abs(R), theta


def merge_lines(segments: np.ndarray, max_angle: float = np.radians(3.0), max_offset: float = 0.05,
                max_gap: float = 0.3) -> np.ndarray:
    """Merge segments (k, 4: x0, y0, x1, y1, world) whose lines differ by less than ``max_angle``
    rad and ``max_offset`` m and that overlap or lie within ``max_gap`` m along the line; returns
    (m, 7) R, theta, x0, y0, x1, y1, count (segments merged), longest first."""
    seg = np.asarray(segments, float).reshape(-1, 4)
    n = seg.shape[0]
    if n == 0:
        return np.zeros((0, 7))
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    R, th = normal_form(seg)
    gR, gth, glo, ghi, gn, gc, gs, m = _merge(seg, R, th, np.argsort(-length), max_angle, max_offset, max_gap)
    c, s_ = gc[:m], gs[:m]
    ax, ay = gR[:m] * c - glo[:m] * s_, gR[:m] * s_ + glo[:m] * c
    bx, by = gR[:m] * c - ghi[:m] * s_, gR[:m] * s_ + ghi[:m] * c
    return np.column_stack((gR[:m], gth[:m], ax, ay, bx, by, gn[:m]))


@kernel
def _merge(seg, R, th, order, max_angle, max_offset, max_gap):
    """The greedy merge (compiled): each segment, longest first, joins the first group it fits,
    else starts one. Groups: line (R, theta), cos/sin theta, extent [lo, hi] along (-sin, cos), count."""
    n = seg.shape[0]
    gR, gth, glo, ghi, gn = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    gc, gs = np.zeros(n), np.zeros(n)
    m = 0
    for i in order:
        x0, y0, x1, y1 = seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3]
        joined = False
        for g in range(m):
            c, s_ = gc[g], gs[g]
            dth = abs(wrap_one(th[i] - gth[g]))
            if dth > max_angle:
                continue
            off0, off1 = x0 * c + y0 * s_ - gR[g], x1 * c + y1 * s_ - gR[g]
            if max(abs(off0), abs(off1)) > max_offset:
                continue
            s0, s1 = -x0 * s_ + y0 * c, -x1 * s_ + y1 * c
            lo, hi = min(s0, s1), max(s0, s1)
            if hi >= glo[g] - max_gap and lo <= ghi[g] + max_gap:
                glo[g], ghi[g] = min(glo[g], lo), max(ghi[g], hi)
                gn[g] += 1
                joined = True
                break
        if joined:
            continue
        gR[m], gth[m] = R[i], th[i]
        gc[m], gs[m] = np.cos(th[i]), np.sin(th[i])
        s0, s1 = -x0 * gs[m] + y0 * gc[m], -x1 * gs[m] + y1 * gc[m]
        glo[m], ghi[m], gn[m] = min(s0, s1), max(s0, s1), 1
        m += 1
    return gR, gth, glo, ghi, gn, gc, gs, m
