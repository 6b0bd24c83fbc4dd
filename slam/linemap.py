"""A line map from many world-frame segments: near-collinear overlapping segments are merged."""

from __future__ import annotations

import numpy as np

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
    if seg.shape[0] == 0:
        return np.zeros((0, 7))
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    order = np.argsort(-length)
    R, th = normal_form(seg)
    groups: list[dict] = []
    for i in order:
        placed = False
        for g in groups:
            if abs(wrap(th[i] - g["theta"])) > max_angle:
                continue
            u = np.array([-np.sin(g["theta"]), np.cos(g["theta"])])
            nrm = np.array([np.cos(g["theta"]), np.sin(g["theta"])])
            ends = seg[i].reshape(2, 2)
            if np.max(np.abs(ends @ nrm - g["R"])) > max_offset:
                continue
            s = ends @ u
            if s.max() < g["lo"] - max_gap or s.min() > g["hi"] + max_gap:
                continue
            g["lo"], g["hi"] = min(g["lo"], s.min()), max(g["hi"], s.max())
            g["n"] += 1
            placed = True
            break
        if not placed:
            u = np.array([-np.sin(th[i]), np.cos(th[i])])
            s = seg[i].reshape(2, 2) @ u
            groups.append({"R": R[i], "theta": th[i], "lo": s.min(), "hi": s.max(), "n": 1})
    out = []
    for g in groups:
        c, s_ = np.cos(g["theta"]), np.sin(g["theta"])
        p = np.array([g["R"] * c, g["R"] * s_])
        u = np.array([-s_, c])
        a, b = p + g["lo"] * u, p + g["hi"] * u
        out.append((g["R"], g["theta"], a[0], a[1], b[0], b[1], g["n"]))
    return np.array(out, float).reshape(-1, 7)
