"""Keyframe records, the local map built from them, and the loop-closure search over them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .config import AlignmentConfig, LoopClosureConfig
from .geometry import between, rotate_covariance, to_world
from .models import chi2_quantile, wrap
from .icp import Match, Reference, make_reference, match


@dataclass
class Keyframe:
    """A scan kept for matching: its points and normals in its own sensor frame.

    Attributes:
        key: its key in the pose graph.
        scan: index of the scan in the input.
        stamp: s.
        pose: current world pose estimate (updated after every optimisation).
        points, normals: (p, 2) sensor frame.
        travelled: path length (m) from the first scan to this keyframe.
    """

    key: int
    scan: int
    stamp: float
    pose: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    travelled: float
    _world: tuple[bytes, np.ndarray, np.ndarray] | None = field(default=None, repr=False, compare=False)

    def world(self) -> tuple[np.ndarray, np.ndarray]:
        """Its points and normals in the world frame at its current pose (kept until the pose changes)."""
        key = np.asarray(self.pose, float).tobytes()
        if self._world is None or self._world[0] != key:
            c, s = np.cos(self.pose[2]), np.sin(self.pose[2])
            self._world = (key, to_world(self.pose, self.points), self.normals @ np.array([[c, s], [-s, c]]))
        return self._world[1], self._world[2]


@dataclass(frozen=True)
class LoopClosure:
    """A verified closure: keyframe ``new`` seen from the pose ``relative`` in the frame of ``old``."""

    old: int
    new: int
    relative: np.ndarray
    inliers: float
    rms: float
    correction: float  # m, how far the closure moves the new keyframe from its estimate
    covariance: np.ndarray  # (3, 3) of ``relative``, in the frame of the new keyframe (the match's)
    distance: float  # Mahalanobis distance^2 of the correction against the drift the graph allows


def local_map(keyframes: list[Keyframe], voxel: float) -> Reference:
    """The points and normals of ``keyframes`` in the world frame, thinned to ``voxel`` m cells
    (newest keyframe first, so its points win a cell)."""
    pts, nrm = [], []
    for kf in reversed(keyframes):
        p, n = kf.world()
        pts.append(p)
        nrm.append(n)
    return make_reference(np.concatenate(pts), np.concatenate(nrm), voxel)


def find_closure(new: Keyframe, scan_points: np.ndarray, keyframes: list[Keyframe], cfg: LoopClosureConfig,
                 alignment: AlignmentConfig, voxel: float, since_closure: float = 0.0,
                 drift: Callable[[Keyframe], np.ndarray] | None = None, positions: np.ndarray | None = None,
                 travelled: np.ndarray | None = None, normals: np.ndarray | None = None) -> LoopClosure | None:
    """Match ``scan_points`` (the new keyframe's matching points, sensor frame) against the submaps
    of the nearest earlier keyframes within ``search_radius`` of the new one's estimate and at
    least ``min_travel`` of path behind it; the first match that passes every check is returned.

    ``drift(candidate)`` is the (3, 3) world-frame covariance of the new keyframe's estimate
    relative to the candidate's (from the graph's marginals); a closure whose correction lies
    outside its ``gate_probability`` chi-square gate (3 dof, with the match's own covariance
    added) is refused, and only heading hypotheses inside that gate are tried. Without
    ``drift`` the gate is not applied (any correction, any heading hypothesis). ``positions``
    (n, 2) and ``travelled`` (n,) are the keyframes' positions and path lengths when the caller
    keeps them as arrays (else they are gathered here); ``normals`` (n, 2) are the scan points'
    own normals (sensor frame, (0, 0) for none) for the matcher's normal check."""
    if travelled is None:
        travelled = np.array([kf.travelled for kf in keyframes], float)
    if positions is None:
        positions = np.array([kf.pose[:2] for kf in keyframes], float).reshape(-1, 2)
    idx = np.flatnonzero(new.travelled - travelled >= cfg.min_travel)
    if not idx.size:
        return None
    dist = np.hypot(*(positions[idx] - new.pose[:2]).T)
    radius = cfg.search_radius + cfg.search_growth * since_closure
    order = [int(idx[k]) for k in np.argsort(dist) if dist[k] <= radius]
    gate = chi2_quantile(cfg.gate_probability, 3)
    tried: list[int] = []
    for k in order:
        if len(tried) >= cfg.candidates:
            break
        if any(abs(keyframes[k].key - t) <= cfg.visit_gap for t in tried):
            continue  # the same visit as a candidate already matched: try other visits of the place
        cand = keyframes[k]
        prior = drift(cand) if drift is not None else None
        max_heading = np.inf if prior is None else float(np.sqrt(gate * max(prior[2, 2], 0.0)))
        if not _could_overlap(new, cand, cfg.min_inliers, max_heading):
            continue  # looking away from it (a corridor passed the other way): not a visit to spend a try on
        tried.append(cand.key)
        lo = max(0, cand.key - cfg.submap)
        sub = [kf for kf in keyframes[lo: cand.key + cfg.submap + 1] if new.travelled - kf.travelled >= cfg.min_travel]
        ref = local_map(sub, voxel)
        m = match(scan_points, ref, [new.pose], alignment, max_heading, normals=normals)
        d2 = _distance2(m, new.pose, prior)
        if not _verified(m, cfg, alignment):
            continue
        if d2 > gate:
            continue  # further than the drift since the candidate allows: an aliased place
        return LoopClosure(cand.key, new.key, between(cand.pose, m.pose), m.inliers, m.rms,
                           float(np.hypot(*(m.pose[:2] - new.pose[:2]))),
                           rotate_covariance(m.covariance, -m.pose[2]), d2)  # world -> frame of the new keyframe
    return None


