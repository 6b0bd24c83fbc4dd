"""Keyframe records, the local map built from them, and the loop-closure search over them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .config import AlignmentConfig, LoopClosureConfig
from .geometry import between, rotate_covariance, to_world
from .models import chi2_quantile, wrap
from .correlative import fit, make_field, search
from .icp import Match, Reference, make_reference, match, refine

#: poses this far apart (m, rad) are distinct: the search's candidates, and the rivals of an ambiguous step
DISTINCT_XY = 0.3
DISTINCT_THETA = 0.1

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
        closure = _accepted(new, cand, m, prior, gate, cfg, alignment)
        if closure is not None:
            return closure
    return None


def find_closure_window(new: Keyframe, scan_points: np.ndarray, keyframes: list[Keyframe], cfg: LoopClosureConfig,
                        alignment: AlignmentConfig, voxel: float, relative: Callable[[Keyframe], np.ndarray],
                        positions: np.ndarray, travelled: np.ndarray,
                        normals: np.ndarray | None = None) -> LoopClosure | None:
    """A closure found by a correlative search over the window the relative uncertainty allows.

    ``relative(candidate)`` is the (3, 3) world-frame covariance of the new keyframe's estimate
    relative to the candidate's (the joint marginal: the drift of the path between them, less
    what the closures in between fixed); times ``window_inflation`` it is the drift ``P``.
    Candidates are the earlier keyframes at least ``min_travel`` of path behind, looked at
    nearest first; one is searched when its estimate lies within ``search_radius`` plus its own
    window of the new one's and its heading within a quarter turn plus the window's heading of it
    (beyond, a 180-degree scan shares less than half its view: passes the other way down a
    corridor share only the side walls, whose door recesses alias), at most one per visit
    (``visit_gap``) and ``candidates`` in all; one whose ``P`` is not finite is passed over (no
    window). ``loop_closure.drift`` and ``drift_inflation`` are not used here. The window is ``sqrt(chi2(gate_probability, 3))`` std of ``P`` either
    side (at least the ICP's reach and ``DISTINCT_THETA``, at most ``window_xy`` and
    ``window_theta``); every pose of it (``alignment.search_step`` m, ``search_step_theta`` rad
    apart) scores the likelihood field of the candidate's visit: its keyframes within the window
    and ``submap`` either side of them (:mod:`slam.correlative`), the best
    ``search_candidates`` distinct poses are refined by the ICP held near each (a prior of the
    window's step) and ranked by their fit. The best is a closure only when it passes
    :func:`_verified`, its correction lies inside the gate of ``P`` plus the match's covariance,
    and no distinct pose (``DISTINCT_XY`` m or ``DISTINCT_THETA`` rad away) fits within
    ``alignment.fit_margin`` of it (a door's spacing along a corridor, a corridor's axis)."""
    idx = np.flatnonzero(new.travelled - travelled >= cfg.min_travel)
    if not idx.size:
        return None
    gate = chi2_quantile(cfg.gate_probability, 3)
    dist = np.hypot(*(positions[idx] - new.pose[:2]).T)
    turned = np.full(idx.size, np.inf)  # rad between the headings, for the keyframes near enough
    near = np.flatnonzero(dist <= cfg.search_radius + cfg.window_xy)
    turned[near] = np.abs(wrap(new.pose[2] - np.array([keyframes[int(k)].pose[2] for k in idx[near]])))
    order = [int(idx[k]) for k in np.argsort(dist) if turned[k] <= 0.5 * np.pi + cfg.window_theta]
    hold = np.diag([alignment.search_step**-2, alignment.search_step**-2, alignment.search_step_theta**-2])
    min_cos = float(np.cos(alignment.normal_agreement))
    pts = scan_points[:: max(1, -(-scan_points.shape[0] // alignment.search_points))]
    tried: list[int] = []
    for k in order:
        if len(tried) >= cfg.candidates:
            break
        if any(abs(keyframes[k].key - t) <= cfg.visit_gap for t in tried):
            continue
        cand = keyframes[k]
        P = cfg.window_inflation * relative(cand)
        if not np.isfinite(P).all():
            continue  # no window to search (a NaN or infinite covariance from the graph)
        sxy = float(np.sqrt(max(np.linalg.eigvalsh(P[:2, :2]).max(), 0.0)))
        half_xy = min(max(np.sqrt(gate) * sxy, alignment.max_correspondence), cfg.window_xy)
        half_th = min(max(np.sqrt(gate * max(P[2, 2], 0.0)), DISTINCT_THETA), cfg.window_theta)
        if dist[np.searchsorted(idx, k)] > cfg.search_radius + half_xy or \
                turned[np.searchsorted(idx, k)] > 0.5 * np.pi + half_th:
            continue  # the drift cannot bring it within view of the new keyframe
        tried.append(cand.key)
        # the visit's keyframes within the window (the places the new keyframe may be), and the
        # ``submap`` keyframes either side of them: the scan is matched to what was seen there
        visit = np.arange(max(0, cand.key - cfg.visit_gap), min(len(keyframes), cand.key + cfg.visit_gap + 1))
        inside = visit[np.all(np.abs(positions[visit] - new.pose[:2]) <= half_xy + DISTINCT_XY,
                              axis=1)]
        lo = max(0, int(min(inside.min(initial=cand.key), cand.key)) - cfg.submap)
        hi = int(max(inside.max(initial=cand.key), cand.key)) + cfg.submap + 1
        sub = [kf for kf in keyframes[lo:hi] if new.travelled - kf.travelled >= cfg.min_travel]
        ref = local_map(sub, voxel)
        field = make_field(ref.points, alignment.search_resolution, alignment.search_sigma, new.pose,
                           alignment.max_range + half_xy)
        peaks = search(pts, field, new.pose, half_xy, half_th, alignment.search_step, alignment.search_step_theta,
                       alignment.search_candidates, DISTINCT_XY, DISTINCT_THETA, peaks=True)
        results = [refine(scan_points, ref, c.pose, alignment, prior=hold, normals=normals) for c in peaks]
        if not results:
            continue
        fits = [fit(scan_points, normals, ref, r.pose, alignment.fine_correspondence, alignment.fit_sigma, min_cos)
                for r in results]
        b = int(np.argmax(fits))
        m = results[b]
        if any(i != b and fits[i] >= fits[b] - alignment.fit_margin
               and (np.hypot(*(r.pose[:2] - m.pose[:2])) > DISTINCT_XY or abs(wrap(r.pose[2] - m.pose[2])) > DISTINCT_THETA)
               for i, r in enumerate(results)):
            continue  # a distinct pose fits as well: aliased
        closure = _accepted(new, cand, m, P, gate, cfg, alignment)
        if closure is not None:
            return closure
    return None


def _accepted(new: Keyframe, cand: Keyframe, m: Match, drift: np.ndarray | None, gate: float,
              cfg: LoopClosureConfig, alignment: AlignmentConfig) -> LoopClosure | None:
    """The closure of ``new`` to ``cand`` by the match ``m`` (world frame) when it passes
    :func:`_verified` and its correction lies inside the chi-square ``gate`` of ``drift`` (the
    world-frame covariance the graph allows) plus the match's covariance; no ``drift``: no gate.
    Beyond the gate: an aliased place. The closure's covariance is in the new keyframe's frame."""
    if not _verified(m, cfg, alignment):
        return None
    d = m.pose - new.pose
    d[2] = wrap(d[2])
    d2 = float(d @ np.linalg.solve(drift + m.covariance, d)) if drift is not None else 0.0
    if d2 > gate:
        return None
    return LoopClosure(cand.key, new.key, between(cand.pose, m.pose), m.inliers, m.rms,
                       float(np.hypot(*(m.pose[:2] - new.pose[:2]))),
                       rotate_covariance(m.covariance, -m.pose[2]), d2)  # world -> frame of the new keyframe


def _verified(m: Match, cfg: LoopClosureConfig, alignment: AlignmentConfig) -> bool:
    """Geometric checks of a closure: enough points explained, small residual, and a position
    fixed in every direction (by the match's geometry: the point-to-line Hessian over the floor
    ``alignment.sigma_point`` squared, before the match's residual variance and the inflation)."""
    if m.inliers < cfg.min_inliers or not m.rms <= cfg.max_rms:
        return False
    cov = np.linalg.inv(m.hessian + 1e-9 * np.eye(3)) * alignment.sigma_point**2
    return bool(np.sqrt(np.linalg.eigvalsh(cov[:2, :2]).max()) <= cfg.max_sigma_xy)
