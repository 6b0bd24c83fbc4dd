"""The sensor-coordinate extractor (method "sensor"): the one implementation, compiled with numba.

Every step works in range-bearing space, on the beams of one scan, in the order of the paper:

1. per-beam signals (``signal_block``): the invariant AD_ik (eq. 4), the slope estimate theta_i
   (eq. 6-7 as corrected in NOTES.md) and psi_i = theta_i - theta_{i+k}, with their noise std;
2. runs of beams on straight lines (``candidate_runs``): the AD test, broken where psi peaks;
3. the Log-Hough transform (eq. 5) searched in a narrow band of normal angles around each run's
   mean slope (``band_search``): every vote is a lookup in one log-cos template;
4. two weighted Gauss-Newton steps on the range residuals, with the covariance of (rho, alpha)
   implied by the range noise, and the acceptance checks (``fit_runs``); a run that fails is
   split at its chord's farthest beam and fitted again, unless it is one circle, and lines on a
   round surface are dropped (``find_lines``, ``circle_fits``);
5. lines grown over the beams past their ends and refitted with Tukey's biweight, neighbours
   merged, overlaps split, endpoints projected, short segments dropped (``extend_ends``,
   ``robust_refit``, ``merge_neighbours``, ``segments``);
6. corners where two segments meet and psi shows the turn, with the paper's remedy against
   false acute corners (``corners``).

Beam i has bearing b_i = angle_min + i D. The noise estimate and the range variance of the
acute-corner remedy sum in numpy's pairwise order (``pairwise_sum``), as the numpy estimators they
equal; the fits' sums over a run's beams (``gn_sums``, ``biweight_sums``, ``circle_gn_sums``, ...)
add beam after beam. No kernel is compiled with fast-math: a regrouped sum's order would follow
the CPU's vector width, and so would the rare beam whose inlier test sits on the threshold.
Parameters come in as a
typed record (``Params``, built once per config by ``features.sensor.config``), the scan's grid
constants as another (``Grid``, built once per beam step by ``features.sensor.grid``).
Importing this module imports numba (``features.jit``).

One module on purpose: numba's on-disk cache is invalidated by the modification time of the file
that defines a function, not of the files of the functions it calls, so kernels that call each
other live in one file. Nor does the cache see the compiler's flags (``features.jit``): a change of
them needs a change of this file. The kernels run without the GIL (``extract_many``'s threads).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from lms200.noise import CLIP_SIGMAS, JUMP_FRACTION, MIN_RANGE_M, QUANTUM_CANDIDATES_M, QUANTUM_SHARE
from lms200.noise import _CLIP_STD_FACTOR as CLIP_STD_FACTOR

from ..jit import inline_kernel, kernel
from ..jit import wrap_one as wrap  # the project's one wrap (lms200.angles), compiled
from ..rows import append_rows, finish_rows, new_rows

PW_BLOCKSIZE = 128  # numpy's pairwise-summation block (numpy/_core/src/umath/loops_utils.h.src)
N_BINS = 13  # log-range cells of a run's Log-Hough accumulator around its middle vote
MIN_COS = 0.05  # beams within ~3 deg of grazing a line get no weight and do not extend it
BAND_MAX = 0.5  # largest half-width of a run's band of normal angles, rad
TAN_SPAN_CAP = 40.0  # cap on |tan(b - a)| differences across a run (grazing runs), dimensionless
VOTE_BLOCK = 16  # beams a run's vote loop takes at a time (its vectorised width); runs are padded to it
TIE_BREAK = 1e-3  # votes a band angle loses per step from the band centre (prefers the centre on ties)
MERGE_FLOOR_RHO_VAR = 0.005**2  # model-error floor added to the merge test's (rho) variance, m^2
MERGE_FLOOR_ALPHA_VAR = 0.005**2  # ... and (alpha) variance, rad^2
ARC_TAU = 3.0  # the arc test's chi^2 comparisons, in std of the chi^2 difference
ARC_GN_STEPS = 1  # geometric Gauss-Newton steps of a circle fit after the algebraic (Taubin) start
TAUBIN_NEWTON_STEPS = 99  # most Newton steps on the Taubin fit's characteristic polynomial (it stops when they do)
BREAK_LAMBDA = math.radians(10.0)  # adaptive breakpoint angle of a smooth surface (Borges & Aldon 2004)
ONE_DEG = math.radians(1.0)  # an LMS200 mirror turn's beam step (finer scans interlace such turns)
ROBUST_STEPS = 1  # reweighted steps of the final biweight refit (``robust_refit``): one step from the
# least-squares line is one iteratively-reweighted step, not the fixed point (nor Bickel's Newton
# step): it removes most, not all, of the least-squares line's pull towards outliers
TUKEY_C = 4.685  # biweight tuning constant, in robust scales (95 % efficiency under Gaussian noise)
MAD_TO_SIGMA = 1.4826  # median absolute deviation -> std of a Gaussian
SIGMA_FLOOR_RAY = 0.001  # smallest robust scale of a line's residuals (m): noiseless scans
LOCAL_MIN_TRIPLES = 6  # fewest triples of a run's own beams that give its local noise scale
SPACING_CAP = 1.0  # largest point spacing (grazing incidence) allowed for in the corner contact test, m


class Params(NamedTuple):
    """The fields of a ``SensorMethodConfig`` as the kernels read them (units as in the config;
    counts already rounded as the tests on integers need them)."""

    k: int  # half-width of the AD / slope window, beams
    ad_tau: float
    psi_split: float  # rad
    psi_tau: float
    hough_subdiv: int
    hough_angles: int
    band_tau: float
    band_min: float  # rad
    bin_tau: float
    inlier_tau: float
    max_chi2: float
    min_inlier_fraction: float
    curvature_tau: float
    min_points: int  # ceil(config.min_points): n >= min_points for an integer n
    min_length: float  # m
    merge_gap: int  # floor(config.merge_gap): gap > merge_gap for an integer gap
    merge_tau: float
    bridge_invalid: int  # floor
    corners: bool
    corner_min_turn: float  # rad
    corner_psi: float
    corner_max_gap: int  # floor
    corner_max_dist: float  # m
    acute_check: bool
    acute_min_var: float  # in sigma_r**2
    arc_check: bool  # drop lines that are chords of a round surface (``on_arcs``)
    sigma_bearing: float  # bearing noise std, rad (``ray_sd``)


# rows of a scan's bearing table (``features.sensor.grid.bearings_of``, (3, n), built once per
# geometry): the bearings b_i = angle_min + i D (rad), their cosines and sines. One array, not a
# record of three: every call of a kernel that takes an array costs two atomic reference counts
# per array (~12 ns; a record's arrays count one by one)
B_ANGLE, B_COS, B_SIN = 0, 1, 2


class Grid(NamedTuple):
    """Constants of a scan's angle grid for window half-width k and beam step D."""

    ad_line: float  # 1 + 2 sum_{j=1..k} cos(jD): AD on any straight line (eq. 4)
    two_sin_sum: float  # 2 sum_{m=1..k} sin(mD): the slope denominator (NOTES.md, eq. 7)
    step: float  # Log-Hough angle step D / hough_subdiv, rad
    zero: int  # index of angle 0 in the template
    template: np.ndarray  # log cos(m step) for |m| <= zero, floored (eq. 5)
    twice_cos: float  # 2 cos(D), as numpy computes it: the noise estimate's collinearity residuals
    phases: np.ndarray  # (subdiv, L): template[r + subdiv q] at [r, L - 1 - q] (the floor past its end)


# -- sums in numpy's pairwise order ---------------------------------------------------------------


@inline_kernel
def block_sum(a: np.ndarray, lo: int, n: int) -> float:
    """numpy's pairwise sum of a[lo : lo + n] for n <= 128: sequential below 8, else 8 accumulators
    (indexed unsigned: numba then adds no negative-index wraparound, and the loop vectorises)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    b = np.uint64(lo)
    r0, r1, r2, r3 = a[b], a[b + np.uint64(1)], a[b + np.uint64(2)], a[b + np.uint64(3)]
    r4, r5, r6, r7 = a[b + np.uint64(4)], a[b + np.uint64(5)], a[b + np.uint64(6)], a[b + np.uint64(7)]
    m = b + np.uint64(n - (n % 8))
    i = b + np.uint64(8)
    while i < m:
        r0 += a[i]
        r1 += a[i + np.uint64(1)]
        r2 += a[i + np.uint64(2)]
        r3 += a[i + np.uint64(3)]
        r4 += a[i + np.uint64(4)]
        r5 += a[i + np.uint64(5)]
        r6 += a[i + np.uint64(6)]
        r7 += a[i + np.uint64(7)]
        i += np.uint64(8)
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    end = b + np.uint64(n)
    while i < end:
        res += a[i]
        i += np.uint64(1)
    return res


@inline_kernel
def pairwise_halves(n: int):  # noqa: ANN201
    """numpy's split of a pairwise sum of n > 128 terms: the left half rounded down to a multiple of 8."""
    n2 = n // 2
    n2 -= n2 % 8
    return n2, n - n2


# The fixed levels below are inlined into ``pairwise_sum`` (a kernel call costs two atomic reference
# counts per array passed: ~145 of a 310-term sum's ~150 ns went to the 12 calls and 4 views of
# the levels). Each level calls the one below at one place, in a loop over its one or two
# halves, so that the inlined code holds one copy of each level.


@inline_kernel
def pairwise_248(a: np.ndarray, lo: int, n: int) -> float:
    """``pairwise_sum`` for n <= 248 (one block, or both halves of one split are blocks)."""
    k = 1 if n <= PW_BLOCKSIZE else 2
    n2 = n if k == 1 else pairwise_halves(n)[0]
    res = 0.0
    for j in range(k):
        v = block_sum(a, lo + j * n2, n2 if j == 0 else n - n2)
        res = v if j == 0 else res + v
    return res


@inline_kernel
def pairwise_488(a: np.ndarray, lo: int, n: int) -> float:
    """``pairwise_sum`` for n <= 488 (``pairwise_248`` of n, or of its halves of at most 248)."""
    k = 1 if n <= 248 else 2
    n2 = n if k == 1 else pairwise_halves(n)[0]
    res = 0.0
    for j in range(k):
        v = pairwise_248(a, lo + j * n2, n2 if j == 0 else n - n2)
        res = v if j == 0 else res + v
    return res


@inline_kernel
def pairwise_968(a: np.ndarray, lo: int, n: int) -> float:
    """``pairwise_sum`` for n <= 968 (``pairwise_488`` of n, or of its halves of at most 488)."""
    k = 1 if n <= 488 else 2
    n2 = n if k == 1 else pairwise_halves(n)[0]
    res = 0.0
    for j in range(k):
        v = pairwise_488(a, lo + j * n2, n2 if j == 0 else n - n2)
        res = v if j == 0 else res + v
    return res


@inline_kernel
def pairwise_1928(a: np.ndarray, lo: int, n: int) -> float:
    """``pairwise_sum`` for n <= 1928 (``pairwise_968`` of n, or of its halves of at most 968)."""
    k = 1 if n <= 968 else 2
    n2 = n if k == 1 else pairwise_halves(n)[0]
    res = 0.0
    for j in range(k):
        v = pairwise_968(a, lo + j * n2, n2 if j == 0 else n - n2)
        res = v if j == 0 else res + v
    return res


@kernel
def pairwise_sum(a: np.ndarray, lo: int, n: int) -> float:
    """Sum of a[lo : lo + n] in numpy's pairwise order (blocks of 128 halved at multiples of 8):
    up to 1928 terms by the fixed levels above (no allocation), beyond by walking numpy's
    recursion tree with an explicit stack (numba cannot cache recursive functions)."""
    if n <= 1928:
        return pairwise_1928(a, lo, n)
    st_lo = np.empty(64, np.int64)
    st_n = np.empty(64, np.int64)
    st_state = np.empty(64, np.int64)
    vals = np.empty(64)
    sp = 1
    st_lo[0], st_n[0], st_state[0] = lo, n, 0
    nv = 0
    while sp > 0:
        top = sp - 1
        l, m = st_lo[top], st_n[top]
        if m <= 1928:
            vals[nv] = pairwise_1928(a, l, m)
            nv += 1
            sp -= 1
            continue
        n2, _ = pairwise_halves(m)
        if st_state[top] == 0:  # left half first
            st_state[top] = 1
            st_lo[sp], st_n[sp], st_state[sp] = l, n2, 0
            sp += 1
        elif st_state[top] == 1:  # then the right half
            st_state[top] = 2
            st_lo[sp], st_n[sp], st_state[sp] = l + n2, m - n2, 0
            sp += 1
        else:  # both done: left + right
            vals[nv - 2] = vals[nv - 2] + vals[nv - 1]
            nv -= 1
            sp -= 1
    return vals[0]


@kernel
def segment_sum(a: np.ndarray, lo: int, n: int) -> float:
    """The sum of one segment as ``np.add.reduceat`` forms it: the first element plus the
    pairwise sum of the rest."""
    return a[lo] + pairwise_sum(a, lo + 1, n - 1)


# -- 0. the range noise of sigma_r = "auto" (``features.noise_estimate``) -------------------------

SIGMA_FLOOR_M = 0.001  # smallest noise assumed (m): noiseless synthetic scans still get finite thresholds
MIN_TRIPLES = 20  # fewer usable triples than this: the scale cannot be had (the caller's fallback)
MAX_TRIPLES = 1_000_000  # memory bound when pooling many scans: no scan is read past this many triples
SAMPLE_STEP = 5  # every 5th finite range of a scan enters the quantisation step's sample


@kernel
def neighbour_residuals(ranges, c2, lo, hi, z, m):  # noqa: ANN001, ANN201
    """``lms200.noise.line_residuals`` at stride 1 written to z[m:] (room for ranges.size - 2):
    the normalised collinearity residual (m) of each triple of neighbouring beams in [lo, hi)
    (lo >= MIN_RANGE_M) without a depth step; ``c2`` = 2 cos(D). Returns the new end of z.
    Every triple's residual first (nan where it is not used; a used one is finite), in a loop that
    vectorises, then the used ones moved to the front."""
    n = ranges.size - 2
    if n <= 0:
        return m
    zz = z[m:m + n]
    rm_, r0_, rp_ = ranges[:n], ranges[1:n + 1], ranges[2:n + 2]
    for i in range(n):
        rm, r0, rp = rm_[i], r0_[i], rp_[i]
        q = 1.0 / (rm + rp)  # one division a triple for the three by r- + r+ or its square
        q2 = q * q
        wm = c2 * (rp * rp) * q2
        wp = c2 * (rm * rm) * q2
        res = (r0 - c2 * rm * rp * q) / math.sqrt(1.0 + wm * wm + wp * wp)
        # in range (False on nan, inf < inf) and no depth step
        use = lo <= rm < hi and lo <= r0 < hi and lo <= rp < hi and abs(rp - rm) <= JUMP_FRACTION * r0
        zz[i] = res if use else np.nan
    q = m
    for i in range(n):
        v = zz[i]
        z[q] = v
        q += v == v
    return q


