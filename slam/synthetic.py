"""Analytic line observations of a polygonal world, for tests and benchmarks without a ray caster.

The world is a list of wall segments (x1, y1, x2, y2 in metres). From a sensor pose, each wall
clipped to the sensor's front half-plane and to ``max_range`` gives one line observation
(rho, alpha) with endpoints in the sensor frame; occlusion is ignored (use convex rooms seen from
inside, where nothing is occluded). Noise is drawn from a seeded ``numpy.random.Generator``.
"""

from __future__ import annotations

import numpy as np

from .models import wrap
from .observations import Observations

# an irregular convex room (m): walls at several angles so that headings are unambiguous
CONVEX_ROOM = np.array([
    [0.0, 0.0, 9.0, 0.0],
    [9.0, 0.0, 11.0, 3.0],
    [11.0, 3.0, 10.0, 8.0],
    [10.0, 8.0, 3.0, 9.0],
    [3.0, 9.0, -1.0, 6.0],
    [-1.0, 6.0, 0.0, 0.0],
])


def _clip_half_plane(a: np.ndarray, b: np.ndarray, x_min: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Clip segment ab (sensor frame) to x >= x_min."""
    if a[0] < x_min and b[0] < x_min:
        return None
    if a[0] < x_min or b[0] < x_min:
        t = (x_min - a[0]) / (b[0] - a[0])
        p = a + t * (b - a)
        a, b = (p, b) if a[0] < x_min else (a, p)
    return a, b


def _clip_circle(a: np.ndarray, b: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray] | None:
    d = b - a
    A, B, C = d @ d, 2 * a @ d, a @ a - r * r
    disc = B * B - 4 * A * C
    if disc <= 0:
        return None
    t0, t1 = (-B - np.sqrt(disc)) / (2 * A), (-B + np.sqrt(disc)) / (2 * A)
    lo, hi = max(t0, 0.0), min(t1, 1.0)
    if hi <= lo:
        return None
    return a + lo * d, a + hi * d


def observe_walls(walls: np.ndarray, pose: np.ndarray, sigma_rho: float = 0.01, sigma_alpha: float = 0.005,
                  max_range: float = 8.0, min_length: float = 0.5, rng: np.random.Generator | None = None,
                  corners: bool = False, sigma_corner: float = 0.02) -> Observations:
    """Line observations of ``walls`` from sensor ``pose`` (X, Y, Phi), with Gaussian noise of
    the given std on (rho m, alpha rad) (none without ``rng``). With ``corners``, wall endpoints
    within the field of view are observed as corners."""
    X, Y, Phi = pose
    c, s = np.cos(Phi), np.sin(Phi)
    Rt = np.array([[c, s], [-s, c]])
    lines, ends, cs = [], [], []
    for w in np.asarray(walls, float):
        a = Rt @ (w[:2] - (X, Y))
        b = Rt @ (w[2:] - (X, Y))
        clipped = _clip_half_plane(a, b, 1e-3)
        clipped = clipped and _clip_circle(*clipped, max_range)
        if not clipped:
            continue
        a, b = clipped
        if np.hypot(*(b - a)) < min_length:
            continue
        n = np.array([-(b - a)[1], (b - a)[0]]) / np.hypot(*(b - a))
        rho = n @ a
        if rho < 0:
            n, rho = -n, -rho
        alpha = np.arctan2(n[1], n[0])
        if rng is not None:
            rho = abs(rho + rng.normal(0, sigma_rho))
            alpha = wrap(alpha + rng.normal(0, sigma_alpha))
        lines.append((rho, alpha))
        ends.append((*a, *b))
    if corners:
        for w in np.asarray(walls, float):
            p = Rt @ (w[:2] - (X, Y))
            if p[0] > 0.05 and np.hypot(*p) < max_range:
                if rng is not None:
                    p = p + rng.normal(0, sigma_corner, 2)
                cs.append(p)
    m = len(lines)
    cov = np.tile(np.diag([sigma_rho**2, sigma_alpha**2]), (m, 1, 1))
    k = len(cs)
    return Observations(np.array(lines).reshape(-1, 2), cov.reshape(-1, 2, 2), np.array(ends).reshape(-1, 4),
                        np.array(cs).reshape(-1, 2), np.tile(np.eye(2) * sigma_corner**2, (k, 1, 1)).reshape(-1, 2, 2))


def circle_path(n: int, rate_hz: float, center=(5.0, 4.0), radius: float = 2.0, speed: float = 0.8) -> tuple[np.ndarray, np.ndarray]:
    """(stamps (n,) s, poses (n, 3)) of a robot driving a circle counter-clockwise, heading tangent."""
    t = np.arange(n) / rate_hz
    ang = speed / radius * t - np.pi / 2
    poses = np.column_stack((center[0] + radius * np.cos(ang), center[1] + radius * np.sin(ang), wrap(ang + np.pi / 2)))
    return t, poses


def scan_points(walls: np.ndarray, pose: np.ndarray, n_beams: int = 361, fov: float = np.pi,
                max_range: float = 8.0, sigma: float = 0.0, rng: np.random.Generator | None = None) -> np.ndarray:
    """(p, 2) points in the sensor frame where the beams (``fov`` centred ahead) first hit a wall
    (exact ray casting against the segments), with optional Gaussian range noise; beams without a
    hit within ``max_range`` are left out."""
    X, Y, Phi = pose
    b = np.linspace(-fov / 2, fov / 2, n_beams)
    d = np.column_stack((np.cos(b + Phi), np.sin(b + Phi)))  # (n, 2) world directions
    w = np.asarray(walls, float)
    a, e = w[:, :2] - (X, Y), w[:, 2:] - w[:, :2]  # wall start relative to the sensor, wall vector
    den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]  # cross(d, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / den  # range along the ray
        u = (a[None, :, 0] * d[:, None, 1] - a[None, :, 1] * d[:, None, 0]) / den  # position on the wall
    hit = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
    r = np.where(hit, t, np.inf).min(axis=1)
    if rng is not None and sigma > 0:
        r = r + rng.normal(0, sigma, r.size)
    ok = r < max_range
    return np.column_stack((r[ok] * np.cos(b[ok]), r[ok] * np.sin(b[ok])))
