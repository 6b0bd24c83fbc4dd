"""Split-and-merge and iterative end-point fit (methods "split_merge" and "iepf"), and the
Cartesian corner step of every baseline: the one implementation, compiled with numba.

Steps of ``segment_lines``, as loops over the valid points of one scan: adaptive breakpoints cut
the scan into clusters (Borges & Aldon 2004); each cluster is split depth-first while some point
lies farther than the threshold from its least-squares line (split_merge, Pavlidis & Horowitz
1974) or from its chord (iepf, Duda & Hart 1973 / Douglas & Peucker 1973), at the point farthest
from the chord; neighbours sharing a split point merge, pass by pass, where their joint fit keeps
an RMS residual within merge_rms (the pairs with a locally smallest merged residual first); split
points shared by two neighbours are dropped from both; end points off the fitted line are trimmed
(twice, refitting); segments of enough points and length become lines with the covariance of a
total-least-squares fit (Arras & Siegwart 1997).

One module on purpose: numba's on-disk cache is invalidated by the modification time of the file
that defines a function, not of the files of the functions it calls, so kernels that call each
other live in one file. Nor does the cache see the compiler's flags (``features.jit``): a change of
them needs a change of this file. The kernels run without the GIL (``extract_many``'s threads).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..jit import inline_kernel, kernel
from ..jit import wrap_one as wrap  # the project's one wrap (lms200.angles), compiled
from ..rows import append_rows, finish_rows, new_rows

TRIM_TOL_SIGMA = 3.0  # end points farther than this many sigma from the fitted line are trimmed
BREAK_SIGMA = 3.0  # the adaptive breakpoint distance's noise margin, in sigma


class SplitParams(NamedTuple):
    """The fields of a ``SplitMergeConfig`` / ``IepfConfig`` as ``segment_lines`` reads them."""

    sigma: float  # range noise, m
    breakpoint_lambda: float  # rad
    split_threshold: float  # m
    merge_rms: float  # m
    min_points: int
    min_length: float  # m
    max_skip: int  # beams
    runs_z: float
    chord: bool  # split at the chord (iepf) instead of the least-squares line (split_merge)


class CornerParams(NamedTuple):
    """The fields of a ``CornerConfig`` as ``corners`` reads them."""

    min_turn: float  # rad
    max_gap_beams: int
    max_distance: float  # m
    breakpoint_lambda: float  # rad
    sigma: float  # m

@kernel
def breakpoint_distance(r_prev: float, dphi: float, lam: float, sigma: float) -> float:
    """The adaptive breakpoint distance (Borges & Aldon 2004, m): r sin(dphi) / sin(lambda - dphi)
    + 3 sigma for a point at range r_prev and the bearing step dphi to its neighbour (rad);
    <= 0 or nan where dphi >= lambda (never connected)."""
    return r_prev * math.sin(dphi) / math.sin(lam - dphi) + BREAK_SIGMA * sigma


@kernel
def npmax(a: float, b: float) -> float:
    """np.maximum for two floats (nan propagates)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a >= b else b


class Fit(NamedTuple):
    """A total-least-squares line fit of a range of points (``fit_range``)."""

    rho: float  # m, >= 0
    alpha: float  # rad, (-pi, pi]
    cos: float  # cos(alpha)
    sin: float  # sin(alpha)
    n: float  # points
    mx: float  # centroid, m
    my: float
    along: float  # scatter along the line, m^2
    across: float  # residual sum of squares across it, m^2


@inline_kernel
def moments(sx, sy, sxx, syy, sxy, s, e):  # noqa: ANN001, ANN201
    """(n, mean x, mean y, cxx, cyy, cxy) of points s..e (inclusive) from prefix sums: the count,
    centroid (m) and central second moments (m^2) every fit below starts from."""
    lo, hi = s, e + 1
    n = float(hi - lo)
    mx = (sx[hi] - sx[lo]) / n
    my = (sy[hi] - sy[lo]) / n
    cxx = (sxx[hi] - sxx[lo]) - n * mx * mx
    cyy = (syy[hi] - syy[lo]) - n * my * my
    cxy = (sxy[hi] - sxy[lo]) - n * mx * my
    return n, mx, my, cxx, cyy, cxy


