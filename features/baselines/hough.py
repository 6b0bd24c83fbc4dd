"""``hough``: the full Hough transform of the Cartesian points (Duda & Hart 1972 normal form
``rho = x cos(a) + y sin(a)``) over the whole (rho, alpha) space, with sequential peak picking.

Each valid point votes once per alpha bin (a vectorised N x A index array and one ``bincount``).
Then, until the highest peak has fewer than ``min_points`` votes: take the peak's line, select the
points near it and refit them by least squares (two shrinking bands), cut them into runs contiguous
in the scan, keep the runs long enough as Lines, and withdraw those points' votes from the
accumulator. A peak that yields no line has its neighbourhood suppressed; ``max_failures`` such
peaks in a row end the search.

Resolution (default): 1 deg in alpha over [0, 180) deg and 2 cm in rho over [-R, R] with R the
scan's largest valid range: 180 x 820 cells at the LMS200's 8.18 m. The peak only seeds the
least-squares fit, so this coarse grid costs no accuracy and keeps the transform fast.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lms200 import Scan

from ..errors import ScanGeometryError
from ..registry import register
from ..types import FeatureSet, Lines
from . import checks
from .common import CornerConfig, feature_set, valid_points
from .runs import collect, refine, segments_of


MAX_ANGLES = 1 << 14  # most alpha bins over [0, pi)


@dataclass(frozen=True)
class HoughConfig:
    """Defaults:

    - alpha_step / rho_step: 1 deg (in rad) x 0.02 m accumulator cells (see the module docstring).
    - band_coarse: 0.05 m, the first inlier band around a peak: the half-diagonal of a cell's
      spread over a 4 m wall (4 m x sin 0.5 deg + 1 cm) plus noise.
    - band_fine: 0.025 m = 5 sigma, the final inlier band after the first refit.
    - min_points, min_length, sigma, breakpoint_lambda: as the other baselines (8 points,
      0.15 m, 5 mm, Borges & Aldon's 10 deg); max_skip: 3, a run may jump over two outliers
      or invalid beams, never over a no-return (+inf) beam.
    - max_lines: 60, an upper bound on peaks taken per scan; max_failures: 5 peaks in a row that
      yield no line end the search (such peaks gather collinear points scattered across the scan:
      once the walls are out, what is left is clutter).
    - runs_z: 0 (off), the runs test on residual signs that drops arcs (see ``split_merge``).
    """

    alpha_step: float = float(np.deg2rad(1.0))  # rad
    rho_step: float = 0.02
    band_coarse: float = 0.05
    band_fine: float = 0.025
    min_points: int = 8
    min_length: float = 0.15
    sigma: float = 0.005
    breakpoint_lambda: float = float(np.deg2rad(10.0))  # rad
    max_skip: int = 3
    runs_z: float = 0.0
    max_lines: int = 60
    max_failures: int = 5
    corners: CornerConfig = field(default_factory=CornerConfig)

    def __post_init__(self) -> None:
        """Raise ConfigError naming the field when a value cannot work."""
        checks.angle("alpha_step", self.alpha_step, np.pi)
        if self.alpha_step < np.pi / MAX_ANGLES:
            checks.fail("alpha_step", f"must be at least pi / {MAX_ANGLES} rad", self.alpha_step)
        checks.band("rho_step", self.rho_step)  # 1e300: one rho cell, no line, F1 0, exit 0
        checks.band("band_coarse", self.band_coarse)
        checks.band("band_fine", self.band_fine)
        checks.shared_fields(self)
        checks.integer("max_lines", self.max_lines, 1)
        checks.integer("max_failures", self.max_failures, 1, checks.MAX_FAILURES)
        checks.plain_numbers(self)  # after every check: they see (and quote) the values given


MAX_CELLS = 1 << 21  # most accumulator cells (16 MB of counts)
CHUNK_VOTES = 1 << 16  # votes computed at once (bounds the temporaries)
SMALL_ACC = 1 << 18  # accumulators up to this many cells take the votes by bincount


class Votes:
    """The accumulator cells the points vote for: one per (point, alpha), computed in float32 on
    the rho-step grid (|rho| / step stays below ~1e5 at MAX_CELLS, where float32 places every
    vote exactly enough), chunk by chunk so that memory stays bounded whatever the scan."""

    def __init__(self, pts, theta: np.ndarray, n_rho: int, r_ext: float, rho_step: float) -> None:  # noqa: ANN001
        self.xs = (pts.x / rho_step).astype(np.float32)
        self.ys = (pts.y / rho_step).astype(np.float32)
        self.cos = np.cos(theta).astype(np.float32)
        self.sin = np.sin(theta).astype(np.float32)
        self.shift = np.float32(r_ext / rho_step)
        self.base = (np.arange(theta.size) * n_rho).astype(np.int32)

    def cells(self, rows: np.ndarray) -> np.ndarray:
        """(len(rows), A) flat accumulator index of the votes of the points ``rows``."""
        cells = (self.xs[rows, None] * self.cos + self.ys[rows, None] * self.sin + self.shift).astype(np.int32)
        cells += self.base
        return cells

    def add(self, acc: np.ndarray, rows: np.ndarray, sign: int) -> None:
        """Add (sign 1) or withdraw (-1) the votes of the points ``rows`` to / from ``acc``, in place."""
        step = max(CHUNK_VOTES // self.cos.size, 1)
        for lo in range(0, rows.size, step):
            cells = self.cells(rows[lo : lo + step]).ravel()
            if acc.size <= SMALL_ACC:  # one bincount is faster than ufunc.at, and its temporary small
                acc += sign * np.bincount(cells, minlength=acc.size)
            else:
                np.add.at(acc, cells, sign)


def run(scan: Scan, cfg: HoughConfig) -> FeatureSet:
    """Extract lines and corners from ``scan`` (sensor frame) with the full Hough transform."""
    pts = valid_points(scan)
    if pts.idx.size < cfg.min_points:
        return feature_set(Lines.empty(), cfg.corners, "hough", scan.angle_increment)
    n_alpha = int(round(np.pi / cfg.alpha_step))
    theta = np.arange(n_alpha) * cfg.alpha_step
    r_ext = float(pts.r.max()) + cfg.rho_step
    steps = r_ext / cfg.rho_step  # range in rho steps (2 * r_ext overflows for rho_step near 1e308)
    n_rho = int(np.ceil(2 * steps)) + 1 if steps < MAX_CELLS else MAX_CELLS + 1
    if n_alpha * n_rho > MAX_CELLS:
        raise ScanGeometryError(
            f"hough: the accumulator for the largest valid range {pts.r.max():.6g} m at rho_step {cfg.rho_step:g} m "
            f"and {n_alpha} angles needs more than {MAX_CELLS} cells; raise rho_step or alpha_step, or lower the "
            "scan's range_max so that such returns are not valid"
        )
    votes = Votes(pts, theta, n_rho, r_ext, cfg.rho_step)
    acc = np.zeros(n_alpha * n_rho, np.int64)
    votes.add(acc, np.arange(pts.idx.size), 1)
    remaining = np.ones(pts.idx.size, dtype=bool)
    lam = cfg.breakpoint_lambda
    starts, ends, fits = [], [], []
    failures = 0
    while len(starts) < cfg.max_lines and failures < cfg.max_failures:
        peak = int(np.argmax(acc))
        if acc[peak] < cfg.min_points:
            break
        ia, ir = divmod(peak, n_rho)
        a0 = float(theta[ia])
        r0 = (ir + 0.5) * cfg.rho_step - r_ext
        cand = np.flatnonzero(remaining)
        inl, rho, alpha = refine(pts, cand, r0, a0, (cfg.band_coarse, cfg.band_fine))
        found = None
        if inl.size >= cfg.min_points:
            found = segments_of(pts, inl, scan.angle_increment, lam, cfg.sigma, cfg.max_skip,
                                cfg.min_points, cfg.min_length, cfg.runs_z)
        if found is None:
            grid = acc.reshape(n_alpha, n_rho)
            grid[max(ia - 1, 0): ia + 2, max(ir - 2, 0): ir + 3] = 0
            failures += 1
            continue
        failures = 0
        used, s, e, fit = found
        starts.append(s)
        ends.append(e)
        fits.append(fit)
        remaining[used] = False
        votes.add(acc, used, -1)
    return collect(pts, starts, ends, fits, cfg.sigma, cfg.corners, "hough", scan.angle_increment)


register("hough", HoughConfig, run)
