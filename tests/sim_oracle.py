"""Independent exact 2-D ray caster for the sim tests (shares no code with sim)."""

from __future__ import annotations

import numpy as np


def oracle_ranges(boxes: np.ndarray, cylinders: np.ndarray, height: float, origin: np.ndarray,
                  headings: np.ndarray, range_max: float) -> np.ndarray:
    """Nearest hit of rays from origin along headings with the solids cut by z = height, and a
    mask of rays passing within 1 um of a box's vertex (where which face is hit is ambiguous)."""
    ux, uy = np.cos(headings), np.sin(headings)
    best = np.full(len(headings), np.inf)
    grazing = np.zeros(len(headings), dtype=bool)
    for cx, cy, yaw, hx, hy, z0, z1 in boxes:
        if not z0 <= height <= z1:
            continue
        c, s = np.cos(yaw), np.sin(yaw)
        pts = [(cx + c * a - s * b, cy + s * a + c * b) for a, b in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]
        for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1]):
            along = (ax - origin[0]) * ux + (ay - origin[1]) * uy
            grazing |= (along > 0) & (np.abs((ax - origin[0]) * uy - (ay - origin[1]) * ux) < 1e-6)
            ex, ey = bx - ax, by - ay
            den = ux * ey - uy * ex
            wx, wy = ax - origin[0], ay - origin[1]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (wx * ey - wy * ex) / den
                u = (wx * uy - wy * ux) / den
            hit = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
            best = np.where(hit & (t < best), t, best)
    for cx, cy, r, z0, z1 in cylinders:
        if not z0 <= height <= z1:
            continue
        fx, fy = origin[0] - cx, origin[1] - cy
        b = fx * ux + fy * uy
        disc = b * b - (fx * fx + fy * fy - r * r)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        hit = (disc > 0) & (t > 0)
        best = np.where(hit & (t < best), t, best)
    return np.where(best < range_max, best, np.inf), grazing


def free_poses(world, rng: np.random.Generator, n: int) -> np.ndarray:
    """Random poses on the route graph's edges (free space), random headings."""
    edges = world.route_edges[rng.integers(0, len(world.route_edges), n)]
    f = rng.random(n)[:, None]
    xy = world.route_nodes[edges[:, 0]] * (1 - f) + world.route_nodes[edges[:, 1]] * f
    return np.column_stack((xy, rng.uniform(-np.pi, np.pi, n)))


def oracle_glass(glass: np.ndarray, origin: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """Distance along each ray to the nearest glass segment it crosses (+inf if none)."""
    ux, uy = np.cos(headings), np.sin(headings)
    best = np.full(len(headings), np.inf)
    for ax, ay, bx, by in np.asarray(glass, dtype=float).reshape(-1, 4):
        ex, ey = bx - ax, by - ay
        den = ux * ey - uy * ex
        wx, wy = ax - origin[0], ay - origin[1]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (wx * ey - wy * ex) / den
            u = (wx * uy - wy * ux) / den
        hit = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
        best = np.where(hit & (t < best), t, best)
    return best