@inline_kernel
def fit_range(sx, sy, sxx, syy, sxy, s, e):  # noqa: ANN001, ANN201
    """Total-least-squares line ``x cos(alpha) + y sin(alpha) = rho`` of points s..e (inclusive)
    from prefix sums (Arras & Siegwart 1997), a Fit."""
    n, mx, my, cxx, cyy, cxy = moments(sx, sy, sxx, syy, sxy, s, e)
    alpha = 0.5 * math.atan2(-2.0 * cxy, cyy - cxx)
    c, si = math.cos(alpha), math.sin(alpha)
    rho = mx * c + my * si
    turned = rho < 0
    if turned:
        alpha = alpha + math.pi
    wrapped = wrap(alpha)
    if turned or wrapped != alpha:  # else cos and sin are those of alpha already
        c, si = math.cos(wrapped), math.sin(wrapped)
    rho = abs(rho)
    across = npmax(cxx * c * c + cyy * si * si + 2 * cxy * si * c, 0.0)
    along = npmax(cxx + cyy - across, 1e-12)
    return Fit(rho, wrapped, c, si, n, mx, my, along, across)


@inline_kernel
def split_line(sx, sy, sxx, syy, sxy, s, e):  # noqa: ANN001, ANN201
    """(cos, sin, rho) of the total-least-squares line of points s..e: ``fit_range``'s line to
    rounding, without its arctangent, cosine and sine (the split test needs only distances to
    it): alpha = atan2(-2 cxy, cyy - cxx) / 2 by the half-angle formulas, each in its stable form."""
    n, mx, my, cxx, cyy, cxy = moments(sx, sy, sxx, syy, sxy, s, e)
    y2 = -2.0 * cxy  # r (sin 2 alpha, cos 2 alpha)
    x2 = cyy - cxx
    r = math.sqrt(x2 * x2 + y2 * y2)
    if not r > 0.0:  # no direction (atan2(0, 0) = 0), or nan
        c, si = 1.0, 0.0
    elif x2 >= 0.0:  # |alpha| <= pi / 4: cos from 1 + cos 2 alpha, sin from sin 2 alpha / (2 cos)
        c = math.sqrt((r + x2) / (2.0 * r))
        si = y2 / (2.0 * r * c)
    else:  # the other way round (alpha in (-pi/2, pi/2], cos >= 0, sin with the sign of sin 2 alpha)
        si = math.copysign(math.sqrt((r - x2) / (2.0 * r)), y2)
        c = y2 / (2.0 * r * si)
    rho = mx * c + my * si
    if rho < 0:
        return -c, -si, -rho
    return c, si, rho


@inline_kernel
def exact_rms(sx, sy, sxx, syy, sxy, s, e):  # noqa: ANN001, ANN201
    """The RMS residual (m) of the total-least-squares line of points s..e (``fit_range``)."""
    f = fit_range(sx, sy, sxx, syy, sxy, s, e)
    return math.sqrt(f.across / f.n)


@inline_kernel
def merged_rms(sx, sy, sxx, syy, sxy, s, e):  # noqa: ANN001, ANN201
    """(``exact_rms`` of points s..e to rounding, a bound of its difference to it), for finite
    coordinates: the residual sum of squares as the smaller eigenvalue of the scatter matrix,
    (cxx + cyy) / 2 - sqrt(((cxx - cyy) / 2)^2 + cxy^2), without fit_range's arctangent, cosine
    and sine. Both sums of squares come from the same moments and round within ~10 ulp of
    |cxx| + |cyy| + 2 |cxy| (the angle's error enters squared), far within the 1e-12 of it
    allowed; |sqrt(a) - sqrt(b)| <= sqrt(|a - b|) carries that to the root."""
    n, mx, my, cxx, cyy, cxy = moments(sx, sy, sxx, syy, sxy, s, e)
    h = 0.5 * (cxx - cyy)
    across = npmax(0.5 * (cxx + cyy) - math.sqrt(h * h + cxy * cxy), 0.0)
    rms = math.sqrt(across / n)
    return rms, math.sqrt(1e-12 * (abs(cxx) + abs(cyy) + 2.0 * abs(cxy)) / n) + 1e-12 * rms + 1e-300


@inline_kernel
def trim(x, y, s, e, rho, c, si, tol, keep):  # noqa: ANN001, ANN201
    """The range s..e left after dropping the leading and trailing points farther than ``tol``
    (m) from the line x c + y si = rho (a small neighbouring face the split threshold let in);
    never below ``keep`` points (then s..e whole)."""
    lo = -1
    hi = -1
    for p in range(s, e + 1):
        if abs(x[p] * c + y[p] * si - rho) <= tol:
            if lo < 0:
                lo = p
            hi = p
    if lo < 0 or hi - lo + 1 < keep:
        return s, e
    return lo, hi


