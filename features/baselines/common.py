"""Shared pieces of the vectorised Cartesian baselines (``hough``, ``ransac``): points, batched
least-squares line fits, Lines, and the FeatureSet with the Cartesian corner step
(``engine.corners``, shared with split_merge and iepf).

Everything works on the compacted arrays of valid beams (``idx`` = beam indices, ``x``, ``y`` in the
sensor frame, metres). Line fits are batched over many index ranges at once with prefix sums, so a
fit costs O(1) per range whatever its length (the total-least-squares fit of Arras & Siegwart 1997,
the one used by every algorithm in Nguyen et al. 2007).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lms200 import Scan

from lms200.angles import wrap
from ..types import Corners, FeatureSet, Lines
from . import checks, engine


@dataclass(frozen=True)
class Points:
    """Valid beams of a scan in Cartesian form (sensor frame)."""

    idx: np.ndarray  # beam index of each valid point
    x: np.ndarray  # m
    y: np.ndarray  # m
    r: np.ndarray  # range, m
    bearing: np.ndarray  # rad
    no_return: np.ndarray  # number of +inf (no-return) beams before each point's beam


def valid_points(scan: Scan) -> Points:
    """The valid beams of ``scan`` (REP-117: +inf and nan dropped) as Cartesian points."""
    valid = scan.valid
    idx = np.flatnonzero(valid)
    r = scan.ranges[idx]
    b = scan.angles[idx]
    no_return = np.cumsum(np.isposinf(scan.ranges))[idx]
    return Points(idx, r * np.cos(b), r * np.sin(b), r, b, no_return)


def open_between(no_return: np.ndarray) -> np.ndarray:
    """For consecutive points (their ``Points.no_return`` counts): whether a no-return (+inf) beam
    lies between them. Such a beam saw open space (a doorway, or beyond range), so the surface
    is not continuous there and no segment is bridged across it; invalid (nan or out-of-limits)
    beams carry no information and up to ``max_skip - 1`` of them may be stepped over."""
    return np.diff(no_return) > 0


def breakpoint_distance(r_prev: np.ndarray, dphi: np.ndarray, lambda_rad: float, sigma: float) -> np.ndarray:
    """The adaptive breakpoint distance (Borges & Aldon 2004, m): ``D_max = r_{n-1} sin(dphi) /
    sin(lambda - dphi) + 3 sigma`` for a point at range ``r_prev`` (m) and the bearing step
    ``dphi`` (rad) to its neighbour; <= 0 or nan where dphi >= lambda (never connected)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return r_prev * np.sin(dphi) / np.sin(lambda_rad - dphi) + 3.0 * sigma


def fit_moments(n, sx, sy, sxx, syy, sxy) -> tuple[np.ndarray, ...]:
    """Total-least-squares line from raw sums (Arras & Siegwart 1997): the normal angle minimising
    ``sum (x cos a + y sin a - rho)^2``. Returns rho (>= 0), alpha, n, centroid x, y, scatter along
    the line and the residual sum of squares across it."""
    mx, my = sx / n, sy / n
    cxx = sxx - n * mx * mx
    cyy = syy - n * my * my
    cxy = sxy - n * mx * my
    alpha = 0.5 * np.arctan2(-2.0 * cxy, cyy - cxx)
    rho = mx * np.cos(alpha) + my * np.sin(alpha)
    alpha = wrap(np.where(rho < 0, alpha + np.pi, alpha))
    rho = np.abs(rho)
    c, s = np.cos(alpha), np.sin(alpha)
    across = np.maximum(cxx * c * c + cyy * s * s + 2 * cxy * s * c, 0.0)
    along = np.maximum(cxx + cyy - across, 1e-12)
    return rho, alpha, n, mx, my, along, across


def fit_groups(x: np.ndarray, y: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, ...]:
    """Least-squares lines of consecutive groups of points starting at ``offsets`` (as fit_moments)."""
    red = np.add.reduceat
    n = np.diff(np.concatenate((offsets, [x.size]))).astype(float)
    return fit_moments(n, red(x, offsets), red(y, offsets), red(x * x, offsets), red(y * y, offsets),
                       red(x * y, offsets))


