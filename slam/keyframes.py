"""Keyframe records, the local map built from them, and the loop-closure search over them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .config import AlignmentConfig, LoopClosureConfig
from .geometry import between, to_world
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


@dataclass(frozen=True)
class LoopClosure:
    """A verified closure: keyframe ``new`` seen from the pose ``relative`` in the frame of ``old``."""

    old: int
    new: int
    relative: np.ndarray
    inliers: float
    rms: float
    correction: float  # m, how far the closure moves the new keyframe from its estimate


def local_map(keyframes: list[Keyframe], voxel: float) -> Reference:
    """The points and normals of ``keyframes`` in the world frame, thinned to ``voxel`` m cells
    (newest keyframe first, so its points win a cell)."""
    pts, nrm = [], []
    for kf in reversed(keyframes):
        pts.append(to_world(kf.pose, kf.points))
        c, s = np.cos(kf.pose[2]), np.sin(kf.pose[2])
        nrm.append(kf.normals @ np.array([[c, s], [-s, c]]))
    return make_reference(np.concatenate(pts), np.concatenate(nrm), voxel)


def find_closure(new: Keyframe, scan_points: np.ndarray, keyframes: list[Keyframe], cfg: LoopClosureConfig,
                 alignment: AlignmentConfig, voxel: float, since_closure: float = 0.0) -> LoopClosure | None:
    """Match ``scan_points`` (the new keyframe's matching points, sensor frame) against the submaps
    of the nearest earlier keyframes within ``search_radius`` of the new one's estimate and at
    least ``min_travel`` of path behind it; the first match that passes every check is returned."""
    old = [kf for kf in keyframes if new.travelled - kf.travelled >= cfg.min_travel]
    if not old:
        return None
    xy = np.array([kf.pose[:2] for kf in old])
    dist = np.hypot(*(xy - new.pose[:2]).T)
    radius = cfg.search_radius + cfg.search_growth * since_closure
    order = [int(k) for k in np.argsort(dist) if dist[k] <= radius]
    tried: list[int] = []
    for k in order:
        if len(tried) >= cfg.candidates:
            break
        if any(abs(old[k].key - t) <= cfg.visit_gap for t in tried):
            continue  # the same visit as a candidate already matched: try other visits of the place
        tried.append(old[k].key)
        cand = old[k]
        lo = max(0, cand.key - cfg.submap)
        sub = [kf for kf in keyframes[lo: cand.key + cfg.submap + 1] if new.travelled - kf.travelled >= cfg.min_travel]
        ref = local_map(sub, voxel)
        m = match(scan_points, ref, [new.pose], alignment)
        if not _verified(m, cfg, alignment.covariance_inflation):
            continue
        return LoopClosure(cand.key, new.key, between(cand.pose, m.pose), m.inliers, m.rms,
                           float(np.hypot(*(m.pose[:2] - new.pose[:2]))))
    return None


def _verified(m: Match, cfg: LoopClosureConfig, inflation: float) -> bool:
    """Geometric checks of a closure: enough points explained, small residual, and a position
    fixed in every direction (by the match's geometry: the covariance before inflation)."""
    if m.inliers < cfg.min_inliers or not m.rms <= cfg.max_rms:
        return False
    cov = m.covariance / inflation
    return bool(np.sqrt(np.linalg.eigvalsh(cov[:2, :2]).max()) <= cfg.max_sigma_xy)