@inline_kernel
def straight_enough(x, y, s, e, rho, c, si, z_min, dead_zone) -> bool:  # noqa: ANN001
    """Wald-Wolfowitz runs test on the signs of the residuals of points s..e from their line
    x c + y si = rho: False when the runs are ``z_min`` std fewer than noise would give (an arc);
    residuals within ``dead_zone`` (m) carry no sign."""
    n_signed = 0
    n_pos = 0.0
    changes = 0.0
    prev = False
    for p in range(s, e + 1):
        res = x[p] * c + y[p] * si - rho
        if abs(res) > dead_zone:
            pos = res > 0
            if n_signed > 0 and pos != prev:
                changes += 1.0
            n_pos += 1.0 if pos else 0.0
            prev = pos
            n_signed += 1
    n = float(n_signed)
    runs = 1 + changes
    prod = 2.0 * n_pos * (n - n_pos)
    expected = 1.0 + prod / n
    var = prod * (prod - n) / (n * n * (n - 1.0))
    z = (runs - expected) / math.sqrt(var)
    return not (var > 0) or z >= -z_min


@kernel
def bearing_table(bearings):  # noqa: ANN001, ANN201
    """(cos, sin) of every beam's bearing (rad), computed once per scan geometry with the libm
    calls a kernel would make per beam (so the points are the same to the last bit)."""
    c = np.empty(bearings.size)
    s = np.empty(bearings.size)
    for i in range(bearings.size):
        c[i] = math.cos(bearings[i])
        s[i] = math.sin(bearings[i])
    return c, s


@kernel
def gap_exceeds(dx: float, dy: float, limit: float) -> bool:
    """hypot(dx, dy) > limit, decided as math.hypot decides it: from sqrt(dx^2 + dy^2) (a few
    times cheaper; within 3 ulp of hypot) unless that lies within 1e-12 of the limit, overflows,
    or the limit is nan, where hypot itself decides."""
    gap = math.sqrt(dx * dx + dy * dy)
    if not abs(gap - limit) > 1e-12 * abs(limit) or gap == np.inf:
        gap = math.hypot(dx, dy)
    return gap > limit


@inline_kernel
def length_at_least(dx: float, dy: float, limit: float) -> bool:
    """hypot(dx, dy) >= limit, decided as math.hypot decides it: from sqrt(dx^2 + dy^2) (within a
    few ulp of hypot; a libm call a line was ~3 % of split_merge's time) where dx^2 + dy^2 is a
    normal number and the root lies farther than 1e-12 of the limit from it; else hypot decides."""
    g2 = dx * dx + dy * dy
    if 1e-280 < g2 < np.inf:
        g = math.sqrt(g2)
        if abs(g - limit) > 1e-12 * abs(limit):
            return g >= limit
    return math.hypot(dx, dy) >= limit


@kernel
def disconnected(dx, dy, r_prev, sin_step, sin_rest, ratio, margin) -> bool:  # noqa: ANN001
    """Whether two neighbouring points (dx, dy) apart (m) are not connected: farther apart than the
    adaptive breakpoint distance D = r_prev sin_step / sin_rest + margin (``breakpoint_distance``),
    or D <= 0 or nan. Decided from squares and ``ratio`` = sin_step / sin_rest (no square root, no
    division; both sides within 1e-14 of hypot's and the quotient's) except within 1e-9 of the
    limit or outside the normal range of squares, where ``gap_exceeds`` and D itself decide: the
    decisions are those of ``math.hypot(dx, dy) > D or D <= 0``."""
    g2 = dx * dx + dy * dy
    lim = r_prev * ratio + margin
    lim2 = lim * lim
    if lim > 0 and 1e-280 < lim2 < np.inf and g2 < np.inf and abs(g2 - lim2) > 1e-9 * lim2:
        return g2 > lim2
    dmax = r_prev * sin_step / sin_rest + margin
    return gap_exceeds(dx, dy, dmax) or dmax <= 0


