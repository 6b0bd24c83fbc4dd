"""Compiled inner loops of the ICP (numba): a uniform-grid nearest-neighbour search and the
Gauss-Newton point-to-line iterations. One implementation; tests check the search against
``scipy.spatial.cKDTree`` and the solver against exact synthetic poses.

Grid: reference points sorted by cell (cell side = the widest reach, so the cells that overlap the
square of the reach about a query, at most 3x3 and often one, hold every point within reach);
``start[c]:start[c + 1]`` indexes cell ``c = i * ny + j``.
"""

from __future__ import annotations

import math
from typing import Any, Callable, TypeVar, cast

import numpy as np

from features.jit import wrap_one
from lms200.numba_required import numba

_F = TypeVar("_F", bound=Callable[..., Any])
_njit = numba.njit(cache=True, error_model="numpy", fastmath=False)


def kernel(fn: _F) -> _F:
    """Compile ``fn`` with numba (nopython, cached), keeping its signature for the type checker."""
    return cast(_F, _njit(fn))


def build_grid(points: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(order, start, origin (2,), shape (2,)) of a grid of ``cell`` m over points (m, 2): ``order``
    lists the points by cell (in input order within a cell), ``start`` the first slot of every cell."""
    p = np.asarray(points, float)
    return _grid(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), float(cell))


@kernel
def _grid(px, py, cell):
    """:func:`build_grid`, compiled: one counting sort of the cells (stable, as an argsort by cell)."""
    lox, loy = px.min() - cell, py.min() - cell
    n = px.shape[0]
    ci = np.empty(n, np.int64)
    cj = np.empty(n, np.int64)
    for k in range(n):
        ci[k] = int(math.floor((px[k] - lox) / cell))
        cj[k] = int(math.floor((py[k] - loy) / cell))
    nx, ny = ci.max() + 2, cj.max() + 2
    start = np.zeros(nx * ny + 1, np.int64)
    for k in range(n):
        start[ci[k] * ny + cj[k] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, np.int64)
    for k in range(n):
        c = ci[k] * ny + cj[k]
        order[fill[c]] = k
        fill[c] += 1
    return order, start, np.array([lox, loy]), np.array([nx, ny], np.int64)


def first_per_cell(points: np.ndarray, size: float) -> np.ndarray:
    """Sorted indices of the first of points (p, 2) to fall in each distinct ``size`` m square."""
    p = np.asarray(points, float)
    keep, ok = _first_dense(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), float(size), _DENSE_CELLS)
    if ok:
        return keep
    cells = np.floor(p / size).astype(np.int64)  # too wide for a table of every cell: sort instead
    cells -= cells.min(axis=0)
    key = cells[:, 0] * (cells[:, 1].max() + 1) + cells[:, 1]
    return np.sort(np.unique(key, return_index=True)[1])


_DENSE_CELLS = 1 << 24


@kernel
def _first_dense(px, py, size, max_cells):
    """:func:`first_per_cell` with a table of every cell over the points' extent (not ok: wider
    than ``max_cells`` cells)."""
    n = px.shape[0]
    keep = np.empty(n, np.int64)
    if n == 0:
        return keep, True
    ci = np.empty(n, np.int64)
    cj = np.empty(n, np.int64)
    for k in range(n):
        ci[k] = int(math.floor(px[k] / size))
        cj[k] = int(math.floor(py[k] / size))
    lo_i, lo_j = ci.min(), cj.min()
    nx, ny = ci.max() - lo_i + 1, cj.max() - lo_j + 1
    if nx * ny > max_cells:
        return keep[:0], False
    seen = np.zeros(nx * ny, np.bool_)
    m = 0
    for k in range(n):
        c = (ci[k] - lo_i) * ny + cj[k] - lo_j
        if not seen[c]:
            seen[c] = True
            keep[m] = k
            m += 1
    return keep[:m], True


@kernel
def chord_normals(px, py, index, step, max_gap, gap_per_range, toward_sensor):
    """Unit normals (n, 2) at the points ``index`` from the chord between the points ``step``
    before and after, and whether that chord is short enough to be a surface (see
    :func:`slam.icp.chord_normals`)."""
    n = index.shape[0]
    out = np.empty((n, 2))
    good = np.empty(n, np.bool_)
    for k in range(n):
        i = index[k]
        dx, dy = px[i + step] - px[i - step], py[i + step] - py[i - step]
        length = math.hypot(dx, dy)
        good[k] = length > 1e-3 and length < max_gap + gap_per_range * math.hypot(px[i], py[i])
        scale = max(length, 1e-12)
        nx, ny = dy / scale, -dx / scale
        if toward_sensor and nx * px[i] + ny * py[i] > 0:
            nx, ny = -nx, -ny
        out[k, 0], out[k, 1] = nx, ny
    return out, good


@kernel
def _cells_within(qx, qy, lox, loy, cell, nx, ny, reach2):
    """Cell ranges [i0, i1) x [j0, j1) that overlap the square of half-side ``sqrt(reach2)``
    (at most the cell) about (qx, qy): the cells that can hold a point within reach."""
    r = math.sqrt(reach2)
    i0 = max(int(math.floor((qx - r - lox) / cell)), 0)
    i1 = min(int(math.floor((qx + r - lox) / cell)) + 1, nx)
    j0 = max(int(math.floor((qy - r - loy) / cell)), 0)
    j1 = min(int(math.floor((qy + r - loy) / cell)) + 1, ny)
    return i0, i1, j0, j1


@kernel
def _nearest_facing(qx, qy, qnx, qny, rx, ry, nrx, nry, order, start, lox, loy, cell, nx, ny, reach2, min_cos):
    """Index (-1 if none) and squared distance of the reference point nearest (qx, qy) within reach,
    among those whose normal (nrx, nry) lies within ``acos(min_cos)`` of the query's normal
    (qnx, qny); a query without a normal (0, 0) takes the nearest point."""
    facing = qnx != 0.0 or qny != 0.0
    i0, i1, j0, j1 = _cells_within(qx, qy, lox, loy, cell, nx, ny, reach2)
    best = -1
    bd = reach2
    for i in range(i0, i1):
        for j in range(j0, j1):
            c = i * ny + j
            for k in range(start[c], start[c + 1]):
                m = order[k]
                dx = rx[m] - qx
                dy = ry[m] - qy
                d = dx * dx + dy * dy
                if d < bd and (not facing or qnx * nrx[m] + qny * nry[m] >= min_cos):
                    bd = d
                    best = m
    return best, bd


@kernel
def _nearest(qx, qy, rx, ry, order, start, lox, loy, cell, nx, ny, reach2):
    """Index (-1 if none) and squared distance of the reference point nearest (qx, qy) within reach."""
    return _nearest_facing(qx, qy, 0.0, 0.0, rx, ry, rx, ry, order, start, lox, loy, cell, nx, ny, reach2, 0.0)


@kernel
def nearest_many(qx, qy, rx, ry, order, start, lox, loy, cell, nx, ny, reach):
    """Nearest reference index (-1 beyond ``reach`` m) and distance (inf) for every query point."""
    n = qx.shape[0]
    idx = np.empty(n, np.int64)
    dist = np.empty(n)
    for q in range(n):
        m, d = _nearest(qx[q], qy[q], rx, ry, order, start, lox, loy, cell, nx, ny, reach * reach)
        idx[q] = m
        dist[q] = math.sqrt(d) if m >= 0 else np.inf
    return idx, dist


@kernel
def count_within(px, py, pose, rx, ry, order, start, lox, loy, cell, nx, ny, reach):
    """Number of points (sensor frame) at ``pose`` within ``reach`` m of a reference point."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    count = 0
    for q in range(px.shape[0]):
        wx = c * px[q] - s * py[q] + pose[0]
        wy = s * px[q] + c * py[q] + pose[1]
        m, _ = _nearest(wx, wy, rx, ry, order, start, lox, loy, cell, nx, ny, reach * reach)
        if m >= 0:
            count += 1
    return count


