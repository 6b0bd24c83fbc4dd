"""Range noise and quantisation step of a laser scan or a whole log, from the data alone.

Method (no map, no poses, no knowledge of the scene):

- **Collinearity residual.** Three beams (bearings phi - d, phi, phi + d) that hit one
  straight face obey ``1/r0 = (1/r- + 1/r+) / (2 cos d)`` exactly, whatever the face's distance
  and incidence angle (for a line ``x cos a + y sin a = p``, ``1/r(phi) = cos(phi - a) / p``). The
  residual ``e = r0 - 2 cos d r- r+ / (r- + r+)`` of a noisy triple is, to first order,
  ``n0 - w- n- - w+ n+`` with ``w- = 2 cos d r+^2 / (r- + r+)^2`` (and symmetrically), so
  ``z = e / sqrt(1 + w-^2 + w+^2)`` has the standard deviation of one beam's range noise.
- **Robust scale.** Triples across depth steps, on corners and on curved surfaces are outliers
  of z: the scale starts from the median absolute deviation and is refined by a clipped
  standard deviation (2.5 sigma, iterated, corrected for the clipping of a Gaussian).
- **Quantisation.** The step is the largest of 10, 5, 2, 1, 0.5, 0.2, 0.1 mm on whose grid at
  least 99 % of the finite readings lie (0 = continuous). A reading rounded to a step q carries
  an extra error of variance q^2 / 12 (the geometry dithers it), so the Gaussian sigma is
  ``sqrt(s^2 - q^2 / 12)`` (Sheppard's correction) of the observed scale s.
- **Uncertainty.** A bootstrap over scans (blocks of beams within a single scan) of the clipped
  residuals, seeded, so the same data give the same interval.

Everything is in metres; scans follow REP-117 (+inf no return, nan invalid; both are skipped).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from .codes import real_numbers, real_vector
from .errors import InputError
from .finite import check_integer, check_number, check_seed, float_of, is_number
from .scan import Scan

QUANTUM_CANDIDATES_M = (0.01, 0.005, 0.002, 0.001, 0.0005, 0.0002, 0.0001)
QUANTUM_SHARE = 0.99  # share of finite readings that must sit on a step's grid
CLIP_SIGMAS = 2.5  # residuals beyond this many scales from the centre are outliers
# std of a unit Gaussian truncated at +-CLIP_SIGMAS: sqrt(1 - 2 c phi(c) / (2 Phi(c) - 1))
_CLIP_STD_FACTOR = float(np.sqrt(1 - 2 * CLIP_SIGMAS * np.exp(-CLIP_SIGMAS**2 / 2) / np.sqrt(2 * np.pi)
                                 / math.erf(CLIP_SIGMAS / np.sqrt(2))))
JUMP_FRACTION = 0.2  # a triple with |r+ - r-| > this x r0 straddles a depth step: not used
MIN_RANGE_M = 0.05  # readings nearer than this are not used
#: readings this far or farther are not used (m): no rangefinder measures them (``lms200.laser_geometry``'s
#: largest range_max), and a scan of 1e160 m readings (range_max 1e308) overflowed the triples' products,
#: RuntimeWarnings on stderr and an inf scale
MAX_USED_RANGE_M = 10_000.0
BOOTSTRAP_RESAMPLES = 200
SINGLE_SCAN_BLOCK = 30  # beams per bootstrap block when there is only one scan
MAX_TRIPLES = 4_000_000  # memory bound: triples beyond this many are not read
MAX_STRIDE = 2**31  # interlace_stride's cap: a subnormal beam step made it round(inf), an OverflowError


@dataclass(frozen=True)
class RangeNoise:
    """Range noise of a set of scans.

    Attributes:
        sigma_m: Gaussian range noise of one beam, 1 sigma (m), the quantisation removed.
        sigma_std_m: standard error of sigma_m (m), from the bootstrap.
        quantum_m: range quantisation step found in the data (m); 0.0 = continuous values.
        n_used: beam triples whose residual entered the estimate (after clipping).
        sigma_observed_m: scale of the residuals before the quantisation was removed (m).
        outlier_share: share of usable triples rejected by the clipping (corners, edges, curves).
        resolved: False when sigma_m is not distinguishable from zero (below twice its standard
            error, e.g. noise far below the quantisation step); sigma_m is then an upper bound.
    """

    sigma_m: float
    sigma_std_m: float
    quantum_m: float
    n_used: int
    sigma_observed_m: float
    outlier_share: float
    resolved: bool

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def estimate_quantum(ranges: np.ndarray) -> float:
    """The largest step of ``QUANTUM_CANDIDATES_M`` on whose grid at least 99 % of the finite
    readings (m) lie; 0.0 when none fits (continuous values) or nothing is finite. InputError for
    ``ranges`` that are not real numbers (text was numpy's ValueError)."""
    v = real_vector(ranges, "ranges", "m", finite=False)
    v = v[np.isfinite(v) & (v > 0)]
    if v.size == 0:
        return 0.0
    for q in QUANTUM_CANDIDATES_M:
        with np.errstate(over="ignore", invalid="ignore"):  # 1e308 / 1 mm: off the grid (nan), not a RuntimeWarning
            off = np.abs(v - np.rint(v / q) * q)
        if np.mean(off < q / 20) >= QUANTUM_SHARE:
            return float(q)
    return 0.0


def interlace_stride(angle_increment: float) -> int:
    """Beams between two of the same mirror turn: an LMS200 takes a 0.5 deg scan in two interlaced
    1 deg turns (0.25 deg: four), so neighbours come from poses 13 ms apart on a moving robot.
    InputError for an ``angle_increment`` that is no finite number in (0, 2 pi] rad (None was a
    TypeError, 0 an OverflowError)."""
    increment = check_number(angle_increment, "angle_increment", 0.0, 2 * math.pi, lo_open=True, unit="rad")
    return _stride(increment)


def _stride(increment: float) -> int:
    """:func:`interlace_stride` of a checked beam step."""
    return max(1, int(round(min(np.deg2rad(1.0) / increment, MAX_STRIDE)))) if increment < np.deg2rad(0.99) else 1


def line_residuals(ranges: np.ndarray, angle_increment: float, range_min: float = 0.0,
                   range_max: float = np.inf, stride: int | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalised collinearity residuals of every usable triple of beams (i - k, i, i + k).

    Args:
        ranges: (n,) ranges of one scan (m), REP-117 special values allowed.
        angle_increment: bearing step between beams (rad).
        range_min, range_max: readings outside [max(range_min, MIN_RANGE_M), range_max) are
            not used, nor readings of MAX_USED_RANGE_M (10 km) or more.
        stride: k; default :func:`interlace_stride` (beams of one mirror turn, so the robot's
            motion between interlaced turns is not taken for noise).

    Returns:
        z: residual of each usable triple scaled to one beam's noise (m);
        r0: range of its middle beam (m);
        centre: index of its middle beam.

    Raises:
        InputError: ``ranges`` that are no 1-D array of real numbers (text was numpy's ValueError),
            an ``angle_increment`` that is no finite number in (0, 2 pi] rad, a ``range_min`` that
            is no finite number >= 0 m or a ``range_max`` no number >= 0 m (None was a TypeError), a
            ``stride`` that is no integer >= 1 (0 or -1 was numpy's broadcast error, 2.5 taken as 2).
    """
    r = np.asarray(real_numbers(ranges), dtype=np.float64)
    if r.ndim != 1:
        raise InputError(f"ranges: must be 1-D (the ranges of one scan, m), got shape {r.shape}")
    increment = check_number(angle_increment, "angle_increment", 0.0, 2 * math.pi, lo_open=True, unit="rad")
    range_min = check_number(range_min, "range_min", 0.0, math.inf, unit="m")
    range_max = check_number(range_max, "range_max", 0.0, math.inf, unit="m", finite=False)
    k = _stride(increment) if stride is None else check_integer(stride, "stride", 1, what="(beams)")
    return _line_residuals(r, increment, range_min, range_max, k)


def _line_residuals(r: np.ndarray, angle_increment: float, range_min: float, range_max: float, k: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`line_residuals` of checked arguments."""
    if r.size < 2 * k + 1:
        empty = np.zeros(0)
        return empty, empty, np.zeros(0, dtype=np.int64)
    lo = max(range_min, MIN_RANGE_M)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= lo) & (r < min(range_max, MAX_USED_RANGE_M))
    rm, r0, rp = r[: -2 * k], r[k:-k], r[2 * k :]
    use = ok[: -2 * k] & ok[k:-k] & ok[2 * k :]
    with np.errstate(invalid="ignore"):
        use &= np.abs(rp - rm) <= JUMP_FRACTION * r0
    idx = np.flatnonzero(use)
    rm, r0, rp = rm[idx], r0[idx], rp[idx]
    c2 = 2.0 * np.cos(k * angle_increment)
    q = 1.0 / (rm + rp)  # one division a triple (``features.sensor.engine`` computes it in this order)
    q2 = q * q
    e = r0 - c2 * rm * rp * q
    wm, wp = c2 * (rp * rp) * q2, c2 * (rm * rm) * q2
    z = e / np.sqrt(1.0 + wm * wm + wp * wp)
    return z, r0, idx + k


def scan_residuals(scan: Scan, range_min: float, range_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`line_residuals` of a Scan (whose geometry the Scan checked) between ``range_min`` and
    ``range_max`` (numbers, m) at its interlace stride, without the argument checks: this module's
    estimators and ``lms200.calibration`` call it once a scan."""
    return _line_residuals(scan.ranges, scan.angle_increment, range_min, range_max, _stride(scan.angle_increment))


def robust_scale(z: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(centre, scale, kept mask) of residuals: MAD start, then iterated CLIP_SIGMAS clipping with the
    clipped Gaussian's standard deviation corrected back to sigma. InputError for ``z`` that are not
    real numbers (text was numpy's ValueError)."""
    if not (isinstance(z, np.ndarray) and z.dtype == np.float64 and z.ndim == 1):  # the estimators' own: no copy
        z = real_vector(z, "z", "residuals, m", finite=False)
    if z.size == 0:
        return 0.0, float("nan"), np.zeros(0, dtype=bool)
    m = float(np.median(z))
    s = 1.4826 * float(np.median(np.abs(z - m)))
    if s <= 0:  # more than half the residuals identical (coarse quantisation): start from the spread
        s = float(np.std(z)) or 1e-12
    keep = np.ones(z.size, dtype=bool)
    for _ in range(50):
        new_keep = np.abs(z - m) <= CLIP_SIGMAS * s
        kz = z[new_keep]
        if kz.size < 2:
            break
        m, s_new = float(kz.mean()), float(kz.std()) / _CLIP_STD_FACTOR
        converged = np.array_equal(new_keep, keep) and abs(s_new - s) <= 1e-9 * max(s, 1e-12)
        keep, s = new_keep, s_new
        if converged:
            break
    return m, s, keep


def scans_of(scans: Scan | Iterable[Any], name: str = "scans") -> Iterator[Scan]:
    """The Scans of ``scans`` (one Scan, or an iterable of Scans or of records with ``.scan``),
    one at a time; InputError naming ``name`` for what is not iterable and the index of an item
    that is no Scan. Found by fuzzing the Python API: None or a number was Python's "object is not
    iterable", a text or an array of ranges an AttributeError ("no attribute 'ranges'") deep in
    the estimators (this module's, ``features.noise_estimate``'s and ``calibrate_scans``)."""
    if isinstance(scans, Scan):
        yield scans
        return
    if isinstance(scans, (str, bytes)) or not isinstance(scans, Iterable):
        raise InputError(f"{name}: must be an lms200.Scan or an iterable of Scans or records, got {type(scans).__name__}")
    for i, item in enumerate(scans):
        scan = getattr(item, "scan", item)
        if not isinstance(scan, Scan):
            raise InputError(f"{name}[{i}]: must be an lms200.Scan or a record with .scan, got {type(item).__name__}")
        yield scan


def estimate_range_noise(scans: Scan | Iterable[Any], min_range: float = 0.0,
                         max_range: float = np.inf, seed: int = 0) -> RangeNoise:
    """Range noise sigma (m), its standard error and the quantisation step of some scans.

    Args:
        scans: one Scan, or an iterable of Scans or of records with ``.scan`` (a log reader).
        min_range, max_range: only triples whose readings lie in [min_range, max_range) (m),
            e.g. to measure the noise at a range band.
        seed: seed of the bootstrap (the estimate itself does not depend on it).

    Returns:
        A :class:`RangeNoise`. With fewer than 10 usable triples sigma_m is nan.
    """
    check_seed(seed)
    for name, value in (("min_range", min_range), ("max_range", max_range)):  # None was a TypeError deep inside
        number = float_of(value, name, InputError) if is_number(value) else math.nan
        if math.isnan(number) or number < 0:
            raise InputError(f"{name}: must be a number >= 0 (m; max_range may be inf), got {value!r}")
    if not min_range < max_range:  # an empty band: sigma_m was nan, silently (max_range 0, min_range inf)
        raise InputError(f"min_range, max_range: the band [min_range, max_range) is empty, got [{min_range!r}, {max_range!r})")
    zs: list[np.ndarray] = []
    finite: list[np.ndarray] = []
    total = 0
    for scan in scans_of(scans):
        z, _, _ = scan_residuals(scan, max(scan.range_min, min_range), min(scan.range_max, max_range))
        r = scan.ranges
        with np.errstate(invalid="ignore"):  # readings beyond range_max are out of limits, no measurement
            measured = r[np.isfinite(r) & (r <= scan.range_max)]
        finite.append(measured[::7].astype(np.float64))  # a thinned sample is plenty for the grid
        zs.append(z.astype(np.float32))
        total += z.size
        if total >= MAX_TRIPLES:
            break
    quantum = estimate_quantum(np.concatenate(finite)) if finite else 0.0
    single = len(zs) == 1
    z_all = np.concatenate(zs).astype(np.float64) if zs else np.zeros(0)
    if single:
        blocks = np.arange(z_all.size) // SINGLE_SCAN_BLOCK
    else:
        blocks = np.repeat(np.arange(len(zs)), [z.size for z in zs])
    if z_all.size < 10:
        return RangeNoise(float("nan"), float("nan"), quantum, int(z_all.size), float("nan"), float("nan"), False)
    m, s_obs, keep = robust_scale(z_all)
    sigma = _remove_quantisation(s_obs, quantum)
    s_boot = _bootstrap_scale(z_all[keep], blocks[keep], seed)
    if sigma > 0:
        sigma_std = s_obs * s_boot / sigma
    else:  # the noise is below the quantisation's share: report the bound's spread
        sigma_std = s_boot
    return RangeNoise(
        sigma_m=float(sigma),
        sigma_std_m=float(sigma_std),
        quantum_m=quantum,
        n_used=int(keep.sum()),
        sigma_observed_m=float(s_obs),
        outlier_share=float(1.0 - keep.mean()),
        resolved=bool(sigma > 2 * sigma_std),
    )


def _remove_quantisation(scale: float, quantum: float) -> float:
    """Sheppard's correction: the Gaussian sigma under an observed scale with a rounding step."""
    return float(np.sqrt(max(scale**2 - quantum**2 / 12.0, 0.0)))


def _bootstrap_scale(z: np.ndarray, blocks: np.ndarray, seed: int) -> float:
    """Standard error of the clipped scale, resampling whole blocks (scans) with replacement."""
    ids, inverse = np.unique(blocks, return_inverse=True)
    nb = ids.size
    if nb < 2:
        return float("nan")
    cnt = np.bincount(inverse, minlength=nb).astype(np.float64)
    s1 = np.bincount(inverse, weights=z, minlength=nb)
    s2 = np.bincount(inverse, weights=z * z, minlength=nb)
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, nb, size=(BOOTSTRAP_RESAMPLES, nb))
    n, a, b = cnt[pick].sum(1), s1[pick].sum(1), s2[pick].sum(1)
    var = np.maximum(b / n - (a / n) ** 2, 0.0)
    return float(np.std(np.sqrt(var) / _CLIP_STD_FACTOR, ddof=1))