@kernel
def split_at_point(x, y, s, e, threshold, finite):  # noqa: ANN001, ANN201
    """``split_at`` of iepf where the end points s and e coincide (a closed ring: a 360 deg scan
    whose last beam repeats its first, which ``lms200.Scan`` takes), so that no chord joins them:
    the interior point farthest from that point (the first of equal ones) when it lies farther
    than ``threshold`` (m), else -1; -1 too when a distance is nan. (The chord's normal, divided by
    a length clamped at 1e-12 m, had a length near 0 there: every distance came out near 0, no
    ring was ever split, and iepf found no line in such a scan of a square room.)"""
    dmax = -1.0
    at = s
    for q in range(s + 1, e):
        d = math.hypot(x[q] - x[s], y[q] - y[s])
        if not finite and d != d:
            return -1
        if d > dmax:
            dmax = d
            at = q
    if not dmax > threshold:
        return -1
    return at


@inline_kernel
def split_at(x, y, s, e, threshold, cf, sf, rho_f, chord, finite):  # noqa: ANN001, ANN201
    """Where points s..e (e - s >= 2) split: the interior point farthest from the chord between the
    end points (the first of equal ones) when some point lies farther than ``threshold`` (m) from
    the chord (``chord``: iepf) or from the fitted line x cf + y sf = rho_f (split_merge; end
    points included); -1 when none does, or when a distance is nan (``finite``: none can be, the
    checks are skipped)."""
    dx, dy = x[e] - x[s], y[e] - y[s]
    chord_length = math.hypot(dx, dy)
    if chord and chord_length < 1e-12:  # the end points coincide: no chord, the point itself
        return split_at_point(x, y, s, e, threshold, finite)
    norm = npmax(chord_length, 1e-12)
    nx, ny = -dy / norm, dx / norm
    rho_c = nx * x[s] + ny * y[s]
    cmax = -1.0  # the end points count as -1 from the chord
    at = s
    if chord:
        dmax = -1.0
    else:
        d_s = abs(x[s] * cf + y[s] * sf - rho_f)
        d_e = abs(x[e] * cf + y[e] * sf - rho_f)
        dmax = max(d_s, d_e)
        if not finite and (d_s != d_s or d_e != d_e):
            return -1
    # two interleaved scans of the interior points (even and odd offsets), so that consecutive
    # points do not wait on each other's maximum; the first farthest point is the smaller index of
    # the two scans' on a tie; a nan distance (never a maximum) makes the whole answer -1
    cmax2, at2, dmax2 = cmax, at, dmax
    nan = False
    q = s + 1
    while q + 1 < e:
        dc = abs(x[q] * nx + y[q] * ny - rho_c)
        dc2 = abs(x[q + 1] * nx + y[q + 1] * ny - rho_c)
        d = dc if chord else abs(x[q] * cf + y[q] * sf - rho_f)
        d2 = dc2 if chord else abs(x[q + 1] * cf + y[q + 1] * sf - rho_f)
        if dc > cmax:
            cmax = dc
            at = q
        if dc2 > cmax2:
            cmax2 = dc2
            at2 = q + 1
        dmax = d if d > dmax else dmax
        dmax2 = d2 if d2 > dmax2 else dmax2
        if not finite:
            nan |= (dc != dc) | (d != d) | (dc2 != dc2) | (d2 != d2)
        q += 2
    if q < e:
        dc = abs(x[q] * nx + y[q] * ny - rho_c)
        d = dc if chord else abs(x[q] * cf + y[q] * sf - rho_f)
        if dc > cmax:
            cmax = dc
            at = q
        dmax = d if d > dmax else dmax
        if not finite:
            nan |= (dc != dc) | (d != d)
    if cmax2 > cmax or (cmax2 == cmax and at2 < at):
        at = at2
    if nan or not max(dmax, dmax2) > threshold:
        return -1
    return at


