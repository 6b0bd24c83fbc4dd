"""A guess-free search of a scan's pose against the local map: an exhaustive correlative search
(Olson 2009) over a window of positions and headings, for scans whose motion since the last is
beyond the reach of the ICP (seconds between scans, a metre and tens of degrees of motion).

The map's points become a likelihood field: a raster of ``exp(-d^2 / 2 sigma^2)``, d the distance
(m) from the cell to the nearest map point. Every pose of the window (positions ``step`` m apart,
headings ``step_theta`` rad apart) scores the mean field value under the scan's points; the best
few distinct poses are the candidates the ICP then refines. Frames: scan points in the sensor
frame, the map and every pose in the world frame. Pure; the inner loop is compiled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import distance_transform_edt, maximum_filter

from .icp import Reference
from .icpkernel import _nearest_facing, kernel
from .models import wrap


MAX_FIELD_SIDE = 2000  # cells: a field about a centre is at most 2,000 x 2,000 cells (32 MB of float64)


@dataclass(frozen=True)
class Field:
    """A likelihood raster: ``values[i, j]`` at world (origin[0] + i res, origin[1] + j res)."""

    values: np.ndarray  # (nx, ny), in [0, 1]; -1 in known free space (:func:`free_space`)
    origin: np.ndarray  # (2,) m, world position of cell (0, 0)
    resolution: float  # m


def make_field(points: np.ndarray, resolution: float, sigma: float, centre: np.ndarray | None = None,
               radius: float = np.inf) -> Field:
    """The likelihood field of map points (m, 2; world frame) with cells of ``resolution`` m and a
    Gaussian of ``sigma`` m about each point, over the points within ``radius`` m (a square) of
    ``centre`` (all points when no centre), with a margin of 3 sigma; about a centre, the radius
    is cut to keep the raster within ``MAX_FIELD_SIDE`` cells a side."""
    p = np.asarray(points, float).reshape(-1, 2)
    margin = 3.0 * sigma + resolution
    if centre is not None:  # at most MAX_FIELD_SIDE cells a side
        radius = min(radius, 0.5 * (MAX_FIELD_SIDE - 2) * resolution - margin)
        p = p[np.all(np.abs(p - np.asarray(centre, float)[:2]) <= radius, axis=1)]
    if p.shape[0] == 0:
        return Field(np.zeros((1, 1)), np.zeros(2), float(resolution))
    lo = p.min(axis=0) - margin
    shape = np.ceil((p.max(axis=0) + margin - lo) / resolution).astype(int) + 1
    free = np.ones(tuple(shape), bool)
    idx = np.rint((p - lo) / resolution).astype(int)
    free[idx[:, 0], idx[:, 1]] = False
    d = distance_transform_edt(free, sampling=resolution)
    return Field(np.exp(-0.5 * (d / sigma) ** 2), lo, float(resolution))


@dataclass(frozen=True)
class Candidate:
    """A pose of the window (world frame, m, m, rad) and its score (mean field value, in [0, 1]; in
    [-1, 1] on a field with known free space, :func:`free_space`)."""

    pose: np.ndarray
    score: float


def search(points: np.ndarray, field: Field, centre: np.ndarray, half_xy: float, half_theta: float,
           step: float, step_theta: float, count: int, min_xy: float, min_theta: float,
           turn: tuple[float, float] | None = None, peaks: bool = False) -> list[Candidate]:
    """The ``count`` best poses of the window ``centre`` +- ``half_xy`` m (x and y, ``step`` m
    apart, rounded to whole cells of the field) and +- ``half_theta`` rad (``step_theta`` apart;
    the full turn when ``half_theta`` >= pi), best first; each at least ``min_xy`` m or
    ``min_theta`` rad from every better one (distinct local maxima, not neighbours of one).
    ``turn`` = (heading rad, max_turn rad): only headings within ``max_turn`` of that heading
    (the last pose's: the turn a robot can make since) are scored (none left: no candidates).
    ``peaks``: only local maxima of the window (no better pose among the 26 neighbours on its
    grid) are candidates, so the runner-up is another place that fits, not a neighbour of the best;
    with the full turn, ``half_theta`` >= pi, the heading axis wraps there: the first and last
    headings are neighbours (unwrapped, a slope that crossed the turn's seam gave a candidate, the
    best pose's neighbour 10 degrees and 0.3 m off), and the headings ``turn`` keeps are taken
    from the start of their arc, so that they stay neighbours across the seam too."""
    p = np.asarray(points, float).reshape(-1, 2)
    if p.shape[0] == 0:
        return []
    res = field.resolution
    k = max(1, int(round(step / res)))  # cells per translation step
    n = int(math.floor(half_xy / (k * res)))
    full = half_theta >= math.pi
    if full:
        m = int(math.ceil(2 * math.pi / step_theta))
        thetas = centre[2] + (np.arange(m) - m // 2) * (2 * math.pi / m)
    else:
        m = int(math.floor(half_theta / step_theta))
        thetas = centre[2] + np.arange(-m, m + 1) * step_theta
    ring = full  # the headings go round the whole turn: the peaks' heading axis wraps
    if turn is not None and turn[1] < math.pi:
        keep = np.abs(wrap(thetas - turn[0])) <= turn[1]
        if not keep.any():
            return []
        if peaks and full and not keep.all():  # one arc of the ring: start at its first heading
            thetas = np.roll(thetas, -int(np.flatnonzero(keep & ~np.roll(keep, 1))[0]))
            keep = np.abs(wrap(thetas - turn[0])) <= turn[1]
        ring = full and bool(keep.all())
        thetas = thetas[keep]
    scores = _scores(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), field.values,
                     float(field.origin[0]), float(field.origin[1]), res, float(centre[0]), float(centre[1]),
                     thetas, n, k)
    flat = scores.ravel()
    if peaks:
        modes = ("wrap" if ring else "nearest", "nearest", "nearest")
        flat = np.where(scores >= maximum_filter(scores, size=3, mode=modes), scores, -np.inf).ravel()
    top = min(flat.size, max(64, 32 * count))
    order = np.argpartition(-flat, top - 1)[:top]
    order = order[np.argsort(-flat[order], kind="stable")]
    side = 2 * n + 1
    out: list[Candidate] = []
    for f in order:
        if flat[f] == -np.inf:  # not a peak (scores with known free space may be negative)
            break
        a, rest = divmod(int(f), side * side)
        i, j = divmod(rest, side)
        pose = np.array([centre[0] + (i - n) * k * res, centre[1] + (j - n) * k * res,
                         wrap(thetas[a])])
        if all(np.hypot(*(pose[:2] - c.pose[:2])) >= min_xy
               or abs(wrap(pose[2] - c.pose[2])) >= min_theta for c in out):
            out.append(Candidate(pose, float(flat[f])))
            if len(out) == count:
                break
    return out


@kernel
def _scores(px, py, values, ox, oy, res, cx, cy, thetas, n, k):
    """(headings, 2n+1, 2n+1) mean field value of the points at every pose of the window
    (positions k cells apart about (cx, cy)); points off the raster score 0."""
    nx, ny = values.shape
    side = 2 * n + 1
    npts = px.shape[0]
    out = np.zeros((thetas.shape[0], side, side))
    gi = np.empty(npts, np.int64)
    gj = np.empty(npts, np.int64)
    for a in range(thetas.shape[0]):
        c, s = math.cos(thetas[a]), math.sin(thetas[a])
        for q in range(npts):  # cell of each point at the window's centre
            gi[q] = int(math.floor((cx + c * px[q] - s * py[q] - ox) / res + 0.5))
            gj[q] = int(math.floor((cy + s * px[q] + c * py[q] - oy) / res + 0.5))
        for i in range(side):
            di = (i - n) * k
            for j in range(side):
                dj = (j - n) * k
                acc = 0.0
                for q in range(npts):
                    u = gi[q] + di
                    v = gj[q] + dj
                    if u >= 0 and u < nx and v >= 0 and v < ny:
                        acc += values[u, v]
                out[a, i, j] = acc / npts
    return out


def fit(points: np.ndarray, normals: np.ndarray | None, ref: Reference, pose: np.ndarray, reach: float, sigma: float,
        min_cos: float) -> float:
    """How well the scan's points (p, 2, sensor frame; ``normals`` (p, 2) or None) lie on the
    reference at ``pose``: the mean over the points of
    ``exp(-r^2 / 2 sigma^2)``, r the point-to-line residual (m) to the nearest reference point
    within ``reach`` m whose normal agrees within ``acos(min_cos)`` (0 for a point without one).
    Unlike the inlier fraction (points within a distance) it tells a tight fit from a loose one:
    a corridor seen half a turn the wrong way puts most points near a wall, but not on it."""
    p = np.asarray(points, float).reshape(-1, 2)
    if p.shape[0] == 0:
        return 0.0
    if normals is None:
        qn = np.zeros_like(p)
    else:
        qn = np.asarray(normals, float).reshape(-1, 2)
    rx, ry, order, start, lox, loy, cell, nx, ny = ref.grid()
    nrx, nry = ref._normals
    return float(_fit(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), np.ascontiguousarray(qn[:, 0]),
                      np.ascontiguousarray(qn[:, 1]), np.asarray(pose, float), rx, ry, nrx, nry, order, start, lox,
                      loy, cell, nx, ny, float(reach) ** 2, float(sigma), float(min_cos)))


@kernel
def _fit(px, py, qnx, qny, pose, rx, ry, nrx, nry, order, start, lox, loy, cell, nx, ny, reach2, sigma, min_cos):
    """:func:`fit`, compiled."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    acc = 0.0
    for q in range(px.shape[0]):
        wx = c * px[q] - s * py[q] + pose[0]
        wy = s * px[q] + c * py[q] + pose[1]
        m, _ = _nearest_facing(wx, wy, c * qnx[q] - s * qny[q], s * qnx[q] + c * qny[q], rx, ry, nrx, nry,
                               order, start, lox, loy, cell, nx, ny, reach2, min_cos)
        if m >= 0:
            r = (wx - rx[m]) * nrx[m] + (wy - ry[m]) * nry[m]
            acc += math.exp(-0.5 * (r / sigma) ** 2)
    return acc / px.shape[0]


def see_through(map_points: np.ndarray, pose: np.ndarray, bearings: np.ndarray, ranges: np.ndarray,
                gap: float, gap_per_range: float, max_range: float) -> float:
    """The share of the map's points in the scan's view that the scan, placed at ``pose`` (world
    m, m, rad), sees through: a beam at the point's bearing and both its neighbours return from
    beyond the point's range plus ``gap + gap_per_range * range`` m (the chord test's tolerance
    for one surface). ``bearings`` (rad, ascending) and ``ranges`` (m) are the scan's valid
    beams (sensor frame); a map point further than ``max_range``, or whose bearing lies more
    than 1.5 beam steps from a valid beam (outside the view, or where the beams returned
    nothing), says nothing. 0 when no map point is in view. A scan of a full turn (its first and
    last beams one step apart across +-pi) wraps: those two are neighbours.

    Negative information: a scan turned half a turn, or slid along a corridor, puts its beams
    through the walls the map holds behind the robot, while the fit (:func:`fit`) counts only the
    points that land on something and a map is richest where the robot has been."""
    q = np.asarray(map_points, float).reshape(-1, 2)
    b = np.asarray(bearings, float)
    r = np.asarray(ranges, float)
    if q.shape[0] == 0 or b.size < 3:
        return 0.0
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = q[:, 0] - pose[0], q[:, 1] - pose[1]
    x, y = c * dx + s * dy, -s * dx + c * dy
    rho = np.hypot(x, y)
    near = rho <= max_range
    rho, beta = rho[near], np.arctan2(y[near], x[near])
    step = float(np.median(np.diff(b)))
    n = b.size
    ring = b[0] + 2.0 * math.pi - b[-1] <= 1.5 * step  # a full turn of beams: the first and last are neighbours
    be = np.concatenate(([b[-1] - 2.0 * math.pi], b, [b[0] + 2.0 * math.pi])) if ring else b
    j = np.clip(np.searchsorted(be, beta), 1, be.size - 1)
    j = np.where(np.abs(be[j - 1] - beta) < np.abs(be[j] - beta), j - 1, j)  # the nearest valid beam
    seen = np.abs(be[j] - beta) <= 1.5 * step
    if not np.any(seen):
        return 0.0
    j, rho = j[seen], rho[seen]
    if ring:  # back to the scan's beams, neighbours across the seam
        j = (j - 1) % n
        lo, hi = (j - 1) % n, (j + 1) % n
    else:
        lo, hi = np.maximum(j - 1, 0), np.minimum(j + 1, n - 1)
    reach = np.minimum(np.minimum(r[lo], r[j]), r[hi])
    return float(np.mean(reach > rho + gap + gap_per_range * rho))


def free_space(field: Field, origins: np.ndarray, points: list[np.ndarray], gap: float, gap_per_range: float,
               sigma: float) -> Field:
    """``field`` with the known free space counted against a point: -1 in every cell that a
    keyframe's beam crossed (from its sensor at ``origins[k]`` (2,) to each of its world points
    ``points[k]`` (p, 2), up to ``gap + gap_per_range * range`` m short of the point, the chord test's
    tolerance for one surface) and that lies more than ``gap`` m from every map point (so a point a
    surface's tolerance off the wall still scores as on it), the field's value elsewhere.

    The field counts only the points that land on the map; a point in space the map's own beams
    crossed is evidence against the pose (a scan turned half a turn, or slid along a corridor, puts
    its far points there), and a point where no beam went (unknown) says nothing either way."""
    res = field.resolution
    crossed = np.zeros(field.values.shape, np.bool_)
    for o, p in zip(np.asarray(origins, float).reshape(-1, 2), points):
        q = np.asarray(p, float).reshape(-1, 2)
        if q.shape[0]:
            _trace(crossed, float(o[0]), float(o[1]), np.ascontiguousarray(q[:, 0]), np.ascontiguousarray(q[:, 1]),
                   float(field.origin[0]), float(field.origin[1]), res, float(gap), float(gap_per_range))
    level = math.exp(-0.5 * (gap / sigma) ** 2)  # the field's value gap m from the nearest map point
    if level > 0.0:
        far = field.values < level  # more than gap m from every map point
    else:  # gap > ~38.6 sigma: that value underflows to 0, and so does the field's beyond ~38.6 sigma
        far = distance_transform_edt(field.values < 1.0, sampling=field.resolution) > gap  # 1 on map points' cells
    return Field(np.where(crossed & far, -1.0, field.values), field.origin, res)


@kernel
def _trace(crossed, ox, oy, px, py, gx, gy, res, gap, gap_per_range):
    """Mark the cells of ``crossed`` (origin (gx, gy), ``res`` m cells) that the beams from (ox, oy)
    to each point cross, sampled every half cell, stopping ``gap + gap_per_range * range`` m short."""
    nx, ny = crossed.shape
    h = 0.5 * res
    for q in range(px.shape[0]):
        dx, dy = px[q] - ox, py[q] - oy
        r = math.sqrt(dx * dx + dy * dy)
        stop = r - gap - gap_per_range * r
        if stop <= 0.0:
            continue
        ux, uy = dx / r, dy / r
        for t in range(int(stop / h) + 1):
            u = int(math.floor((ox + ux * t * h - gx) / res + 0.5))
            v = int(math.floor((oy + uy * t * h - gy) / res + 0.5))
            if u >= 0 and u < nx and v >= 0 and v < ny:
                crossed[u, v] = True


def free_share(points: np.ndarray, field: Field, pose: np.ndarray) -> float:
    """The share of the scan's points (p, 2, sensor frame) that land, at ``pose`` (world m, m, rad),
    in a cell of ``field`` marked known free (value -1, :func:`free_space`); 0 without points."""
    p = np.asarray(points, float).reshape(-1, 2)
    if p.shape[0] == 0:
        return 0.0
    c, s = math.cos(pose[2]), math.sin(pose[2])
    u = np.floor((c * p[:, 0] - s * p[:, 1] + pose[0] - field.origin[0]) / field.resolution + 0.5).astype(int)
    v = np.floor((s * p[:, 0] + c * p[:, 1] + pose[1] - field.origin[1]) / field.resolution + 0.5).astype(int)
    nx, ny = field.values.shape
    inside = (u >= 0) & (u < nx) & (v >= 0) & (v < ny)
    return float(np.sum(field.values[u[inside], v[inside]] < 0.0)) / p.shape[0]
