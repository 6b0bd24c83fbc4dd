"""Rotation (then translation) between a scan's lines and the map's lines, without an initial guess.

The heading: circular cross-correlation (FFT) of the length-weighted histograms of line normal
angles, the scan's in the sensor frame against the map's in the world frame (each map line oriented
to face the predicted position). Its peaks are candidate headings whatever the turn since the last
scan. For each candidate (plus the predicted heading) the translation follows by weighted least
squares on the line distances of paired lines; the candidate explaining the most line length wins.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .models import wrap

N_BINS = 360  # 1 degree bins


@dataclass(frozen=True)
class Alignment:
    """A scan-to-map pose found without an initial guess."""

    pose: np.ndarray  # (3,) X m, Y m, Phi rad in the world frame
    matched_length: float  # m of scan line length explained by map lines
    total_length: float  # m of scan line length
    candidates: int  # headings tried
    verify_score: float = float("nan")  # fraction of points confirmed by the verifier (nan: none)
    information: np.ndarray = field(default_factory=lambda: np.zeros((2, 2)))  # sum n n^T of matched normals


def angle_histogram(angles: np.ndarray, weights: np.ndarray, sigma_deg: float = 2.0) -> np.ndarray:
    """Length-weighted circular histogram of angles (rad) in 1-degree bins, smoothed by a
    wrapped Gaussian of ``sigma_deg``."""
    pos = np.mod(np.degrees(angles), 360.0)
    lo = np.floor(pos)
    frac = pos - lo
    lo = lo.astype(int) % N_BINS
    h = np.bincount(lo, weights=weights * (1 - frac), minlength=N_BINS).astype(float)
    h += np.bincount((lo + 1) % N_BINS, weights=weights * frac, minlength=N_BINS)  # linear splatting
    k = np.arange(N_BINS)
    k = np.minimum(k, N_BINS - k)
    kernel = np.exp(-0.5 * (k / sigma_deg) ** 2)
    return np.real(np.fft.ifft(np.fft.fft(h) * np.fft.fft(kernel)))


def rotation_candidates(scan_alpha: np.ndarray, scan_w: np.ndarray, map_theta: np.ndarray, map_w: np.ndarray,
                        max_candidates: int = 4, min_ratio: float = 0.4) -> np.ndarray:
    """Headings Phi (rad) such that ``scan_alpha + Phi`` matches ``map_theta``: the highest peaks
    of the circular correlation of the two histograms, refined below the bin size."""
    hs = angle_histogram(scan_alpha, scan_w)
    hm = angle_histogram(map_theta, map_w)
    corr = np.real(np.fft.ifft(np.conj(np.fft.fft(hs)) * np.fft.fft(hm)))  # corr[k] = sum_b hs[b] hm[b+k]
    left, right = np.roll(corr, 1), np.roll(corr, -1)
    peaks = np.nonzero((corr >= left) & (corr > right) & (corr >= min_ratio * corr.max()))[0]
    peaks = peaks[np.argsort(corr[peaks])[::-1]][:max_candidates]
    out = []
    for p in peaks:
        a, b, c = left[p], corr[p], right[p]
        denom = a - 2 * b + c
        off = 0.5 * (a - c) / denom if denom < 0 else 0.0
        out.append(wrap(np.radians(p + off)))
    return np.array(out)


def _overlaps(scan_ends: np.ndarray, map_ends: np.ndarray, pose: np.ndarray, margin: float) -> np.ndarray:
    """(m, L) mask: scan segment (sensor frame) moved by ``pose`` overlaps map segment (world frame)
    along the map segment's direction, within ``margin`` m."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    a = np.column_stack((pose[0] + c * scan_ends[:, 0] - s * scan_ends[:, 1], pose[1] + s * scan_ends[:, 0] + c * scan_ends[:, 1]))
    b = np.column_stack((pose[0] + c * scan_ends[:, 2] - s * scan_ends[:, 3], pose[1] + s * scan_ends[:, 2] + c * scan_ends[:, 3]))
    d = map_ends[:, 2:] - map_ends[:, :2]
    length = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    d = d / length[:, None]
    origin = np.sum(map_ends[:, :2] * d, axis=1)
    ta, tb = a @ d.T - origin[None, :], b @ d.T - origin[None, :]
    lo, hi = np.minimum(ta, tb), np.maximum(ta, tb)
    return (hi >= -margin) & (lo <= length[None, :] + margin)