def trim_ends(x: np.ndarray, y: np.ndarray, offsets: np.ndarray, rho: np.ndarray, alpha: np.ndarray,
              tol: float, keep: int) -> tuple[np.ndarray, np.ndarray]:
    """For groups of points (starting at ``offsets`` in the concatenated ``x``, ``y``) fitted by
    lines: the index range [lo, hi] (into the concatenation) left after dropping the leading and
    trailing points farther than ``tol`` (m) from the line. Such end points belong to a small
    neighbouring face (a door frame, a pillar's edge) that the split threshold let in; they tilt
    the fit. Never trims a group below ``keep`` points (then it is left whole)."""
    sizes = np.diff(np.concatenate((offsets, [x.size])))
    g = np.repeat(np.arange(offsets.size), sizes)
    good = np.abs(x * np.cos(alpha)[g] + y * np.sin(alpha)[g] - rho[g]) <= tol
    idx = np.arange(x.size)
    ends = offsets + sizes - 1
    lo = np.minimum.reduceat(np.where(good, idx, x.size), offsets)
    hi = np.maximum.reduceat(np.where(good, idx, -1), offsets)
    whole = (hi - lo + 1) < keep
    return np.where(whole, offsets, lo), np.where(whole, ends, hi)


def straight_enough(x: np.ndarray, y: np.ndarray, offsets: np.ndarray, rho: np.ndarray,
                    alpha: np.ndarray, z_min: float, dead_zone: float) -> np.ndarray:
    """Wald-Wolfowitz runs test (Wald & Wolfowitz 1940) on the signs of each group's residuals
    from its fitted line: noise on a straight surface gives random signs, an arc fitted by a line
    (a pillar, a curved wall) gives a few long runs (+ - +). Groups start at ``offsets`` in the
    concatenated ``x``, ``y``; a group fails when its runs are ``z_min`` standard deviations fewer
    than expected. Residuals within ``dead_zone`` (m; the callers use sigma / 2) carry no sign, so
    the small tilt one stray point gives an otherwise exact fit is no evidence of curvature.
    Returns a mask of the groups that pass (``z_min <= 0`` passes all)."""
    n_groups = offsets.size
    if z_min <= 0 or n_groups == 0:
        return np.ones(n_groups, dtype=bool)
    sizes = np.diff(np.concatenate((offsets, [x.size])))
    g = np.repeat(np.arange(n_groups), sizes)
    res = x * np.cos(alpha)[g] + y * np.sin(alpha)[g] - rho[g]
    signed = np.abs(res) > dead_zone
    g = g[signed]
    positive = res[signed] > 0
    sizes = np.bincount(g, minlength=n_groups)
    offsets = np.cumsum(sizes) - sizes
    if positive.size == 0:
        return np.ones(n_groups, dtype=bool)
    change = np.empty(positive.size, dtype=np.int64)
    change[0] = 0
    change[1:] = positive[1:] != positive[:-1]
    change[offsets[sizes > 0]] = 0  # no run boundary across groups
    runs = 1 + np.bincount(g, weights=change, minlength=n_groups)
    n = sizes.astype(float)
    n_pos = np.bincount(g, weights=positive, minlength=n_groups)
    prod = 2.0 * n_pos * (n - n_pos)
    with np.errstate(divide="ignore", invalid="ignore"):
        expected = 1.0 + prod / n
        var = prod * (prod - n) / (n * n * (n - 1.0))  # Wald & Wolfowitz's variance of the runs
        z = (runs - expected) / np.sqrt(var)
    return ~(var > 0) | (z >= -z_min)


def contiguous_runs(pts: Points, pos: np.ndarray, angle_increment: float, lambda_rad: float,
                    sigma: float, max_skip: int) -> np.ndarray:
    """Split sorted point positions ``pos`` (inliers of one line) into runs that are contiguous in
    the scan: at most ``max_skip`` - 1 points skipped between neighbours, no no-return (+inf) beam
    between them (``open_between``), and neighbours no farther apart than the adaptive breakpoint
    distance (Borges & Aldon 2004) for their bearing step.
    Returns the offsets of the runs' starts into ``pos``."""
    if pos.size < 2:
        return np.zeros(min(pos.size, 1), dtype=np.int64)
    skip = np.diff(pos)
    dphi = np.diff(pts.idx[pos]) * angle_increment
    gap = np.hypot(np.diff(pts.x[pos]), np.diff(pts.y[pos]))
    dmax = breakpoint_distance(pts.r[pos[:-1]], dphi, lambda_rad, sigma)
    cut = (skip > max_skip) | (gap > dmax) | (dmax <= 0) | open_between(pts.no_return[pos])
    return np.concatenate(([0], np.flatnonzero(cut) + 1))


