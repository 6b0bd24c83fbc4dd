"""Exact synthetic scans of polygonal rooms with their ground truth, independent of ``sim``.

A small analytic ray caster (ray / segment intersection, vectorised over beams x walls) for tests
and benchmarks of the extractors and of the scoring. Truth comes in the shape of
``sim.VisibleTruth``: ``segments`` (k,4 sensor frame, from the first to the last beam hitting each
visible run of a wall), ``segment_beams`` (k,2), ``corners`` (m,4: x, y, interior angle, convex),
``corner_beams`` (m,).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lms200 import Scan


@dataclass(frozen=True)
class SyntheticTruth:
    """Visible ground truth of one synthetic scan (sensor frame, metres, radians)."""

    segments: np.ndarray
    segment_beams: np.ndarray
    corners: np.ndarray
    corner_beams: np.ndarray


def cast(walls: np.ndarray, pose: tuple[float, float, float], angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact range (m, inf where nothing is hit) and hit wall index (-1) of each beam."""
    px, py, th = pose
    dx, dy = np.cos(angles + th)[:, None], np.sin(angles + th)[:, None]
    ax, ay = walls[:, 0][None, :] - px, walls[:, 1][None, :] - py
    ex, ey = (walls[:, 2] - walls[:, 0])[None, :], (walls[:, 3] - walls[:, 1])[None, :]
    den = dx * ey - dy * ex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (ax * ey - ay * ex) / den  # distance along the beam
        u = (ax * dy - ay * dx) / den  # position along the wall, 0..1
    hit = (np.abs(den) > 1e-12) & (t > 1e-9) & (u >= 0) & (u <= 1)
    t = np.where(hit, t, np.inf)
    wall = np.argmin(t, axis=1)
    rng = t[np.arange(angles.size), wall]
    wall = np.where(np.isfinite(rng), wall, -1)
    return rng, wall


def room_scan(
    walls: np.ndarray,
    pose: tuple[float, float, float],
    sigma: float = 0.0,
    seed: int = 0,
    range_max: float = 8.183,
) -> tuple[Scan, SyntheticTruth]:
    """An LMS200 scan (361 beams, 0.5 deg) of ``walls`` from ``pose`` with Gaussian range noise
    ``sigma`` (m, seeded) and its exact visible truth."""
    angles = -np.pi / 2 + np.arange(361) * np.deg2rad(0.5)
    exact, wall = cast(np.asarray(walls, float), pose, angles)
    wall = np.where(exact <= range_max, wall, -1)
    exact = np.where(wall >= 0, exact, np.inf)
    noisy = exact + np.random.default_rng(seed).normal(0.0, sigma, exact.size) * np.isfinite(exact)
    scan = Scan.lms200(np.where(np.isfinite(noisy), np.maximum(noisy, 0.0), np.inf), range_max=range_max)
    return scan, truth_from_hits(np.asarray(walls, float), pose, angles, exact, wall)


def truth_from_hits(walls: np.ndarray, pose, angles, exact, wall) -> SyntheticTruth:
    """Visible segments (runs of consecutive beams on one wall) and corners between runs."""
    px, py, th = pose
    change = np.flatnonzero(np.diff(wall) != 0) + 1
    starts = np.concatenate(([0], change))
    ends = np.concatenate((change - 1, [wall.size - 1]))
    keep = wall[starts] >= 0
    starts, ends = starts[keep], ends[keep]
    seen = np.where(np.isfinite(exact), exact, 0.0)  # no-return beams are never a run's end: no inf * 0
    xs, ys = seen * np.cos(angles), seen * np.sin(angles)
    segments = np.column_stack((xs[starts], ys[starts], xs[ends], ys[ends]))
    c, s = np.cos(-th), np.sin(-th)
    corners, corner_beams = [], []
    for k in range(starts.size - 1):
        if starts[k + 1] != ends[k] + 1:
            continue
        wa, wb = walls[wall[ends[k]]], walls[wall[starts[k + 1]]]
        shared = [p for p in (wa[:2], wa[2:]) if any(np.allclose(p, q) for q in (wb[:2], wb[2:]))]
        if not shared:
            continue
        vx, vy = shared[0][0] - px, shared[0][1] - py
        sx, sy = c * vx - s * vy, s * vx + c * vy
        fa = segments[k, :2] - (sx, sy)
        fb = segments[k + 1, 2:] - (sx, sy)
        ang = float(np.arccos(np.clip(fa @ fb / (np.linalg.norm(fa) * np.linalg.norm(fb)), -1, 1)))
        convex = float(np.hypot(sx, sy) < min(exact[ends[k]], exact[starts[k + 1]]))
        corners.append((sx, sy, ang, convex))
        corner_beams.append(ends[k])
    return SyntheticTruth(
        segments,
        np.column_stack((starts, ends)).astype(int),
        np.array(corners, float).reshape(-1, 4),
        np.array(corner_beams, int),
    )


def polygon(vertices: list[tuple[float, float]]) -> np.ndarray:
    """Walls (n,4) of a closed polygon."""
    v = np.asarray(vertices, float)
    return np.column_stack((v, np.roll(v, -1, axis=0)))


# An L-shaped room with a convex corner, an obtuse bend and walls at several angles (metres).
L_ROOM = polygon([(-2.0, -3.0), (5.0, -3.0), (5.0, 0.5), (3.0, 2.5), (3.0, 4.0), (-2.0, 4.0)])
