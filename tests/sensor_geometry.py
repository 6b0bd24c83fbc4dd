"""Exact synthetic scans for the sensor-method tests: an independent ray caster over segments and
circles in the sensor frame (no simulator needed)."""

from __future__ import annotations

import numpy as np

from lms200 import Scan


def cast(
    segments: np.ndarray | list = (),
    circles: np.ndarray | list = (),
    n: int = 361,
    angle_min: float = -np.pi / 2,
    increment: float = np.deg2rad(0.5),
    range_max: float = 8.183,
    sigma: float = 0.0,
    seed: int = 0,
) -> Scan:
    """Ranges of the nearest hit of every beam on segments (x1, y1, x2, y2) and circles
    (cx, cy, r), all in the sensor frame (m); +inf where nothing is hit; Gaussian range noise."""
    b = angle_min + np.arange(n) * increment
    dx, dy = np.cos(b), np.sin(b)
    best = np.full(n, np.inf)
    for x1, y1, x2, y2 in np.asarray(segments, dtype=float).reshape(-1, 4):
        ex, ey = x2 - x1, y2 - y1
        den = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (x1 * ey - y1 * ex) / den  # distance along the ray
            s = (x1 * dy - y1 * dx) / den  # position along the segment
        hit = (np.abs(den) > 1e-12) & (t > 0) & (s >= 0) & (s <= 1)
        best = np.where(hit & (t < best), t, best)
    for cx, cy, r in np.asarray(circles, dtype=float).reshape(-1, 3):
        proj = cx * dx + cy * dy
        disc = proj**2 - (cx**2 + cy**2 - r**2)
        with np.errstate(invalid="ignore"):
            t = proj - np.sqrt(disc)
        hit = (disc >= 0) & (t > 0)
        best = np.where(hit & (t < best), t, best)
    if sigma > 0:
        best = best + sigma * np.random.default_rng(seed).standard_normal(n)
    best = np.where(best > range_max, np.inf, best)
    return Scan(best, angle_min, increment, 0.0, range_max)


def line_scan(rho: float, alpha: float, **kw) -> Scan:
    """A single infinite line x cos(alpha) + y sin(alpha) = rho (beams that miss it: +inf)."""
    c, s = np.cos(alpha), np.sin(alpha)
    far = 1e4
    px, py = rho * c, rho * s
    seg = [(px + far * s, py - far * c, px - far * s, py + far * c)]
    return cast(seg, **kw)


def polygon(points: list[tuple[float, float]]) -> np.ndarray:
    """Closed polygon -> (n, 4) segments."""
    p = np.asarray(points, dtype=float)
    q = np.roll(p, -1, axis=0)
    return np.hstack((p, q))


ROOM = polygon([(-1.0, -2.5), (3.0, -2.5), (3.0, 2.0), (-1.0, 2.0)])  # walls x=3, y=2, y=-2.5, x=-1


def room(seed: int, n: int = 361, increment: float = np.deg2rad(0.5), sigma: float = 0.005) -> Scan:
    """A noisy rectangular room with a box and a pillar, seen from a random pose."""
    rng = np.random.default_rng(seed)
    w, h = rng.uniform(3, 9), rng.uniform(3, 7)
    x, y, th = rng.uniform(0.6, w - 0.6), rng.uniform(0.6, h - 0.6), rng.uniform(-np.pi, np.pi)
    bx, by = rng.uniform(0.5, w - 1.5), rng.uniform(0.5, h - 1.5)
    world = np.vstack((polygon([(0, 0), (w, 0), (w, h), (0, h)]), polygon([(bx, by), (bx + 0.8, by), (bx + 0.8, by + 0.5), (bx, by + 0.5)])))
    c, s = np.cos(th), np.sin(th)
    pts = world.reshape(-1, 2) - (x, y)
    local = np.column_stack((c * pts[:, 0] + s * pts[:, 1], -s * pts[:, 0] + c * pts[:, 1])).reshape(-1, 4)
    circle = [(rng.uniform(-3, 3), rng.uniform(-3, 3), 0.2)]
    return cast(local, circle, n=n, angle_min=-(n - 1) * increment / 2, increment=increment, sigma=sigma, seed=seed)