def _translation(scan_rho, scan_alpha, scan_w, map_R, map_theta, phi, p0, angle_tol, trans_tols,
                 scan_ends=None, map_ends=None, extent_margin=0.5):
    """Weighted least squares for the position given heading ``phi``; returns (p, phi, matched
    length, information (2x2) = sum of n n^T over the matched lines' world normals)."""
    p = np.array(p0, float)
    matched = 0.0
    info = np.zeros((2, 2))
    cos_m, sin_m = np.cos(map_theta), np.sin(map_theta)
    base = map_R[None, :] - scan_rho[:, None]
    for tol in trans_tols:
        theta_i = scan_alpha + phi
        dang = wrap(map_theta[None, :] - theta_i[:, None])  # (m, L)
        r = base - (cos_m * p[0] + sin_m * p[1])[None, :]
        ok_pair = np.abs(dang) < angle_tol
        if scan_ends is not None and map_ends is not None:
            ok_pair &= _overlaps(scan_ends, map_ends, np.array([p[0], p[1], phi]), extent_margin + tol)
        cost = np.where(ok_pair, np.abs(r), np.inf)
        j = np.argmin(cost, axis=1)
        ok = cost[np.arange(len(j)), j] < tol
        if ok.sum() == 0:
            return p, phi, 0.0, np.zeros((2, 2))
        jj, w = j[ok], scan_w[ok]
        A = np.column_stack((cos_m[jj], sin_m[jj]))
        b = r[np.nonzero(ok)[0], jj]
        N = A.T @ (A * w[:, None]) + 1e-3 * np.eye(2)  # regularised: a corridor fixes one direction only
        p = p + np.linalg.solve(N, A.T @ (w * b))
        phi = wrap(phi + np.sum(w * dang[np.nonzero(ok)[0], jj]) / np.sum(w))
        matched = float(w.sum())
        info = A.T @ A
    return p, phi, matched, info


