"""Turning the inliers of one candidate line into Line segments (shared by ``hough`` and ``ransac``)."""

from __future__ import annotations

import numpy as np

from ..types import FeatureSet, Lines
from .common import (CornerConfig, Points, build_lines, contiguous_runs, feature_set, fit_groups, fit_moments,
                     point_line_distance, straight_enough, trim_ends)


def refine(pts: Points, cand: np.ndarray, rho: float, alpha: float, tolerances: tuple[float, ...]):
    """Re-select the inliers among candidate positions ``cand`` and refit by least squares, once
    per tolerance (m), shrinking the band around the line. Returns (inlier positions, rho, alpha);
    no inliers where their least-squares moments overflow float64 (points beyond ~1e154 m)."""
    inl = cand
    for tol in tolerances:
        inl = cand[point_line_distance(pts.x[cand], pts.y[cand], rho, alpha) <= tol]
        if inl.size < 2:
            return inl, rho, alpha
        x, y = pts.x[inl], pts.y[inl]
        with np.errstate(over="ignore", invalid="ignore"):  # inf + -inf among the x * y
            sxx, syy, sxy = (x * x).sum(), (y * y).sum(), (x * y).sum()
        if not (np.isfinite(sxx) and np.isfinite(syy) and np.isfinite(sxy)):  # (their sum warned: inf + -inf)
            # points beyond ~1e154 m (valid under range_max 1e308): their moments overflow float64, and the
            # fit gave RuntimeWarnings on stderr; no line, as split_merge, iepf and sensor give none there
            return inl[:0], rho, alpha
        rho, alpha, *_ = fit_moments(float(inl.size), x.sum(), y.sum(), sxx, syy, sxy)
        rho, alpha = float(rho), float(alpha)
    return inl, rho, alpha


def segments_of(pts: Points, inl: np.ndarray, angle_increment: float, lambda_rad: float, sigma: float,
                max_skip: int, min_points: int, min_length: float, runs_z: float = 0.0):
    """Contiguous runs of the inliers ``inl`` with at least ``min_points`` points and ``min_length``
    (m), each fitted by least squares after trimming end points off the line (``trim_ends``, which
    returns them to the pool). Runs that fail the runs test (``straight_enough``) are used up but
    give no line. Returns (used positions, start, end, fit tuple) or None when no run is
    long enough; the fit arrays may then be empty (every run an arc)."""
    offsets = contiguous_runs(pts, inl, angle_increment, lambda_rad, sigma, max_skip)
    counts = np.diff(np.concatenate((offsets, [inl.size])))
    ok = counts >= min_points
    if not ok.any():
        return None
    labels = np.repeat(ok, counts)
    used = inl[labels]
    offs = (np.cumsum(counts[ok]) - counts[ok])
    fit = fit_groups(pts.x[used], pts.y[used], offs)
    sizes = counts[ok]
    for _ in range(2):  # drop end points off the fitted line (a neighbouring small face), refit
        lo, hi = trim_ends(pts.x[used], pts.y[used], offs, fit[0], fit[1], 3.0 * sigma, min_points)
        if np.array_equal(lo, offs) and np.array_equal(hi, offs + sizes - 1):
            break
        sizes = hi - lo + 1
        offs = np.cumsum(sizes) - sizes
        used = used[np.arange(int(sizes.sum())) - np.repeat(offs - lo, sizes)]
        fit = fit_groups(pts.x[used], pts.y[used], offs)
    start, end = used[offs], used[offs + sizes - 1]
    length = np.hypot(pts.x[end] - pts.x[start], pts.y[end] - pts.y[start])
    keep = length >= min_length
    if not keep.any():
        return None
    straight = straight_enough(pts.x[used], pts.y[used], offs, fit[0], fit[1], runs_z, 0.5 * sigma)
    keep &= straight
    return used, start[keep], end[keep], tuple(f[keep] for f in fit[:6])


def collect(pts: Points, starts: list, ends: list, fits: list, sigma: float, corners: CornerConfig, method: str,
            angle_increment: float) -> FeatureSet:
    """The FeatureSet of the segments ``segments_of`` found, one (start, end, fit) per found line
    (lists in the order found): beam-ordered Lines plus the shared corner step."""
    if not starts:
        return feature_set(Lines.empty(), corners, method, angle_increment)
    s, e = np.concatenate(starts), np.concatenate(ends)
    rho, alpha, n, mx, my, along = (np.concatenate(f) for f in zip(*fits))
    lines = build_lines(pts, s, e, rho, alpha, n, mx, my, along, sigma)
    return feature_set(lines, corners, method, angle_increment)
