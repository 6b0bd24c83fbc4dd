"""``ransac``: sequential RANSAC line extraction (Fischler & Bolles 1981), as evaluated by Nguyen et
al. (2007).

Each round draws ``hypotheses`` point pairs at once from the points not yet explained, scores
every pair's line against every remaining point in one (hypotheses x points) array, keeps the line
with most inliers, refits it by least squares, cuts its inliers into runs contiguous in the scan,
keeps the long-enough runs as Lines and removes their points. The second point of a pair is drawn
within ``window`` beams of the first (neighbourhood sampling, NAPSAC, Myatt et al. 2002), which
raises the chance that both lie on one wall; ``window=0`` draws both uniformly. Rounds stop when
the best line has fewer than ``min_points`` inliers or ``max_failures`` rounds in a row yield no
line. Random draws come from ``numpy.random.default_rng(seed)``: the same scan gives the same lines.

Work bound: a round scores every hypothesis against every remaining point, so a scan costs the sum
over its rounds of ``hypotheses x points left`` point-to-line distances (about 5 ns each, numpy).
That sum is counted before each round: a round that would take it past ``MAX_DISTANCES`` (2^30,
about 5-6 s of CPU) is not run, and a ``ScanGeometryError`` says how far the scan got and to lower
``hypotheses`` or ``max_lines`` (``max_lines`` has no cap: hypotheses=4096 on a 16,384-beam scan of
many facets ran for 18 s, and 10**6 rounds were possible). The count is of the work done, not of
a worst case: hypotheses=60,000 on a 361-beam office scan costs ~0.4 s and runs. Scans within the
bound give the same lines as before it; the defaults use at most 1.4e6 on a 361-beam scan and 6.3e7
on 16,384 beams.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lms200 import Scan

from ..errors import ScanGeometryError
from ..registry import register
from ..types import FeatureSet
from . import checks
from .common import CornerConfig, valid_points
from .runs import collect, refine, segments_of


MAX_HYPOTHESES = 1 << 16  # most point pairs drawn per round (bounds the draws' memory)
#: most point-to-line distances one scan may cost (summed over its rounds): 2^30, about 5-6 s of CPU at
#: ~5 ns a distance (measured 2026-12-04: 5.1 ns at 4096 x 16,384, 6.2 ns at 65,536 x 361)
MAX_DISTANCES = 1 << 30


#: most beams a NAPSAC window reaches: numpy draws int64 offsets (window=2**70 was "high is out of
#: bounds for int64"); any window past the scan's beams already reaches every beam (the pair is clipped)
MAX_WINDOW = 1 << 62


@dataclass(frozen=True)
class RansacConfig:
    """Defaults:

    - hypotheses: 64 pairs per round: with neighbourhood sampling a pair lies on a wall holding a
      fraction w of the remaining points with probability ~0.9 w, so 64 draws find a wall with
      w = 0.08 with probability 1 - (1 - 0.072)^64 = 0.99 (Fischler & Bolles' formula, p = 0.99).
    - window: 10 beams for the second point of a pair (NAPSAC neighbourhood).
    - inlier_band: 0.025 m = 5 sigma for counting inliers and the final refit.
    - min_points, min_length, sigma, breakpoint_lambda, max_skip, runs_z: as ``hough``.
    - max_failures: 3 rounds in a row without a line end the search; max_lines: 60.
    - seed: 0 (the generator is seeded per scan, so results are deterministic).
    """

    hypotheses: int = 64
    window: int = 10
    inlier_band: float = 0.025
    min_points: int = 8
    min_length: float = 0.15
    sigma: float = 0.005
    breakpoint_lambda: float = float(np.deg2rad(10.0))  # rad
    max_skip: int = 3
    runs_z: float = 0.0
    max_failures: int = 3
    max_lines: int = 60
    seed: int = 0
    corners: CornerConfig = field(default_factory=CornerConfig)

    def __post_init__(self) -> None:
        """Raise ConfigError naming the field when a value cannot work."""
        checks.integer("hypotheses", self.hypotheses, 1)
        if self.hypotheses > MAX_HYPOTHESES:
            checks.fail("hypotheses", f"must be an integer in [1, {MAX_HYPOTHESES}]", self.hypotheses)
        checks.integer("window", self.window, 0)
        checks.band("inlier_band", self.inlier_band)  # 1e-300: no inlier, no line, F1 0, exit 0
        checks.shared_fields(self)
        checks.integer("max_failures", self.max_failures, 1, checks.MAX_FAILURES)
        checks.integer("max_lines", self.max_lines, 1)
        checks.integer("seed", self.seed, 0)
        checks.plain_numbers(self)  # after every check: they see (and quote) the values given


CHUNK = 1 << 18  # (hypothesis, point) distances computed at once (bounds the temporaries)


def inlier_counts(nx: np.ndarray, ny: np.ndarray, rho: np.ndarray, x: np.ndarray, y: np.ndarray,
                  band: float) -> np.ndarray:
    """For each hypothesis line (unit normal nx, ny, distance rho), how many points (x, y) lie
    within ``band`` (m) of it; computed a block of hypotheses at a time."""
    step = max(CHUNK // max(x.size, 1), 1)
    counts = np.empty(nx.size, np.int64)
    for lo in range(0, nx.size, step):
        sl = slice(lo, lo + step)
        dist = np.abs(np.outer(nx[sl], x) + np.outer(ny[sl], y) - rho[sl, None])
        counts[sl] = np.count_nonzero(dist <= band, axis=1)
    return counts


def over_budget(cfg: RansacConfig, rounds: int, points: int, spent: int) -> ScanGeometryError:
    """The error of a scan whose next round (hypotheses x ``points`` left) would take the
    ``spent`` point-to-line distances of its ``rounds`` rounds past MAX_DISTANCES."""
    return ScanGeometryError(
        f"ransac: this scan needs more than {MAX_DISTANCES:,} point-to-line distances (ransac.MAX_DISTANCES, "
        f"about 5 s of CPU): {spent:,} in {rounds} rounds, and round {rounds + 1} would score {cfg.hypotheses} "
        f"hypotheses against {points} points left; lower hypotheses (or max_lines, {cfg.max_lines})")


def run(scan: Scan, cfg: RansacConfig) -> FeatureSet:
    """Extract lines and corners from ``scan`` (sensor frame) by sequential RANSAC.

    Raises:
        ScanGeometryError: the rounds' point-to-line distances would exceed ``MAX_DISTANCES`` (the module doc).
    """
    pts = valid_points(scan)
    rng = np.random.default_rng(cfg.seed)
    remaining = np.ones(pts.idx.size, dtype=bool)
    lam = cfg.breakpoint_lambda
    starts, ends, fits = [], [], []
    failures = 0
    spent = 0  # point-to-line distances scored so far
    for rounds in range(cfg.max_lines):
        cand = np.flatnonzero(remaining)
        m = cand.size
        if m < cfg.min_points or failures >= cfg.max_failures:
            break
        if spent + cfg.hypotheses * m > MAX_DISTANCES:
            raise over_budget(cfg, rounds, m, spent)
        spent += cfg.hypotheses * m
        i = rng.integers(0, m, cfg.hypotheses)
        if cfg.window > 0:
            window = min(int(cfg.window), MAX_WINDOW)
            j = i + rng.integers(1, window + 1, cfg.hypotheses) * (2 * rng.integers(0, 2, cfg.hypotheses) - 1)
            j = np.clip(j, 0, m - 1)
        else:
            j = rng.integers(0, m, cfg.hypotheses)
        pi, pj = cand[i], cand[j]
        dx, dy = pts.x[pj] - pts.x[pi], pts.y[pj] - pts.y[pi]
        norm = np.hypot(dx, dy)
        good = norm > 1e-9
        nx, ny = -dy[good] / norm[good], dx[good] / norm[good]
        if nx.size == 0:
            failures += 1
            continue
        rho = nx * pts.x[pi[good]] + ny * pts.y[pi[good]]
        counts = inlier_counts(nx, ny, rho, pts.x[cand], pts.y[cand], cfg.inlier_band)
        best = int(np.argmax(counts))
        if counts[best] < cfg.min_points:
            failures += 1
            continue
        alpha0 = float(np.arctan2(ny[best], nx[best]))
        inl, r, a = refine(pts, cand, float(rho[best]), alpha0, (cfg.inlier_band, cfg.inlier_band))
        found = None
        if inl.size >= cfg.min_points:
            found = segments_of(pts, inl, scan.angle_increment, lam, cfg.sigma, cfg.max_skip,
                                cfg.min_points, cfg.min_length, cfg.runs_z)
        if found is None:
            failures += 1
            continue
        failures = 0
        used, s, e, fit = found
        starts.append(s)
        ends.append(e)
        fits.append(fit)
        remaining[used] = False
    return collect(pts, starts, ends, fits, cfg.sigma, cfg.corners, "ransac", scan.angle_increment)


register("ransac", RansacConfig, run)