def point_line_distance(x: np.ndarray, y: np.ndarray, rho: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Absolute perpendicular distance of points from lines (broadcasting; m)."""
    return np.abs(x * np.cos(alpha) + y * np.sin(alpha) - rho)


def build_lines(
    pts: Points,
    start: np.ndarray,
    end: np.ndarray,
    rho: np.ndarray,
    alpha: np.ndarray,
    n: np.ndarray,
    mx: np.ndarray,
    my: np.ndarray,
    along: np.ndarray,
    sigma: float,
) -> Lines:
    """The Lines (arrays) of fitted ranges ``start..end`` (positions into ``pts``), sorted by beam.

    Endpoints are the projections of the first and last points on the line. The (rho, alpha)
    covariance is that of a total-least-squares fit under isotropic noise ``sigma`` (m):
    var(alpha) = s^2/S, var(rho) = s^2/n + t^2 s^2/S, cov = t s^2/S, with t the centroid's
    coordinate along the line and S the scatter along it.
    """
    if start.size == 0:
        return Lines.empty()
    order = np.argsort(pts.idx[start], kind="stable")
    c, s = np.cos(alpha), np.sin(alpha)
    # projections of the first / last points onto their lines
    x0, y0 = pts.x[start], pts.y[start]
    x1, y1 = pts.x[end], pts.y[end]
    d0 = x0 * c + y0 * s - rho
    d1 = x1 * c + y1 * s - rho
    px0, py0 = x0 - d0 * c, y0 - d0 * s
    px1, py1 = x1 - d1 * c, y1 - d1 * s
    t = -mx * s + my * c
    s2 = sigma * sigma
    var_a = s2 / along
    var_r = s2 / n + t * t * var_a
    cov_ra = t * var_a
    o = order
    cov = np.column_stack((var_r[o], cov_ra[o], cov_ra[o], var_a[o]))
    return Lines.of(rho[o], alpha[o], np.column_stack((px0[o], py0[o])), np.column_stack((px1[o], py1[o])),
                    cov, pts.idx[start][o], pts.idx[end][o], n[o])


@dataclass(frozen=True)
class CornerConfig:
    """The shared Cartesian corner step: corners where consecutive segments meet (Castellanos et al.
    1996; computed by ``engine.corners``). Two lines neighbouring in beam order make a corner when
    - they are at most ``max_gap_beams`` (6) apart in beam order,
    - their facing end points are connected in the scan: no farther apart than the adaptive
      breakpoint distance for that bearing step (Borges & Aldon 2004, ``breakpoint_lambda`` =
      10 deg in rad, ``sigma`` = 5 mm), so an occlusion's depth jump is no corner,
    - the direction turns by at least ``min_turn`` (30 deg in rad: interior angle <= 150 deg), and
    - the lines' intersection lies within ``max_distance`` (0.15 m: several times the end-point
      scatter at 5 mm noise) plus the gap between the facing end points of each of them (far
      away, the beams dropped at a corner leave a gap of tens of centimetres).

    Raises:
        ConfigError: naming the field, when a value cannot work.
    """

    min_turn: float = float(np.deg2rad(30.0))  # rad
    max_gap_beams: int = 6
    max_distance: float = 0.15  # m
    breakpoint_lambda: float = float(np.deg2rad(10.0))  # rad
    sigma: float = 0.005  # m

    def __post_init__(self) -> None:
        checks.angle("min_turn", self.min_turn, np.pi, low_open=False)
        checks.integer("max_gap_beams", self.max_gap_beams, 1)
        # 1e300: any turn of neighbours a corner, however far; 0: contact within the beams' gap only (the
        # rule is dist <= max_distance + gap), as before the bound
        checks.between("max_distance", self.max_distance, 0.0, checks.MAX_BAND_M, "m")
        checks.breakpoint_angle("breakpoint_lambda", self.breakpoint_lambda)
        checks.noise_sigma("sigma", self.sigma)
        checks.plain_numbers(self)  # as the methods' own fields: a Fraction sigma was kept as given
        object.__setattr__(self, "_params", engine.CornerParams(
            float(self.min_turn), checks.beams(self.max_gap_beams), float(self.max_distance), float(self.breakpoint_lambda),
            float(self.sigma)))

    @property
    def params(self) -> engine.CornerParams:
        """The kernel's typed record of this config (built once, in ``__post_init__``)."""
        return self._params


def feature_set(rows: Lines, corner_cfg: CornerConfig, method: str, angle_increment: float) -> FeatureSet:
    """FeatureSet of beam-ordered lines plus the shared corner step (``engine.corners``)."""
    if len(rows) < 2:
        return FeatureSet.of(rows, Corners.empty(), method)
    cv, cb = engine.corners(rows.values, rows.beams, angle_increment, corner_cfg.params)
    return FeatureSet.of(rows, Corners(cv, cb), method)