def field_of_view(points: np.ndarray) -> float:
    """The bearing span (rad) of a scan's points (sensor frame): pi for a 180-degree scanner, about
    2 pi for a full turn (the widest gap between neighbouring bearings left out)."""
    p = np.asarray(points, float).reshape(-1, 2)
    if p.shape[0] < 2:
        return 0.0
    b = np.sort(np.arctan2(p[:, 1], p[:, 0]))
    gaps = np.diff(np.append(b, b[0] + 2 * np.pi))
    return float(2 * np.pi - gaps.max())


def shared_view(fov: float, turn: float) -> float:
    """The share of a field of view ``fov`` (rad, centred on the heading) that a second one of the same
    width, turned by ``turn`` rad, also covers (on the circle: a full turn always covers all of it)."""
    d = abs(float(wrap(turn)))
    if fov <= 0.0:
        return 0.0
    return min(1.0, (max(0.0, fov - d) + max(0.0, fov - (2 * np.pi - d))) / fov)


def _could_overlap(new: Keyframe, cand: Keyframe, min_inliers: float, heading_tolerance: float) -> bool:
    """Whether the two keyframes' views can share ``min_inliers`` of their field of view (the
    narrower of the two, :func:`field_of_view`), their headings' difference taken at the least the
    drift allows (``heading_tolerance`` rad less): a closure must explain that share of the scan's
    points, and points outside the candidate's view cannot be explained. A 180-degree scan looking
    back along a corridor the candidate looked down shares its side walls alone: the points that
    fix the axis (door recesses) then alias, and such closures were metres off."""
    fov = min(field_of_view(new.points), field_of_view(cand.points))
    d = abs(float(wrap(new.pose[2] - cand.pose[2])))
    lo = max(0.0, d - heading_tolerance)
    # shared_view is piecewise linear in the turn: its largest value over [lo, d] is at an end or a kink
    turns = [lo, d] + [k for k in (fov, 2 * np.pi - fov) if lo < k < d]
    return max(shared_view(fov, t) for t in turns) >= min_inliers


def _distance2(m: Match, estimate: np.ndarray, prior: np.ndarray | None) -> float:
    """Mahalanobis distance^2 of the match's correction of ``estimate`` against the drift ``prior``
    (world frame) plus the match's own covariance (0 without a prior)."""
    if prior is None:
        return 0.0
    d = m.pose - estimate
    d[2] = wrap(d[2])
    return float(d @ np.linalg.solve(prior + m.covariance, d))


def _verified(m: Match, cfg: LoopClosureConfig, alignment: AlignmentConfig) -> bool:
    """Geometric checks of a closure: enough points explained, small residual, and a position
    fixed in every direction (by the match's geometry: the point-to-line Hessian over the floor
    ``alignment.sigma_point`` squared, before the match's residual variance and the inflation)."""
    if m.inliers < cfg.min_inliers or not m.rms <= cfg.max_rms:
        return False
    cov = np.linalg.inv(m.hessian + 1e-9 * np.eye(3)) * alignment.sigma_point**2
    return bool(np.sqrt(np.linalg.eigvalsh(cov[:2, :2]).max()) <= cfg.max_sigma_xy)
