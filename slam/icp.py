"""Robust point-to-line ICP of a scan against a reference point set (a keyframe or a local map).

The search and the Gauss-Newton steps are compiled (:mod:`slam.icpkernel`): a uniform grid finds
each point's nearest map point, one pass over the points builds the 3x3 normal equations. Frames: scan points are in the sensor frame; the reference, its normals and
every pose are in one parent frame (the world, or a keyframe's frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from typing import Callable

import numpy as np

from . import icpkernel
from .config import SEARCH_CELL_M, AlignmentConfig
from .models import wrap


_EYE3 = np.eye(3)
#: the kernels' description of a reference: x, y, order, start, origin x, origin y, cell, nx, ny
Grid = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float, float, int, int]
_NO_PRIOR = np.zeros((3, 3))


@dataclass(frozen=True)
class Reference:
    """Points (m, 2) with unit normals (m, 2), in the parent frame, and their search grid
    (:func:`slam.icpkernel.build_grid`, cells of ``cell`` m)."""

    points: np.ndarray
    normals: np.ndarray
    cell: float
    order: np.ndarray
    start: np.ndarray
    origin: np.ndarray
    shape: np.ndarray
    _grid: Grid = field(init=False, repr=False, compare=False)
    _normals: tuple[np.ndarray, np.ndarray] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        xy = np.ascontiguousarray(self.points.T)
        nn = np.ascontiguousarray(self.normals.T)
        object.__setattr__(self, "_grid", (xy[0], xy[1], self.order, self.start, float(self.origin[0]),
                                           float(self.origin[1]), float(self.cell), int(self.shape[0]), int(self.shape[1])))
        object.__setattr__(self, "_normals", (nn[0], nn[1]))

    @property
    def size(self) -> int:
        return int(self.points.shape[0])

    def grid(self) -> Grid:
        """The arguments of the kernels that describe the reference."""
        return self._grid

    def nearest(self, queries: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """Index (-1 beyond ``reach`` m) and distance (inf) of the nearest point of each query (q, 2)."""
        q = np.asarray(queries, float).reshape(-1, 2)
        return icpkernel.nearest_many(q[:, 0].copy(), q[:, 1].copy(), *self.grid(), float(reach))


@dataclass(frozen=True)
class Match:
    """Result of :func:`match`.

    Attributes:
        pose: (3,) sensor pose in the reference's frame (m, m, rad).
        information: (3, 3) information of the pose (inverse covariance): the point-to-line
            sandwich of the match's own residuals (:func:`sandwich_information`) over
            ``covariance_inflation``; near-singular along a corridor.
        inliers: fraction of the scan's points within ``inlier_distance`` of a reference point.
        rms: rms point-to-line residual of the inliers (m).
        n_points: scan points used.
        hessian: (3, 3) point-to-line Hessian (sum of the Huber-weighted squared Jacobians, m^-2
            units of the residuals): the match's geometry alone.
        start: index of the starting hypothesis that won (0 = the given initial pose).
    """

    pose: np.ndarray
    information: np.ndarray
    inliers: float
    rms: float
    n_points: int
    hessian: np.ndarray
    start: int = 0

    @property
    def covariance(self) -> np.ndarray:
        """(3, 3) covariance of the pose; large (not infinite) along unconstrained directions."""
        return np.linalg.inv(self.information + 1e-9 * np.eye(3))


def chord_normals(points: np.ndarray, step: int = 2, max_gap: float = 0.3,
                  gap_per_range: float = 0.05, toward_sensor: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (p, 2) of points (p, 2) given in beam order, from the chord between the points
    ``step`` beams before and after (turned to face the sensor at the origin if
    ``toward_sensor``); and the mask of points whose chord is shorter than
    ``max_gap + gap_per_range * range`` m (a surface, not a depth jump; beams spread with range)."""
    p = np.asarray(points, float).reshape(-1, 2)
    n = np.zeros_like(p)
    ok = np.zeros(p.shape[0], bool)
    if p.shape[0] < 2 * step + 1:
        return n, ok
    i = np.arange(step, p.shape[0] - step)
    n[step:-step], ok[step:-step] = chord_normals_at(p, i, step, max_gap, gap_per_range, toward_sensor)
    return n, ok


def chord_normals_at(points: np.ndarray, index: np.ndarray, step: int, max_gap: float,
                     gap_per_range: float, toward_sensor: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """:func:`chord_normals` at the points ``index`` (each at least ``step`` from either end); compiled."""
    p = np.asarray(points, float)
    return icpkernel.chord_normals(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]),
                                   np.asarray(index, np.int64), int(step), float(max_gap), float(gap_per_range),
                                   bool(toward_sensor))


def voxel_filter(points: np.ndarray, size: float) -> np.ndarray:
    """Indices of one point per ``size`` m square cell (the first in the input's order)."""
    if points.shape[0] == 0 or size <= 0:
        return np.arange(points.shape[0])
    return icpkernel.first_per_cell(points, size)


def make_reference(points: np.ndarray, normals: np.ndarray, voxel: float = 0.0,
                   cell: float = SEARCH_CELL_M) -> Reference:
    """A :class:`Reference` of points and normals (same frame), thinned to one per ``voxel`` m
    cell; its search grid has cells of ``cell`` m (at least the widest reach of a search)."""
    keep = voxel_filter(points, voxel)
    p, n = np.ascontiguousarray(points[keep], float), np.ascontiguousarray(normals[keep], float)
    if p.shape[0] == 0:
        p, n = np.zeros((1, 2)) + 1e9, np.array([[1.0, 0.0]])  # far away: nothing within reach
    return Reference(p, n, float(cell), *icpkernel.build_grid(p, cell))


