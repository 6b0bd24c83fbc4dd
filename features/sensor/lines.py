"""Line extraction in sensor coordinates: AD runs -> Log-Hough band search -> weighted refinement.

Every stage works on all candidate runs of a scan at once (beams stacked with a run id); the only
Python loops run over the few accepted lines (merging neighbours, building the output).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .config import SensorMethodConfig
from .hough import band_search
from .refine import gauss_newton, range_residuals
from .signals import BeamSignals, wrap


class LineTable(NamedTuple):
    """Accepted lines, sorted by first beam (all arrays of length L, cov (L, 2, 2))."""

    rho: np.ndarray
    alpha: np.ndarray
    cov: np.ndarray
    first: np.ndarray
    last: np.ndarray
    n_points: np.ndarray


EMPTY = LineTable(*(np.empty(0) for _ in range(2)), np.empty((0, 2, 2)), *(np.empty(0, int) for _ in range(3)))


def candidate_runs(sig: BeamSignals, k: int, cfg: SensorMethodConfig) -> tuple[np.ndarray, np.ndarray]:
    """First centre and last centre of each run of beams whose window passes the AD test (eq. 4,
    threshold scaled by the AD noise at that beam) and holds no slope break (|psi| large)."""
    n = sig.AD.size
    with np.errstate(invalid="ignore"):
        ok = np.abs(sig.AD - sig.ad_line) <= cfg.ad_tau * sig.AD_sigma
        big = np.abs(sig.psi) > np.maximum(cfg.psi_split, cfg.psi_tau * sig.psi_sigma)
    if big.any():
        # a slope break between the windows at i and i+k peaks near i + k/2: drop the centres
        # whose windows reach it (those within k), as the AD test does at sharp corners
        mag = np.where(big, np.abs(sig.psi), 0.0)
        peak = big.copy()
        peak[1:] &= mag[1:] >= mag[:-1]
        peak[:-1] &= mag[:-1] >= mag[1:]
        hit = np.zeros(n, np.int8)
        hit[np.minimum(np.flatnonzero(peak) + k // 2, n - 1)] = 1
        ok &= np.convolve(hit, np.ones(2 * k + 1, np.int8), "same") == 0  # n >= 2k+1 here
    edges = np.diff(ok.view(np.int8), prepend=np.int8(0), append=np.int8(0))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1


def stack_spans(first: np.ndarray, last: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Beam indices of the spans [first, last] stacked end to end, their run ids, row starts, counts."""
    counts = last - first + 1
    starts = np.cumsum(counts) - counts
    total = int(counts.sum())
    run_id = np.repeat(np.arange(first.size), counts)
    beam = np.arange(total) + np.repeat(first - starts, counts)
    return beam, run_id, starts, counts


def fit_spans(
    first: np.ndarray,
    last: np.ndarray,
    rho: np.ndarray,
    alpha: np.ndarray,
    inlier0: np.ndarray | None,
    ranges: np.ndarray,
    bearings: np.ndarray,
    valid: np.ndarray,
    cfg: SensorMethodConfig,
    stacked: tuple | None = None,
) -> tuple[LineTable, np.ndarray]:
    """Refine (rho, alpha) of lines over the beam spans [first, last] from a starting estimate by
    two Gauss-Newton steps, re-selecting inliers (|range residual| <= inlier_tau sigma_r) between
    them. Returns the table of lines (unfiltered) and a mask of the lines that pass the checks."""
    beam, run_id, starts, counts = stacked if stacked is not None else stack_spans(first, last)
    d = ranges[beam]
    b = bearings[beam]
    ok = valid[beam]
    sigma = cfg.sigma_r
    mask = ok if inlier0 is None else (inlier0 & ok)
    rho, alpha, _ = gauss_newton(d, b, run_id, starts, mask, rho, alpha, sigma)
    with np.errstate(invalid="ignore"):
        inl = ok & (np.abs(range_residuals(d, b, run_id, rho, alpha, sigma)) <= cfg.inlier_tau)
    rho, alpha, cov = gauss_newton(d, b, run_id, starts, inl, rho, alpha, sigma)
    with np.errstate(invalid="ignore"):
        z = range_residuals(d, b, run_id, rho, alpha, sigma)
        inl = ok & (np.abs(z) <= cfg.inlier_tau)
    # curvature: t-statistic of the residuals against a parabola in the beam index, centred on
    # the inliers (orthogonal to the constant and slope the fit absorbs); ~N(0, 1) on a line
    w_in = inl.astype(float)
    zi = np.where(inl, z, 0.0)
    t = (beam - beam[starts][run_id]).astype(float)
    t2 = t * t
    stats = np.add.reduceat(np.stack((w_in, zi * zi, w_in * t, w_in * t2, t2 * t2 * w_in, t * t2 * w_in)), starts, axis=1)
    n_in = stats[0].astype(np.int64)
    n_f = np.maximum(stats[0], 1.0)
    chi2 = stats[1] / np.maximum(n_in - 2, 1)
    # parabola q = t^2 - a - b t fitted out against 1 and t over the inliers (weighted normal eqs)
    m1, m2, m4, m3 = stats[2] / n_f, stats[3] / n_f, stats[4] / n_f, stats[5] / n_f
    var_t = np.maximum(m2 - m1 * m1, 1e-12)
    b_lin = (m3 - m1 * m2) / var_t
    a_lin = m2 - b_lin * m1
    qq = t2 - a_lin[run_id] - b_lin[run_id] * t
    cs = np.add.reduceat(np.stack((zi * qq, w_in * qq * qq)), starts, axis=1)
    curvature = np.abs(cs[0]) / np.sqrt(np.maximum(cs[1], 1e-300))
    big = np.iinfo(np.int64).max
    first_in = np.minimum.reduceat(np.where(inl, beam, big), starts)
    last_in = np.maximum.reduceat(np.where(inl, beam, -1), starts)
    good = (
        (n_in >= cfg.min_points)
        & (n_in >= cfg.min_inlier_fraction * counts)
        & (chi2 <= cfg.max_chi2)
        & (curvature <= cfg.curvature_tau)
        & np.isfinite(rho)
        & np.isfinite(alpha)
        & np.isfinite(cov).all(axis=(1, 2))
    )
    # normal form with rho >= 0, alpha in (-pi, pi]
    neg = rho < 0
    rho = np.where(neg, -rho, rho)
    alpha = wrap(np.where(neg, alpha + np.pi, alpha))
    if neg.any():
        cov[neg, 0, 1] *= -1.0
        cov[neg, 1, 0] *= -1.0
    return LineTable(rho, alpha, cov, first_in, last_in, n_in), good


