"""Compiled distance from points to the nearest solid of a plan (numba, cached on disk): what
``sim.clutter`` asks each time it tries to place an item (~3,600 calls of up to 300 points for
one ``mit`` world). In numpy every point met every edge of every box near the points' bounding
box (~1 ms a call); here a box is skipped when its axis-aligned bounds lie beyond ``horizon``
or beyond the nearest distance found so far, so each point meets a few boxes.

Each point-edge distance is the numpy expression of ``sim.geometry.distance_to_segments``,
operation for operation (IEEE division, no fast-math), and skipping a box never skips the
nearest one, so every distance below ``horizon`` is bit for bit the numpy one.
"""

from __future__ import annotations

import math

import numpy as np

from lms200.numba_required import numba

_kernel = numba.njit(cache=True, error_model="numpy")

_BOUND_SLACK_M = 1e-9  # a box is skipped when its bounds lie this much beyond the nearest distance (rounding)


@_kernel
def nearest_solid(pts: np.ndarray, corners: np.ndarray, lo: np.ndarray, hi: np.ndarray, ids: np.ndarray,
                  exclude: int, circles: np.ndarray, horizon: float) -> np.ndarray:
    """Distance (m) from each of (n, 2) points to the nearest solid: 0 inside a box, negative
    inside a circle.

    Args:
        pts: (n, 2) points (m, world frame).
        corners: (b, 4, 2) boxes' CCW corners; lo, hi: (b, 2) their axis-aligned bounds.
        ids: (b,) an id per box; the boxes whose id is ``exclude`` are left out.
        circles: (c, 3) cx, cy, r.
        horizon: boxes whose bounds lie farther than this (m) from a point are left out for it,
            so the distance is exact up to ``horizon`` and at least ``horizon`` (maybe inf) beyond.
    """
    n, nb, nc = pts.shape[0], corners.shape[0], circles.shape[0]
    out = np.empty(n)
    for i in range(n):
        px, py = pts[i, 0], pts[i, 1]
        best = np.inf
        for j in range(nb):
            if ids[j] == exclude:
                continue
            dx = max(lo[j, 0] - px, px - hi[j, 0], 0.0)
            dy = max(lo[j, 1] - py, py - hi[j, 1], 0.0)
            if dx > horizon or dy > horizon or math.hypot(dx, dy) > best + _BOUND_SLACK_M:
                continue
            inside = True
            d = np.inf
            for e in range(4):
                ax, ay = corners[j, e, 0], corners[j, e, 1]
                f = (e + 1) % 4
                abx, aby = corners[j, f, 0] - ax, corners[j, f, 1] - ay
                rx, ry = px - ax, py - ay
                if not abx * ry - aby * rx > 0:
                    inside = False
                t = (rx * abx + ry * aby) / max(abx * abx + aby * aby, 1e-18)
                t = min(max(t, 0.0), 1.0)
                d = min(d, math.hypot(px - (ax + t * abx), py - (ay + t * aby)))
            best = 0.0 if inside else min(best, d)
        for k in range(nc):
            best = min(best, math.hypot(px - circles[k, 0], py - circles[k, 1]) - circles[k, 2])
        out[i] = best
    return out