def refine(points: np.ndarray, ref: Reference, pose: np.ndarray, cfg: AlignmentConfig,
           prior: np.ndarray | None = None, normals: np.ndarray | None = None) -> Match:
    """Gauss-Newton point-to-line ICP from ``pose`` with Huber weights (``huber`` m) on the
    residuals: up to ``max_iterations`` steps with correspondences within ``max_correspondence``
    m, then up to ``fine_iterations`` within ``fine_correspondence`` m (points without a
    counterpart in a partial overlap no longer pull the pose). ``prior`` (3, 3), an information
    matrix (1/m^2, 1/rad^2) about ``pose``, makes it a MAP estimate: the motion's prediction holds
    the directions the scan does not fix (a corridor's axis). The returned information is the
    scan's alone. Compiled: :mod:`slam.icpkernel`."""
    reach = max(cfg.max_correspondence, cfg.fine_correspondence)
    if reach > ref.cell + 1e-12:
        raise ValueError(f"a reach of {reach} m needs grid cells at least as wide (have {ref.cell} m)")
    p = np.asarray(points, float)
    n = p.shape[0]
    pose_out, H, inliers, ss, B, used = icpkernel.gauss_newton(
        p[:, 0].copy(), p[:, 1].copy(), np.asarray(pose, float), *ref.grid()[:2], *ref._normals, *ref.grid()[2:],
        np.array([cfg.max_correspondence, cfg.fine_correspondence]), np.array([cfg.max_iterations, cfg.fine_iterations]),
        cfg.huber, cfg.damping, cfg.tolerance_xy, cfg.tolerance_theta, min(cfg.inlier_distance, cfg.fine_correspondence),
        np.asarray(pose, float).copy(), _NO_PRIOR if prior is None else np.asarray(prior, float) * cfg.sigma_point**2,
        cfg.sigma_point**2, *_query_normals(normals, n), float(np.cos(cfg.normal_agreement)))
    rms = float(np.sqrt(ss / inliers)) if inliers >= 3 else np.inf
    info = sandwich_information(H, B, int(used)) / cfg.covariance_inflation
    return Match(pose_out, info, float(inliers) / max(n, 1), rms, n, 0.5 * (H + H.T))


def _query_normals(normals: np.ndarray | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    if normals is None:
        z = np.zeros(n)
        return z, z
    q = np.asarray(normals, float).reshape(n, 2)
    return q[:, 0].copy(), q[:, 1].copy()


def sandwich_information(H: np.ndarray, B: np.ndarray, used: int) -> np.ndarray:
    """Information (3, 3) of an M-estimate from its own residuals: the covariance is the sandwich
    ``H^-1 B H^-1`` (``H`` the Huber-weighted Hessian, ``B`` the sum of each point's squared
    weighted residual, floored, times its squared Jacobian), times ``used / (used - 3)`` for the 3
    degrees of freedom spent on the pose. Unlike one pooled residual variance, it follows the
    points that fix each direction: along a corridor the few door edges that fix the axis, with
    their own residuals, set its variance. Zero information with 3 points or fewer."""
    return icpkernel.sandwich(np.ascontiguousarray(H, float), np.ascontiguousarray(B, float), int(used))


def score(points: np.ndarray, ref: Reference, pose: np.ndarray, distance: float) -> float:
    """Fraction of the scan's points within ``distance`` m of a reference point at ``pose``."""
    p = np.asarray(points, float)
    if p.shape[0] == 0:
        return 0.0
    return icpkernel.count_within(p[:, 0].copy(), p[:, 1].copy(), np.asarray(pose, float), *ref.grid(),
                                  float(distance)) / p.shape[0]


def match(points: np.ndarray, ref: Reference, starts: list[np.ndarray], cfg: AlignmentConfig,
          max_heading: float = np.inf, prior: np.ndarray | None = None, normals: np.ndarray | None = None,
          turn: tuple[float, float] | None = None,
          within: Callable[[np.ndarray], bool] | None = None) -> Match:
    """ICP from the first start; when it explains fewer than ``retry_inliers`` of the points, also
    from every other start and from heading offsets ``heading_hypotheses`` (rad) about the first
    (those up to ``max_heading`` rad: a loop closure tries only headings its drift allows); the
    start with most inliers wins (ties keep the earlier start). ``prior`` (information, see
    :func:`refine`) holds the first start only: a retry is a different motion. ``turn`` (heading
    rad, bound rad): the retry's other starts and hypotheses only within the bound of that heading.
    ``within(pose)``: a retry's pose is a candidate only where it is true (the prediction's gate:
    a heading hypothesis recovers a heading, not a position the prediction rules out)."""
    best = refine(points, ref, starts[0], cfg, prior, normals)
    if best.inliers >= cfg.retry_inliers:
        return best
    first = np.asarray(starts[0], float)
    extra = list(starts[1:]) + [first + (0.0, 0.0, dh) for dh in cfg.heading_hypotheses if abs(dh) <= max_heading]
    if turn is not None:
        extra = [s for s in extra if abs(wrap(float(s[2]) - turn[0])) <= turn[1]]
    # cheap screening: refine only the few starts that already explain most points
    scored = sorted(((score(points, ref, s, cfg.max_correspondence), k + 1, s) for k, s in enumerate(extra)),
                    key=lambda t: -t[0])
    for _, k, s in scored[: cfg.refine_hypotheses]:
        m = refine(points, ref, s, cfg, normals=normals)
        if within is not None and not within(m.pose):
            continue
        if m.inliers > best.inliers + cfg.hypothesis_margin:
            best = Match(m.pose, m.information, m.inliers, m.rms, m.n_points, m.hessian, k)
    return best
