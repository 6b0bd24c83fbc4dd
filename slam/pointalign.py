"""Fallback heading for scans with too few lines: the same circular correlation of normal-angle
histograms, on point normals of this scan against the previous scan's, each candidate refined by a
few translation-only nearest-neighbour steps and scored by the fraction of points that land on the
previous scan.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .models import wrap
from .prealign import rotation_candidates


def _chord_normals(p: np.ndarray, step: int, max_gap: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normals (p - 2 step, 2) of the chords between the points ``step`` beams before and after
    each inner point of ``p`` (p, 2; at least 2 step + 1 points), the chord lengths (m), and the mask
    of chords short enough to be a surface."""
    d = p[2 * step :] - p[: -2 * step]
    length = np.hypot(d[:, 0], d[:, 1])
    ok = (length > 1e-3) & (length < max_gap)
    n = np.column_stack((d[:, 1], -d[:, 0])) / np.maximum(length, 1e-12)[:, None]
    return n, length, ok


def point_normals(points: np.ndarray, step: int = 2, max_gap: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    """Normal angles (rad, pointing away from the sensor) and weights (m of surface) of the
    points (p, 2) in beam order, from the chord between the neighbours ``step`` beams apart."""
    p = np.asarray(points, float)
    if p.shape[0] < 2 * step + 1:
        return np.zeros(0), np.zeros(0)
    n, length, ok = _chord_normals(p, step, max_gap)
    mid = p[step:-step]
    n = np.where((np.sum(n * mid, axis=1) < 0)[:, None], -n, n)
    return np.arctan2(n[ok, 1], n[ok, 0]), length[ok] / (2 * step)


def align_to_previous(points: np.ndarray, prev_world: np.ndarray, tree: cKDTree, predicted: np.ndarray,
                      reference_heading: float, max_turn: float, tolerance: float = 0.1,
                      max_candidates: int = 4, iterations: int = 4) -> list[tuple[float, np.ndarray]]:
    """Candidate poses (score, pose) of the scan ``points`` (sensor frame) against the previous
    scan's points ``prev_world`` (world frame, indexed by ``tree``), best first. Headings come from
    the normal histograms (plus the predicted and the previous heading); positions from
    ``iterations`` translation-only nearest-neighbour steps from the predicted position."""
    a_scan, w_scan = point_normals(points)
    a_prev, w_prev = point_normals(prev_world - predicted[:2])  # previous scan seen from the prediction
    cands = [float(predicted[2]), float(reference_heading)]
    if a_scan.size and a_prev.size:
        for c in rotation_candidates(a_scan, w_scan, a_prev, w_prev, max_candidates):
            if all(abs(wrap(c - d)) > np.radians(3.0) for d in cands):
                cands.append(float(c))
    out = []
    for phi in cands:
        if abs(wrap(phi - reference_heading)) > max_turn:
            continue
        c, s = np.cos(phi), np.sin(phi)
        rotated = points @ np.array([[c, s], [-s, c]])
        t = np.array(predicted[:2], float)
        for k in range(iterations):
            gate = 0.5 if k == 0 else 0.25
            d, j = tree.query(rotated + t, distance_upper_bound=gate)
            ok = np.isfinite(d)
            if ok.sum() < 5:
                break
            t = t + np.median(prev_world[j[ok]] - (rotated[ok] + t), axis=0)
        d, _ = tree.query(rotated + t, distance_upper_bound=tolerance)
        out.append((float(np.mean(np.isfinite(d))), np.array([t[0], t[1], phi])))
    out.sort(key=lambda r: -r[0])
    return out


def beam_normals(points: np.ndarray, step: int = 2, max_gap: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (p, 2) of points (p, 2) in beam order from the chord between the neighbours
    ``step`` beams apart, and the mask of points whose chord is short enough to be a surface."""
    p = np.asarray(points, float)
    n = np.zeros_like(p)
    ok = np.zeros(p.shape[0], bool)
    if p.shape[0] < 2 * step + 1:
        return n, ok
    n[step:-step], _, ok[step:-step] = _chord_normals(p, step, max_gap)
    return n, ok


def point_to_line_translation(points: np.ndarray, tree: cKDTree, ref: np.ndarray, ref_normals: np.ndarray,
                              start: np.ndarray, tolerance: float, iterations: int = 8) -> tuple[np.ndarray, float, np.ndarray]:
    """Translation (2,) of ``points`` (already rotated into the world frame) onto the reference
    points ``ref`` with normals ``ref_normals`` (indexed by ``tree``), point-to-line least squares
    from ``start``; its score (fraction of the points within ``tolerance`` m of a reference point)
    and the information sum n n^T of the matched normals."""
    t = np.array(start, float)
    for k in range(iterations):
        gate = 0.5 if k < 2 else 2 * tolerance
        d, j = tree.query(points + t, distance_upper_bound=gate)
        ok = np.isfinite(d)
        if ok.sum() < 10:
            break
        n = ref_normals[j[ok]]
        r = np.sum(n * (ref[j[ok]] - points[ok] - t), axis=1)
        A = n.T @ n
        step = np.linalg.solve(A + 1e-3 * ok.sum() * np.eye(2), n.T @ r)
        t = t + step
        if step @ step < 1e-8:
            break
    d, j = tree.query(points + t, distance_upper_bound=tolerance)
    ok = np.isfinite(d)
    n = ref_normals[j[ok]]
    return t, float(np.mean(ok)) if ok.size else 0.0, n.T @ n
