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
    relative to the candidate's (from the graph: ``loop_closure.drift``); a closure whose correction lies
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
        tried.append(keyframes[k].key)
        cand = keyframes[k]
        lo = max(0, cand.key - cfg.submap)
        sub = [kf for kf in keyframes[lo: cand.key + cfg.submap + 1] if new.travelled - kf.travelled >= cfg.min_travel]
        ref = local_map(sub, voxel)
        prior = drift(cand) if drift is not None else None
        max_heading = np.inf if prior is None else float(np.sqrt(gate * max(prior[2, 2], 0.0)))
        m = match(scan_points, ref, [new.pose], alignment, max_heading, normals=normals)
        d = m.pose - new.pose
        d[2] = wrap(d[2])
        d2 = float(d @ np.linalg.solve(prior + m.covariance, d)) if prior is not None else 0.0
        if not _verified(m, cfg, alignment):
            continue
        if d2 > gate:
            continue  # further than the drift since the candidate allows: an aliased place
        return LoopClosure(cand.key, new.key, between(cand.pose, m.pose), m.inliers, m.rms,
                           float(np.hypot(*(m.pose[:2] - new.pose[:2]))),
                           rotate_covariance(m.covariance, -m.pose[2]), d2)  # world -> frame of the new keyframe
    return None


def _verified(m: Match, cfg: LoopClosureConfig, alignment: AlignmentConfig) -> bool:
    """Geometric checks of a closure: enough points explained, small residual, and a position
    fixed in every direction (by the match's geometry: the point-to-line Hessian over the floor
    ``alignment.sigma_point`` squared, before the match's residual variance and the inflation)."""
    if m.inliers < cfg.min_inliers or not m.rms <= cfg.max_rms:
        return False
    cov = np.linalg.inv(m.hessian + 1e-9 * np.eye(3)) * alignment.sigma_point**2
    return bool(np.sqrt(np.linalg.eigvalsh(cov[:2, :2]).max()) <= cfg.max_sigma_xy)