def align(scan_rho: np.ndarray, scan_alpha: np.ndarray, scan_len: np.ndarray,
          map_R: np.ndarray, map_theta: np.ndarray, map_len: np.ndarray, predicted: np.ndarray,
          angle_tol: float = np.radians(6.0), trans_tols: tuple[float, ...] = (1.0, 0.5, 0.2, 0.1),
          max_candidates: int = 4, prefer_margin: float = 0.1, trans_scale: float = 0.5,
          rot_scale: float = np.pi / 2, scan_ends: np.ndarray | None = None,
          map_ends: np.ndarray | None = None, extent_margin: float = 0.5,
          reference_heading: float | None = None, max_turn: float = np.inf,
          near_tol: float = np.radians(10.0), near_accept: float = 0.6, far_factor: float = 1.5,
          verify: Callable[[np.ndarray], float] | None = None, verify_margin: float = 0.1,
          early_accept: float = 0.8) -> Alignment | None:
    """Pose of the scan in the map frame, without using the predicted heading to find it.

    Args:
        scan_rho, scan_alpha, scan_len: the scan's lines (sensor frame, m, rad, m).
        map_R, map_theta, map_len: map lines (world frame), R >= 0 or signed; each is tried in the
            orientation that faces ``predicted``.
        predicted: (3,) predicted pose; its position seeds the translation and its heading is one
            more candidate. A candidate scores its matched line length times
            ``exp(-0.5 (|dp| / trans_scale)^2)``: a fast turn is plausible, a jump in position is
            not. Among candidates within ``prefer_margin`` of the best score, the one closest to
            the prediction (``|dp| / trans_scale + |dphi| / rot_scale``) wins.
        scan_ends, map_ends: optional segment endpoints (m, 4) sensor frame and (L, 4) world frame
            in the map lines' original orientation order; a pairing then also needs the segments
            to overlap within ``extent_margin`` m.
        reference_heading, max_turn: headings more than ``max_turn`` rad from the reference (the
            previous scan's heading) are physically out of reach and not considered; this removes
            the 180-degree ambiguity of a corridor, which looks the same both ways.
        near_tol, near_accept, far_factor: the prediction comes first: the best candidate within
            ``near_tol`` of the predicted heading is taken when it explains ``near_accept`` of
            the scan's line length; a candidate further away replaces it only when it scores
            ``far_factor`` times better (a rectilinear building matches itself every 90 deg).
        verify, verify_margin: optional independent check ``verify(pose) -> score in [0, 1]``
            (e.g. the fraction of scan points that land on the previous scan's points). With it,
            candidates are ranked by that score instead, and one far from the prediction must
            beat the best near one by ``verify_margin``.
        early_accept: when the predicted heading alone explains this fraction of the line length
            (and of the verifier's points) with a small position change, it is taken at once.

    Returns:
        The best Alignment, or None when there are no lines to align.
    """
    if scan_rho.size == 0 or map_R.size == 0:
        return None
    p0 = np.asarray(predicted[:2], float)
    signed = map_R - (np.cos(map_theta) * p0[0] + np.sin(map_theta) * p0[1])
    flip = signed < 0
    R = np.where(flip, -map_R, map_R)
    th = wrap(np.where(flip, map_theta + np.pi, map_theta))
    w_scan = np.minimum(scan_len, 5.0)
    total = float(w_scan.sum())
    peaks = list(rotation_candidates(scan_alpha, w_scan, th, np.minimum(map_len, 5.0), max_candidates))
    cands = [float(predicted[2])]  # the prediction first: most scans need nothing else
    if reference_heading is not None:
        cands.append(float(reference_heading))  # no turn at all
    for c in peaks:  # distinct histogram peaks
        if all(abs(wrap(c - d)) > 0.5 * angle_tol for d in cands):
            cands.append(c)
    if reference_heading is not None and np.isfinite(max_turn):
        cands = [c for c in cands if abs(wrap(c - reference_heading)) <= max_turn + angle_tol]
    results = []
    for k, phi in enumerate(cands):
        p, phi_r, m, info = _translation(scan_rho, scan_alpha, w_scan, R, th, phi, p0, angle_tol, trans_tols,
                                         scan_ends, map_ends, extent_margin)
        if k == 0 and m >= early_accept * total and np.hypot(*(p - p0)) < 0.5 * trans_scale and (
                verify is None or verify(np.array([p[0], p[1], phi_r])) >= early_accept):
            # the prediction explains the scan: no need to look further (the common case)
            return Alignment(np.array([p[0], p[1], phi_r]), float(m), total, 1, float("nan"), info)
        if reference_heading is not None and abs(wrap(phi_r - reference_heading)) > max_turn:
            continue
        jump = np.hypot(*(p - p0)) / trans_scale
        closeness = jump + abs(wrap(phi_r - predicted[2])) / rot_scale
        results.append(_Candidate(m * np.exp(-0.5 * jump**2), closeness, np.array([p[0], p[1], phi_r]), m, info))
    if not results:
        return None
    if verify is not None:
        for r in results:
            r.score = verify(r.pose)
        margin = verify_margin
    else:
        margin = None
    is_near = [abs(wrap(r.pose[2] - predicted[2])) <= near_tol for r in results]
    best_near = _pick([r for r, n in zip(results, is_near) if n], prefer_margin)
    best_far = _pick([r for r, n in zip(results, is_near) if not n], prefer_margin)
    if margin is not None:  # verified scores: a far candidate must beat the near one by the margin
        take_near = best_near is not None and (best_far is None or best_far.score <= best_near.score + margin)
    else:
        take_near = best_near is not None and (best_near.score >= near_accept * total or best_far is None
                                               or best_far.score < far_factor * best_near.score)
    chosen = best_near if take_near else best_far
    if chosen is None:
        return None
    return Alignment(chosen.pose, float(chosen.matched), total, len(cands),
                     float(chosen.score) if verify is not None else float("nan"), chosen.info)


@dataclass
class _Candidate:
    score: float  # matched length damped by the position jump, or the verifier's score
    closeness: float  # to the prediction: |dp| / trans_scale + |dphi| / rot_scale
    pose: np.ndarray
    matched: float
    info: np.ndarray


def _pick(results: list[_Candidate], prefer_margin: float) -> _Candidate | None:
    """The candidate closest to the prediction among those within ``prefer_margin`` of the best."""
    if not results:
        return None
    best = max(r.score for r in results)
    return min((r for r in results if r.score >= (1.0 - prefer_margin) * best), key=lambda r: r.closeness)
