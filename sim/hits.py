"""Compiled per-beam steps of the emulator around Bullet's ray test (numba, cached on disk).

After ``rayTestBatch`` every beam needs a few dozen flops of exact geometry: its range, the exact
entry into the box Bullet hit (which also rejects hits Bullet accepts just outside a box's edge),
the move of a prism hit onto its exact circle, the nearest glass panel, and, at depth steps, the
mixed-pixel mean of the spot's samples. Written as numpy expressions these were ~40 array calls a
scan, a third of a cluttered scan's time; as loops they cost a few microseconds. The arithmetic of
the circle, glass and mixed-pixel steps is the numpy expressions' own, operation for operation
(same order, IEEE division, no fast-math); a box range is the slab entry instead of the distance
to Bullet's interpolated hit point (equal to 1e-13 m). Checked against the exact ray caster of
the tests (``tests/test_sim_lidar.py``); see docs/simulator.md, "Speed".
"""

from __future__ import annotations

import math

import numpy as np

from lms200.numba_required import numba

_kernel = numba.njit(cache=True, error_model="numpy")


@_kernel
def box_entry(ox: float, oy: float, ux: float, uy: float, cx: float, cy: float, hx: float, hy: float, c: float,
              s: float) -> float:
    """Distance (m) at which a ray from (ox, oy) along (ux, uy) enters the box of centre (cx, cy),
    half sizes hx, hy and yaw cos c, sin s (slab method in the box frame); +inf if it misses."""
    px, py = ox - cx, oy - cy
    lo_x, lo_y = c * px + s * py, -s * px + c * py
    dx, dy = c * ux + s * uy, -s * ux + c * uy
    tx1, tx2 = (-hx - lo_x) / dx, (hx - lo_x) / dx
    ty1, ty2 = (-hy - lo_y) / dy, (hy - lo_y) / dy
    # np.fmin / np.fmax drop the nan of a ray lying in a slab's plane (0 / 0), np.maximum /
    # np.minimum keep a nan (no entry then); Python's min / max would not: their nan handling
    # depends on the argument order
    t_in = np.maximum(np.fmin(tx1, tx2), np.fmin(ty1, ty2))
    t_out = np.minimum(np.fmax(tx1, tx2), np.fmax(ty1, ty2))
    if t_in <= t_out and t_in > 0:
        return t_in
    return np.inf


