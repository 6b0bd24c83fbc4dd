"""Robust point-to-line ICP of a scan against a reference point set (a keyframe or a local map).

Pure numpy + ``scipy.spatial.cKDTree``, vectorised over the points: one tree query and one 3x3
solve per iteration. Frames: scan points are in the sensor frame; the reference, its normals and
every pose are in one parent frame (the world, or a keyframe's frame).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .config import AlignmentConfig
from .geometry import to_world
from .models import wrap


_EYE3 = np.eye(3)


@dataclass(frozen=True)
class Reference:
    """Points (m, 2) with unit normals (m, 2), in the parent frame, and their k-d tree."""

    points: np.ndarray
    normals: np.ndarray
    tree: cKDTree

    @property
    def size(self) -> int:
        return int(self.points.shape[0])


@dataclass(frozen=True)
class Match:
    """Result of :func:`match`.

    Attributes:
        pose: (3,) sensor pose in the reference's frame (m, m, rad).
        information: (3, 3) information of the pose (inverse covariance), from the point-to-line
            Hessian over ``sigma_point``; near-singular along a corridor.
        inliers: fraction of the scan's points within ``inlier_distance`` of a reference point.
        rms: rms point-to-line residual of the inliers (m).
        n_points: scan points used.
        start: index of the starting hypothesis that won (0 = the given initial pose).
    """

    pose: np.ndarray
    information: np.ndarray
    inliers: float
    rms: float
    n_points: int
    start: int = 0

    @property
    def covariance(self) -> np.ndarray:
        """(3, 3) covariance of the pose; large (not infinite) along unconstrained directions."""
        return np.linalg.inv(self.information + 1e-9 * np.eye(3))


def chord_normals(points: np.ndarray, step: int = 2, max_gap: float = 0.3,
                  gap_per_range: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (p, 2) of points (p, 2) given in beam order, from the chord between the points
    ``step`` beams before and after; and the mask of points whose chord is shorter than
    ``max_gap + gap_per_range * range`` m (a surface, not a depth jump; beams spread with range)."""
    p = np.asarray(points, float).reshape(-1, 2)
    n = np.zeros_like(p)
    ok = np.zeros(p.shape[0], bool)
    if p.shape[0] < 2 * step + 1:
        return n, ok
    d = p[2 * step:] - p[:-2 * step]
    length = np.hypot(d[:, 0], d[:, 1])
    rng = np.hypot(p[step:-step, 0], p[step:-step, 1])
    good = (length > 1e-3) & (length < max_gap + gap_per_range * rng)
    n[step:-step] = np.column_stack((d[:, 1], -d[:, 0])) / np.maximum(length, 1e-12)[:, None]
    ok[step:-step] = good
    return n, ok


def voxel_filter(points: np.ndarray, size: float) -> np.ndarray:
    """Indices of one point per ``size`` m square cell (the first in the input's order)."""
    if points.shape[0] == 0 or size <= 0:
        return np.arange(points.shape[0])
    cells = np.floor(points / size).astype(np.int64)
    _, first = np.unique(cells[:, 0] * 1_000_003 + cells[:, 1], return_index=True)
    return np.sort(first)


def make_reference(points: np.ndarray, normals: np.ndarray, voxel: float = 0.0) -> Reference:
    """A :class:`Reference` of points and normals (same frame), thinned to one per ``voxel`` m cell."""
    keep = voxel_filter(points, voxel)
    p, n = np.ascontiguousarray(points[keep]), np.ascontiguousarray(normals[keep])
    return Reference(p, n, cKDTree(p))


def refine(points: np.ndarray, ref: Reference, pose: np.ndarray, cfg: AlignmentConfig) -> Match:
    """Gauss-Newton point-to-line ICP from ``pose`` with Huber weights (``huber`` m) on the
    residuals and correspondences within ``max_correspondence`` m, then, once converged, within
    ``fine_correspondence`` m."""
    pose = np.array(pose, float)
    n = points.shape[0]
    H = np.zeros((3, 3))
    r = np.zeros(0)
    reach = cfg.max_correspondence
    for it in range(cfg.max_iterations):
        w = to_world(pose, points)
        d, j = ref.tree.query(w, distance_upper_bound=reach)
        ok = np.isfinite(d)
        if ok.sum() < 3:
            return Match(pose, np.zeros((3, 3)), 0.0, np.inf, n)
        wk, jk = w[ok], j[ok]
        nk = ref.normals[jk]
        r = np.einsum("ij,ij->i", wk - ref.points[jk], nk)
        a = np.abs(r)
        weight = np.where(a <= cfg.huber, 1.0, cfg.huber / np.maximum(a, 1e-12))
        J = np.column_stack((nk[:, 0], nk[:, 1], nk[:, 1] * (wk[:, 0] - pose[0]) - nk[:, 0] * (wk[:, 1] - pose[1])))
        Jw = J * weight[:, None]
        H = Jw.T @ J
        g = Jw.T @ r
        # Levenberg damping: an unconstrained direction (a corridor's axis) stays where it started
        step = -np.linalg.solve(H + (cfg.damping * np.trace(H) / 3.0 + 1e-12) * _EYE3, g)
        pose = pose + step
        pose[2] = wrap(pose[2])
        if abs(step[0]) + abs(step[1]) < cfg.tolerance_xy and abs(step[2]) < cfg.tolerance_theta:
            if reach == cfg.fine_correspondence:
                break
            # converged with the wide reach: finish with the narrow one, so points without a
            # counterpart (a partial overlap) no longer pull the pose
            reach = cfg.fine_correspondence
    w = to_world(pose, points)
    d, j = ref.tree.query(w, distance_upper_bound=cfg.inlier_distance)
    inl = np.isfinite(d)
    if inl.sum() >= 3:
        res = np.einsum("ij,ij->i", w[inl] - ref.points[j[inl]], ref.normals[j[inl]])
        rms = float(np.sqrt(np.mean(res**2)))
    else:
        rms = np.inf
    info = H / cfg.sigma_point**2 / cfg.covariance_inflation
    return Match(pose, 0.5 * (info + info.T), float(inl.sum()) / max(n, 1), rms, n)


def score(points: np.ndarray, ref: Reference, pose: np.ndarray, distance: float) -> float:
    """Fraction of the scan's points within ``distance`` m of a reference point at ``pose``."""
    d, _ = ref.tree.query(to_world(pose, points), distance_upper_bound=distance)
    return float(np.mean(np.isfinite(d))) if d.size else 0.0


def match(points: np.ndarray, ref: Reference, starts: list[np.ndarray], cfg: AlignmentConfig) -> Match:
    """ICP from the first start; when it explains fewer than ``retry_inliers`` of the points, also
    from every other start and from heading offsets ``heading_hypotheses`` (rad) about the first;
    the start with most inliers wins (ties keep the earlier start)."""
    best = refine(points, ref, starts[0], cfg)
    if best.inliers >= cfg.retry_inliers:
        return best
    first = np.asarray(starts[0], float)
    extra = list(starts[1:]) + [first + (0.0, 0.0, dh) for dh in cfg.heading_hypotheses]
    # cheap screening: refine only the few starts that already explain most points
    scored = sorted(((score(points, ref, s, cfg.max_correspondence), k + 1, s) for k, s in enumerate(extra)),
                    key=lambda t: -t[0])
    for _, k, s in scored[: cfg.refine_hypotheses]:
        m = refine(points, ref, s, cfg)
        if m.inliers > best.inliers + cfg.hypothesis_margin:
            best = Match(m.pose, m.information, m.inliers, m.rms, m.n_points, k)
    return best