@kernel
def finite_sample(ranges, out, m):  # noqa: ANN001, ANN201
    """Every SAMPLE_STEP-th finite range (from the first) appended to out[m:]; the new end."""
    t = 0
    for i in range(ranges.size):
        if math.isfinite(ranges[i]):
            if t % SAMPLE_STEP == 0:
                out[m] = ranges[i]
                m += 1
            t += 1
    return m


@kernel
def quantum_step(sample) -> float:  # noqa: ANN001
    """``lms200.noise.estimate_quantum``: the largest step of QUANTUM_CANDIDATES_M (m) on whose grid
    QUANTUM_SHARE of the positive finite ``sample`` lie, 0.0 when none does. A step is given up at
    the first value off its grid that decides it (at 99 %, of a scan's ~72 values the first)."""
    n_pos = 0
    for x in sample:
        n_pos += math.isfinite(x) and x > 0
    if n_pos == 0:
        return 0.0
    need = min(int(math.ceil(QUANTUM_SHARE * n_pos)), n_pos)  # the fewest values on a grid that pass:
    while need > 0 and (need - 1) / n_pos >= QUANTUM_SHARE:  # near / n_pos >= QUANTUM_SHARE exactly
        need -= 1  # when near >= need (the division rises with near)
    while need <= n_pos and need / n_pos < QUANTUM_SHARE:
        need += 1
    for q in QUANTUM_CANDIDATES_M:
        miss = 0  # a step has failed once more than n_pos - need values are off its grid: stop there
        for x in sample:
            if math.isfinite(x) and x > 0 and not abs(x - np.rint(x / q) * q) < q / 20:
                miss += 1
                if miss > n_pos - need:
                    break
        if miss <= n_pos - need:
            return q
    return 0.0


@kernel
def median3(x: float, y: float, z: float) -> float:
    """The middle one of three values (no nan)."""
    return max(min(x, y), min(max(x, y), z))