def find_lines(
    sig: BeamSignals,
    ranges: np.ndarray,
    bearings: np.ndarray,
    angle_min: float,
    increment: float,
    cfg: SensorMethodConfig,
) -> LineTable:
    """Lines of one scan, before merging: AD runs, Log-Hough band search, weighted refinement."""
    k = cfg.k
    c0, c1 = candidate_runs(sig, k, cfg)
    if c0.size == 0:
        return EMPTY
    first, last = c0 - k, c1 + k
    long_enough = last - first + 1 >= cfg.min_points
    if not long_enough.all():
        c0, c1, first, last = c0[long_enough], c1[long_enough], first[long_enough], last[long_enough]
        if c0.size == 0:
            return EMPTY
    beam, run_id, starts, counts = stack_spans(first, last)
    # slope estimate of each run: circular mean of theta over its centres, and its std
    theta = np.where(np.isfinite(sig.theta), sig.theta, 0.0)
    cums = np.cumsum(np.stack((np.cos(theta), np.sin(theta), np.nan_to_num(sig.theta_sigma) ** 2)), axis=1)
    cums = np.concatenate((np.zeros((3, 1)), cums), axis=1)
    sums = cums[:, c1 + 1] - cums[:, c0]
    n_c = c1 - c0 + 1
    centre = np.arctan2(sums[1], sums[0])
    centre_sigma = np.sqrt(sums[2] / n_c / (1.0 + n_c / (2 * k + 1)))
    half_width = np.clip(cfg.band_tau * centre_sigma, cfg.band_min, 0.5)
    # log-range window of a peak: range noise at the nearest beam + the spread that an angle error
    # of half an angle step causes over the run (d log p / d a = -tan(a - b))
    d = ranges[beam]
    with np.errstate(divide="ignore", invalid="ignore"):
        log_d = np.log(d)
        d_min = np.minimum.reduceat(d, starts)
        tan_span = np.abs(
            np.clip(np.tan(bearings[last] - centre), -20, 20) - np.clip(np.tan(bearings[first] - centre), -20, 20)
        )
        h = max((cfg.hough_angles - 1) // 2, 1)
        angle_step = np.maximum(half_width / h, increment / cfg.hough_subdiv)
        bin_half = cfg.bin_tau * cfg.sigma_r / d_min + 0.5 * angle_step * tan_span
    peak = band_search(
        beam, log_d, run_id, starts, counts, centre, half_width, bin_half,
        angle_min, increment, cfg.hough_subdiv, cfg.hough_angles,
    )
    table, good = fit_spans(
        first, last, peak.rho, peak.alpha, peak.inlier, ranges, bearings, sig.valid, cfg,
        stacked=(beam, run_id, starts, counts),
    )
    if not good.all():
        table = LineTable(*(a[good] for a in table))
    return extend_ends(table, ranges, bearings, sig.valid, k + 2, cfg)


def extend_ends(
    table: LineTable, ranges: np.ndarray, bearings: np.ndarray, valid: np.ndarray, reach: int,
    cfg: SensorMethodConfig,
) -> LineTable:
    """Grow every line over the up to ``reach`` beams beyond each end that continue it (valid and
    |range residual| <= inlier_tau sigma_r, without a break): the AD windows stop short of corners."""
    n = ranges.size
    if table.rho.size == 0:
        return table
    steps = np.concatenate((np.arange(1, reach + 1), -np.arange(1, reach + 1)))
    base = np.where(steps > 0, table.last[:, None], table.first[:, None])
    idx = base + steps  # (L, 2 * reach): after the last beam, then before the first
    inside = (idx >= 0) & (idx < n)
    idx_c = np.clip(idx, 0, n - 1)
    c = np.cos(bearings[idx_c] - table.alpha[:, None])
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (ranges[idx_c] * c - table.rho[:, None]) / (cfg.sigma_r * c)
        ok = inside & valid[idx_c] & (c > 0.05) & (np.abs(z) <= cfg.inlier_tau)
    grow = np.cumprod(ok.reshape(-1, 2, reach), axis=2).sum(axis=2)  # (L, 2) contiguous beams
    return table._replace(
        first=table.first - grow[:, 1], last=table.last + grow[:, 0], n_points=table.n_points + grow.sum(axis=1)
    )
