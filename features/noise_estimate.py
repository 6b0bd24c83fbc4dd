"""``sigma_r="auto"``: the range noise the extractors' thresholds should assume, from the data.

An extractor compares neighbouring beams, so what its noise-scaled thresholds must allow for is the
scatter of a range about a straight face *between neighbouring beams*: the sensor's noise, the
rounding of the range codes (1 cm steps in SICK cm mode: an error of variance q^2 / 12), and, at
0.5 and 0.25 deg, the offset between the interlaced 1 deg sweeps a moving scanner takes 13 ms
apart. :func:`neighbour_sigma` measures exactly that: the robust scale (median absolute deviation,
then clipped standard deviation) of the collinearity residuals of neighbouring beam triples
(``lms200.noise.line_residuals`` with stride 1 and ``robust_scale``: the estimator of
``lms200.noise``, used at the beam step the extractors see). Depth steps, corners and curved
surfaces are outliers of those residuals and do not enter the scale.

The estimate is compiled (``features.sensor.engine``, section 0: ``pooled_sigma``), since the sensor
method runs it on every cm-mode scan; it equals the numpy estimator of ``lms200.noise`` bit for bit.

Measured on the real logs of ../shared/data (pooled over each log): MIT CSAIL and the CSAIL
ROBOTLASER1 log (0.5 deg, cm codes) 12 mm, against 5.3 mm within one mirror turn; Intel (1 deg,
cm codes) 5.3 mm; ACES (1 deg) 25 mm.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Iterable

import numpy as np

from lms200 import Scan
from lms200.codes import real_rows
from lms200.noise import MAX_USED_RANGE_M, MIN_RANGE_M, scans_of

from .baselines.checks import MAX_BEAMS, fail, integer, positive
from .errors import not_a_scan

from .jit import FixedTypeCall

AUTO = "auto"
AUTO_FALLBACK = 0.005  # m: the noise assumed when a scan has too few usable triples


@lru_cache(maxsize=1)
def _engine() -> tuple[Any, FixedTypeCall]:
    """The sensor engine (imported on first use: its package imports this module) and its
    ``pooled_sigma`` called with fixed types ((S, n) float64 ranges, floats)."""
    from .sensor import engine  # noqa: PLC0415

    return engine, FixedTypeCall(engine.pooled_sigma)


@lru_cache(maxsize=64)
def twice_cos(increment: float) -> float:
    """2 cos(D) of a beam step D (rad), as numpy computes it (``lms200.noise.line_residuals``)."""
    return float(2.0 * np.cos(increment))


def scan_sigma(scan: Scan, fallback: float = AUTO_FALLBACK) -> float:
    """:func:`neighbour_sigma` of one scan (the sensor method's per-scan "auto"), in one compiled call."""
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "scan_sigma")
    positive("fallback", fallback, "m")
    return _engine()[1](scan.ranges.reshape(1, -1), twice_cos(scan.angle_increment), float(scan.range_min),
                         float(scan.range_max), float(fallback))


def stacked_sigma(ranges: np.ndarray, scan: Scan, fallback: float = AUTO_FALLBACK) -> float:
    """:func:`neighbour_sigma` of scans of ``scan``'s geometry stacked as rows of ``ranges`` (S, n).
    InputError for ``ranges`` that are no (S, n) array of real numbers (n = the scan's beams: a
    number, text, None or one scan's (n,) ranges were numba's TypingError), ScanTypeError for a
    ``scan`` that is no Scan, ConfigError for a ``fallback`` that is no finite number > 0."""
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "stacked_sigma")
    positive("fallback", fallback, "m")
    ranges = real_rows(ranges, "ranges", len(scan), "one scan of the geometry a row, m", finite=False)
    return _engine()[0].pooled_sigma(ranges, twice_cos(scan.angle_increment), float(scan.range_min), float(scan.range_max),
                        float(fallback))