class Workspace(NamedTuple):
    """Scratch arrays of ``segment_lines`` and ``corners`` for scans of up to n beams, allocated once
    per call of ``extract_scan`` / ``extract_batch`` (``workspace``) and overwritten per scan."""

    idx: np.ndarray  # (n,) beam index of each valid point
    x: np.ndarray  # (n,) m
    y: np.ndarray  # (n,) m
    ends: np.ndarray  # (n,) the last point of each cluster
    sums: np.ndarray  # (5, n + 1) prefix sums of x, y, x^2, y^2, xy
    seg_s: np.ndarray  # (2n + 2,) first and last point of each segment
    seg_e: np.ndarray
    stack_s: np.ndarray  # (2n + 2,) the depth-first split stack
    stack_e: np.ndarray
    rms: np.ndarray  # (2n + 2,) merged RMS residual of each neighbour pair
    slack: np.ndarray  # (2n + 2,) its bound of the difference to fit_range's (0: fit_range's)
    src: np.ndarray  # (2n + 2,) the segment of the previous merge pass each one is (-1: merged)
    pick: np.ndarray  # (2n + 2,) bool
    sin_step: np.ndarray  # (min(max_skip, n) + 1,) sin(k increment) of the bearing steps k = 1 .. max_skip
    sin_rest: np.ndarray  # sin(lambda - k increment)
    ratio: np.ndarray  # sin_step / sin_rest: the breakpoint distance per metre of range
    lv: np.ndarray  # (n + 1, 10) the rows of features.types.Lines
    lb: np.ndarray  # (n + 1, 3)
    cv: np.ndarray  # (n + 1, 3) the rows of features.types.Corners
    cb: np.ndarray  # (n + 1, 3)


@kernel
def workspace(n, increment, p):  # noqa: ANN001, ANN201
    """The Workspace of scans of n beams, ``increment`` (rad) apart, extracted with the SplitParams
    ``p``: scratch arrays, and the sines of the breakpoint distance (``breakpoint_distance``) of the
    bearing steps a cluster may bridge (1 .. max_skip beams), computed once per call."""
    m = 2 * n + 2
    n_steps = min(p.max_skip, n) + 1
    sin_step = np.empty(n_steps)
    sin_rest = np.empty(n_steps)
    ratio = np.empty(n_steps)
    for step in range(1, n_steps):
        dphi = step * increment
        sin_step[step] = math.sin(dphi)
        sin_rest[step] = math.sin(p.breakpoint_lambda - dphi)
        ratio[step] = sin_step[step] / sin_rest[step]
    return Workspace(
        np.empty(n, np.int64), np.empty(n), np.empty(n), np.empty(n, np.int64), np.zeros((5, n + 1)),
        np.empty(m, np.int64), np.empty(m, np.int64), np.empty(m, np.int64), np.empty(m, np.int64), np.empty(m),
        np.empty(m), np.empty(m, np.int64), np.zeros(m, np.bool_), sin_step, sin_rest, ratio, np.empty((n + 1, 10)),
        np.empty((n + 1, 3), np.int64), np.empty((n + 1, 3)), np.empty((n + 1, 3), np.int64),
    )