@_kernel
def resolve_hits(body: np.ndarray, dist: np.ndarray, origins: np.ndarray, ux: np.ndarray, uy: np.ndarray,
                 kind_of_body: np.ndarray, index_of_body: np.ndarray, boxes: np.ndarray, box_cos: np.ndarray,
                 box_sin: np.ndarray, circles: np.ndarray, box_tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Ranges (m) of Bullet's hits and which rays must be cast again.

    Args:
        body: (n,) the solid hit (-1 for none); dist: (n,) Bullet's distance of the hit (m);
            origins: (n, 2) ray starts; ux, uy: (n,) ray directions.
        kind_of_body, index_of_body: by solid (the last slot for -1): 0 box, 1 cylinder, -1
            nothing; the solid's row in ``boxes`` (cx, cy, yaw, hx, hy, ...) or ``circles``
            (cx, cy, r).
        box_tol: a box hit farther than this (m) outside the box is Bullet's edge tolerance.

    Returns:
        ranges: +inf for no hit; for a box hit the exact entry of the ray into that box (where the
        ray misses the box, Bullet's hit lay outside it: the distance of that false hit); for a
        cylinder hit the exact entry onto its circle (the prism hit's distance if the ray misses
        the circle). again: the false hits (the ray goes on past them).
    """
    n = body.shape[0]
    ranges = np.empty(n)
    again = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        b = body[i]
        kind = kind_of_body[b]
        if kind < 0:
            ranges[i] = np.inf
            continue
        r = dist[i]
        k = index_of_body[b]
        if kind == 0:  # the exact entry into the box Bullet hit (none: its hit lies outside the box)
            c, s = box_cos[k], box_sin[k]
            entry = box_entry(origins[i, 0], origins[i, 1], ux[i], uy[i], boxes[k, 0], boxes[k, 1], boxes[k, 3],
                              boxes[k, 4], c, s)
            if math.isfinite(entry):
                r = entry
            else:
                dx = origins[i, 0] + r * ux[i] - boxes[k, 0]
                dy = origins[i, 1] + r * uy[i] - boxes[k, 1]
                if abs(c * dx + s * dy) > boxes[k, 3] + box_tol or abs(-s * dx + c * dy) > boxes[k, 4] + box_tol:
                    again[i] = True
        else:
            fx, fy = origins[i, 0] - circles[k, 0], origins[i, 1] - circles[k, 1]
            bb = fx * ux[i] + fy * uy[i]
            disc = bb * bb - (fx * fx + fy * fy - circles[k, 2] * circles[k, 2])
            if disc >= 0:
                r = -bb - math.sqrt(disc)
            else:
                again[i] = True
        ranges[i] = r
    return ranges, again


@_kernel
def finish_ranges(ranges: np.ndarray, origins: np.ndarray, ux: np.ndarray, uy: np.ndarray, glass: np.ndarray,
                  range_max: float) -> None:
    """In place: +inf where a glass segment (rows x1, y1, x2, y2) lies nearer along the ray than
    the range, or where the range exceeds range_max."""
    n, m = ranges.shape[0], glass.shape[0]
    for i in range(n):
        if m:
            ox, oy = origins[i, 0], origins[i, 1]
            near = np.inf
            for j in range(m):
                ax, ay = glass[j, 0], glass[j, 1]
                ex, ey = glass[j, 2] - ax, glass[j, 3] - ay
                wx, wy = ax - ox, ay - oy
                den = ux[i] * ey - uy[i] * ex
                t = (wx * ey - wy * ex) / den  # along the ray
                s = (wx * uy[i] - wy * ux[i]) / den  # along the glass, 0..1
                if abs(den) > 1e-12 and t > 0 and s >= 0 and s <= 1 and t < near:
                    near = t
            if near < ranges[i]:
                ranges[i] = np.inf
        if ranges[i] > range_max:
            ranges[i] = np.inf


@_kernel
def depth_steps(ranges: np.ndarray, gap: float) -> np.ndarray:
    """Beams g whose neighbour g + 1 lies more than ``gap`` (m) nearer or farther, or of which
    one reads a return and the other none."""
    n = ranges.shape[0]
    out = np.empty(max(n - 1, 0), dtype=np.int64)
    k = 0
    for g in range(n - 1):
        a, b = ranges[g], ranges[g + 1]
        if abs(b - a) > gap or math.isfinite(a) != math.isfinite(b):
            out[k] = g
            k += 1
    return out[:k]


@_kernel
def mix_samples(ranges: np.ndarray, g: np.ndarray, sub: np.ndarray, gap: float) -> np.ndarray:
    """The mixed-pixel ranges (see ``LMS200Sim._mix_edges``): beam g's samples 3, 4 and beam
    g + 1's samples 0, 1 are the sub-ray ranges ``sub`` (g's pairs, then g + 1's pairs), the
    others the beam's own range; a beam whose samples split into a near and a far group (far: more
    than ``gap`` beyond the nearest, or no return) reads their mean (all finite), else the near
    group's mean when it holds the larger share, else +inf."""
    n, m = ranges.shape[0], g.shape[0]
    samples = np.empty((n, 5))
    touched = np.zeros(n, dtype=np.bool_)
    for k in range(m):
        i = g[k]
        touched[i] = True
        touched[i + 1] = True
    for i in range(n):
        if touched[i]:
            for j in range(5):
                samples[i, j] = ranges[i]
    for k in range(m):
        i = g[k]
        samples[i, 3], samples[i, 4] = sub[2 * k], sub[2 * k + 1]
        samples[i + 1, 0], samples[i + 1, 1] = sub[2 * m + 2 * k], sub[2 * m + 2 * k + 1]
    out = ranges.copy()
    for i in range(n):
        if not touched[i]:
            continue
        near = samples[i, 0]
        for j in range(1, 5):
            if samples[i, j] < near:
                near = samples[i, j]
        if not math.isfinite(near):
            continue
        n_far, finite = 0, True
        total, near_total = samples[i, 0], 0.0
        for j in range(5):
            v = samples[i, j]
            if j:
                total += v
            if not v <= near + gap:
                n_far += 1
                near_total += 0.0
            else:
                near_total += v
            if not math.isfinite(v):
                finite = False
        if n_far == 0:
            continue
        if finite:
            out[i] = total / 5
        elif 2 * n_far > 5:
            out[i] = np.inf
        else:
            out[i] = near_total / max(5 - n_far, 1)
    return out
