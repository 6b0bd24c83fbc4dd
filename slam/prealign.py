"""Rotation (then translation) between a scan's lines and the map's lines, without an initial guess.

The heading: circular cross-correlation (FFT) of the length-weighted histograms of line normal
angles, the scan's in the sensor frame against the map's in the world frame (each map line oriented
to face the predicted position). Its peaks are candidate headings whatever the turn since the last
scan. For each candidate (plus the predicted heading) the translation follows by weighted least
squares on the line distances of paired lines; the candidate explaining the most line length wins.
"""

from __future__ import annotations

from dataclasses import dataclass

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
    """Weighted least squares for the position given heading ``phi``; returns (p, phi, matched length)."""
    p = np.array(p0, float)
    matched = 0.0
    for tol in trans_tols:
        theta_i = scan_alpha + phi
        dang = wrap(map_theta[None, :] - theta_i[:, None])  # (m, L)
        r = map_R[None, :] - scan_rho[:, None] - (np.cos(map_theta) * p[0] + np.sin(map_theta) * p[1])[None, :]
        ok_pair = np.abs(dang) < angle_tol
        if scan_ends is not None and map_ends is not None:
            ok_pair &= _overlaps(scan_ends, map_ends, np.array([p[0], p[1], phi]), extent_margin + tol)
        cost = np.where(ok_pair, np.abs(r), np.inf)
        j = np.argmin(cost, axis=1)
        ok = cost[np.arange(len(j)), j] < tol
        if ok.sum() == 0:
            return p, phi, 0.0
        jj, w = j[ok], scan_w[ok]
        A = np.column_stack((np.cos(map_theta[jj]), np.sin(map_theta[jj])))
        b = r[np.nonzero(ok)[0], jj]
        N = A.T @ (A * w[:, None]) + 1e-3 * np.eye(2)  # regularised: a corridor fixes one direction only
        p = p + np.linalg.solve(N, A.T @ (w * b))
        phi = wrap(phi + np.sum(w * dang[np.nonzero(ok)[0], jj]) / np.sum(w))
        matched = float(w.sum())
    return p, phi, matched


def align(scan_rho: np.ndarray, scan_alpha: np.ndarray, scan_len: np.ndarray,
          map_R: np.ndarray, map_theta: np.ndarray, map_len: np.ndarray, predicted: np.ndarray,
          angle_tol: float = np.radians(6.0), trans_tols: tuple[float, ...] = (1.0, 0.5, 0.2, 0.1),
          max_candidates: int = 4, prefer_margin: float = 0.1, trans_scale: float = 0.5,
          rot_scale: float = np.pi / 2, scan_ends: np.ndarray | None = None,
          map_ends: np.ndarray | None = None, extent_margin: float = 0.5) -> Alignment | None:
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
    cands = list(rotation_candidates(scan_alpha, w_scan, th, np.minimum(map_len, 5.0), max_candidates))
    cands.append(float(predicted[2]))
    results = []
    for phi in cands:
        p, phi_r, m = _translation(scan_rho, scan_alpha, w_scan, R, th, phi, p0, angle_tol, trans_tols,
                                   scan_ends, map_ends, extent_margin)
        jump = np.hypot(*(p - p0)) / trans_scale
        closeness = jump + abs(wrap(phi_r - predicted[2])) / rot_scale
        results.append((m * np.exp(-0.5 * jump**2), closeness, p, phi_r, m))
    best_m = max(r[0] for r in results)
    near = [r for r in results if r[0] >= (1.0 - prefer_margin) * best_m]
    _, _, p, phi, m = min(near, key=lambda r: r[1])
    return Alignment(np.array([p[0], p[1], phi]), float(m), float(w_scan.sum()), len(cands))