def neighbour_sigma(scans: Scan | Iterable[Any], fallback: float = AUTO_FALLBACK) -> float:
    """Range scatter (m, 1 sigma) of neighbouring beams about straight faces, pooled over ``scans``
    (one Scan, or Scans or records with ``.scan``), at least the quantisation's q / sqrt(12) and
    ``features.sensor.engine.SIGMA_FLOOR_M`` (1 mm); ``fallback`` when fewer than
    ``features.sensor.engine.MIN_TRIPLES`` (20) triples are usable."""
    if isinstance(scans, Scan):
        return scan_sigma(scans, fallback)
    positive("fallback", fallback, "m")  # nan came back as the sigma of too few triples
    engine = _engine()[0]
    zs: list[np.ndarray] = []
    sample: list[np.ndarray] = []
    total = 0
    for scan in scans_of(scans):
        r = scan.ranges
        z = np.empty(max(r.size - 2, 0))
        m = engine.neighbour_residuals(r, twice_cos(scan.angle_increment), max(float(scan.range_min), MIN_RANGE_M),
                                float(scan.range_max), z, 0)
        zs.append(z[:m])
        s = np.empty(r.size // engine.SAMPLE_STEP + 1)
        sample.append(s[: engine.finite_sample(r, s, 0)])
        total += m
        if total >= engine.MAX_TRIPLES:
            break
    z_all = np.concatenate(zs) if zs else np.empty(0)
    return float(engine.sigma_of_residuals(z_all, np.concatenate(sample) if sample else np.empty(0), float(fallback)))


FIT_WINDOW = 7  # beams of the local line a beam's fit residual is taken about (odd)


def fit_residuals(scan: Scan, window: int = FIT_WINDOW) -> np.ndarray:
    """:func:`fit_residuals_and_slopes` without the slopes and ranges."""
    return fit_residuals_and_slopes(scan, window)[0]


def fit_residuals_and_slopes(scan: Scan, window: int = FIT_WINDOW) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Range residuals (m) of the middle beam of every run of ``window`` consecutive valid beams of
    ``scan`` about the straight line fitted to the run, scaled so that under independent range
    noise of sigma their scale is sigma.

    A straight line is ``1 / r = A cos(b) + B sin(b)`` in a beam's range r and bearing b, so the
    fit is linear least squares in u = 1 / r with one hat matrix H for every run (its bearings
    differ by a rotation only); the middle beam's residual is ``k . u`` with k the middle row of
    I - H, taken back to range by -r^2 and divided by |k| (the residual's share of the noise).
    Unlike the neighbour triples of :func:`neighbour_sigma`, an offset between the interlaced
    sweeps of a 0.5 deg scan (beams alternating by +-d / 2 about the face) enters as about d / 2,
    the size it has about any line fitted through both sweeps, not as the 0.82 d of a second
    difference.

    Also returns each residual's |dr / db| (m/rad; the run's end ranges' difference over its
    bearings' span): d |tan(b - alpha)| on a face at incidence b - alpha, the factor by which a
    bearing error becomes a range error (:func:`bearing_sigma`), and the middle beam's range d (m).

    Raises:
        ScanTypeError: ``scan`` is no lms200.Scan. ConfigError: ``window`` is no odd integer in
            [3, MAX_BEAMS] (fuzzing: 0, -1 or True were numpy's LinAlgError, 2.5 an IndexError,
            None a TypeError).
    """
    if not isinstance(scan, Scan):
        raise not_a_scan(scan, "fit_residuals")
    integer("window", window, 3, MAX_BEAMS)
    if window % 2 == 0:
        fail("window", "must be odd (the residual is the middle beam's)", window)
    r = np.asarray(scan.ranges, dtype=np.float64)
    if r.size < window:
        return np.empty(0), np.empty(0), np.empty(0)
    with np.errstate(invalid="ignore"):
        # readings of 10 km or more are no rangefinder's (lms200.noise.MAX_USED_RANGE_M): 1e160 m ones,
        # which a Scan of range_max 1e308 takes, overflowed r^2 with RuntimeWarnings
        ok = (np.isfinite(r) & (r >= max(float(scan.range_min), MIN_RANGE_M)) & (r <= float(scan.range_max))
              & (r < MAX_USED_RANGE_M))
    k = fit_kernel(float(scan.angle_increment), window)
    view = np.lib.stride_tricks.sliding_window_view
    full = view(ok, window).all(axis=1)
    if not full.any():
        return np.empty(0), np.empty(0), np.empty(0)
    u = np.where(ok, 1.0 / np.where(ok, r, 1.0), 0.0)
    mid = window // 2
    r_mid = r[mid : mid + full.size][full]
    slope = np.abs(r[window - 1:][full] - r[: full.size][full]) / ((window - 1) * float(scan.angle_increment))
    return -(r_mid * r_mid) * (view(u, window)[full] @ k) / np.sqrt(k[mid]), slope, r_mid


@lru_cache(maxsize=16)
def fit_kernel(increment: float, window: int) -> np.ndarray:
    """The middle row of I - H for the line fit ``1 / r = A cos(b) + B sin(b)`` over ``window``
    beams ``increment`` apart (rad; :func:`fit_residuals`)."""
    t = (np.arange(window) - window // 2) * increment
    design = np.column_stack((np.cos(t), np.sin(t)))
    hat = design @ np.linalg.solve(design.T @ design, design.T)
    k = -hat[window // 2]
    k[window // 2] += 1.0
    k.setflags(write=False)
    return k


def fit_sigma(scans: Scan | Iterable[Any], fallback: float = AUTO_FALLBACK, window: int = FIT_WINDOW) -> float:
    """Scatter (m, 1 sigma) of beams about lines fitted through them, pooled over ``scans`` (one
    Scan, or Scans or records with ``.scan``): the robust scale (``lms200.noise.robust_scale``: MAD,
    then clipped standard deviation, so corners, depth steps and curves are outliers) of
    :func:`fit_residuals`. What a split test and a merge test must allow for, the residuals of a
    true face's beams about its fitted line: the sensor noise, the quantisation and the interlaced
    sweeps' offset. ``fallback`` with fewer than ``features.sensor.engine.MIN_TRIPLES`` (20) residuals."""
    from lms200.noise import MAX_TRIPLES, robust_scale  # noqa: PLC0415

    positive("fallback", fallback, "m")
    zs: list[np.ndarray] = []
    total = 0
    for scan in scans_of(scans):
        z = fit_residuals(scan, window)
        zs.append(z)
        total += z.size
        if total >= MAX_TRIPLES:
            break
    z_all = np.concatenate(zs) if zs else np.empty(0)
    engine = _engine()[0]  # the bounds neighbour_sigma applies: fewest residuals, noise floor
    if z_all.size < engine.MIN_TRIPLES:
        return float(fallback)
    return max(float(robust_scale(z_all)[1]), engine.SIGMA_FLOOR_M)  # noiseless scans: finite thresholds


#: |dr / db| bins (m/rad) of :func:`bearing_sigma`: the first holds faces seen about head-on (range
#: noise alone), the others oblique ones; beyond 8 m/rad (incidence past ~75 deg at 2 m) a window
#: of 7 beams spans metres of face and reaches corners and ends: its scale says little
SLOPE_EDGES = (0.0, 1.0, 2.0, 4.0, 8.0)
#: range bands (m) of :func:`bearing_sigma`: range noise grows with range, and oblique faces are
#: seen farther on average, so slopes are compared within a band only
RANGE_EDGES = (0.0, 2.0, 4.0, 8.0, np.inf)
MIN_BIN = 200  # fewest residuals of a (range, slope) bin that enters the estimate
SCALE_FLOOR_M = 0.001  # m: the least scale a bin's weight assumes (noiseless scans: finite weights)


def spread_residuals(scans: Scan | Iterable[Any], window: int = FIT_WINDOW) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`fit_residuals_and_slopes` (residuals m, |dr / db| m/rad, ranges m) of scans spread
    evenly over all of ``scans`` (one Scan, or Scans or records with ``.scan``; read once), within
    ``lms200.noise.MAX_TRIPLES`` residuals: every scan while they fit, else every k-th (k a power of
    2: when the kept residuals reach the bound, every other kept scan is dropped and k doubles), so
    the sample spans the whole log, not a prefix of it. Deterministic."""
    from lms200.noise import MAX_TRIPLES  # noqa: PLC0415

    kept: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = []
    stride, total = 1, 0
    for i, scan in enumerate(scans_of(scans)):
        if i % stride:
            continue
        z, t, d = fit_residuals_and_slopes(scan, window)
        kept.append((i, z, t, d))
        total += z.size
        while total >= MAX_TRIPLES and len(kept) > 1:
            stride *= 2
            kept = [k for k in kept if k[0] % stride == 0]
            total = sum(k[1].size for k in kept)
    if not kept:
        return np.empty(0), np.empty(0), np.empty(0)
    return (np.concatenate([k[1] for k in kept]), np.concatenate([k[2] for k in kept]),
            np.concatenate([k[3] for k in kept]))


def bearing_sigma(scans: Scan | Iterable[Any], window: int = FIT_WINDOW) -> float:
    """Bearing noise (rad, 1 sigma) of ``scans`` (one Scan, or Scans or records with ``.scan``):
    how the scatter of beams about fitted lines (:func:`fit_residuals_and_slopes`, of scans spread
    over the whole of ``scans``: :func:`spread_residuals`) grows with |dr / db| = d |tan(incidence)|,
    the factor that turns a bearing error into a range error.

    Within each range band (RANGE_EDGES), binned by |dr / db| (SLOPE_EDGES), each bin's robust
    scale s_b (``lms200.noise.robust_scale``) of n_b residuals at median slope t_b follows
    s_b^2 = s_0^2 + t_b^2 sigma^2 (s_0 the band's head-on bin). One weighted least-squares sigma^2
    over every oblique bin of every band, y_b = s_b^2 - s_0^2 against x_b = t_b^2 with weights
    1 / var(y_b) = 1 / (s_b^4 / n_b + s_0^4 / n_0) (the variance of a squared scale, up to a common
    factor), clipped at 0: every bin counts by its information, so no single bin (the smallest of
    twelve noisy values, as before) decides. 0.0 without a band holding a head-on and an oblique bin
    of MIN_BIN residuals each.

    The logs of ../shared/data (whole log; halves; quarters, mrad): MIT CSAIL 6.0; 4.5, 6.5;
    7.6, 2.7, 6.1, 6.5 (the smallest-bin form before: 5.2; 0.1, 4.4; 0, 0, 4.8, 4.1), CSAIL
    ROBOTLASER1 5.8; 4.9, 6.6; 6.9, 3.1, 6.0, 7.1, Intel 0.9 (0.7-1.0 on every part), ACES 2.8
    (2.1-3.7: its 0-2 m band's scatter grows with the slope, 23.5 -> 31.4 mm at 0.5 -> 2.9 m/rad),
    MIT cut to one 1 deg sweep 1.0. Simulated sweeps offset by 8 / 12 mrad read 4.7 / 7.0 (1.15-1.2x
    the offset / 2), exact bearings under 1 mrad. Weak spot: weights from a bin's own scale favour
    a bin whose scale is low by accident (an office of 8 exact scans and 24 offset by 12 mrad reads
    1.0 mrad through one bin of 202 residuals)."""
    from lms200.noise import robust_scale  # noqa: PLC0415

    z_all, t_all, d_all = spread_residuals(scans, window)
    sxy = sxx = 0.0
    for near, far in zip(RANGE_EDGES[:-1], RANGE_EDGES[1:]):
        band = (d_all >= near) & (d_all < far)
        bins: list[tuple[float, float, int]] = []
        for lo, hi in zip(SLOPE_EDGES[:-1], SLOPE_EDGES[1:]):
            inside = band & (t_all >= lo) & (t_all < hi)
            n = int(np.count_nonzero(inside))
            if n >= MIN_BIN:
                bins.append((float(np.median(t_all[inside])), float(robust_scale(z_all[inside])[1]), n))
            elif lo == 0.0:
                break  # no head-on reference in this band
        if len(bins) < 2:
            continue
        _, s0, n0 = bins[0]
        for t, s, n in bins[1:]:
            weight = 1.0 / (max(s, SCALE_FLOOR_M) ** 4 / n + max(s0, SCALE_FLOOR_M) ** 4 / n0)
            x, y = t * t, s * s - s0 * s0
            sxy += weight * x * y
            sxx += weight * x * x
    return float(np.sqrt(max(sxy / sxx, 0.0))) if sxx > 0.0 else 0.0