@kernel
def select(w, ra, rb, n, k):  # noqa: ANN001, ANN201
    """The k-th smallest of w[ra, :n] (0-based; no nan) and the (k-1)-th (-inf for k = 0), by
    quickselect with three-way partitions written to the other of rows ``ra`` and ``rb`` of ``w``
    (both overwritten; one array, not two: a kernel call costs two atomic reference counts per
    array it is passed): the values below the pivot to its front, those above to its back, the
    pivot's copies dropped. Both writes are made for every value, without branches: which side a
    value takes is data, not predictable, and no value is read back from a slot just written (an
    in-place partition waits on a store to load every next value). The pivot: the median of three,
    of three medians of three on long ranges. Indexed unsigned: numba then adds no negative-index
    wraparound."""
    src, dst = ra, rb  # rows of w
    off = np.uint64(0)  # the candidates: w[src, off:off + m], k counted from off
    m = np.uint64(n)
    kk = np.uint64(k)
    below = -np.inf  # the largest value known to be below the candidates
    while m > np.uint64(1):
        if m > np.uint64(64):
            st = m // np.uint64(9)
            b = off + st // np.uint64(2)
            pivot = median3(median3(w[src, b], w[src, b + st], w[src, b + np.uint64(2) * st]),
                            median3(w[src, b + np.uint64(3) * st], w[src, b + np.uint64(4) * st], w[src, b + np.uint64(5) * st]),
                            median3(w[src, b + np.uint64(6) * st], w[src, b + np.uint64(7) * st], w[src, b + np.uint64(8) * st]))
        else:
            pivot = median3(w[src, off], w[src, off + m // np.uint64(2)], w[src, off + m - np.uint64(1)])
        nl = np.uint64(0)
        nh = np.uint64(0)
        end = off + m - np.uint64(1)
        for i in range(m):
            x = w[src, off + i]
            w[dst, off + nl] = x
            w[dst, end - nh] = x
            nl += np.uint64(x < pivot)
            nh += np.uint64(x > pivot)
        if kk < nl:
            m = nl
        elif kk >= m - nh:  # above the pivot: its copies and the values below it are smaller
            kk -= m - nh
            off += m - nh
            m = nh
            below = pivot
        else:  # the pivot's value
            if kk > nl:
                return pivot, pivot
            for i in range(nl):  # kk == nl: the next smaller is the largest value below the pivot
                below = max(below, w[dst, off + i])
            return pivot, below
        src, dst = dst, src
    return w[src, off], below


@kernel
def median(x) -> float:  # noqa: ANN001
    """np.median(x) (nan when x holds a nan or is empty): ``median_rows`` of a copy."""
    w = np.empty((2, x.size))
    for i in range(x.size):
        w[0, i] = x[i]
    return median_rows(w, 0, 1, x.size)


@kernel
def median_rows(w, ra, rb, n) -> float:  # noqa: ANN001
    """np.median(w[ra, :n]) (nan when it holds a nan or n is 0), overwriting w[ra, :n] and
    w[rb, :n] (the selection's): the middle value, or the mean of the two middle ones. Rows of one
    block, not views (a view is two atomic reference counts, and so is each array passed)."""
    if n == 0:
        return np.nan
    bad = False
    for i in range(n):  # without an early exit: the loop vectorises
        x = w[ra, i]
        bad |= x != x
    if bad:
        return np.nan
    hi, lo = select(w, ra, rb, n, n // 2)
    return hi if n % 2 else (lo + hi) / 2.0


@kernel
def mean_std(x, n, scratch):  # noqa: ANN001, ANN201
    """numpy's x[:n].mean() and x[:n].std() (pairwise sums), with ``scratch`` (>= n) for the squares."""
    mean = pairwise_sum(x, 0, n) / n
    for i in range(n):
        d = x[i] - mean
        scratch[i] = d * d
    return mean, math.sqrt(pairwise_sum(scratch, 0, n) / n)


# rows of the noise estimate's block (``pooled_sigma``, ``clipped_scale_rows``): the residuals z, then
# two rows the medians select in and the clipping steps gather the kept residuals and their squares in
Z_ROW, KZ_ROW, SQ_ROW = 0, 1, 2
# the largest floor a quantisation step can set (m): a scale at least this large is the estimate
# whatever the step (``floored``), so the step is not looked for
FLOOR_MAX = max(max(QUANTUM_CANDIDATES_M) / math.sqrt(12.0), SIGMA_FLOOR_M)


@kernel
def clipped_scale(z) -> float:  # noqa: ANN001
    """``lms200.noise.robust_scale``'s scale of the residuals z (nan when empty): ``clipped_scale_rows``
    of a copy."""
    w = np.empty((3, z.size))
    for i in range(z.size):
        w[Z_ROW, i] = z[i]
    return clipped_scale_rows(w, z.size)


@kernel
def clipped_scale_rows(w, n) -> float:  # noqa: ANN001
    """``lms200.noise.robust_scale``'s scale of the residuals z = w[Z_ROW, :n] (nan when n is 0):
    the median absolute deviation, then the standard deviation of those within CLIP_SIGMAS scales
    of the centre, iterated and corrected for the clipping. Rows KZ_ROW and SQ_ROW are overwritten.
    A step's set of residuals is not stored: the last step's is recomputed from its centre and
    limit (the same comparison, the same result)."""
    if n == 0:
        return np.nan
    z = w[Z_ROW]
    kz = w[KZ_ROW]
    scratch = w[SQ_ROW]
    for i in range(n):
        kz[i] = z[i]
    m = median_rows(w, KZ_ROW, SQ_ROW, n)
    for i in range(n):
        kz[i] = abs(z[i] - m)
    s = 1.4826 * median_rows(w, KZ_ROW, SQ_ROW, n)
    if s <= 0:  # more than half the residuals identical (coarse quantisation): start from the spread
        s = mean_std(z, n, scratch)[1]
        if s == 0:
            s = 1e-12
    pm = m  # the last step's set: |z - pm| <= plim (before the first step: every residual)
    plim = np.inf
    for it in range(50):
        lim = CLIP_SIGMAS * s
        nk = 0
        same = True
        for i in range(n):  # no store at a place an earlier value found: the loop vectorises
            x = z[i]
            inside = abs(x - m) <= lim
            same &= inside == (abs(x - pm) <= plim)
            nk += inside
        if it == 0:
            same = nk == n
        if nk < 2:
            break
        if same and it > 0:  # the residuals of the last step again: the same centre and scale, converged
            break
        q = 0
        for i in range(n):  # only then the kept residuals to the front of kz, without branches (which stay is data)
            x = z[i]
            kz[q] = x
            q += abs(x - m) <= lim
        pm, plim = m, lim
        m, s_new = mean_std(kz, nk, scratch)
        s_new = s_new / CLIP_STD_FACTOR
        converged = same and abs(s_new - s) <= 1e-9 * max(s, 1e-12)
        s = s_new
        if converged:
            break
    return s


@kernel
def floored(scale, sample, fallback) -> float:  # noqa: ANN001
    """The noise (m) of a clipped ``scale``: at least the quantisation's q / sqrt(12) (q of the
    range ``sample``) and SIGMA_FLOOR_M; ``fallback`` when the scale is not finite."""
    if not math.isfinite(scale):
        return fallback
    if scale >= FLOOR_MAX:
        return scale
    return max(scale, max(quantum_step(sample) / math.sqrt(12.0), SIGMA_FLOOR_M))


@kernel
def sigma_of_residuals(z, sample, fallback) -> float:  # noqa: ANN001
    """The noise (m) from pooled residuals z and range sample: their clipped scale, at least the
    quantisation's q / sqrt(12) and SIGMA_FLOOR_M; ``fallback`` below MIN_TRIPLES residuals."""
    if z.size < MIN_TRIPLES:
        return fallback
    return floored(clipped_scale(z), sample, fallback)


@kernel
def pooled_sigma(ranges, c2, range_min, range_max, fallback) -> float:  # noqa: ANN001
    """``features.noise_estimate.neighbour_sigma`` of the scans of one geometry (rows of ``ranges``
    (S, n), beam step D with c2 = 2 cos(D), valid range limits in m), pooled in row order until
    MAX_TRIPLES residuals. The range sample of the quantisation step is taken only when the scale
    is below FLOOR_MAX."""
    n_scans, n = ranges.shape
    lo = max(range_min, MIN_RANGE_M)
    w = np.empty((3, max(min(n_scans * max(n - 2, 0), MAX_TRIPLES + n), n // SAMPLE_STEP + 1)))
    m = 0
    read = 0
    for s in range(n_scans):
        m = neighbour_residuals(ranges[s], c2, lo, range_max, w[Z_ROW], m)
        read += 1
        if m >= MAX_TRIPLES:
            break
    if m < MIN_TRIPLES:
        return fallback
    scale = clipped_scale_rows(w, m)
    if not math.isfinite(scale) or scale >= FLOOR_MAX:
        return floored(scale, w[0, :0], fallback)
    per_scan = n // SAMPLE_STEP + 1
    sample = w[Z_ROW] if read * per_scan <= w.shape[1] else np.empty(read * per_scan)
    ms = 0
    for s in range(read):
        ms = finite_sample(ranges[s], sample, ms)
    return floored(scale, sample[:ms], fallback)


# -- 1. per-beam signals --------------------------------------------------------------------------

# arctan(x) = x + x^3 P(x^2) / Q(x^2) on |x| <= 0.66 (S. L. Moshier's Cephes atan.c, relative error
# ~1e-16: within an ulp or two of libm's), the rest reduced onto it
ATAN_P = (-8.750608600031904122785e-1, -1.615753718733365076637e1, -7.500855792314704667340e1,
          -1.228866684490136173410e2, -6.485021904942025371773e1)
ATAN_Q = (2.485846490142306297962e1, 1.650270098316988542046e2, 4.328810604912902668951e2,
          4.853903996359136964868e2, 1.945506571482613964425e2)
TAN_3PI_8 = 2.41421356237309504880  # tan(3 pi / 8)
PI_2_LOW = 6.123233995736765886130e-17  # pi/2 - float(pi/2)


@kernel
def arctan(x: float) -> float:
    """arctan(x) (rad) as Cephes computes it, without a libm call, so that a loop of it vectorises
    (the per-beam slope theta and its noise need two a beam: two libm calls took ~8 us a scan)."""
    ax = abs(x)
    big = ax > TAN_3PI_8
    mid = not big and ax > 0.66
    t = -1.0 / ax if big else ((ax - 1.0) / (ax + 1.0) if mid else ax)
    y0 = 0.5 * math.pi if big else (0.25 * math.pi if mid else 0.0)
    extra = PI_2_LOW if big else (0.5 * PI_2_LOW if mid else 0.0)
    z = t * t
    p = (((ATAN_P[0] * z + ATAN_P[1]) * z + ATAN_P[2]) * z + ATAN_P[3]) * z + ATAN_P[4]
    q = ((((z + ATAN_Q[0]) * z + ATAN_Q[1]) * z + ATAN_Q[2]) * z + ATAN_Q[3]) * z + ATAN_Q[4]
    r = y0 + ((t * (z * p / q) + t) + extra)
    return math.copysign(r, x)


@kernel
def fix_slope_sd(x: float, sd: float) -> bool:
    """Whether the arctangent form of the slope's std (``beam_signals``) does not hold, at x = 1 +
    (T + s)(T - s) = 0 or an infinite x or s; not at a nan x (a window with an invalid beam), where
    both forms give nan."""
    return x == x and not (x != 0.0 and math.isfinite(x) and math.isfinite(sd))


# rows of ``signal_block``'s (11, n) block: the seven signals, three scratch rows and u = 1/d
S_AD, S_AD_VAR, S_AD_SLOPE, S_THETA, S_THETA_VAR, S_PSI, S_PSI_VAR, S_TAN_T, S_TAN_S, S_U4, S_U = range(11)
N_SIGNAL_ROWS = 11


@kernel
def signal_block(ranges, bearings, k, range_lo, range_hi, sigma_r, two_sin_sum):  # noqa: ANN001, ANN201
    """Per-beam signals of one scan (nan where a window is incomplete or holds an invalid beam):
    ``valid`` and one (N_SIGNAL_ROWS, n) block whose rows (``S_*``) hold AD (eq. 4), its variance
    per sigma_r**2, ad (eq. 6), theta (rad, unwrapped) and its variance, psi = theta_i - theta_{i+k}
    (wrapped) and its variance, three scratch rows and u = 1/d.

    Noise, first order in the range noise e_j (std sigma_r): u_j = 1/(d_j + e_j) ~ u_j - u_j^2 e_j,
    so var(AD) / sigma_r^2 = (sum_j u_j^4 - u_i^4) / u_i^2 + (AD - 1)^2 u_i^2, the same for ad.
    The std of theta = b + arctan(T) is the half-difference of arctan over T +- std(T), which stays
    right at grazing incidence.

    Rows are indexed in the block (``out[row, i]``, beams unsigned), never cut out as views: a view
    that outlives a loop is two atomic reference counts, and views of rows and shifted windows
    were ~0.35 us of this kernel's ~2.7 us a scan (numba prunes counts within a block, not across
    loops). Unsigned indices: numba then adds no negative-index wraparound and the loops vectorise.
    """
    n = ranges.size
    valid = np.empty(n, np.bool_)
    out = np.empty((N_SIGNAL_ROWS, n))  # nan written where no loop below writes (not np.full: ~32 KB a scan)
    if n >= 2 * k + 1:  # the centres k .. n - k - 1 get the window rows; psi the beams 0 .. n - k - 1
        for row in range(N_SIGNAL_ROWS):
            if row != S_U and row != S_U4:
                lo_edge = k if row != S_PSI and row != S_PSI_VAR else 0
                for i in range(lo_edge):
                    out[row, i] = np.nan
                for i in range(n - k, n):
                    out[row, i] = np.nan
    else:
        out[:] = np.nan
    for i in range(n):  # without branches, so that it vectorises
        d = ranges[i]
        ok = d >= range_lo and d > 0.0 and d <= range_hi  # 0 m is no reading (lms200.Scan.valid)
        valid[i] = ok
        out[S_U, i] = 1.0 / d if ok else np.nan
    if n >= 2 * k + 1:
        # the window sums of the centres c = k .. n - k - 1: left = sum_{m=1..k} u_{c-m} (in
        # S_TAN_T), right = sum_{m=0..k} u_{c+m} (in S_TAN_S) and quad = sum_{j=-k..k} u_{c+j}^4
        # (in S_AD_VAR), each summed term by term in beam order, one shifted window of u (or u^4)
        # at a time: passes over the scan that vectorise. A window that holds an invalid beam (u
        # nan) gets nan sums; then s1 = left + right, sd = right - left and s4 = quad go to the
        # rows of AD, ad and AD_var, which the next loop turns into the signals in place
        m = np.uint64(n - 2 * k)  # k >= 1 (the config's check)
        ku = np.uint64(k)
        for i in range(np.uint64(n)):
            u2 = out[S_U, i] * out[S_U, i]
            out[S_U4, i] = u2 * u2
        for i in range(m):
            out[S_TAN_T, ku + i] = out[S_U, i]
            out[S_TAN_S, ku + i] = out[S_U, ku + i]
            out[S_AD_VAR, ku + i] = out[S_U4, i]
        for j in range(1, 2 * k + 1):
            ju = np.uint64(j)
            if j < k:
                for i in range(m):
                    out[S_TAN_T, ku + i] += out[S_U, ju + i]
            elif j > k:
                for i in range(m):
                    out[S_TAN_S, ku + i] += out[S_U, ju + i]
            for i in range(m):
                out[S_AD_VAR, ku + i] += out[S_U4, ju + i]
        for i in range(m):
            c = ku + i
            out[S_AD, c] = out[S_TAN_T, c] + out[S_TAN_S, c]
            out[S_AD_SLOPE, c] = out[S_TAN_S, c] - out[S_TAN_T, c]
        s_scale = sigma_r / two_sin_sum
        inv_sin_sum = 1.0 / two_sin_sum
        for i in range(m):  # dividing by u_c = 1 / d_c is multiplying by d_c (an invalid centre's sums are nan)
            c = ku + i
            uc = out[S_U, c]
            dc = ranges[c]
            u2 = uc * uc
            a = out[S_AD, c] * dc  # eq. 4: AD_ik = sum_j (1/d_{i+j}) / (1/d_i)
            ad_c = out[S_AD_SLOPE, c] * dc  # eq. 6: ad_ik
            other = out[S_AD_VAR, c] * (dc * dc) - u2  # sum over j != i of u_j^4 / u_i^2
            ad1 = ad_c - 1.0
            a1 = a - 1.0
            out[S_AD, c] = a
            out[S_AD_VAR, c] = other + a1 * a1 * u2
            out[S_AD_SLOPE, c] = ad_c
            # eq. 7 as corrected in NOTES.md: ad - 1 = 2 tan(a - b_i) sum_{m=1..k} sin(mD): the
            # slope T = tan(a - b_i) and its std s here, their arctangents in the next loop
            out[S_TAN_T, c] = ad1 * inv_sin_sum
            out[S_TAN_S, c] = math.sqrt(other + ad1 * ad1 * u2) * s_scale
        n_fix = 0
        for i in range(m):
            c = ku + i
            t, sd_c = out[S_TAN_T, c], out[S_TAN_S, c]
            out[S_THETA, c] = bearings[c] + arctan(t)
            # (arctan(T + s) - arctan(T - s)) / 2 = atan2(2 s, 1 + (T + s)(T - s)) / 2, as
            # arctan(2 s / x) for x > 0 and pi - arctan(2 s / -x) for x < 0 (s >= 0)
            x = 1.0 + (t + sd_c) * (t - sd_c)
            h = arctan(2.0 * sd_c / abs(x))
            theta_sd = 0.5 * (h if x > 0.0 else math.pi - h)
            out[S_THETA_VAR, c] = theta_sd * theta_sd
            n_fix += fix_slope_sd(x, sd_c)
        i = np.uint64(0)
        while n_fix > 0 and i < m:  # where that form does not hold: atan2 (a loop that cannot vectorise, so
            # that the libm call is made for these few beams only, not speculated for all)
            c = ku + i
            t, sd_c = out[S_TAN_T, c], out[S_TAN_S, c]
            x = 1.0 + (t + sd_c) * (t - sd_c)
            if fix_slope_sd(x, sd_c):
                theta_sd = 0.5 * math.atan2(2.0 * sd_c, x)
                out[S_THETA_VAR, c] = theta_sd * theta_sd
                n_fix -= 1
            i += np.uint64(1)
    if n > k:
        ku = np.uint64(k)
        n_wrap = 0
        for i in range(np.uint64(n - k)):
            dpsi = out[S_THETA, i] - out[S_THETA, ku + i]  # the corner signal psi_i = theta_i - theta_{i+k}
            out[S_PSI, i] = dpsi + 0.0  # (+0.0: -0.0 becomes 0.0)
            n_wrap += abs(dpsi) >= math.pi
            out[S_PSI_VAR, i] = out[S_THETA_VAR, i] + out[S_THETA_VAR, ku + i]
        i = np.uint64(0)
        while n_wrap > 0:  # psi wrapped to (-pi, pi] where it lies outside: a few beams a scan (a loop
            # of its own, so that the one above stays branch-free and vectorises)
            if abs(out[S_PSI, i]) >= math.pi:
                out[S_PSI, i] = wrap(out[S_PSI, i])
                n_wrap -= 1
            i += np.uint64(1)
    return valid, out


@kernel
def beam_signals(ranges, bearings, k, range_lo, range_hi, sigma_r, two_sin_sum):  # noqa: ANN001, ANN201
    """``signal_block``'s signals as separate arrays: valid, u = 1/d, AD (eq. 4), its variance per
    sigma_r**2, ad (eq. 6), theta (rad, unwrapped) and its variance, psi = theta_i - theta_{i+k}
    (wrapped) and its variance (``features.sensor.signals``, the paper's figures 4-6)."""
    valid, out = signal_block(ranges, bearings, k, range_lo, range_hi, sigma_r, two_sin_sum)
    return (valid, out[S_U], out[S_AD], out[S_AD_VAR], out[S_AD_SLOPE], out[S_THETA], out[S_THETA_VAR], out[S_PSI],
            out[S_PSI_VAR])


# log(x) as Cephes' log.c computes it (S. L. Moshier; x = m 2^e, m in [sqrt(1/2), sqrt(2)), a rational
# approximation in m - 1 and ln 2 in two parts), without a libm call, so that a loop of it vectorises;
# within 1 ulp of libm's (3.7 % of 3.1e6 ranges of 1 mm - 1 km one ulp apart, none more)
LOG_P = (1.01875663804580931796e-4, 4.97494994976747001425e-1, 4.70579119878881725854e0,
         1.44989225341610930846e1, 1.79368678507819816313e1, 7.70838733755885391666e0)
LOG_Q = (1.12873587189167450590e1, 4.52279145837532221105e1, 8.29875266912776603211e1,
         7.11544750618563894466e1, 2.31251620126765340583e1)
SQRT_HALF = 0.70710678118654752440
LN2_HI = 0.693359375  # ln 2 = LN2_HI - LN2_LO; e LN2_HI is exact for any exponent e
LN2_LO = 2.121944400546905827679e-4
# 2^(1022 - E) for each biased exponent E of a double: x 2^(1022 - E) = m in [0.5, 1) (frexp) for a normal x
HALF_MANTISSA_SCALE = np.array([2.0 ** (1022 - e) if 1022 - e >= -1074 else 0.0 for e in range(2048)])


@kernel
def log_ranges(ranges):  # noqa: ANN001, ANN201
    """log of every range (``ranges`` C-contiguous, m; the values of invalid beams, inf or nan, are
    meaningless), Cephes' log of the positive normal ones: within 1 ulp of math.log, in one loop that
    vectorises (a libm call a beam was ~3 ns, ~1 us a scan)."""
    n = np.uint64(ranges.size)
    out = np.empty(ranges.size)
    bits = ranges.view(np.uint64)
    for i in range(n):
        eb = (bits[i] >> np.uint64(52)) & np.uint64(0x7FF)
        m = ranges[i] * HALF_MANTISSA_SCALE[eb]  # frexp's mantissa: exact (a power of two)
        e = float(np.int64(eb)) - 1022.0
        low = m < SQRT_HALF
        e = e - 1.0 if low else e
        t = (m + m - 1.0) if low else m - 1.0
        z = t * t
        p = ((((LOG_P[0] * t + LOG_P[1]) * t + LOG_P[2]) * t + LOG_P[3]) * t + LOG_P[4]) * t + LOG_P[5]
        q = ((((t + LOG_Q[0]) * t + LOG_Q[1]) * t + LOG_Q[2]) * t + LOG_Q[3]) * t + LOG_Q[4]
        y = t * (z * p / q) - e * LN2_LO
        y = y - 0.5 * z
        out[i] = (t + y) + e * LN2_HI
    return out


# -- 2. runs of line beams ------------------------------------------------------------------------


@kernel
def candidate_runs(sig, k, ad_line, sigma_r, p):  # noqa: ANN001, ANN201
    """First and last centre of each run of beams whose window passes the AD test (eq. 4, the
    threshold scaled by the AD noise at that beam) and reaches no slope break (|psi| large).
    ``sig``: the scan's signal block (``signal_block``)."""
    n = sig.shape[1]
    ad_c = p.ad_tau * p.ad_tau * (sigma_r * sigma_r)
    psi_split2 = p.psi_split * p.psi_split
    psi_tau2 = p.psi_tau * p.psi_tau
    ok = np.empty(n, np.bool_)
    for i in range(n):
        dev = sig[S_AD, i] - ad_line
        ok[i] = dev * dev <= ad_c * sig[S_AD_VAR, i]  # nan -> False
    mag = np.zeros(n)  # psi^2 where it marks a slope break, else 0 (no allocation for big)
    any_big = False
    if n > k:
        ku = np.uint64(k)
        for i in range(np.uint64(n - k)):  # without branches, so that it vectorises
            # a slope break between two straight windows (both pass the AD test): where either
            # window fails, the AD test already ends the run, and theta there is not a line's
            # normal (a window across a depth jump), so its psi would cut the neighbouring
            # straight run short
            p2 = sig[S_PSI, i] * sig[S_PSI, i]
            big = ok[i] & ok[ku + i] & (p2 > psi_split2) & (p2 > psi_tau2 * sig[S_PSI_VAR, i])  # > max(.,.) (False on nan)
            mag[i] = p2 if big else 0.0
            any_big |= big
    if any_big:
        # a slope break between the windows at i and i+k peaks near i + k/2: drop the centres
        # whose windows reach it (those within k), as the AD test does at sharp corners
        hit = np.zeros(n, np.bool_)
        for i in range(n):
            if mag[i] > 0.0 and (i == 0 or mag[i] >= mag[i - 1]) and (i == n - 1 or mag[i] >= mag[i + 1]):
                hit[min(i + k // 2, n - 1)] = True
        for i in range(n):
            if hit[i]:
                for j in range(max(0, i - k), min(n, i + k + 1)):
                    ok[j] = False
    runs = np.empty((2, n), np.int64)
    c0, c1 = runs[0], runs[1]
    m = 0
    i = 0
    while i < n:
        if ok[i]:
            j = i
            while j + 1 < n and ok[j + 1]:
                j += 1
            c0[m] = i
            c1[m] = j
            m += 1
            i = j + 1
        else:
            i += 1
    return c0[:m], c1[:m]


@kernel
def slope_sums(sig):  # noqa: ANN001, ANN201
    """(2, n) cumulative sums of theta and theta_var (rows of the signal block ``sig``) as np.cumsum forms them, nan counted as 0
    (``band_of_runs``' means over runs of centres; once per scan)."""
    n = sig.shape[1]
    cs = np.empty((2, n))
    acc_t = 0.0
    acc_v = 0.0
    for i in range(n):
        th = sig[S_THETA, i]
        tv = sig[S_THETA_VAR, i]
        acc_t += 0.0 if np.isnan(th) else th
        acc_v += 0.0 if np.isnan(tv) else tv
        cs[0, i] = acc_t
        cs[1, i] = acc_v
    return cs


# rows of a pass's run table (``fit_spans``, int64 (R_ROWS, runs)): each run's first and last beam,
# beam count, first row in the pass's packed beam arrays, first and last window centre. One block,
# not six arrays: a kernel call costs two atomic reference counts per array it is passed
R_FIRST, R_LAST, R_COUNT, R_START, R_C0, R_C1 = range(6)
R_ROWS = 6

# rows of the scratch blocks ``find_lines`` allocates once a scan and every pass of ``fit_spans``
# reuses, ``cap`` columns (``find_lines``: at least the beams of a pass), instead of ~14 arrays a
# pass (a gain within the machine's noise, docs/history/sensor-speed.md's ninth round; kept as the passes'
# one data layout): floats (W_ROWS, cap + VOTE_BLOCK): a pass's log ranges, bands (centre,
# half-width, cell half-width), Log-Hough peaks (alpha, rho), one angle's votes, a run's
# residuals z and scratch, the refined lines (rho, alpha, covariance 00, 01, 11); the vote
# reference of each band angle
W_LOG_D, W_CENTRE, W_HALF, W_BIN, W_ALPHA, W_RHO, W_VOTES, W_Z, W_SCRATCH, W_VRHO, W_VALPHA, W_C00, W_C01, W_C11, W_REF = range(15)
W_ROWS = 15
# ints (I_ROWS, cap): the run table (``R_*`` rows), the refined lines' first / last inlier beam and
# inlier count, and two span tables of four rows (first, last, shrink0, shrink1) that alternate
# between passes (``find_lines``)
I_FIRST_IN, I_LAST_IN, I_N_IN, I_SPANS_A, I_SPANS_B = 6, 7, 8, 9, 13
I_ROWS = 17
# flags (F_ROWS, cap): the Log-Hough inliers of a pass's beams, a run's inliers, the runs that pass
F_INLIER0, F_INL_RUN, F_GOOD = range(3)
F_ROWS = 3


@kernel
def band_of_runs(runs, sig, cs, ranges, bearings, increment, sigma_r, k, p, fw):  # noqa: ANN001, ANN201
    """Each run's band of normal angles: its slope estimate (the mean of theta over its centres,
    continuous along a run), the band half-width (band_tau std of that mean, at least band_min)
    and the half-width of the peak's log-range window: range noise at the nearest beam plus the
    spread an angle error of half a band step causes over the run (d log p / d a = -tan(a - b)).
    ``runs``: the run table (``R_*`` rows); ``cs``: the cumulative sums of theta and theta_var
    (``slope_sums``). Writes rows W_CENTRE, W_HALF, W_BIN of ``fw``: centre, half-width, peak
    window half-width of each run (column r)."""
    cs_t, cs_v = cs[0], cs[1]
    h = max((p.hough_angles - 1) // 2, 1)
    n_runs = runs.shape[1]
    for r in range(n_runs):
        a, e = runs[R_C0, r], runs[R_C1, r]
        n_c = e - a + 1
        t0 = 0.0 if np.isnan(sig[S_THETA, a]) else sig[S_THETA, a]
        v0 = 0.0 if np.isnan(sig[S_THETA_VAR, a]) else sig[S_THETA_VAR, a]
        centre = (cs_t[e] - cs_t[a] + t0) / n_c
        cvar = (cs_v[e] - cs_v[a] + v0) / (n_c * (1.0 + n_c / (2 * k + 1)))
        half_width = min(max(p.band_tau * math.sqrt(cvar), p.band_min), BAND_MAX)
        angle_step = max(half_width / h, increment / p.hough_subdiv)
        tan_span = abs(math.tan(bearings[B_ANGLE, e + k] - centre) - math.tan(bearings[B_ANGLE, a - k] - centre))
        d_min = np.inf
        for j in range(a - k, e + k + 1):
            d_min = min(d_min, ranges[j])
        fw[W_CENTRE, r] = centre
        fw[W_HALF, r] = half_width
        fw[W_BIN, r] = p.bin_tau * sigma_r / d_min + 0.5 * angle_step * min(tan_span, TAN_SPAN_CAP)


# -- 3. the Log-Hough transform in a band ---------------------------------------------------------


@inline_kernel
def template_at(template, idx) -> float:  # noqa: ANN001
    """template[idx], clipped onto its ends (which hold the floor: beyond them the beam cannot see the line)."""
    return template[min(max(idx, 0), template.size - 1)]


@kernel
def band_peaks(runs, fw, fb, angle_counts, angle_min, subdiv, n_angles, grid):  # noqa: ANN001, ANN201
    """The Log-Hough peak of every run in its band of normal angles, and the beams that voted in it.

    Args: the run table ``runs`` (``R_*`` rows): run r holds beams f .. f + count - 1 (f its
    first beam), whose log ranges are row W_LOG_D of the float block ``fw`` (``find_lines``)
    at columns start .. start + count - 1; per run (column r of rows W_CENTRE, W_HALF, W_BIN,
    ``band_of_runs``) the band centre and half-width (rad) and the half-width of a log-range cell;
    ``angle_counts``: (n_angles, N_BINS + 3) int scratch; the scan's ``angle_min`` (rad).
    Writes rows W_ALPHA, W_RHO of ``fw``: alpha (rad, not wrapped), rho (m) of each run's peak;
    and row F_INLIER0 of the flag block ``fb``: the inlier mask of the beams (log_d's columns).
    """
    template, zero, step, phases = grid.template, grid.zero, grid.step, grid.phases
    n_runs = runs.shape[1]
    h2 = (n_angles - 1) // 2
    h = max(h2, 1)
    n_tmpl = template.size
    n_phase = phases.shape[1]
    flat = phases.reshape(phases.size)  # row r of phases from r * n_phase
    log_d, inlier, votes, ref = fw[W_LOG_D], fb[F_INLIER0], fw[W_VOTES], fw[W_REF]  # rows as views: the vote loops as written
    max_cnt = 0
    for r in range(n_runs):
        max_cnt = max(max_cnt, runs[R_COUNT, r])
    votes[max_cnt:max_cnt + VOTE_BLOCK] = 0.0  # one run's votes at one angle (the generic path), padded
    # per angle: its index, then the vote counts of cells 1..N_BINS (0 and N_BINS + 1 outside)
    a_idx, counts_a = angle_counts[:, 0], angle_counts[:, 1:]
    for r in range(n_runs):
        s, cnt, f = runs[R_START, r], runs[R_COUNT, r], runs[R_FIRST, r]
        centre_idx = np.int64(np.rint((fw[W_CENTRE, r] - angle_min) / step))
        stride = np.int64(max(np.rint(fw[W_HALF, r] / (h * step)), 1.0))
        bin_half = fw[W_BIN, r]
        inv_width = 1.0 / bin_half
        # cells are laid out around the median vote of the beams at 1/4, 1/2 and 3/4 of the run
        # (a mean would be dragged off by neighbour-line beams at its ends; one beam can be a spike)
        t1, t2, t3 = cnt // 4, cnt // 2, (3 * cnt) // 4
        for a in range(n_angles):
            a_idx[a] = centre_idx + stride * (a - h2)
        # the template entries of beams f + t at angle a: template[base - t subdiv], base = a_idx +
        # zero - f subdiv; inside the template (no clipping) for every angle of the band, they are
        # phases[base % subdiv, L - 1 - base // subdiv + t], contiguous in t (``flat``)
        lo_base = a_idx[0] + zero - f * subdiv
        hi_base = a_idx[n_angles - 1] + zero - f * subdiv
        inside = lo_base - (cnt - 1) * subdiv >= 0 and hi_base <= n_tmpl - 1
        s_u = np.uint64(s)
        n_pad = (cnt + VOTE_BLOCK - 1) // VOTE_BLOCK * VOTE_BLOCK
        # the angles by their distance from the band centre (the centre, then h2 -+ 1, h2 -+ 2, ...):
        # once two adjacent cells of an angle hold all cnt votes, no farther angle can beat it (at
        # most cnt votes, less a larger tie-break), and the farther ones are not counted (the same
        # peak as counting them all: the centre alone in 56 % of the office scans' runs, 48 % on MIT CSAIL)
        full = False
        n_done = n_angles
        for ai in range(n_angles):
            if full and ai % 2 == 1:  # a distance done, an angle there held all the votes
                n_done = ai
                break
            a = h2 - (ai + 1) // 2 if ai % 2 == 1 else h2 + ai // 2
            base = a_idx[a] + zero - f * subdiv
            q1 = template_at(template, base - t1 * subdiv) + log_d[s + t1]
            q2 = template_at(template, base - t2 * subdiv) + log_d[s + t2]
            q3 = template_at(template, base - t3 * subdiv) + log_d[s + t3]
            ref[a] = max(min(q1, q2), min(max(q1, q2), q3))  # median of three
            offset = (N_BINS / 2.0 + 1.0) - ref[a] * inv_width
            # eq. 5: log p = log d + log cos(a - b), a lookup at a - b in the template (clipped
            # onto its ends, where it holds the floor)
            if inside:  # indexed unsigned (no negative-index wraparound, no slice to count references of): the loop vectorises
                o = np.uint64((base % subdiv) * n_phase + n_phase - 1 - base // subdiv)
                for t in range(cnt):
                    tu = np.uint64(t)
                    votes[t] = flat[o + tu] + log_d[s_u + tu]
            else:
                for t in range(cnt):
                    votes[t] = template_at(template, base - t * subdiv) + log_d[s + t]
            # the votes counted in cells rel = (log p - ref) / width + N_BINS / 2 + 1, floored and
            # clipped onto 0 .. N_BINS + 1, as 16-bit fields of four words (cells 4w .. 4w + 3 in
            # word w; a run has fewer than 2^16 beams, as the registry takes scans of at most
            # MAX_BEAMS = 16,384). The loop runs over whole VOTE_BLOCKs (``votes`` is padded, the
            # padding counts nowhere) without stores: it vectorises, without a scalar remainder
            w0 = w1 = w2 = w3 = np.uint64(0)
            for t in range(n_pad):
                rel = votes[t] * inv_width + offset
                rel = rel if rel >= 0.0 else 0.0  # nan votes go to the outside cell 0
                cell = np.uint64(min(rel, N_BINS + 1.0))
                one = (np.uint64(1) if t < cnt else np.uint64(0)) << ((cell & np.uint64(3)) * np.uint64(16))
                word = cell >> np.uint64(2)
                w0 += one if word == 0 else np.uint64(0)
                w1 += one if word == 1 else np.uint64(0)
                w2 += one if word == 2 else np.uint64(0)
                w3 += one if word == 3 else np.uint64(0)
            for c in range(N_BINS + 2):
                w = w0 if c < 4 else (w1 if c < 8 else (w2 if c < 12 else w3))
                counts_a[a, c] = np.int64((w >> np.uint64(16 * (c % 4))) & np.uint64(0xFFFF))
            for c in range(N_BINS - 1):
                full |= counts_a[a, c + 1] + counts_a[a, c + 2] == cnt
        best = -np.inf
        best_a = 0
        best_c = 0
        reach = (n_done - 1) // 2  # the angles counted: h2 - reach .. h2 + reach
        for a in range(h2 - reach, h2 + reach + 1):
            tie = -TIE_BREAK * abs(a - h2)
            for c in range(N_BINS - 1):
                v = (counts_a[a, c + 1] + counts_a[a, c + 2]) + tie  # two adjacent cells
                if v > best:
                    best, best_a, best_c = v, a, c
        # the pair (c, c+1) covers (log p - ref) / width in [c - N_BINS/2, c + 2 - N_BINS/2)
        peak_log_p = ref[best_a] + (best_c + 1 - N_BINS / 2.0) * bin_half
        fw[W_ALPHA, r] = angle_min + a_idx[best_a] * step
        fw[W_RHO, r] = math.exp(peak_log_p)
        base = a_idx[best_a] + zero - f * subdiv
        if inside:
            o = np.uint64((base % subdiv) * n_phase + n_phase - 1 - base // subdiv)
            for t in range(cnt):
                tu = np.uint64(t)
                inlier[s_u + tu] = abs((flat[o + tu] + log_d[s_u + tu]) - peak_log_p) <= bin_half
        else:
            for t in range(cnt):
                inlier[s + t] = abs((template_at(template, base - t * subdiv) + log_d[s + t]) - peak_log_p) <= bin_half


@kernel
def band_search(first, log_d, starts, counts, centre, half_width, bin_half, angle_min, subdiv, n_angles, grid):  # noqa: ANN001, ANN201
    """``band_peaks`` of runs given as arrays: first beams, rows of ``log_d`` from ``starts``, beam
    counts, band centres and half-widths (rad), log-range cell half-widths. Returns alpha (rad,
    not wrapped), rho (m) of each run's peak and the inlier mask of the rows."""
    runs = np.zeros((R_ROWS, first.size), np.int64)
    runs[R_FIRST], runs[R_COUNT], runs[R_START] = first, counts, starts
    width = max(log_d.size, first.size, n_angles, 1) + VOTE_BLOCK
    fw = np.empty((W_ROWS, width))
    fb = np.zeros((F_ROWS, width), np.bool_)
    fw[W_LOG_D, :log_d.size] = log_d
    fw[W_CENTRE, :first.size], fw[W_HALF, :first.size], fw[W_BIN, :first.size] = centre, half_width, bin_half
    band_peaks(runs, fw, fb, np.empty((n_angles, N_BINS + 3), np.int64), angle_min, subdiv, n_angles, grid)
    return fw[W_ALPHA, :first.size].copy(), fw[W_RHO, :first.size].copy(), fb[F_INLIER0, :log_d.size].copy()


# -- 4. weighted refinement -----------------------------------------------------------------------


@kernel
def local_scale(ranges, valid, f, l, t, c2, w, ra, rb) -> float:  # noqa: ANN001
    """Robust scale (m, 1.4826 x the median absolute value) of the collinearity residuals of the
    triples (j - t, j, j + t) of valid beams in f..l without a depth step (``lms200.noise.line_residuals``;
    c2 = 2 cos(t D)), 0 when there are fewer than LOCAL_MIN_TRIPLES; rows ``ra`` and ``rb`` of ``w`` are scratch of l - f + 1 or more."""
    m = 0
    for j in range(f + t, l - t + 1):
        if valid[j - t] and valid[j] and valid[j + t]:
            rm, r0, rp = ranges[j - t], ranges[j], ranges[j + t]
            if not abs(rp - rm) <= JUMP_FRACTION * r0:  # a depth step, as lms200.noise skips it
                continue
            q = 1.0 / (rm + rp)  # as ``neighbour_residuals``
            q2 = q * q
            wm = c2 * (rp * rp) * q2
            wp = c2 * (rm * rm) * q2
            w[ra, m] = abs(r0 - c2 * rm * rp * q) / math.sqrt(1.0 + wm * wm + wp * wp)
            m += 1
    if m < LOCAL_MIN_TRIPLES:
        return 0.0
    return MAD_TO_SIGMA * median_rows(w, ra, rb, m)  # selected in place (np.median copies)


@kernel
def add_normal_terms(sums, wr, g, res):  # noqa: ANN001, ANN201
    """The normal-equation sums (sum w, sum w g, sum w g^2, sum w r, sum w g r) of a line fit with
    one more beam: weight ``wr``, residual ``res`` and its derivative ``g`` by alpha (the one
    accumulation of ``gn_sums``, ``gn_sums_inliers`` and ``biweight_sums``; added beam after beam)."""
    sw, swg, swgg, swr, swgr = sums
    wg = wr * g
    return sw + wr, swg + wg, swgg + wg * g, swr + wr * res, swgr + wg * res


@inline_kernel
def ray_sd(d: float, c: float, sigma_r: float, st2: float) -> float:
    """Std (m) of a beam's ray residual about a line it meets at cos(b - alpha) = c, range d (m):
    the range noise sigma_r (m) and the bearing noise st2 (rad^2), which moves the range by
    d tan(b - alpha) per radian (large at grazing incidence; on interlaced 0.5 deg logs the two
    sweeps' bearings differ by the robot's turn between them, ``noise_estimate.bearing_sigma``)."""
    if st2 == 0.0:
        return sigma_r  # exact bearings: the range noise alone, bit for bit
    t = d * math.sqrt(max(1.0 - c * c, 0.0)) / c
    return math.sqrt(sigma_r * sigma_r + t * t * st2)


@inline_kernel
def gn_sums(d, bt, valid, use, f, s, cnt, ca, sa, rho, kb):  # noqa: ANN001, ANN201
    """The weighted normal equations of a Gauss-Newton step of a line (rho, alpha = atan2(sa, ca))
    on the beams j = f .. f + cnt - 1 where valid[j] and use[s + j - f] (range d, bearing b with
    cos(b), sin(b) in rows B_COS, B_SIN of ``bt``): (sum w, sum w g, sum w g^2, sum w r, sum w g r) with residual
    r = d cos(b - alpha) - rho, g = d r / d alpha = d sin(b - alpha) and weight
    w = 1 / (cos(b - alpha)^2 + kb g^2) (0 within MIN_COS of grazing): the inverse variance of r in
    units of sigma_r^2, kb = sigma_bearing^2 / sigma_r^2 (``ray_sd``; 1 / cos^2 exactly at kb = 0).
    Without branches on data: the loop
    runs in vector lanes. Offsets into whole arrays, not slices (a slice a run is two atomic
    reference counts)."""
    sums = (0.0, 0.0, 0.0, 0.0, 0.0)
    if f < 0 or s < 0:
        return sums
    for t in range(cnt):
        j = f + t
        c = bt[B_COS, j] * ca + bt[B_SIN, j] * sa  # cos(b - alpha)
        dt = d[j] if valid[j] else 0.0  # an invalid beam's range is inf or nan
        res = dt * c - rho  # d res / d rho = -1
        g = dt * (bt[B_SIN, j] * ca - bt[B_COS, j] * sa)
        ic = 1.0 / c
        ic2 = ic * ic
        # 1 / c^2 at kb = 0, where the division by 1 + 0 is skipped (a used beam's g and 1 / c are finite: the
        # same value; one division a beam fewer)
        wb = ic2 if kb == 0.0 else ic2 / (1.0 + g * g * ic2 * kb)
        wr = wb if (c > MIN_COS) & valid[j] & use[s + t] else 0.0
        sums = add_normal_terms(sums, wr, g, res)
    return sums


@inline_kernel
def gn_sums_inliers(d, bt, valid, f, cnt, ca, sa, rho, inv_sigma, st2, tau, z, inl):  # noqa: ANN001, ANN201
    """``gn_sums`` on the beams j = f .. f + cnt - 1 within ``tau`` std of the line (|z| <= tau,
    z = r / (cos(b - alpha) sd_j) the ray residual in its std sd_j = sqrt(s2 + (d tan(b - alpha))^2
    st2): range noise sigma_r = 1 / inv_sigma plus bearing noise st2 (rad^2), ``ray_sd``; written
    to z[j - f], the inliers to inl[j - f]), weighted as in ``gn_sums``, with
    the line checks' sums over the inliers: chi^2 = sum z^2, their count, sums of t, t^2, t^3
    (t = j - f, integers: exact in any order below 2^53, runs under ~13,000 beams) and the first
    and last inlier's t (cnt and -1 when there is none)."""
    sums = (0.0, 0.0, 0.0, 0.0, 0.0)
    chi = 0.0
    ni = i_t = i_t2 = i_t3 = 0
    lo = cnt
    hi = -1
    if f < 0:
        return sums, chi, ni, i_t, i_t2, i_t3, lo, hi
    kb = st2 * inv_sigma * inv_sigma
    for t in range(cnt):
        j = f + t
        c = bt[B_COS, j] * ca + bt[B_SIN, j] * sa
        dt = d[j] if valid[j] else 0.0
        res = dt * c - rho
        g = dt * (bt[B_SIN, j] * ca - bt[B_COS, j] * sa)
        ic = 1.0 / c
        gi = g * ic  # d tan(b - alpha)
        kg = gi * gi * kb  # (d tan(b - alpha) sigma_bearing / sigma_r)^2
        zt = res * ic * (inv_sigma if kb == 0.0 else inv_sigma / math.sqrt(1.0 + kg))
        use = (c > MIN_COS) & valid[j] & (abs(zt) <= tau)
        ic2 = ic * ic
        wr = (ic2 if kb == 0.0 else ic2 / (1.0 + kg)) if use else 0.0  # gn_sums' weight (its division skipped at kb = 0)
        sums = add_normal_terms(sums, wr, g, res)
        z[t] = zt
        inl[t] = use
        chi += zt * zt if use else 0.0
        ti = t if use else 0
        ni += use
        i_t += ti
        i_t2 += ti * ti
        i_t3 += ti * ti * ti
        lo = min(lo, t if use else cnt)
        hi = max(hi, t if use else -1)
    return sums, chi, ni, i_t, i_t2, i_t3, lo, hi


@inline_kernel
def curvature_sums(z, inl, cnt, a_lin, b_lin):  # noqa: ANN001, ANN201
    """(sum z q, sum q^2) over the inliers inl[:cnt], q = t^2 - a_lin - b_lin t (t the beam's offset)."""
    zq = qq = 0.0
    for t in range(cnt):
        tf = float(t)
        q = tf * tf - a_lin - b_lin * tf
        zq += z[t] * q if inl[t] else 0.0
        qq += q * q if inl[t] else 0.0
    return zq, qq


@kernel
def fit_runs(runs, fw, fb, iw, ranges, bearings, valid, sigma_r, p):  # noqa: ANN001, ANN201
    """Refine every run's line (the run table ``runs``: run r holds beams f .. f + count - 1, its
    Log-Hough inliers in row F_INLIER0 of ``fb`` from column start; its Log-Hough alpha, rho in
    rows W_ALPHA, W_RHO of ``fw``) by two weighted Gauss-Newton steps, one on the Log-Hough inliers,
    then one on the beams within inlier_tau sigma_r of that (which gives the covariance), and
    check it: enough inliers (min(min_points, 2k + 1): min_points is asked of the line once
    ``extend_ends`` has grown it), most of the run explained, chi^2 of the inliers (per dof at
    most max_chi2 times sigma_r^2, or times the run's own noise^2 where that is larger:
    ``local_scale`` of its beams within one mirror turn, so that the interlaced sweeps' offset,
    already in sigma_r, does not count twice; real noise grows with range and varies with the
    surface: Intel's 4.3 mm within 1 m, 7.9 mm beyond 8 m, around the log's 5.3 mm), and
    curvature (the t-statistic of the residuals against a parabola in the beam index, orthogonal
    to 1 and t over the inliers: ~N(0, 1) on a line, large on an arc).

    A Gauss-Newton step: beam j (range d, bearing b) on x cos(alpha) + y sin(alpha) = rho has
    residual r_j = d_j cos(b_j - alpha) - rho; range noise moves it by e_j cos(b_j - alpha), so
    its weight is 1 / (sigma_r cos)^2 and (J^T W J)^-1 is the covariance of (rho, alpha). Beams
    within MIN_COS of grazing get no weight. Each step is one pass over the run's beams, its
    sums accumulated as it goes (``gn_sums``); the second also marks the inliers and sums what the
    checks need (``gn_sums_inliers``), so that a run's beams are read twice and, for the
    curvature, a third time.

    Writes the lines in normal form to column r of the blocks (``find_lines``): rows W_VRHO
    (rho >= 0), W_VALPHA (alpha in (-pi, pi]), W_C00, W_C01, W_C11 (covariance) of ``fw``; rows
    I_FIRST_IN, I_LAST_IN, I_N_IN (first / last inlier beam, inlier count) of ``iw``; and row
    F_GOOD of ``fb``, the mask of those that pass."""
    n_runs = runs.shape[1]
    # a run's normalised residuals z (row W_Z) and, after the checks' sums, local_scale's scratch (W_SCRATCH)
    z_run, inl_run, inlier0 = fw[W_Z], fb[F_INL_RUN], fb[F_INLIER0]
    curv2 = p.curvature_tau * p.curvature_tau
    tau = p.inlier_tau
    inv_sigma = 1.0 / sigma_r
    s2 = sigma_r * sigma_r
    step = bearings[B_ANGLE, 1] - bearings[B_ANGLE, 0] if bearings.shape[1] > 1 else 1.0
    st2 = p.sigma_bearing * p.sigma_bearing  # bearing noise variance, rad^2
    sweep = max(1, np.int64(np.rint(ONE_DEG / step))) if step < 0.99 * ONE_DEG else 1  # lms200.noise.interlace_stride
    c2 = 2.0 * math.cos(sweep * step)
    for r in range(n_runs):
        s, cnt, f = runs[R_START, r], runs[R_COUNT, r], runs[R_FIRST, r]
        # step 1, on the Log-Hough inliers
        sw, swg, swgg, swr, swgr = gn_sums(ranges, bearings, valid, inlier0, f, s, cnt, math.cos(fw[W_ALPHA, r]),
                                           math.sin(fw[W_ALPHA, r]), fw[W_RHO, r], st2 / s2)
        inv_det = 1.0 / (sw * swgg - swg * swg)  # normal equations H delta = -J^T W r, J = [-1, g]
        rho1 = fw[W_RHO, r] + (swgg * swr - swg * swgr) * inv_det
        alpha1 = fw[W_ALPHA, r] + (swg * swr - sw * swgr) * inv_det
        # step 2, on the beams within inlier_tau sigma_r of step 1's line, with the checks' sums
        (sw, swg, swgg, swr, swgr), chi, ni, i_t, i_t2, i_t3, lo, hi = gn_sums_inliers(
            ranges, bearings, valid, f, cnt, math.cos(alpha1), math.sin(alpha1), rho1, inv_sigma, st2, tau, z_run, inl_run)
        inv_det = 1.0 / (sw * swgg - swg * swg)
        rho_r = rho1 + (swgg * swr - swg * swgr) * inv_det
        alpha_r = alpha1 + (swg * swr - sw * swgr) * inv_det
        var = s2 * inv_det
        c00, c01, c11 = swgg * var, swg * var, sw * var
        iw[I_FIRST_IN, r] = f + lo
        iw[I_LAST_IN, r] = f + hi
        iw[I_N_IN, r] = ni
        # the checks, each only while the ones before pass (a run that fails one needs no other)
        ok = ni >= min(p.min_points, 2 * p.k + 1) and ni >= p.min_inlier_fraction * cnt  # min_points: of the grown line (find_lines)
        if ok:  # curvature: the residuals against q = t^2 - a - b t, orthogonal to 1 and t over the inliers
            n_f = max(float(ni), 1.0)
            m1, m2, m3 = float(i_t) / n_f, float(i_t2) / n_f, float(i_t3) / n_f
            b_lin = (m3 - m1 * m2) / max(m2 - m1 * m1, 1e-12)
            a_lin = m2 - b_lin * m1
            zq, qq = curvature_sums(z_run, inl_run, cnt, a_lin, b_lin)
            ok = zq * zq <= curv2 * qq
        if ok:
            chi_max = p.max_chi2 * max(ni - 2, 1)
            if chi > chi_max:  # the run's own noise, where it exceeds sigma_r
                loc = local_scale(ranges, valid, f, f + cnt - 1, sweep, c2, fw, W_SCRATCH, W_Z) / sigma_r  # z_run read no more
                chi_max *= max(1.0, loc * loc)
            ok = chi <= chi_max and np.isfinite(rho_r + alpha_r + c00 + c11)
        fb[F_GOOD, r] = ok
        if rho_r < 0:
            rho_r = -rho_r
            alpha_r = alpha_r + math.pi
            c01 = -c01
        fw[W_VRHO, r] = rho_r
        fw[W_VALPHA, r] = wrap(alpha_r)
        fw[W_C00, r], fw[W_C01, r], fw[W_C11, r] = c00, c01, c11


@kernel
def extend_ends(rho, alpha, first, last, n_points, ranges, bearings, valid, reach, inlier_tau, sigma_r, st2):  # noqa: ANN001
    """In place: grow each line over the up to ``reach`` beams past each end that continue it
    (valid, |ray residual| <= inlier_tau of its std, ``ray_sd`` with the bearing noise st2 (rad^2),
    no break): the AD windows stop short of corners."""
    n = ranges.size
    for m in range(rho.size):
        ca, sa = math.cos(alpha[m]), math.sin(alpha[m])
        grow0 = 0
        for s in range(1, reach + 1):
            j = last[m] + s
            if j >= n:
                break
            c = bearings[B_COS, j] * ca + bearings[B_SIN, j] * sa  # cos(b - alpha)
            if not (valid[j] and c > MIN_COS and abs(ranges[j] * c - rho[m]) <= inlier_tau * ray_sd(ranges[j], c, sigma_r, st2) * c):
                break
            grow0 += 1
        grow1 = 0
        for s in range(1, reach + 1):
            j = first[m] - s
            if j < 0:
                break
            c = bearings[B_COS, j] * ca + bearings[B_SIN, j] * sa  # cos(b - alpha)
            if not (valid[j] and c > MIN_COS and abs(ranges[j] * c - rho[m]) <= inlier_tau * ray_sd(ranges[j], c, sigma_r, st2) * c):
                break
            grow1 += 1
        first[m] -= grow1
        last[m] += grow0
        n_points[m] += grow0 + grow1


@inline_kernel
def biweight_sums(x, y, inv_c, n, ca, sa, rho, inv_cut):  # noqa: ANN001, ANN201
    """The normal equations of one reweighted step of Tukey's biweight on the points (x, y)[:n] (m)
    about the line (rho, alpha = atan2(sa, ca)): (sum w, sum w g, sum w g^2, sum w r, sum w g r)
    with r the normal residual, g = d r / d alpha and w = ((1 - u^2)^2 / cos(b - alpha))^2 for
    |u| < 1 (else 0), u = r / cos(b - alpha) * inv_cut the ray residual in cut-offs
    (``inv_c`` = 1 / cos(b - alpha)). A count, not views: a view is two atomic reference counts."""
    sums = (0.0, 0.0, 0.0, 0.0, 0.0)
    for t in range(n):
        res = x[t] * ca + y[t] * sa - rho
        u = res * inv_c[t] * inv_cut
        bw = max(1.0 - u * u, 0.0) * inv_c[t]
        g = y[t] * ca - x[t] * sa  # d res / d alpha = r sin(b - alpha)
        sums = add_normal_terms(sums, bw * bw, g, res)
    return sums


@kernel
def robust_refit(rho, alpha, first, last, ranges, bearings, valid) -> None:  # noqa: ANN001
    """In place: each line (rho, alpha) refitted on the valid beams first..last by ROBUST_STEPS
    iteratively reweighted steps of Tukey's biweight M-estimator (tuning TUKEY_C scales) on the ray
    residuals z = r - rho / cos(b - alpha), the scale 1.4826 median |z| about the line as it comes
    in (at least SIGMA_FLOOR_RAY). The ray normalisation 1 / cos(b - alpha) is taken at the
    incoming line (the steps move alpha by far less than a beam step). Real residuals are
    heavy-tailed (a chair leg before a wall, mixed pixels, a stretch of rough surface) and their
    scatter varies along a scan, so the least-squares line over the inlier_tau sigma_r inliers is
    pulled off the bulk of its beams; the biweight keeps to the bulk. The covariance stays the
    least-squares one (the biweight's efficiency under Gaussian noise is 95 %)."""
    n = ranges.size
    work = np.empty((5, n))  # one block: the used beams' x, y, 1 / cos(b - alpha), |z|, the median's scratch
    x, y, inv_c, z = work[0], work[1], work[2], work[3]  # row 4: the median's buffer
    for m in range(rho.size):
        r_m, a_m = rho[m], alpha[m]
        ca, sa = math.cos(a_m), math.sin(a_m)
        k = 0
        j = np.uint64(first[m])  # beams indexed unsigned: numba then adds no negative-index wraparound
        end = np.uint64(last[m] + 1)
        while j < end:  # every beam written at k, k moved on past the used ones: no branch on data
            c = bearings[B_COS, j] * ca + bearings[B_SIN, j] * sa
            xj = ranges[j] * bearings[B_COS, j]
            yj = ranges[j] * bearings[B_SIN, j]
            x[k] = xj
            y[k] = yj
            ic = 1.0 / c
            inv_c[k] = ic
            z[k] = abs(xj * ca + yj * sa - r_m) * ic
            k += valid[j] & (c > MIN_COS)
            j += np.uint64(1)
        if k < 3:
            continue
        scale = max(MAD_TO_SIGMA * median_rows(work, 3, 4, k), SIGMA_FLOOR_RAY)  # z (row 3) selected in place: not read again
        inv_cut = 1.0 / (TUKEY_C * scale)
        for _ in range(ROBUST_STEPS):
            sw, swg, swgg, swr, swgr = biweight_sums(x, y, inv_c, k, ca, sa, r_m, inv_cut)  # cos, sin of a_m
            det = sw * swgg - swg * swg
            if not det > 0.0:
                break
            r_new = r_m + (swgg * swr - swg * swgr) / det
            a_new = a_m + (swg * swr - sw * swgr) / det
            if not (math.isfinite(r_new) and math.isfinite(a_new)):
                break
            r_m, a_m = r_new, a_new
            if ROBUST_STEPS > 1:
                ca, sa = math.cos(a_m), math.sin(a_m)
        if r_m < 0:
            r_m = -r_m
            a_m += math.pi
        rho[m] = r_m
        alpha[m] = wrap(a_m)


@kernel
def farthest_from_chord(f, l, ranges, bearings) -> int:  # noqa: ANN001
    """The beam of f..l farthest from the chord between the end points of beams f and l
    (Cartesian, sensor frame; the middle one when none is off it): where a span that does not fit
    one line bends (IEPF's split point)."""
    x0, y0 = ranges[f] * bearings[B_COS, f], ranges[f] * bearings[B_SIN, f]
    x1, y1 = ranges[l] * bearings[B_COS, l], ranges[l] * bearings[B_SIN, l]
    dx, dy = x1 - x0, y1 - y0
    norm = max(math.hypot(dx, dy), 1e-12)
    best, at = -1.0, (f + l) // 2
    for j in range(f + 1, l):
        x, y = ranges[j] * bearings[B_COS, j], ranges[j] * bearings[B_SIN, j]
        dist = abs((x - x0) * dy - (y - y0) * dx) / norm
        if dist > best:
            best, at = dist, j
    return at


# rows of ``circle_fits``' per-beam block: the points x, y (m, sensor frame), then each pass's
# terms (the Jacobian's two centre columns, the residual); indexed in the block, not cut into views
C_X, C_Y, C_J0, C_J1, C_E = range(5)
C_ROWS = 5


@inline_kernel
def valid_centroid(work, valid, f, lo, hi):  # noqa: ANN001, ANN201
    """(x, y, n): the mean of the points t = lo .. hi - 1 of ``work`` (rows C_X, C_Y: m, sensor
    frame; point t is beam f + t) whose beams are valid, and their count (x = y = 0 when there is
    none)."""
    n = 0
    mx = 0.0
    my = 0.0
    for t in range(lo, hi):
        if valid[f + t]:
            mx += work[C_X, t]
            my += work[C_Y, t]
            n += 1
    if n > 0:
        mx /= n
        my /= n
    return mx, my, n


@kernel
def tls_clipped(work, valid, f, lo, hi, sigma_r, lim) -> float:  # noqa: ANN001
    """Sum of the squared normalised residuals (each clipped at ``lim``) of the points t = lo ..
    hi - 1 of ``work`` (``valid_centroid``) of valid beams about their total-least-squares line."""
    mx, my, n = valid_centroid(work, valid, f, lo, hi)
    if n < 3:
        return 0.0
    cxx = cyy = cxy = 0.0
    for t in range(lo, hi):
        if valid[f + t]:
            u = work[C_X, t] - mx
            v = work[C_Y, t] - my
            cxx += u * u
            cyy += v * v
            cxy += u * v
    a = 0.5 * math.atan2(-2.0 * cxy, cyy - cxx)
    ca, sa = math.cos(a), math.sin(a)
    out = 0.0
    for t in range(lo, hi):
        if valid[f + t]:
            z = ((work[C_X, t] - mx) * ca + (work[C_Y, t] - my) * sa) / sigma_r
            out += min(z * z, lim)
    return out


@inline_kernel
def theta_turn(a, b, sig) -> float:  # noqa: ANN001
    """How far the slope estimate theta (rad) turns between the first and the last beam of a..b
    where it is known (inf where it is known at fewer than two): a cheap first look at whether
    the surface there turns at all."""
    i = a
    while i <= b and not np.isfinite(sig[S_THETA, i]):
        i += 1
    j = b
    while j > i and not np.isfinite(sig[S_THETA, j]):
        j -= 1
    if j <= i:
        return np.inf
    return abs(wrap(sig[S_THETA, j] - sig[S_THETA, i]))


@inline_kernel
def surface_turn(f, l, cx, cy, ranges, bearings) -> float:  # noqa: ANN001
    """The angle (rad) beams f and l subtend at the centre (cx, cy): how far a circle about it
    turns between them."""
    ax, ay = ranges[f] * bearings[B_COS, f] - cx, ranges[f] * bearings[B_SIN, f] - cy
    bx, by = ranges[l] * bearings[B_COS, l] - cx, ranges[l] * bearings[B_SIN, l] - cy
    return abs(math.atan2(ax * by - ay * bx, ax * bx + ay * by))


@inline_kernel
def circle_gn_sums(work, valid, f, m):  # noqa: ANN001, ANN201
    """The normal equations of a geometric Gauss-Newton step of a circle over the beams where
    valid (point t of ``work`` is beam f + t, t < m), from the Jacobian rows [C_J0, C_J1, -1]
    and residuals C_E of ``work``: (H00, H01, H02, H11, H12, H22, g0, g1, g2), H = J^T J, g = J^T e."""
    h00 = h01 = h02 = h11 = h12 = h22 = g0 = g1 = g2 = 0.0
    for t in range(m):
        ok = valid[f + t]
        w = 1.0 if ok else 0.0
        a = work[C_J0, t] if ok else 0.0  # an invalid beam's terms may be nan: selected, not multiplied
        b = work[C_J1, t] if ok else 0.0
        c = work[C_E, t] if ok else 0.0
        h00 += a * a
        h01 += a * b
        h02 -= a
        h11 += b * b
        h12 -= b
        h22 += w
        g0 += a * c
        g1 += b * c
        g2 -= c
    return h00, h01, h02, h11, h12, h22, g0, g1, g2


@inline_kernel
def taubin_circle(mxx, mxy, myy, mxz, myz, mzz):  # noqa: ANN001, ANN201
    """Taubin's algebraic circle fit (G. Taubin, IEEE PAMI 13(11), 1991, in N. Chernov's Newton
    form, "Circular and linear regression", 2010) from the mean moments of points about their
    centroid (u, v; z = u^2 + v^2; m^2, m^3, m^4): the centre (uc, vc) about the centroid and the
    radius (m). Unlike Kasa's fit (the centre from a 2x2 system, biased towards small circles on
    short arcs and corners), it is close to the geometric (least-squares distance) circle: one
    geometric Gauss-Newton step from it decides the arc check as three from Kasa's did not (see
    ``circle_fits``). Non-finite values where the moments are degenerate."""
    mz = mxx + myy
    cov_xy = mxx * myy - mxy * mxy
    var_z = mzz - mz * mz
    a3 = 4.0 * mz
    a2 = -3.0 * mz * mz - mzz
    a1 = var_z * mz + 4.0 * cov_xy * mz - mxz * mxz - myz * myz
    a0 = mxz * (mxz * myy - myz * mxy) + myz * (myz * mxx - mxz * mxy) - var_z * cov_xy
    x = 0.0  # Newton from 0 on a0 + a1 x + a2 x^2 + a3 x^3: its smallest root (the fit's eigenvalue)
    y = a0
    for _ in range(TAUBIN_NEWTON_STEPS):
        dy = a1 + x * (2.0 * a2 + 3.0 * a3 * x)
        xn = x - y / dy
        if xn == x or not math.isfinite(xn):
            break
        yn = a0 + xn * (a1 + xn * (a2 + xn * a3))
        if abs(yn) >= abs(y):
            break
        x, y = xn, yn
    det = 2.0 * (x * x - x * mz + cov_xy)
    uc = (mxz * (myy - x) - myz * mxy) / det
    vc = (myz * (mxx - x) - mxz * mxy) / det
    return uc, vc, math.sqrt(uc * uc + vc * vc + mz)


@kernel
def circle_fits(f, l, lf, ll, lrho, lalpha, ranges, bearings, valid, sigma_r, p, work) -> bool:  # noqa: ANN001
    """Do the valid beams f..l trace one round surface? One circle (algebraic Taubin fit,
    ``taubin_circle``, then ARC_GN_STEPS geometric Gauss-Newton steps) must fit them as the line
    checks ask of a line (min_inlier_fraction of the beams within inlier_tau sigma_r, chi^2 per dof <= max_chi2), and
    the surface must turn along them by at least corner_min_turn (a smooth turn that a polyline
    would break into false corners; a gently bent wall is no round surface). Then:

    - a span that failed the line checks (``lf`` < 0): the circle must fit it better than two
      lines split at its chord would (its summed squared residuals, each clipped at inlier_tau^2,
      no larger: a kink or a step between two faces is fitted better by the two lines);
    - a line (rho ``lrho``, alpha ``lalpha``) on beams lf..ll inside f..l, its neighbourhood: the
      circle must explain the line's own beams as well as the line does (chi^2 no more than
      ARC_TAU std of the difference above), fit the neighbourhood better than one line does
      (by more than ARC_TAU^2, a likelihood-ratio test at ARC_TAU std for the circle's one more
      parameter: on a straight wall the circle's turn is noise) and fit it as tightly as the line
      fits its own beams (mean squared residual within ARC_TAU std of the line's chi^2 per dof: at
      a real corner the circle is a compromise with far larger residuals; this comparison holds
      whatever the actual scatter, e.g. of the interlaced sweeps of 0.5 deg logs). Every chi^2
      here is clipped at inlier_tau^2 a beam, as the checks see a line (its inliers): unclipped,
      two stray beams on a line (mixed pixels, clutter) made it look as loose as a circle.

    ``work``: a (C_ROWS, l - f + 1 or more) scratch block, for the beams' points and then the
    per-beam terms of each pass over them (the caller's, once a scan: not an allocation a call)."""
    m = l - f + 1
    n = 0  # the points and the centroid of the valid ones in one pass (``valid_centroid``'s sums, in its order)
    mx = 0.0
    my = 0.0
    for t in range(m):
        x = ranges[f + t] * bearings[B_COS, f + t]
        y = ranges[f + t] * bearings[B_SIN, f + t]
        work[C_X, t] = x
        work[C_Y, t] = y
        if valid[f + t]:
            mx += x
            my += y
            n += 1
    if n < 5:
        return False
    mx /= n
    my /= n
    suu = suv = svv = suz = svz = szz = 0.0  # second to fourth moments about the centroid (z = u^2 + v^2)
    for t in range(m):
        if valid[f + t]:
            u = work[C_X, t] - mx
            v = work[C_Y, t] - my
            uu = u * u
            vv = v * v
            z = uu + vv
            suu += uu
            suv += u * v
            svv += vv
            suz += u * z
            svz += v * z
            szz += z * z
    if not abs(suu * svv - suv * suv) > 1e-18:
        return False  # the points on one line (or one point): no circle
    uc, vc, rad = taubin_circle(suu / n, suv / n, svv / n, suz / n, svz / n, szz / n)
    cx, cy = uc + mx, vc + my
    if not surface_turn(f, l, cx, cy, ranges, bearings) >= 0.5 * p.corner_min_turn:
        return False  # nearly straight (most lines): no geometric fit needed
    for _ in range(ARC_GN_STEPS):  # geometric residual e_j = |x_j - c| - R; J = [-(x - c) / |x - c|, -1]
        for t in range(m):  # the square roots and divisions of all beams in a loop that vectorises
            dx = work[C_X, t] - cx
            dy = work[C_Y, t] - cy
            dist = max(math.sqrt(dx * dx + dy * dy), 1e-12)  # not hypot: a libm call a beam
            inv = 1.0 / dist  # one division a beam, not two
            work[C_J0, t] = -dx * inv
            work[C_J1, t] = -dy * inv
            work[C_E, t] = dist - rad
        h00, h01, h02, h11, h12, h22, g0, g1, g2 = circle_gn_sums(work, valid, f, m)
        # H d = -g with H's adjugate (H symmetric: [[h00, h01, h02], [h01, h11, h12], [h02, h12, h22]])
        a00 = h11 * h22 - h12 * h12
        a01 = h02 * h12 - h01 * h22
        a02 = h01 * h12 - h02 * h11
        a11 = h00 * h22 - h02 * h02
        a12 = h01 * h02 - h00 * h12
        a22 = h00 * h11 - h01 * h01
        dt = h00 * a00 + h01 * a01 + h02 * a02
        if not abs(dt) > 1e-18:
            break
        cx -= (a00 * g0 + a01 * g1 + a02 * g2) / dt
        cy -= (a01 * g0 + a11 * g1 + a12 * g2) / dt
        rad -= (a02 * g0 + a12 * g1 + a22 * g2) / dt
    if not (rad > 0.0 and surface_turn(f, l, cx, cy, ranges, bearings) >= p.corner_min_turn):
        return False
    for t in range(m):  # the circle's normalised residuals
        dx = work[C_X, t] - cx
        dy = work[C_Y, t] - cy
        work[C_E, t] = (math.sqrt(dx * dx + dy * dy) - rad) / sigma_r
    lim = p.inlier_tau * p.inlier_tau
    chi = 0.0  # the circle's chi^2 over the inliers of the neighbourhood, and clipped over all of it
    clipped = 0.0
    ni = 0
    for t in range(m):
        if valid[f + t]:
            zz = work[C_E, t]
            z2 = zz * zz
            clipped += min(z2, lim)
            if z2 <= lim:
                chi += z2
                ni += 1
    if not (ni >= p.min_inlier_fraction * n and chi <= p.max_chi2 * max(ni - 3, 1)):
        return False
    if lf < 0:  # a span without a line: the circle must fit it better than two lines split at its chord
        c = farthest_from_chord(f, l, ranges, bearings) - f + 1  # the two lines' beams: :c and c:
        two = tls_clipped(work, valid, f, 0, c, sigma_r, lim) + tls_clipped(work, valid, f, c, m, sigma_r, lim)
        return clipped <= two
    ca, sa = math.cos(lalpha), math.sin(lalpha)
    for t in range(lf - f, ll - f + 1):  # the line's beams: the circle's residuals (in C_E) and the line's
        work[C_J1, t] = (work[C_X, t] * ca + work[C_Y, t] * sa - lrho) / sigma_r
    c_chi = 0.0
    l_chi = 0.0
    nl = 0
    for t in range(lf - f, ll - f + 1):
        if valid[f + t]:
            zc = work[C_E, t]
            zl = work[C_J1, t]
            c_chi += min(zc * zc, lim)
            l_chi += min(zl * zl, lim)
            nl += 1
    if not c_chi <= l_chi + ARC_TAU * math.sqrt(2.0 * nl):
        return False
    if not clipped <= tls_clipped(work, valid, f, 0, m, sigma_r, lim) - ARC_TAU * ARC_TAU:
        return False  # one line fits the neighbourhood about as well: a straight wall, its turn noise
    dof = max(nl - 2, 1)
    return clipped / n <= (l_chi / dof) * (1.0 + ARC_TAU * math.sqrt(2.0 / dof))


@kernel
def on_arcs(rho, alpha, first, last, ranges, bearings, valid, sig, increment, sigma_r, p, work):  # noqa: ANN001, ANN201
    """Which lines [first, last] are chords of a round surface (``circle_fits``): the neighbourhood
    is the line and as many beams again past each end (at least k), while the surface goes on
    without a depth jump (Borges & Aldon's adaptive breakpoint, BREAK_LAMBDA, plus 3 sigma_r).
    Lines that do not reach past their ends by k beams in all are not tested (nothing to compare).
    ``work``: circle_fits' scratch, (C_ROWS, n)."""
    n = ranges.size
    out = np.zeros(first.size, np.bool_)
    ratio = math.sin(increment) / math.sin(BREAK_LAMBDA - increment)
    for m in range(first.size):
        a, b = first[m], last[m]
        reach = max(p.k, b - a + 1)
        while (a > 0 and first[m] - a < reach and valid[a - 1]
               and abs(ranges[a - 1] - ranges[a]) <= ranges[a] * ratio + 3.0 * sigma_r):
            a -= 1
        while (b < n - 1 and b - last[m] < reach and valid[b + 1]
               and abs(ranges[b + 1] - ranges[b]) <= ranges[b] * ratio + 3.0 * sigma_r):
            b += 1
        if (first[m] - a) + (b - last[m]) >= p.k and theta_turn(a, b, sig) >= 0.5 * p.corner_min_turn:
            out[m] = circle_fits(a, b, first[m], last[m], rho[m], alpha[m], ranges, bearings, valid, sigma_r, p, work)
    return out


@kernel
def fit_spans(sp, n_runs, ranges, log_r, bearings, valid, sig, cs, angle_min, increment, sigma_r, grid, p, fw, iw, fb,
              angle_counts):  # noqa: ANN001, ANN201
    """Steps 3-4 on the first ``n_runs`` spans of valid beams (rows sp .. sp + 3 of ``iw``: first,
    last, shrink0, shrink1; each at least 2k + 1 beams): the band of normal angles from theta over the window
    centres first + k .. last - k (less ``shrink0`` / ``shrink1`` centres at each end: those whose
    windows reach across a split), the Log-Hough peak in it and the refined, checked line.
    ``log_r``: log of the ranges (at least of the spans' beams). The scratch blocks ``fw``,
    ``iw``, ``fb`` and ``angle_counts`` are ``find_lines``'; fit_runs' outputs are left in them."""
    k = p.k
    runs = iw[:R_ROWS, :n_runs]
    total = 0
    for r in range(n_runs):
        f, l, sh0, sh1 = iw[sp, r], iw[sp + 1, r], iw[sp + 2, r], iw[sp + 3, r]
        runs[R_FIRST, r], runs[R_LAST, r] = f, l
        runs[R_COUNT, r] = l - f + 1
        runs[R_START, r] = total
        total += l - f + 1
        c0, c1 = f + k, l - k
        if c1 - c0 >= sh0 + sh1:
            c0 += sh0
            c1 -= sh1
        runs[R_C0, r], runs[R_C1, r] = c0, c1
    if total + VOTE_BLOCK > fw.shape[1] or n_runs > iw.shape[1]:  # numba checks no bounds: a smaller block is a bug, not garbage
        raise ValueError("fit_spans: a pass larger than find_lines' scratch blocks")
    log_d = fw[W_LOG_D]
    for r in range(n_runs):  # by offsets, unsigned: a view a run was two atomic reference counts
        f, s = np.uint64(runs[R_FIRST, r]), np.uint64(runs[R_START, r])
        for t in range(np.uint64(runs[R_COUNT, r])):
            log_d[s + t] = log_r[f + t]
    band_of_runs(runs, sig, cs, ranges, bearings, increment, sigma_r, k, p, fw)
    band_peaks(runs, fw, fb, angle_counts, angle_min, p.hough_subdiv, p.hough_angles, grid)
    fit_runs(runs, fw, fb, iw, ranges, bearings, valid, sigma_r, p)


@kernel
def find_lines(ranges, bearings, valid, sig, angle_min, increment,  # noqa: ANN001, ANN201
               sigma_r, grid, p):
    """Steps 2-4 and the end growth: the line table (rho, alpha, cov, first, last, n_points)
    before merging. A run whose line fails the checks (it bends, or holds two faces the AD test
    did not part) is split at the beam farthest from its chord and each part is fitted again, as
    IEPF splits, for as long as the parts keep min_points beams (and 2k + 1). A run's line needs
    2k + 1 inliers; it must have min_points beams once grown over its ends (the AD windows stop
    short of a face's ends, so asking min_points of the run asked more of a face than the
    baselines' min_points). Splitting cuts a round surface into chords short enough to pass the
    line checks, so lines whose neighbourhood is one circle are dropped (``on_arcs``, when arc_check)."""
    k = p.k
    c0, c1 = candidate_runs(sig, k, grid.ad_line, sigma_r, p)
    min_core = min(p.min_points, 2 * k + 1)  # a run's line may grow to min_points past its ends
    # the passes' scratch, once a scan (``W_*``, ``I_*``, ``F_*`` rows), ``cap`` columns: the
    # first pass's spans (centre runs, which are disjoint, grown by k beams at each end) may
    # overlap, so their beams may number more than the scan's n (at most (k + 1) n); a later
    # pass's spans are disjoint parts of the spans before, so no pass has more beams than the
    # first, nor more spans than n (each of min_span >= 2k + 1 beams)
    total = 0
    for r in range(c0.size):
        if c1[r] - c0[r] + 2 * k + 1 >= min_core:
            total += c1[r] - c0[r] + 2 * k + 1
    cap = max(ranges.size, total, p.hough_angles)
    fw = np.empty((W_ROWS, cap + VOTE_BLOCK))
    iw = np.empty((I_ROWS, cap), np.int64)
    fb = np.empty((F_ROWS, cap), np.bool_)
    angle_counts = np.empty((p.hough_angles, N_BINS + 3), np.int64)
    circle_work = np.empty((C_ROWS, ranges.size))  # circle_fits' scratch (spans and neighbourhoods lie within the scan)
    sp = I_SPANS_A  # the first pass's spans (rows first, last, shrink0, shrink1 of iw)
    n_spans = 0
    for r in range(c0.size):
        if c1[r] - c0[r] + 2 * k + 1 >= min_core:
            iw[sp, n_spans], iw[sp + 1, n_spans] = c0[r] - k, c1[r] + k
            iw[sp + 2, n_spans], iw[sp + 3, n_spans] = 0, 0
            n_spans += 1
    log_r = log_ranges(ranges)  # log of the ranges (read at the spans' beams), once (later spans are parts of these)
    min_span = max(p.min_points, 2 * k + 1)
    n_max = ranges.size // min_core + 1  # accepted spans are disjoint, each of min_core beams or more
    o_vals = np.empty((2, n_max))  # the accepted lines: rho, alpha; cov; first, last, n_points
    o_rho, o_alpha = o_vals[0], o_vals[1]
    o_cov = np.empty((n_max, 2, 2))
    o_ints = np.empty((3, n_max), np.int64)
    o_f, o_l, o_n = o_ints[0], o_ints[1], o_ints[2]
    m = 0
    cs = slope_sums(sig)
    while n_spans:
        fit_spans(sp, n_spans, ranges, log_r, bearings, valid, sig, cs, angle_min, increment, sigma_r, grid, p, fw, iw, fb,
                  angle_counts)
        for r in range(n_spans):
            if fb[F_GOOD, r] and m < n_max:
                o_rho[m], o_alpha[m] = fw[W_VRHO, r], fw[W_VALPHA, r]
                o_cov[m, 0, 0], o_cov[m, 0, 1], o_cov[m, 1, 0], o_cov[m, 1, 1] = fw[W_C00, r], fw[W_C01, r], fw[W_C01, r], fw[W_C11, r]
                o_f[m], o_l[m], o_n[m] = iw[I_FIRST_IN, r], iw[I_LAST_IN, r], iw[I_N_IN, r]
                m += 1
        nxt = I_SPANS_B if sp == I_SPANS_A else I_SPANS_A  # the next pass's spans: first, last, shrink0, shrink1
        q = 0
        for r in range(n_spans):
            f0, l0 = iw[sp, r], iw[sp + 1, r]
            if fb[F_GOOD, r] or l0 - f0 < min_span:  # a part of min_span beams may remain
                continue
            if p.arc_check and theta_turn(f0, l0, sig) >= 0.5 * p.corner_min_turn:
                if circle_fits(f0, l0, -1, -1, 0.0, 0.0, ranges, bearings, valid, sigma_r, p, circle_work):
                    continue  # a failing span that is one circle is a round surface: not cut into chords
            at = farthest_from_chord(f0, l0, ranges, bearings)
            for f, l, a, b in ((f0, at - 1, iw[sp + 2, r], k), (at + 1, l0, k, iw[sp + 3, r])):
                if l - f + 1 >= min_span:
                    iw[nxt, q], iw[nxt + 1, q], iw[nxt + 2, q], iw[nxt + 3, q] = f, l, a, b
                    q += 1
        sp, n_spans = nxt, q
    order = np.argsort(o_f[:m], kind="mergesort")  # the lines in beam order
    vals = np.empty((2, m))
    rho, alpha = vals[0], vals[1]
    cov = np.empty((m, 2, 2))
    ints = np.empty((3, m), np.int64)
    f_in, l_in, n_in = ints[0], ints[1], ints[2]
    for t in range(m):
        o = order[t]
        rho[t], alpha[t], f_in[t], l_in[t], n_in[t] = o_rho[o], o_alpha[o], o_f[o], o_l[o], o_n[o]
        cov[t, 0, 0], cov[t, 0, 1], cov[t, 1, 0], cov[t, 1, 1] = o_cov[o, 0, 0], o_cov[o, 0, 1], o_cov[o, 1, 0], o_cov[o, 1, 1]
    extend_ends(rho, alpha, f_in, l_in, n_in, ranges, bearings, valid, k + 2, p.inlier_tau, sigma_r,
                p.sigma_bearing * p.sigma_bearing)
    robust_refit(rho, alpha, f_in, l_in, ranges, bearings, valid)
    arc = (on_arcs(rho, alpha, f_in, l_in, ranges, bearings, valid, sig, increment, sigma_r, p, circle_work)
           if p.arc_check and m else np.zeros(m, np.bool_))
    q = 0  # the lines kept (min_points beams once grown, not a chord of a round surface) moved to the front
    for t in range(m):
        if n_in[t] >= p.min_points and not arc[t]:
            rho[q], alpha[q], f_in[q], l_in[q], n_in[q] = rho[t], alpha[t], f_in[t], l_in[t], n_in[t]
            cov[q, 0, 0], cov[q, 0, 1], cov[q, 1, 0], cov[q, 1, 1] = cov[t, 0, 0], cov[t, 0, 1], cov[t, 1, 0], cov[t, 1, 1]
            q += 1
    return rho[:q], alpha[:q], cov[:q], f_in[:q], l_in[:q], n_in[:q]


# -- 5. segments ----------------------------------------------------------------------------------


@kernel
def inv2(a: float, b: float, d: float):  # noqa: ANN201
    """Inverse of the symmetric 2x2 matrix [[a, b], [b, d]] as (00, 01, 11)."""
    det = a * d - b * b
    return d / det, -b / det, a / det


@inline_kernel
def depth_jump(a, b, ranges, valid, increment, sigma_r) -> bool:  # noqa: ANN001
    """Whether the valid beams a..b (a and b valid) hold a depth jump: two consecutive valid ones
    farther apart than Borges & Aldon's adaptive breakpoint distance (BREAK_LAMBDA, plus 3 sigma_r,
    as ``on_arcs`` and the baselines' clusters), i.e. a nearer surface between two lines' ends."""
    j = a
    for t in range(a + 1, b + 1):
        if valid[t]:
            dphi = (t - j) * increment
            if not dphi < BREAK_LAMBDA:
                return True
            if abs(ranges[t] - ranges[j]) > ranges[j] * math.sin(dphi) / math.sin(BREAK_LAMBDA - dphi) + 3.0 * sigma_r:
                return True
            j = t
    return False


@kernel
def merge_neighbours(rho, alpha, cov, first, last, npts, ranges, valid, increment, sigma_r, p) -> int:  # noqa: ANN001
    """In place: merge neighbouring lines that are one line: at most merge_gap beams apart, at
    most bridge_invalid invalid beams between (none by default: +inf and nan beams break
    segments), no depth jump between (``depth_jump``: a nearer object in front of a wall, a post
    or a table leg, leaves two pieces of the wall, as the baselines' clusters do; merged, one
    segment claimed the wall over the object's beams and matched neither visible piece), and
    (rho, alpha) equal within merge_tau std (plus a model-error floor). The merged
    line is the information-weighted combination of the pieces (independent fits of one line).
    The lines left move to the front of the arrays (alpha wrapped when any merged); returns how
    many there are."""
    n = rho.size
    if n < 2:
        return n
    tau2 = p.merge_tau**2
    cur = 0
    for i in range(1, n):
        gap = first[i] - last[cur] - 1
        apart = gap > p.merge_gap
        if not apart and gap > 0:
            n_invalid = 0
            for j in range(last[cur] + 1, first[i]):
                n_invalid += 0 if valid[j] else 1
            apart = n_invalid > p.bridge_invalid
        if not apart and gap > 0:
            apart = depth_jump(last[cur], first[i], ranges, valid, increment, sigma_r)
        if apart:
            cur += 1
            move_line(rho, alpha, cov, first, last, npts, i, cur)
            continue
        dr = rho[i] - rho[cur]
        da = wrap(alpha[i] - alpha[cur])
        a00, a01, a11 = cov[cur, 0, 0], cov[cur, 0, 1], cov[cur, 1, 1]
        b00, b01, b11 = cov[i, 0, 0], cov[i, 0, 1], cov[i, 1, 1]
        s00, s01, s11 = a00 + b00 + MERGE_FLOOR_RHO_VAR, a01 + b01, a11 + b11 + MERGE_FLOOR_ALPHA_VAR
        det = s00 * s11 - s01 * s01
        if not det > 0 or (s11 * dr * dr - 2 * s01 * dr * da + s00 * da * da) > tau2 * det:
            cur += 1
            move_line(rho, alpha, cov, first, last, npts, i, cur)
            continue
        # information-weighted fusion (alpha of i unwrapped next to cur's)
        pa0, pa1, pa2 = inv2(a00, a01, a11)
        pb0, pb1, pb2 = inv2(b00, b01, b11)
        p00, p01, p11 = pa0 + pb0, pa1 + pb1, pa2 + pb2
        va0 = pa0 * rho[cur] + pa1 * alpha[cur] + pb0 * rho[i] + pb1 * (alpha[cur] + da)
        va1 = pa1 * rho[cur] + pa2 * alpha[cur] + pb1 * rho[i] + pb2 * (alpha[cur] + da)
        q00, q01, q11 = inv2(p00, p01, p11)
        rho[cur] = q00 * va0 + q01 * va1
        alpha[cur] = q01 * va0 + q11 * va1
        cov[cur, 0, 0] = q00
        cov[cur, 0, 1] = q01
        cov[cur, 1, 0] = q01
        cov[cur, 1, 1] = q11
        last[cur] = max(last[cur], last[i])
        npts[cur] += npts[i]
    n_out = cur + 1
    if n_out < n:
        for m in range(n_out):
            if rho[m] < 0:  # a fusion of lines near the origin: the same line, rho >= 0 (alpha + pi)
                rho[m] = -rho[m]
                alpha[m] += math.pi
                cov[m, 0, 1] = -cov[m, 0, 1]
                cov[m, 1, 0] = -cov[m, 1, 0]
            alpha[m] = wrap(alpha[m])
    return n_out


@inline_kernel
def move_line(rho, alpha, cov, first, last, npts, i, to) -> None:  # noqa: ANN001
    """Line i of the table copied to row ``to`` (<= i)."""
    if to != i:
        rho[to], alpha[to], first[to], last[to], npts[to] = rho[i], alpha[i], first[i], last[i], npts[i]
        cov[to, 0, 0], cov[to, 0, 1], cov[to, 1, 0], cov[to, 1, 1] = cov[i, 0, 0], cov[i, 0, 1], cov[i, 1, 0], cov[i, 1, 1]


@kernel
def segments(rho, alpha, cov, first, last, npts, ranges, bearings, valid, increment, sigma_r, p):  # noqa: ANN001, ANN201
    """Merge neighbours, split the beams two neighbours both claim (around a corner) at the middle,
    project the end beams' points on the lines, drop segments shorter than min_length and those
    left with fewer than min_points beams (min_points counts the beams of the reported line); the
    line table (which find_lines made for this) is changed in place.
    Returns the rows of ``features.types.Lines``: line values (L, 10) rho, alpha, x0, y0, x1, y1,
    cov (row by row), line beams (L, 3) first, last, n_points."""
    n_lines = merge_neighbours(rho, alpha, cov, first, last, npts, ranges, valid, increment, sigma_r, p)
    lv = np.empty((n_lines, 10))
    lb = np.empty((n_lines, 3), np.int64)
    min_len2 = p.min_length * p.min_length
    q = 0
    for m in range(n_lines):
        if m + 1 < n_lines and last[m] >= first[m + 1]:  # overlap (of the lines as they came)
            mid = (first[m + 1] + last[m]) // 2
            last[m] = max(mid, first[m])
            first[m + 1] = min(mid + 1, last[m + 1])
        c, s = math.cos(alpha[m]), math.sin(alpha[m])
        for e in range(2):
            j = first[m] if e == 0 else last[m]
            d = ranges[j]
            x, y = d * bearings[B_COS, j], d * bearings[B_SIN, j]
            off = x * c + y * s - rho[m]
            lv[q, 2 + 2 * e] = x - off * c
            lv[q, 3 + 2 * e] = y - off * s
        dx = lv[q, 4] - lv[q, 2]
        dy = lv[q, 5] - lv[q, 3]
        n_pts = min(npts[m], last[m] - first[m] + 1)
        if not (dx * dx + dy * dy >= min_len2 and n_pts >= p.min_points):  # nan -> dropped; min_points
            continue  # also after the split of shared beams: the reported line's beams
        lv[q, 0], lv[q, 1] = rho[m], alpha[m]
        lv[q, 6], lv[q, 7], lv[q, 8], lv[q, 9] = cov[m, 0, 0], cov[m, 0, 1], cov[m, 1, 0], cov[m, 1, 1]
        lb[q, 0], lb[q, 1], lb[q, 2] = first[m], last[m], n_pts
        q += 1
    return lv[:q], lb[:q]


# -- 6. corners -----------------------------------------------------------------------------------


@kernel
def neighbourhood_var(ranges, valid, lo, hi) -> float:  # noqa: ANN001
    """Variance (m^2) of the valid ranges of beams lo..hi: the paper's "variance in range between
    neighbouring points" around a corner (0 when fewer than 3 are valid)."""
    d = np.empty(hi - lo + 1)
    m = 0
    for j in range(lo, hi + 1):
        if valid[j]:
            d[m] = ranges[j]
            m += 1
    if m < 3:
        return 0.0
    mean = pairwise_sum(d, 0, m) / m
    for j in range(m):
        x = d[j] - mean
        d[j] = x * x
    return pairwise_sum(d, 0, m) / m


@kernel
def corners(lv, lb, sig, ranges, valid, angle_min, increment, sigma_r, p):  # noqa: ANN001, ANN201
    """Corners between consecutive lines i, i + 1 (beam order) of the rows ``segments`` made: the
    rows of ``features.types.Corners``, corner values (C, 3) x, y, angle and corner beams (C, 3)
    beam, line i, line i + 1.

    A corner needs the two lines' facing ends within corner_max_gap beams, a turn of the line
    direction in [corner_min_turn, pi - corner_min_turn], their intersection near both facing
    ends, psi_i (the paper's corner signal) reaching corner_psi of the turn there, and (the
    paper's remedy against false acute corners, when acute_check) a range variance of the beams
    within k of it of at least acute_min_var sigma_r^2. ``angle`` is the interior angle (0, pi)."""
    n_lines = lv.shape[0]
    n = ranges.size
    k = p.k
    min_turn = p.corner_min_turn
    acute_var = p.acute_min_var * (sigma_r * sigma_r)
    out_f = np.empty((max(n_lines - 1, 0), 3))
    out_i = np.empty((max(n_lines - 1, 0), 3), np.int64)
    m = 0
    for i in range(n_lines - 1):
        j = i + 1
        last_i, first_j = lb[i, 1], lb[j, 0]
        if first_j - last_i - 1 > p.corner_max_gap:
            continue
        a1, a2 = lv[i, 1], lv[j, 1]
        s = math.sin(a2 - a1)
        if math.cos(a2 - a1) >= 0:
            turn = math.asin(min(1.0, abs(s)))
        else:
            turn = math.pi - math.asin(min(1.0, abs(s)))
        if turn < min_turn or turn > math.pi - min_turn:
            continue
        x = (lv[i, 0] * math.sin(a2) - lv[j, 0] * math.sin(a1)) / s  # x cos a + y sin a = rho for both
        y = (lv[j, 0] * math.cos(a1) - lv[i, 0] * math.cos(a2)) / s
        # near both facing ends: within corner_max_dist plus the point spacing there (one beam
        # step projected on each line, large at grazing incidence)
        b = math.atan2(y, x)
        spacing = math.hypot(x, y) * increment / max(min(math.cos(b - a1), math.cos(b - a2)), 0.1)
        reach = p.corner_max_dist + 1.5 * min(spacing, SPACING_CAP)
        if math.hypot(x - lv[i, 4], y - lv[i, 5]) > reach:  # the end of line i
            continue
        if math.hypot(x - lv[j, 2], y - lv[j, 3]) > reach:  # the start of line j
            continue
        lo, hi = max(0, last_i - k), min(n - 1, first_j)
        peak = -1.0  # largest |psi| between the two segments
        for t in range(lo, hi + 1):
            if np.isfinite(sig[S_PSI, t]):
                peak = max(peak, abs(sig[S_PSI, t]))
        if peak < 0.0 or peak < p.corner_psi * turn:
            continue
        # the beam of bearing b, of the three a full turn apart the one nearest the two lines' facing
        # ends: atan2 gives b in (-pi, pi], the scan's bearings may lie beyond pi (a 360 deg scan from
        # 0 to 2 pi, a scan looking back), where b taken as it was put the corner's beam off the scan,
        # clamped onto a line's end; and a bearing just before the first beam stays there (a wrap
        # of every bearing into [angle_min, angle_min + 2 pi) sent it to the far end of the turn)
        at = (b - angle_min) / increment
        turn_beams = 2.0 * math.pi / increment
        for other in (at - turn_beams, at + turn_beams):
            if max(last_i - other, other - first_j, 0.0) < max(last_i - at, at - first_j, 0.0):
                at = other
        index = np.int64(np.rint(at))
        index = min(max(index, last_i), first_j)
        if p.acute_check:
            var = neighbourhood_var(ranges, valid, max(0, index - k), min(n - 1, index + k))
            if var < acute_var:
                continue
        v1x, v1y = lv[i, 2] - x, lv[i, 3] - y
        v2x, v2y = lv[j, 4] - x, lv[j, 5] - y
        cos_angle = (v1x * v2x + v1y * v2y) / max(math.hypot(v1x, v1y) * math.hypot(v2x, v2y), 1e-300)
        angle = math.acos(min(1.0, max(-1.0, cos_angle)))
        if not (0.0 < angle < math.pi) or not (np.isfinite(x) and np.isfinite(y)):
            continue
        out_f[m, 0] = x
        out_f[m, 1] = y
        out_f[m, 2] = angle
        out_i[m, 0] = index
        out_i[m, 1] = i
        out_i[m, 2] = j
        m += 1
    return out_f[:m], out_i[:m]


# -- the whole method -----------------------------------------------------------------------------


@kernel
def extract_scan(ranges, bearings, angle_min, increment, range_lo, range_hi, sigma_r, auto, range_min, fallback, grid, p):  # noqa: ANN001, ANN201
    """Lines and corners of one scan (sensor frame): steps 1-6. ``bearings``: the (3, n) bearing table (rows B_ANGLE, B_COS, B_SIN);
    ``range_lo``, ``range_hi``: valid range limits (m); ``sigma_r``: the range noise std for this
    scan's units (m), or with ``auto`` estimated from the scan itself in the same call (step 0:
    ``pooled_sigma`` of its one row, ``features.noise_estimate.scan_sigma`` of valid range limits
    ``range_min`` (the scan's own) and ``range_hi``, ``fallback`` m when too few triples; ``sigma_r``
    is then unused). One kernel for both (the switch a parameter): a second entry point compiled
    the whole pipeline a second time (~9 s in a fresh checkout).
    Returns the rows of ``features.types.Lines`` and ``Corners``: line values, line beams
    (``segments``), corner values, corner beams (``corners``)."""
    if auto:
        sigma_r = pooled_sigma(ranges.reshape((1, ranges.size)), grid.twice_cos, range_min, range_hi, fallback)
    valid, sig = signal_block(ranges, bearings[B_ANGLE], p.k, range_lo, range_hi, sigma_r, grid.two_sin_sum)
    rho, alpha, cov, first, last, npts = find_lines(
        ranges, bearings, valid, sig, angle_min, increment, sigma_r, grid, p
    )
    lv, lb = segments(rho, alpha, cov, first, last, npts, ranges, bearings, valid, increment, sigma_r, p)
    if p.corners and lv.shape[0] > 1:
        return (lv, lb) + corners(lv, lb, sig, ranges, valid, angle_min, increment, sigma_r, p)
    return lv, lb, np.empty((0, 3)), np.empty((0, 3), np.int64)


@kernel
def extract_batch(ranges, bearings, angle_min, increment, range_lo, range_hi, sigma_r, auto, range_min, fallback, grid, p):  # noqa: ANN001, ANN201
    """``extract_scan`` of every row of ``ranges`` (S, n), scans of one geometry, in one call (with
    ``auto``, each scan's own noise estimate, as a single call makes it). Returns the packed rows
    of all scans, concatenated, and the (S + 1,) offsets of each scan's lines and corners in them."""
    rows = new_rows(ranges.shape[0])
    for s in range(ranges.shape[0]):
        scan_rows = extract_scan(ranges[s], bearings, angle_min, increment, range_lo, range_hi, sigma_r, auto, range_min,
                                 fallback, grid, p)
        rows = append_rows(rows, s, scan_rows)
    return finish_rows(rows)