@kernel
def segment_lines(ranges, cos_b, sin_b, range_lo, range_hi, p, ws):  # noqa: ANN001, ANN201
    """The lines of one scan (sensor frame) in beam order, written as the rows of
    ``features.types.Lines`` into ``ws.lv`` (values) and ``ws.lb`` (beams); returns their number.
    Beams with a range in [range_lo, range_hi] (m) and > 0 are valid; ``cos_b``, ``sin_b`` the beams'
    bearing cosines and sines (``bearing_table``); ``p`` a SplitParams; ``ws`` the Workspace of
    ``workspace(n, increment, p)`` with at least the scan's beams and the same increment and ``p``
    (its breakpoint sines hold them). The (rho, alpha) covariance is
    that of a total-least-squares fit under isotropic noise sigma: var(alpha) = s^2/S,
    var(rho) = s^2/n + t^2 s^2/S, cov = t s^2/S (t: the centroid's coordinate along the line,
    S: the scatter along it)."""
    sigma, threshold, merge_rms = p.sigma, p.split_threshold, p.merge_rms
    min_points, min_length, max_skip, runs_z, chord = p.min_points, p.min_length, p.max_skip, p.runs_z, p.chord
    n_beams = ranges.size
    # the valid points (Cartesian), the prefix sums of the fits (np.cumsum order) and the clusters'
    # ends, in one pass over the beams
    idx, x, y = ws.idx, ws.x, ws.y
    sx, sy, sxx, syy, sxy = ws.sums[0], ws.sums[1], ws.sums[2], ws.sums[3], ws.sums[4]  # [0] stays 0
    # the adaptive breakpoints in the same pass: a +inf beam between two points saw open space (a
    # doorway, beyond range): always a break; up to max_skip - 1 nan beams are bridged; ends[k]:
    # the last point of cluster k
    sin_step, sin_rest, ratio = ws.sin_step, ws.sin_rest, ws.ratio  # of the bearing steps a cluster may bridge
    margin = BREAK_SIGMA * sigma
    ends = ws.ends
    n_clusters = 0
    n_inf = 0
    n_pts = 0
    ax = ay = axx = ayy = axy = 0.0  # the running sums
    px = py = pr = 0.0  # the previous point and its range
    p_idx = p_inf = 0
    for i in range(n_beams):
        d = ranges[i]
        if d >= range_lo and d > 0.0 and d <= range_hi:  # 0 is no measurement (lms200.Scan.valid)
            q = n_pts
            xq, yq = d * cos_b[i], d * sin_b[i]
            idx[q], x[q], y[q] = i, xq, yq
            if q:
                ax, ay, axx, ayy, axy = ax + xq, ay + yq, axx + xq * xq, ayy + yq * yq, axy + xq * yq
                step = i - p_idx
                if step > max_skip or n_inf > p_inf:
                    cut = True
                else:
                    cut = disconnected(xq - px, yq - py, pr, sin_step[step], sin_rest[step], ratio[step], margin)
                if cut:
                    ends[n_clusters] = q - 1
                    n_clusters += 1
            else:
                ax, ay, axx, ayy, axy = xq, yq, xq * xq, yq * yq, xq * yq
            sx[q + 1], sy[q + 1], sxx[q + 1], syy[q + 1], sxy[q + 1] = ax, ay, axx, ayy, axy
            px, py, pr, p_idx, p_inf = xq, yq, d, i, n_inf
            n_pts += 1
        elif d == np.inf:
            n_inf += 1
    if n_pts < 2:
        return 0
    ends[n_clusters] = n_pts - 1
    n_clusters += 1
    # no distance of the split test can be nan when every coordinate is below 1e70 m in size
    # (squares, their sums and the fit's moments stay finite): then the test skips its nan checks
    finite = abs(range_lo) < 1e70 and abs(range_hi) < 1e70
    # each cluster split depth-first
    min_split = max(min_points, 3)
    segs_s, segs_e, stack_s, stack_e = ws.seg_s, ws.seg_e, ws.stack_s, ws.stack_e
    n_seg = 0
    start = 0
    for k in range(n_clusters):
        p = ends[k]
        sp = 0
        stack_s[0], stack_e[0] = start, p
        sp = 1
        start = p + 1
        while sp > 0:
            sp -= 1
            s, e = stack_s[sp], stack_e[sp]
            if e - s + 1 < min_split:
                segs_s[n_seg], segs_e[n_seg] = s, e
                n_seg += 1
                continue
            if chord:
                at = split_at(x, y, s, e, threshold, 0.0, 0.0, 0.0, True, finite)
            else:
                c, si, rho = split_line(sx, sy, sxx, syy, sxy, s, e)
                at = split_at(x, y, s, e, threshold, c, si, rho, False, finite)
            if at < 0:
                segs_s[n_seg], segs_e[n_seg] = s, e
                n_seg += 1
                continue
            stack_s[sp], stack_e[sp] = at, e
            stack_s[sp + 1], stack_e[sp + 1] = s, at
            sp += 2
    # the segments come in beam order (each cluster's left part is split first)
    m = n_seg
    # merge collinear neighbours, pass by pass
    if merge_rms > 0:
        rms, slack, pick, src = ws.rms, ws.slack, ws.pick, ws.src
        first_pass = True
        while m > 1:
            # each pair's merged RMS residual, from the eigenvalue formula where every coordinate is
            # finite (no arctangent, cosine or sine; within slack[i] of fit_range's), from fit_range
            # where that margin leaves a decision open: every decision is fit_range's
            any_ok = False
            for i in range(m - 1):
                if not first_pass and src[i] >= 0 and src[i + 1] >= 0:  # both unchanged: as before
                    rms[i], slack[i] = rms[src[i]], slack[src[i]]
                elif segs_s[i + 1] != segs_e[i]:
                    rms[i], slack[i] = np.inf, 0.0
                elif finite:
                    rms[i], slack[i] = merged_rms(sx, sy, sxx, syy, sxy, segs_s[i], segs_e[i + 1])
                else:
                    rms[i], slack[i] = exact_rms(sx, sy, sxx, syy, sxy, segs_s[i], segs_e[i + 1]), 0.0
                if slack[i] > 0 and not abs(rms[i] - merge_rms) > slack[i]:
                    rms[i], slack[i] = exact_rms(sx, sy, sxx, syy, sxy, segs_s[i], segs_e[i + 1]), 0.0
                any_ok = any_ok or rms[i] <= merge_rms
            if not any_ok:
                break
            for i in range(m - 2):  # neighbours' residuals within their margins: both exact
                if (slack[i] > 0 or slack[i + 1] > 0) and not abs(rms[i] - rms[i + 1]) > slack[i] + slack[i + 1]:
                    if slack[i] > 0:
                        rms[i], slack[i] = exact_rms(sx, sy, sxx, syy, sxy, segs_s[i], segs_e[i + 1]), 0.0
                    if slack[i + 1] > 0:
                        rms[i + 1], slack[i + 1] = exact_rms(sx, sy, sxx, syy, sxy, segs_s[i + 1], segs_e[i + 2]), 0.0
            for i in range(m - 1):
                left = np.inf if i == 0 else rms[i - 1]
                right = np.inf if i == m - 2 else rms[i + 1]
                pick[i] = rms[i] <= merge_rms and rms[i] < left and rms[i] <= right
            w = 0
            i = 0
            while i < m:
                if i < m - 1 and pick[i]:
                    segs_s[w], segs_e[w] = segs_s[i], segs_e[i + 1]
                    src[w] = -1
                    i += 2
                else:
                    segs_s[w], segs_e[w] = segs_s[i], segs_e[i]
                    src[w] = i
                    i += 1
                w += 1
            m = w
            first_pass = False
    # a split point shared by two neighbours belongs to neither line's fit; drop short segments
    for i in range(m - 1):
        if segs_s[i + 1] == segs_e[i]:
            segs_e[i] -= 1
            segs_s[i + 1] += 1
    lv, lb = ws.lv, ws.lb
    s2 = sigma * sigma
    tol = TRIM_TOL_SIGMA * sigma
    k = 0
    for i in range(m):
        s, e = segs_s[i], segs_e[i]
        if e - s + 1 < min_points:
            continue
        f = fit_range(sx, sy, sxx, syy, sxy, s, e)
        for _ in range(2):  # drop end points off the fitted line, refit
            lo, hi = trim(x, y, s, e, f.rho, f.cos, f.sin, tol, min_points)
            if lo == s and hi == e:
                break
            s, e = lo, hi
            f = fit_range(sx, sy, sxx, syy, sxy, s, e)
        if runs_z > 0 and not straight_enough(x, y, s, e, f.rho, f.cos, f.sin, runs_z, 0.5 * sigma):
            continue
        fr, fa, c, si = f.rho, f.alpha, f.cos, f.sin
        d0 = x[s] * c + y[s] * si - fr
        d1 = x[e] * c + y[e] * si - fr
        ax, ay = x[s] - d0 * c, y[s] - d0 * si
        bx, by = x[e] - d1 * c, y[e] - d1 * si
        if not length_at_least(bx - ax, by - ay, min_length):
            continue
        t = -f.mx * si + f.my * c
        var_a = s2 / f.along
        lv[k, 0], lv[k, 1] = fr, fa
        lv[k, 2], lv[k, 3], lv[k, 4], lv[k, 5] = ax, ay, bx, by
        lv[k, 6] = s2 / f.n + t * t * var_a
        lv[k, 7] = t * var_a
        lv[k, 8] = t * var_a
        lv[k, 9] = var_a
        lb[k, 0], lb[k, 1], lb[k, 2] = idx[s], idx[e], np.int64(f.n)
        k += 1
    return k