@kernel
def _solve3(A, b):
    """x = A^-1 b for a symmetric 3x3 A (Cramer's rule); zeros if singular."""
    a00, a01, a02, a11, a12, a22 = A[0, 0], A[0, 1], A[0, 2], A[1, 1], A[1, 2], A[2, 2]
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    det = a00 * c00 + a01 * c01 + a02 * c02
    x = np.zeros(3)
    if abs(det) < 1e-300:
        return x
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    x[0] = (c00 * b[0] + c01 * b[1] + c02 * b[2]) / det
    x[1] = (c01 * b[0] + c11 * b[1] + c12 * b[2]) / det
    x[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det
    return x


@kernel
def sandwich(H, B, used):
    """``H (B used / (used - 3))^-1 H``, symmetrised (zeros for 3 points or fewer, or a singular B)."""
    out = np.zeros((3, 3))
    if used <= 3:
        return out
    f = used / (used - 3.0)
    Bs = np.empty((3, 3))
    eps = 1e-12 * (B[0, 0] + B[1, 1] + B[2, 2]) * f + 1e-30
    for i in range(3):
        for j in range(3):
            Bs[i, j] = 0.5 * (B[i, j] + B[j, i]) * f
        Bs[i, i] += eps
    X = np.empty((3, 3))  # Bs^-1 H, column by column
    for j in range(3):
        X[:, j] = _solve3(Bs, H[:, j].copy())
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc += H[i, k] * X[k, j]
            out[i, j] = acc
    for i in range(3):
        for j in range(i + 1, 3):
            m = 0.5 * (out[i, j] + out[j, i])
            out[i, j] = m
            out[j, i] = m
    return out


@kernel
def gauss_newton(px, py, pose0, rx, ry, nrx, nry, order, start, lox, loy, cell, nx, ny,
                 reaches, iterations, huber, damping, tol_xy, tol_theta, inlier_distance, prior, prior_info, floor2, qnx, qny, min_cos):
    """Point-to-line ICP stages (reach m, iterations); returns pose (3,), Hessian (3, 3) of the
    last step, inlier count and sum of squared inlier residuals (m^2) at the last correspondences.
    ``prior`` (3,) with ``prior_info`` (3, 3, in the units of the Hessian: information times the
    residual variance; zeros for none) is a Gaussian prior on the pose (MAP estimate)."""
    pose = pose0.copy()
    H = np.zeros((3, 3))
    B = np.zeros((3, 3))
    g = np.zeros(3)
    n = px.shape[0]
    inliers = 0
    used = 0
    ss = 0.0
    for stage in range(reaches.shape[0]):
        reach2 = reaches[stage] * reaches[stage]
        for _ in range(iterations[stage]):
            c, s = math.cos(pose[2]), math.sin(pose[2])
            H[:, :] = 0.0
            B[:, :] = 0.0
            g[:] = 0.0
            used = 0
            inliers = 0
            ss = 0.0
            for q in range(n):
                wx = c * px[q] - s * py[q] + pose[0]
                wy = s * px[q] + c * py[q] + pose[1]
                m, d2 = _nearest_facing(wx, wy, c * qnx[q] - s * qny[q], s * qnx[q] + c * qny[q], rx, ry, nrx, nry,
                                        order, start, lox, loy, cell, nx, ny, reach2, min_cos)
                if m < 0:
                    continue
                used += 1
                ux, uy = nrx[m], nry[m]
                r = (wx - rx[m]) * ux + (wy - ry[m]) * uy
                a = abs(r)
                w = 1.0 if a <= huber else huber / a
                if d2 < inlier_distance * inlier_distance:
                    inliers += 1
                    ss += r * r
                j0, j1, j2 = ux, uy, uy * (wx - pose[0]) - ux * (wy - pose[1])
                H[0, 0] += w * j0 * j0
                H[0, 1] += w * j0 * j1
                H[0, 2] += w * j0 * j2
                H[1, 1] += w * j1 * j1
                H[1, 2] += w * j1 * j2
                H[2, 2] += w * j2 * j2
                v = w * w * max(r * r, floor2)
                B[0, 0] += v * j0 * j0
                B[0, 1] += v * j0 * j1
                B[0, 2] += v * j0 * j2
                B[1, 1] += v * j1 * j1
                B[1, 2] += v * j1 * j2
                B[2, 2] += v * j2 * j2
                g[0] += w * j0 * r
                g[1] += w * j1 * r
                g[2] += w * j2 * r
            H[1, 0], H[2, 0], H[2, 1] = H[0, 1], H[0, 2], H[1, 2]
            B[1, 0], B[2, 0], B[2, 1] = B[0, 1], B[0, 2], B[1, 2]
            if used < 3:
                return pose, np.zeros((3, 3)), 0, np.inf, np.zeros((3, 3)), 0
            A = H + prior_info
            e = pose - prior
            e[2] = wrap_one(e[2])
            b = g + prior_info @ e
            lam = damping * (A[0, 0] + A[1, 1] + A[2, 2]) / 3.0 + 1e-12
            for k in range(3):
                A[k, k] += lam
            step = _solve3(A, b)
            pose[0] -= step[0]
            pose[1] -= step[1]
            pose[2] = pose[2] - step[2]
            pose[2] = wrap_one(pose[2])
            if abs(step[0]) + abs(step[1]) < tol_xy and abs(step[2]) < tol_theta:
                break
    return pose, H, inliers, ss, B, used
