"""Line extraction in sensor coordinates: AD runs -> Log-Hough band search -> weighted refinement.

Every stage works on all candidate runs of a scan at once (beams stacked with a run id); the only
Python loops run over the few accepted lines (merging neighbours, building the output).
Call under ``np.errstate(all="ignore")``: special values turn into nan and fail the tests.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .config import SensorMethodConfig
from .hough import band_search
from .refine import gauss_newton
from .signals import BeamSignals, wrap


class LineTable(NamedTuple):
    """Accepted lines, sorted by first beam (all arrays of length L, cov (L, 2, 2))."""

    rho: np.ndarray
    alpha: np.ndarray
    cov: np.ndarray
    first: np.ndarray
    last: np.ndarray
    n_points: np.ndarray


EMPTY = LineTable(np.empty(0), np.empty(0), np.empty((0, 2, 2)), *(np.empty(0, np.int64) for _ in range(3)))


def candidate_runs(sig: BeamSignals, k: int, cfg: SensorMethodConfig) -> tuple[np.ndarray, np.ndarray]:
    """First and last centre of each run of beams whose window passes the AD test (eq. 4, the
    threshold scaled by the AD noise at that beam) and holds no slope break (|psi| large)."""
    n = sig.AD.size
    s2 = cfg.sigma_r * cfg.sigma_r
    dev = sig.AD - sig.ad_line
    ok = dev * dev <= (cfg.ad_tau * cfg.ad_tau * s2) * sig.AD_var  # nan -> False
    psi2 = sig.psi * sig.psi
    big = psi2 > np.maximum(cfg.psi_split * cfg.psi_split, (cfg.psi_tau * cfg.psi_tau) * sig.psi_var)
    if big.any():
        # a slope break between the windows at i and i+k peaks near i + k/2: drop the centres
        # whose windows reach it (those within k), as the AD test does at sharp corners
        mag = np.where(big, psi2, 0.0)
        peak = big
        peak[1:] &= mag[1:] >= mag[:-1]
        peak[:-1] &= mag[:-1] >= mag[1:]
        hit = np.zeros(n, np.int8)
        hit[np.minimum(np.flatnonzero(peak) + k // 2, n - 1)] = 1
        ok &= np.convolve(hit, np.ones(2 * k + 1, np.int8), "same") == 0  # n >= 2k+1 here
    padded = np.zeros(n + 2, bool)
    padded[1:-1] = ok
    edges = np.flatnonzero(padded[1:] != padded[:-1])
    return edges[::2], edges[1::2] - 1


def stack_spans(first: np.ndarray, last: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Beam indices of the spans [first, last] stacked end to end, their run ids, row starts, counts."""
    counts = last - first + 1
    ends = np.cumsum(counts)
    starts = ends - counts
    run_id = np.repeat(np.arange(first.size), counts)
    beam = np.arange(int(ends[-1])) + (first - starts)[run_id]
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
    core: np.ndarray | None = None,
) -> tuple[LineTable, np.ndarray]:
    """Refine (rho, alpha) of lines over the beam spans [first, last] from a starting estimate:
    a Gauss-Newton step on the starting inliers, then one on the beams within inlier_tau sigma_r
    of that (which also gives the covariance and the checks). Returns the table of lines
    (unfiltered) and a mask of the lines that pass the checks."""
    beam, run_id, starts, counts = stack_spans(first, last) if stacked is None else stacked
    ok = valid[beam]
    d = np.where(ok, ranges[beam], 0.0)  # invalid beams (in merged spans) get no weight and no nan
    b = bearings[beam]
    sigma = cfg.sigma_r
    s1 = gauss_newton(d, b, run_id, starts, ok if inlier0 is None else ok & inlier0, rho, alpha, sigma, with_cov=False)
    s2 = gauss_newton(d, b, run_id, starts, ok, s1.rho, s1.alpha, sigma, cfg.inlier_tau)
    rho, alpha, cov, z = s2.rho, s2.alpha, s2.cov, s2.z
    inl = s2.weight > 0
    # checks: enough inliers, most of the span explained, chi^2 of the inliers, and curvature:
    # the t-statistic of the residuals against a parabola in the beam index, made orthogonal to
    # 1 and t over the inliers (what the line fit absorbs): ~N(0, 1) on a line, large on an arc
    zi = np.where(inl, z, 0.0)
    w_in = inl.astype(float)
    t = (beam - beam[starts][run_id]).astype(float)
    t2 = t * t
    buf = np.empty((5, beam.size))
    buf[0] = w_in
    np.multiply(zi, zi, out=buf[1])
    np.multiply(w_in, t, out=buf[2])
    np.multiply(w_in, t2, out=buf[3])
    np.multiply(buf[2], t2, out=buf[4])
    n_f, chi, s_t, s_t2, s_t3 = np.add.reduceat(buf, starts, axis=1)
    n_in = n_f.astype(np.int64)
    n_f = np.maximum(n_f, 1.0)
    m1, m2, m3 = s_t / n_f, s_t2 / n_f, s_t3 / n_f
    b_lin = (m3 - m1 * m2) / np.maximum(m2 - m1 * m1, 1e-12)
    a_lin = m2 - b_lin * m1
    q = t2 - a_lin[run_id] - b_lin[run_id] * t
    zq = zi * q
    buf[0] = zq
    np.multiply(w_in * q, q, out=buf[1])
    zq, qq = np.add.reduceat(buf[:2], starts, axis=1)
    first_in = np.minimum.reduceat(np.where(inl, beam, beam.size + first.max()), starts)
    last_in = np.maximum.reduceat(np.where(inl, beam, -1), starts)
    good = (
        (n_in >= cfg.min_points)
        & (n_in >= cfg.min_inlier_fraction * (counts if core is None else core))
        & (chi <= cfg.max_chi2 * np.maximum(n_in - 2, 1))
        & (zq * zq <= (cfg.curvature_tau * cfg.curvature_tau) * qq)
        & np.isfinite(rho + alpha + cov[:, 0, 0] + cov[:, 1, 1])
    )
    # normal form with rho >= 0, alpha in (-pi, pi]
    neg = rho < 0
    if neg.any():
        rho = np.abs(rho)
        alpha = np.where(neg, alpha + np.pi, alpha)
        cov[neg, 0, 1] *= -1.0
        cov[neg, 1, 0] *= -1.0
    return LineTable(rho, wrap(alpha), cov, first_in, last_in, n_in), good


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
    long_enough = c1 - c0 + 2 * k + 1 >= cfg.min_points
    if not long_enough.all():
        c0, c1 = c0[long_enough], c1[long_enough]
    if c0.size == 0:
        return EMPTY
    # each run's windows cover c0 - k .. c1 + k (all valid beams); extend_ends grows the fitted
    # lines past them, where the AD windows stop short of a corner
    first = c0 - k
    last = c1 + k
    stacked = stack_spans(first, last)
    beam, run_id, starts, counts = stacked
    # slope estimate of each run: mean of theta over its centres (theta is continuous along a
    # run, so no wrapping is needed), and the std of that mean
    theta = np.where(np.isnan(sig.theta), 0.0, sig.theta)
    tvar = np.where(np.isnan(sig.theta_var), 0.0, sig.theta_var)
    cs_t = np.cumsum(theta)
    cs_v = np.cumsum(tvar)
    n_c = c1 - c0 + 1
    centre = (cs_t[c1] - cs_t[c0] + theta[c0]) / n_c
    centre_var = (cs_v[c1] - cs_v[c0] + tvar[c0]) / (n_c * (1.0 + n_c / (2 * k + 1)))
    half_width = np.minimum(np.maximum(cfg.band_tau * np.sqrt(centre_var), cfg.band_min), 0.5)
    # log-range window of a peak: range noise at the nearest beam + the spread that an angle error
    # of half an angle step causes over the run (d log p / d a = -tan(a - b))
    d = ranges[beam]  # all valid: the AD windows hold no invalid beam
    h = max((cfg.hough_angles - 1) // 2, 1)
    angle_step = np.maximum(half_width / h, increment / cfg.hough_subdiv)
    tan_span = np.abs(np.tan(bearings[c1 + k] - centre) - np.tan(bearings[c0 - k] - centre))
    d_min = np.minimum.reduceat(d, starts)
    bin_half = cfg.bin_tau * cfg.sigma_r / d_min + 0.5 * angle_step * np.minimum(tan_span, 40.0)
    peak = band_search(
        beam, np.log(d), run_id, starts, counts, centre, half_width, bin_half,
        angle_min, increment, cfg.hough_subdiv, cfg.hough_angles,
    )
    table, good = fit_spans(
        first, last, peak.rho, peak.alpha, peak.inlier, ranges, bearings, sig.valid, cfg, stacked=stacked,
        core=n_c + 2 * k,
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
    n_lines = table.rho.size
    if n_lines == 0:
        return table
    steps = np.arange(1, reach + 1)
    idx = np.empty((n_lines, 2, reach), np.int64)
    np.add(table.last[:, None], steps, out=idx[:, 0])
    np.subtract(table.first[:, None], steps, out=idx[:, 1])
    inside = (idx >= 0) & (idx < n)
    np.clip(idx, 0, n - 1, out=idx)
    c = np.cos(bearings[idx] - table.alpha[:, None, None])
    dev = ranges[idx] * c - table.rho[:, None, None]
    ok = inside & valid[idx] & (c > 0.05) & (np.abs(dev) <= (cfg.inlier_tau * cfg.sigma_r) * c)
    grow = np.logical_and.accumulate(ok, axis=2).sum(axis=2)  # (L, 2) contiguous beams
    return table._replace(
        first=table.first - grow[:, 1], last=table.last + grow[:, 0], n_points=table.n_points + grow.sum(axis=1)
    )