@kernel
def corners(lv, lb, increment, c):  # noqa: ANN001, ANN201
    """The Cartesian corner step (Castellanos et al. 1996): corners where consecutive lines k, k + 1
    (beam order) meet, at their intersection. A corner needs the lines at most max_gap_beams apart,
    their facing end points connected in the scan (within the adaptive breakpoint distance, so an
    occlusion's depth jump is no corner), a turn of at least min_turn (rad) between the segment
    directions, and the intersection within max_distance (m) plus the end points' gap of both
    facing ends. ``lv``, ``lb``: the rows of the lines (``features.types.Lines``); ``c`` a
    CornerParams. Returns the rows of ``features.types.Corners``: (x, y, interior angle in
    (0, pi)) and (beam index, line k, line k + 1) of each corner."""
    n_out = max(lv.shape[0] - 1, 0)
    out_f = np.empty((n_out, 3))
    out_i = np.empty((n_out, 3), np.int64)
    m = corners_into(lv, lb, lv.shape[0], increment, c, out_f, out_i)
    return out_f[:m], out_i[:m]


@kernel
def corners_into(lv, lb, n_lines, increment, c, out_f, out_i):  # noqa: ANN001, ANN201
    """``corners`` of the first ``n_lines`` rows of ``lv``, ``lb``, written into ``out_f``, ``out_i``
    (at least n_lines - 1 rows); returns their number. The tests run cheapest first."""
    min_turn, max_gap, max_distance, lam, sigma = c.min_turn, c.max_gap_beams, c.max_distance, c.breakpoint_lambda, c.sigma
    m = 0
    for k in range(n_lines - 1):
        step = float(lb[k + 1, 0] - lb[k, 1])
        if not step <= max_gap:
            continue
        ex, ey = lv[k, 4], lv[k, 5]  # the facing end points: end of line k, start of line k + 1
        sx, sy = lv[k + 1, 2], lv[k + 1, 3]
        gap = math.hypot(sx - ex, sy - ey)
        connect = breakpoint_distance(math.hypot(ex, ey), max(step, 1.0) * increment, lam, sigma)
        if not (gap <= connect and connect > 0):
            continue
        d1x, d1y = ex - lv[k, 2], ey - lv[k, 3]
        d2x, d2y = lv[k + 1, 4] - sx, lv[k + 1, 5] - sy
        n1 = math.sqrt(d1x * d1x + d1y * d1y)
        n2 = math.sqrt(d2x * d2x + d2y * d2y)
        cos_turn = (d1x * d2x + d1y * d2y) / (n1 * n2)
        if cos_turn == cos_turn:
            cos_turn = min(max(cos_turn, -1.0), 1.0)
        turn = math.acos(cos_turn)
        if not turn >= min_turn:
            continue
        a1, a2 = lv[k, 1], lv[k + 1, 1]
        r1, r2 = lv[k, 0], lv[k + 1, 0]
        det = math.sin(a2 - a1)
        cx = (r1 * math.sin(a2) - r2 * math.sin(a1)) / det
        cy = (r2 * math.cos(a1) - r1 * math.cos(a2)) / det
        dist_a = math.hypot(cx - ex, cy - ey)
        dist_b = math.hypot(cx - sx, cy - sy)
        if dist_a <= max_distance + gap and dist_b <= max_distance + gap and np.isfinite(cx):
            out_f[m, 0], out_f[m, 1], out_f[m, 2] = cx, cy, math.pi - turn
            out_i[m, 0], out_i[m, 1], out_i[m, 2] = lb[k, 1], k, k + 1
            m += 1
    return m


