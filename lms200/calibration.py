"""A laser's error model measured from a log alone: noise and its growth with range, the
quantisation step, no-return / invalid / maximum-range rates, mixed pixels and isolated outliers,
each with a standard error.

Everything is counted on the scans themselves, without a map or poses (see ``docs`` of
``lmsbench calibrate``):

- noise: :mod:`lms200.noise` on triples whose beams all lie at 1-4 m, and per range band
  (0.5-1, 1-2, 2-4, 4-8, 8-16, 16-32 m) for a weighted straight-line fit of sigma against range
  (bands up to 16 m; farther, beams 14 cm and more apart see the scene's detail, not noise);
- raw rates: the share of all readings that are nan (invalid), +inf (no return) or the log's
  maximum reading (a finite cap some loggers write for "nothing", e.g. 50 m);
- no-return rate of surfaces: among beams whose two neighbours are finite and on one surface
  (their ranges within 20 %), the share that read +inf or the cap (so far geometry beyond the
  sensor's range, which gives runs of +inf, is not counted);
- mixed pixels: at depth steps (neighbours more than ``STEP_M`` apart, each on a locally
  continuous surface), the share of steps that have a beam lying between the two surfaces, off
  both by more than ``max(4 sigma, 3 cm)`` and off the line through its neighbours;
- the residual tail: a two-Gaussian fit to the triples' residuals at 1-4 m (weight and sigma of
  the wide part), and how it clusters along the scan (``LogCalibration.tail_clustering``);
- isolated outliers: among beams whose neighbours lie within half the gap of each other, the
  share that are off the line through the neighbours by more than the gap
  ``max(OUTLIER_M, 10 sigma)`` (a one-beam object, such as a thin leg far away, counts too: the
  data cannot tell them apart); and the same share among the beams amid a straight stretch (their
  STRAIGHT_HALF neighbours each side on one line within ``max(STRAIGHT_M, 2 sigma)`` rms), where
  no object of the scene but a spurious echo of the sensor puts one (the rate the simulator's
  ``outlier_prob`` is fitted to: on MIT CSAIL 0.012 % of such beams against 1.71 % of all trials).

Standard errors come from a bootstrap over scans (the rates are ratios of per-scan counts).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Iterable

import numpy as np

from .codes import CODE_ABOVE_MAXIMUM, CODE_NOT_VALID, METRES_PER_UNIT
from .errors import InputError
from .finite import check_seed
from .noise import (BOOTSTRAP_RESAMPLES, RangeNoise, _bootstrap_scale, _remove_quantisation, estimate_quantum, scans_of,
                    estimate_range_noise, interlace_stride, robust_scale, scan_residuals)
from .scan import Scan

NOISE_BAND_M = (1.0, 4.0)  # the band whose sigma is the config's noise_sigma
RANGE_BINS_M = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0)  # bands for the noise-against-range fit
MIN_BIN_TRIPLES = 500  # a band with fewer usable triples is not fitted
FIT_MAX_RANGE_M = 16.0  # bands beyond this are reported, not fitted (beams 14+ cm apart see scene detail)
REFERENCE_RANGE_M = 2.5  # the fit's sigma(r) = a + b (r - 2.5 m)
SURFACE_FRACTION = 0.2  # neighbours within this share of their range lie on one surface
STEP_M = 0.3  # m: a depth step for the mixed-pixel count
MIXED_MARGIN_M = 0.03  # m: least distance of a mixed pixel from both surfaces (or 4 sigma)
OUTLIER_M = 0.1  # m: least distance of an isolated outlier from its neighbours' line (or 10 sigma)
STRAIGHT_HALF = 8  # beams each side of a beam that must lie on one line for it to be amid a straight stretch
STRAIGHT_M = 0.01  # m: rms of those 2 x STRAIGHT_HALF points about their line (or 2 sigma) for a straight stretch
MAX_READING_SHARE = 1e-3  # a top value read this often (or more) is the logger's cap
MIN_SCANS = 2  # a bootstrap over scans needs two
MAX_SCANS = 20_000  # memory bound: scans beyond this many are not read
MAX_READ = 10 * MAX_SCANS  # time bound: items read at most, repeats included (an endless repeat never ended)
#: memory bound in beams: MAX_SCANS scans of an LMS200's 361 beams (the scans are kept: every measure is a pass over
#: them, with temporaries of a few times their size). MAX_SCANS alone let wide scans through: 20,000 scans of 16,384
#: beams (a Scan's most over 360 deg) are 2.6 GB of ranges, and 1,081-beam ones (a Hokuyo's 270 deg, which
#: ``lmsbench calibrate`` refuses only once measured) 173 MB; at 361 beams or fewer the scan bound comes first
MAX_KEPT_BEAMS = MAX_SCANS * 361
TAIL_WINDOW = 20.0  # the tail fit uses residuals within this many core sigmas
TAIL_CLUSTER_SIGMAS = 5.0  # a triple whose residual exceeds this many core sigmas is in the tail
TAIL_CLUSTER_STEP = 3  # the tail's clustering pairs triples this many strides apart (no beam shared)


@dataclass(frozen=True)
class Estimate:
    """A measured quantity: value, standard error (bootstrap over scans) and its count basis."""

    value: float
    std: float
    n: int

    def to_dict(self) -> dict[str, float | int]:
        return {"value": float(self.value), "std": float(self.std), "n": int(self.n)}


@dataclass(frozen=True)
class LogCalibration:
    """The error model of the laser that recorded some scans (metres, radians).

    Attributes:
        n_scans, n_beams: scans read and beams per scan (the most common count).
        angle_increment: bearing step (rad); range_max: the scans' range_max (m).
        units: "cm" or "mm", from the quantisation step (mm when finer than 1 cm).
        quantum_m: range quantisation step (0 = continuous).
        noise: noise sigma over triples at 1-4 m (:class:`lms200.noise.RangeNoise`).
        noise_bins: per range band: r_lo, r_hi, mean range, sigma, its standard error, triples.
        noise_slope: fitted growth of sigma with range (m per m).
        nan_rate, inf_rate, max_reading_rate: shares of all readings.
        max_reading: the log's cap for no return (m), or None.
        no_return_rate: share of beams on surfaces that read +inf or the cap.
        mixed_share: share of depth steps with a beam between the two surfaces.
        outlier_rate: share of beams on surfaces that are isolated outliers.
        outlier_straight_rate: the same share among beams amid a straight stretch (STRAIGHT_HALF
            neighbours each side on one line), where the scene puts no one-beam object.
        tail_share, tail_sigma_m: weight and sigma (m) of the wide component of a two-Gaussian fit
            (core sigma fixed) to the residuals of triples at 1-4 m within 20 core sigmas: the
            heavy tail beyond the Gaussian core (from the scene's geometry as well as the sensor).
        tail_clustering: how the tail gathers along a scan: of the triples at 1-4 m whose
            residual exceeds TAIL_CLUSTER_SIGMAS core sigmas, the share whose neighbour triple
            TAIL_CLUSTER_STEP strides on (sharing no beam with it) does too. A tail of independent
            beams gives about the tail's own share; rough stretches of surface give more.
        nan_clustering: how nan readings gather along a scan: of the nan beams, the share whose
            next beam is nan too (about nan_rate for beams dropped one by one; MIT CSAIL: 0.82).
        repeated_scans: scans passed over as the scan before them again (the same stamp, geometry
            and readings: a log written twice over, line by line), not among ``n_scans``.
    """

    n_scans: int
    n_beams: int
    angle_increment: float
    range_max: float
    units: str
    quantum_m: float
    noise: RangeNoise
    noise_bins: list[dict[str, float]] = field(default_factory=list)
    noise_slope: Estimate = Estimate(0.0, float("nan"), 0)
    nan_rate: Estimate = Estimate(0.0, 0.0, 0)
    inf_rate: Estimate = Estimate(0.0, 0.0, 0)
    max_reading_rate: Estimate = Estimate(0.0, 0.0, 0)
    max_reading: float | None = None
    no_return_rate: Estimate = Estimate(0.0, 0.0, 0)
    mixed_share: Estimate = Estimate(0.0, 0.0, 0)
    outlier_rate: Estimate = Estimate(0.0, 0.0, 0)
    outlier_straight_rate: Estimate = Estimate(0.0, 0.0, 0)
    tail_share: Estimate = Estimate(0.0, 0.0, 0)
    tail_sigma_m: float = 0.0
    tail_clustering: Estimate = Estimate(float("nan"), float("nan"), 0)
    nan_clustering: Estimate = Estimate(float("nan"), float("nan"), 0)
    repeated_scans: int = 0

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        for k, v in list(d.items()):
            if isinstance(v, float):
                d[k] = float(v)
        return d


def _ratio(k: np.ndarray, n: np.ndarray, seed: int) -> Estimate:
    """sum(k) / sum(n) over scans, with the bootstrap standard error over scans."""
    k, n = np.asarray(k, float), np.asarray(n, float)
    total = float(n.sum())
    if total <= 0:
        return Estimate(float("nan"), float("nan"), 0)
    value = float(k.sum()) / total
    if k.size < 2:
        return Estimate(value, float("nan"), int(total))
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, k.size, size=(BOOTSTRAP_RESAMPLES, k.size))
    nn = n[pick].sum(1)
    boot = k[pick].sum(1) / np.where(nn > 0, nn, np.nan)
    return Estimate(value, float(np.nanstd(boot, ddof=1)), int(total))


def _beyond_range_max_invalid(scan: Scan) -> Scan:
    """``scan`` with its finite readings beyond range_max as nan: out of limits, invalid (``Scan.valid``,
    ``lmsbench info``), not echoes. One stray 1e308 in a log was taken for the log's largest reading,
    so its cap (MIT CSAIL's 11.95 m, 0.22 % of readings) read 0 %, and the sums over it overflowed
    (RuntimeWarnings on stderr)."""
    with np.errstate(invalid="ignore"):
        beyond = np.isfinite(scan.ranges) & (scan.ranges > scan.range_max)
    if not beyond.any():
        return scan
    return scan.replace(ranges=np.where(beyond, np.nan, scan.ranges))


def _repeats(scan: Scan, before: Scan | None) -> bool:
    """Whether ``scan`` is ``before`` again: the same stamp, geometry and readings (nan as nan)."""
    return (before is not None and scan.stamp == before.stamp and len(scan) == len(before)
            and scan.angle_min == before.angle_min and scan.angle_increment == before.angle_increment
            and scan.range_min == before.range_min and scan.range_max == before.range_max
            and bool(np.array_equal(scan.ranges, before.ranges, equal_nan=True)))


def _mm_mode_codes(scan: Scan) -> Scan:
    """A mm-mode scan's readings at or above the mm mode's maximum (8.183 m, code 8183) as the
    LMS200 means them (``lms200.codes``): 8183 and any reading above the 13-bit distance field
    (8.191 m) measured nothing within range, +inf (REP-117); 8184 .. 8191 (dazzling, operation
    overflow, ...) are invalid, nan. A mm-mode unit sends no distance beyond 8.182 m, so such
    readings come from a logger, not from a surface: a log whose no-returns were written as
    8.5 .. 40 m had them counted as nan (out of the log's range_max) and fitted as dropouts
    (dropout_prob 3.4 % and no_return_prob 0.02 % where the same log with +inf gave 0.08 % and
    3.3 %), and a FLASER line with one such reading was read in cm, its 8.183 m no-returns kept as
    echoes at 8.183 m (taken for a cap)."""
    r = scan.ranges
    with np.errstate(invalid="ignore", over="ignore"):
        code = np.rint(r / METRES_PER_UNIT["mm"])
        above = np.isfinite(r) & (code >= CODE_ABOVE_MAXIMUM)
    if not above.any():
        return scan
    invalid = above & (code > CODE_ABOVE_MAXIMUM) & (code <= CODE_NOT_VALID)
    return scan.replace(ranges=np.where(invalid, np.nan, np.where(above, np.inf, r)))


def _max_reading(scans: list[Scan], quantum: float) -> float | None:
    """The largest finite reading if it is a cap: read at least MAX_READING_SHARE of the time."""
    tops = [float(np.max(s.ranges[np.isfinite(s.ranges)])) for s in scans if np.isfinite(s.ranges).any()]
    if not tops:
        return None
    top = max(tops)
    tol = max(quantum, 1e-6) / 2
    hits = sum(int(np.count_nonzero(np.abs(s.ranges - top) <= tol)) for s in scans)
    total = sum(len(s) for s in scans)
    return top if hits >= MAX_READING_SHARE * total and hits >= 3 else None


def missing_readings(r: np.ndarray) -> np.ndarray:
    """Readings that are no measurement: nan, and 0 m (or less), which loggers write for a missing
    reading (``Scan.valid`` never takes them); the simulator renders both as its nan dropouts."""
    with np.errstate(invalid="ignore"):
        return np.isnan(r) | (r <= 0.0)


def _scan_counts(r: np.ndarray, inc: float, sigma: float, cap: float | None, quantum: float) -> np.ndarray:
    """Counts of one scan: nan, inf, cap, beams, surface trials, surface no-returns, outlier
    trials, outliers, mixed steps, plain steps, outlier trials amid a straight stretch, outliers there."""
    n = r.size
    nan = missing_readings(r)
    at_cap = np.zeros(n, dtype=bool) if cap is None else np.abs(r - cap) <= max(quantum, 1e-6) / 2
    none = np.isposinf(r) | at_cap  # no return
    x = np.where(none | nan, np.nan, r)  # finite echoes only
    out = np.zeros(12)
    out[:4] = nan.sum(), np.isposinf(r).sum(), at_cap.sum(), n
    if n < 5:
        return out
    a, m, b = x[:-2], x[1:-1], x[2:]
    gap = max(OUTLIER_M, 10 * sigma)
    with np.errstate(invalid="ignore"):
        surface = np.isfinite(a) & np.isfinite(b) & (np.abs(b - a) <= SURFACE_FRACTION * np.minimum(a, b))
        # outlier trials: neighbours so close that no edge between them can put a beam gap away
        smooth = surface & (np.abs(b - a) < gap / 2)
    mid_none, mid_nan = none[1:-1], nan[1:-1]
    out[4] = np.count_nonzero(surface & ~mid_nan)
    out[5] = np.count_nonzero(surface & mid_none)
    c2 = 2.0 * np.cos(inc)
    with np.errstate(invalid="ignore", divide="ignore"):
        predicted = c2 * a * b / (a + b)  # the middle beam on the line through its neighbours
        off = np.abs(m - predicted)
        trial = smooth & np.isfinite(m)
        out[6] = np.count_nonzero(trial)
        out[7] = np.count_nonzero(trial & (off > gap))
        amid = _amid_straight(x, inc, max(STRAIGHT_M, 2 * sigma))[1:-1]
        out[10] = np.count_nonzero(trial & amid)
        out[11] = np.count_nonzero(trial & amid & (off > gap))
        # mixed pixels: beam i between two surfaces; neighbours anchored on continuous surfaces
        d = np.abs(np.diff(x))
        cont = d < STEP_M / 2  # (j, j+1) on one surface
        i = np.arange(2, n - 2)
        lo, hi = np.minimum(x[i - 1], x[i + 1]), np.maximum(x[i - 1], x[i + 1])
        margin = np.maximum(MIXED_MARGIN_M, 4 * sigma)
        anchored = cont[i - 2] & cont[i + 1]
        mixed = (anchored & (hi - lo > STEP_M) & (x[i] > lo + margin) & (x[i] < hi - margin)
                 & (off[i - 1] > margin))
        step = d > STEP_M  # (j, j+1): a depth step without a beam between
        j = np.arange(1, n - 2)
        is_mixed = np.zeros(n, dtype=bool)
        is_mixed[i[mixed]] = True
        plain = step[j] & cont[j - 1] & cont[j + 1] & ~is_mixed[j] & ~is_mixed[j + 1]
    out[8] = np.count_nonzero(mixed)
    out[9] = np.count_nonzero(plain)
    return out


def _amid_straight(x: np.ndarray, inc: float, rms_m: float) -> np.ndarray:
    """(n,) bool: beam i's STRAIGHT_HALF neighbours each side (not i itself) are all finite and lie
    on one line within ``rms_m`` (m, rms of their perpendicular distances from the total-least-squares
    line). ``x``: ranges (m, nan for no echo), ``inc``: the bearing step (rad)."""
    n, h = x.size, STRAIGHT_HALF
    out = np.zeros(n, dtype=bool)
    if n < 2 * h + 1:
        return out
    th = np.arange(n) * inc
    px, py = np.nan_to_num(x * np.cos(th)), np.nan_to_num(x * np.sin(th))
    bad = ~np.isfinite(x)

    def window(v: np.ndarray) -> np.ndarray:  # sum over i-h .. i+h without i, for i = h .. n-h-1
        c = np.concatenate(([0.0], np.cumsum(v)))
        return c[2 * h + 1:] - c[:n - 2 * h] - v[h:n - h]

    k = 2.0 * h
    sx, sy = window(px), window(py)
    sxx = window(px * px) - sx * sx / k
    syy = window(py * py) - sy * sy / k
    sxy = window(px * py) - sx * sy / k
    least = (sxx + syy) / 2 - np.sqrt(((sxx - syy) / 2) ** 2 + sxy ** 2)  # smallest eigenvalue x k
    gaps = window(bad.astype(float))  # neighbours without an echo (i's own is not needed)
    out[h:n - h] = (gaps == 0) & (np.maximum(least, 0.0) / k <= rms_m ** 2)
    return out


def _noise_bins(scans: list[Scan], quantum: float, seed: int) -> tuple[list[dict[str, float]], Estimate]:
    """sigma per range band and the weighted straight-line fit sigma(r) = a + b (r - 2.5 m)."""
    zs, rs, blocks = [], [], []
    for k, s in enumerate(scans):
        z, r0, _ = scan_residuals(s, s.range_min, s.range_max)
        zs.append(z.astype(np.float32))
        rs.append(r0.astype(np.float32))
        blocks.append(np.full(z.size, k, dtype=np.int32))
    if not zs:
        return [], Estimate(0.0, float("nan"), 0)
    z, r0, blk = np.concatenate(zs).astype(float), np.concatenate(rs).astype(float), np.concatenate(blocks)
    rows = []
    for lo, hi in zip(RANGE_BINS_M[:-1], RANGE_BINS_M[1:]):
        sel = (r0 >= lo) & (r0 < hi)
        if np.count_nonzero(sel) < MIN_BIN_TRIPLES:
            continue
        _, s_obs, keep = robust_scale(z[sel])
        sigma = _remove_quantisation(s_obs, quantum)
        se = _bootstrap_scale(z[sel][keep], blk[sel][keep], seed)
        se = s_obs * se / sigma if sigma > 0 else se
        rows.append(dict(r_lo=lo, r_hi=hi, r_mean=float(r0[sel].mean()), sigma=float(sigma), std=float(se),
                         n=int(keep.sum())))
    fit = [row for row in rows if row["r_hi"] <= FIT_MAX_RANGE_M]
    if len(fit) < 2:
        return rows, Estimate(0.0, float("nan"), len(fit))
    x = np.array([row["r_mean"] for row in fit]) - REFERENCE_RANGE_M
    y = np.array([row["sigma"] for row in fit])
    w = 1.0 / np.maximum(np.array([row["std"] for row in fit]), 1e-6) ** 2
    A = np.column_stack((np.ones_like(x), x))
    cov = np.linalg.inv(A.T @ (A * w[:, None]))
    coef = cov @ (A.T @ (w * y))
    resid = y - A @ coef
    dof = max(len(fit) - 2, 1)
    scale = max(float((w * resid**2).sum()) / dof, 1.0)  # widen by the misfit between bands
    return rows, Estimate(float(coef[1]), float(np.sqrt(cov[1, 1] * scale)), len(fit))


def _tail_fit(scans: list[Scan], core: float, seed: int) -> tuple[Estimate, float]:
    """EM for the weight and sigma of the wide component of residuals z ~ (1 - w) N(0, core^2) +
    w N(0, wide^2), on triples at 1-4 m with |z| < TAIL_WINDOW core; bootstrap over scans for w."""
    zs, blk = [], []
    for k, s in enumerate(scans):
        z, _, _ = scan_residuals(s, max(s.range_min, NOISE_BAND_M[0]), min(s.range_max, NOISE_BAND_M[1]))
        zs.append(z)
        blk.append(np.full(z.size, k))
    if not zs or core <= 0:
        return Estimate(0.0, float("nan"), 0), 0.0
    z, b = np.concatenate(zs), np.concatenate(blk)
    keep = np.abs(z - np.median(z)) < TAIL_WINDOW * core
    z, b = z[keep] - np.median(z[keep]), b[keep]
    if z.size < 100:
        return Estimate(0.0, float("nan"), int(z.size)), 0.0
    w, wide = 0.1, 3.0 * core
    for _ in range(100):
        p_core = (1 - w) * np.exp(-0.5 * (z / core) ** 2) / core
        p_wide = w * np.exp(-0.5 * (z / wide) ** 2) / wide
        resp = p_wide / np.maximum(p_core + p_wide, 1e-300)
        w_new = float(resp.mean())
        wide_new = float(np.sqrt((resp * z * z).sum() / max(resp.sum(), 1e-12)))
        done = abs(w_new - w) < 1e-6 and abs(wide_new - wide) < 1e-9
        w, wide = w_new, max(wide_new, core)
        if done:
            break
    ids, inv = np.unique(b, return_inverse=True)
    per_scan = np.bincount(inv, weights=resp), np.bincount(inv).astype(float)
    std = _ratio(per_scan[0], per_scan[1], seed).std
    return Estimate(w, std, int(z.size)), wide


def _tail_clustering(scans: list[Scan], core: float, seed: int) -> Estimate:
    """P(a triple TAIL_CLUSTER_STEP strides on is in the tail | this one is), over scans (see
    LogCalibration.tail_clustering)."""
    if core <= 0:
        return Estimate(float("nan"), float("nan"), 0)
    both, first = np.zeros(len(scans)), np.zeros(len(scans))
    for k, s in enumerate(scans):
        z, _, centre = scan_residuals(s, max(s.range_min, NOISE_BAND_M[0]), min(s.range_max, NOISE_BAND_M[1]))
        if z.size == 0:
            continue
        d = TAIL_CLUSTER_STEP * interlace_stride(s.angle_increment)
        usable, tail = np.zeros(len(s), dtype=bool), np.zeros(len(s), dtype=bool)
        usable[centre] = True
        tail[centre] = np.abs(z) > TAIL_CLUSTER_SIGMAS * core
        pair = tail[:-d] & usable[d:]
        first[k] = np.count_nonzero(pair)
        both[k] = np.count_nonzero(pair & tail[d:])
    return _ratio(both, first, seed)


def _nan_clustering(scans: list[Scan], seed: int) -> Estimate:
    """P(the next beam is nan | this one is), over scans (see LogCalibration.nan_clustering)."""
    both, first = np.zeros(len(scans)), np.zeros(len(scans))
    for k, s in enumerate(scans):
        nan = missing_readings(s.ranges)
        first[k] = np.count_nonzero(nan[:-1])
        both[k] = np.count_nonzero(nan[:-1] & nan[1:])
    return _ratio(both, first, seed)


def calibrate_scans(scans: Iterable[Any], seed: int = 0) -> LogCalibration:
    """Measure the error model of the laser behind ``scans`` (Scans or records with ``.scan``).

    Raises:
        InputError: (an LmsbenchError and a ValueError; was a bare ValueError, found by fuzzing)
            for fewer than ``MIN_SCANS`` scans, ``scans`` that are no Scans or records, or a
            ``seed`` that is not a whole number >= 0.

    At most ``MAX_SCANS`` distinct scans (and ``MAX_KEPT_BEAMS`` beams: fewer scans when they have more
    than 361 beams) are used and ``MAX_READ`` items read, repeats included.
    """
    check_seed(seed)
    kept: list[Scan] = []
    repeated = kept_beams = 0
    for s in scans_of(scans):
        # A scan read twice is no second sample: a log whose every line came twice (written twice
        # over) was measured with each scan counted twice, its standard errors 1/sqrt(2) as large.
        if _repeats(s, kept[-1] if kept else None):
            repeated += 1
            if repeated + len(kept) >= MAX_READ:  # itertools.repeat(scan) was read for ever (fuzzing)
                break
            continue
        if kept_beams + s.ranges.size > MAX_KEPT_BEAMS:  # tested before keeping it: never more than the bound
            break
        kept.append(s)
        kept_beams += s.ranges.size
        if len(kept) >= MAX_SCANS or kept_beams >= MAX_KEPT_BEAMS or repeated + len(kept) >= MAX_READ:
            break
    if len(kept) < MIN_SCANS:
        # "got 1" for 50 copies of one scan: the count of distinct scans, not what was given
        got = (f"got {len(kept) + repeated} scans but only {len(kept)} distinct: {repeated} repeat the scan before "
               "them (same stamp, geometry and readings), which is no second sample") if repeated else f"got {len(kept)}"
        raise InputError(f"scans: calibrating needs at least {MIN_SCANS} distinct scans (standard errors are a "
                         f"bootstrap over scans), {got}")
    counts_n = np.bincount([len(s) for s in kept])
    n_beams = int(np.argmax(counts_n))
    inc = float(np.median([s.angle_increment for s in kept]))
    with np.errstate(invalid="ignore"):
        sample = np.concatenate([s.ranges[np.isfinite(s.ranges) & (s.ranges <= s.range_max)][::5] for s in kept])
    quantum = estimate_quantum(sample)
    units = "cm" if quantum >= METRES_PER_UNIT["cm"] - 1e-12 else "mm"
    # mm mode: readings from its maximum on are no echoes (_mm_mode_codes); then any finite reading
    # beyond the log's own range_max is out of limits, invalid (_beyond_range_max_invalid)
    kept = [_beyond_range_max_invalid(_mm_mode_codes(s) if units == "mm" else s) for s in kept]
    noise = estimate_range_noise(kept, *NOISE_BAND_M, seed=seed)
    sigma = noise.sigma_m if np.isfinite(noise.sigma_m) else 0.0
    bins, slope = _noise_bins(kept, quantum, seed)
    core = noise.sigma_observed_m if np.isfinite(noise.sigma_observed_m) else 0.0
    tail, tail_sigma = _tail_fit(kept, core, seed)
    clustering = _tail_clustering(kept, core, seed)
    cap = _max_reading(kept, quantum)
    c = np.array([_scan_counts(s.ranges, s.angle_increment, max(sigma, quantum / np.sqrt(12)), cap, quantum)
                  for s in kept])
    beams = c[:, 3]
    return LogCalibration(
        n_scans=len(kept), n_beams=n_beams, angle_increment=inc, range_max=float(kept[0].range_max),
        units=units, quantum_m=quantum, noise=noise, noise_bins=bins, noise_slope=slope,
        nan_rate=_ratio(c[:, 0], beams, seed), inf_rate=_ratio(c[:, 1], beams, seed),
        max_reading_rate=_ratio(c[:, 2], beams, seed), max_reading=cap,
        no_return_rate=_ratio(c[:, 5], c[:, 4], seed), outlier_rate=_ratio(c[:, 7], c[:, 6], seed),
        outlier_straight_rate=_ratio(c[:, 11], c[:, 10], seed),
        mixed_share=_ratio(c[:, 8], c[:, 8] + c[:, 9], seed),
        tail_share=tail, tail_sigma_m=float(tail_sigma), tail_clustering=clustering,
        nan_clustering=_nan_clustering(kept, seed), repeated_scans=repeated,
    )