@kernel
def extract_into(ranges, cos_b, sin_b, range_lo, range_hi, increment, p, c, ws):  # noqa: ANN001, ANN201
    """Lines (``segment_lines``) and corners (``corners_into``) of one scan, written into the rows of
    ``ws`` (lv, lb; cv, cb); returns (lines, corners)."""
    n_lines = segment_lines(ranges, cos_b, sin_b, range_lo, range_hi, p, ws)
    n_corners = corners_into(ws.lv, ws.lb, n_lines, increment, c, ws.cv, ws.cb) if n_lines > 1 else 0
    return n_lines, n_corners


@kernel
def extract_scan(ranges, cos_b, sin_b, range_lo, range_hi, increment, p, c):  # noqa: ANN001, ANN201
    """Lines and corners of one scan: the rows of ``features.types.Lines`` and ``Corners``."""
    ws = workspace(ranges.size, increment, p)
    nl, nc = extract_into(ranges, cos_b, sin_b, range_lo, range_hi, increment, p, c, ws)
    return ws.lv[:nl].copy(), ws.lb[:nl].copy(), ws.cv[:nc].copy(), ws.cb[:nc].copy()


@kernel
def extract_batch(ranges, cos_b, sin_b, range_lo, range_hi, increment, p, c):  # noqa: ANN001, ANN201
    """``extract_scan`` of every row of ``ranges`` (S, n), scans of one geometry, in one call: the
    rows of all scans concatenated, and the (S + 1,) offsets of each scan's lines and corners."""
    rows = new_rows(ranges.shape[0])
    ws = workspace(ranges.shape[1], increment, p)
    for s in range(ranges.shape[0]):
        nl, nc = extract_into(ranges[s], cos_b, sin_b, range_lo, range_hi, increment, p, c, ws)
        rows = append_rows(rows, s, (ws.lv[:nl], ws.lb[:nl], ws.cv[:nc], ws.cb[:nc]))
    return finish_rows(rows)
