"""``split_merge``: Cartesian split-and-merge with least-squares fits (the algorithm Nguyen et al.
2007, "A comparison of line extraction algorithms using 2D range data for indoor mobile robotics",
found the fastest and among the most correct of six).

Steps: adaptive breakpoints split the scan into clusters (Borges & Aldon 2004); each cluster is
split recursively while some point lies farther than the threshold from its least-squares line
(at the point farthest from the chord, see ``splitting``); neighbours whose joint fit stays within
noise are merged; end points off the fitted line are trimmed; every segment of enough points and
length becomes a Line; corners come from the shared Cartesian corner step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from lms200 import Scan

from ..batch import common_geometry, split_rows, stacked_ranges
from ..jit import FixedTypeCall
from ..registry import register
from ..types import Corners, FeatureSet, Lines
from . import checks, engine
from .common import CornerConfig

MAX_FLOAT = float(np.finfo(np.float64).max)


@dataclass(frozen=True)
class SplitMergeConfig:
    """Defaults, for the LMS200 (sigma = 5 mm in mm mode); the split and merge thresholds follow
    the noise above it (issue #13's audit, [docs/realdata.md](../../docs/realdata.md)):

    - sigma: range noise (m) for breakpoints, end-point trimming and line covariances (``lmsbench
      compare`` gives the source's: the simulator's, or a log's neighbour scatter).
    - sigma_fit: scatter (m) of a true face's beams about their fitted line, which the split and
      merge tests must allow for; None: ``sigma``. On an interlaced 0.5 deg log it is below the
      neighbour scatter (the sweeps' offset d enters a fit residual as d / 2, a neighbour
      difference as 0.82 d): ``compare`` gives a log's ``features.noise_estimate.fit_sigma``
      (MIT CSAIL 9.5 mm against 11.9 mm neighbour scatter).
    - breakpoint_lambda: 10 deg (in rad), Borges & Aldon (2004)'s value for their adaptive
      breakpoint detector.
    - split_threshold, split_sigmas: a segment is split while a point lies farther than
      max(split_threshold, split_sigmas x sigma_fit) from its least-squares line: 0.03 m and 3.
      A false split costs little (the merge step joins the parts again when their joint fit is
      within noise), a missed one is never undone (the segment bridges a corner or a small
      face), so the noise-following part is the 3 sigma of the breakpoints and the trimming,
      not a bound on the largest residual of a long line. 0.03 m (6 sigma of the LMS200's 5 mm;
      a 10 deg bend over 1 m legs exceeds it) stays the least value: at sigma_fit <= 10 mm the
      threshold is the LMS200's as before. ``split_sigmas=0`` keeps it fixed.
    - merge_rms, merge_sigmas: neighbours merge while their joint fit's RMS residual is at most
      max(merge_rms, merge_sigmas x sigma_fit): 0.01 m and 2 (Nguyen et al. 2007 merge collinear
      neighbours after splitting; the RMS residual of n beams of a true face is sigma_fit within
      about sigma_fit / sqrt(2 n), so 2 sigma_fit keeps noise from blocking a merge).
      ``merge_sigmas=0`` keeps it fixed. With both fixed at 25 mm noise every wall is shattered
      (simulated office, 1 deg cm codes: line F1 0.40 against 0.96 with the noise-following
      thresholds; the same at 5 mm: 0.982 either way).
    - min_points / min_length: 8 points and 0.15 m per line (Nguyen et al. 2007 discard segments
      with too few points, "P_min", and too short, "L_min"; values chosen for 0.5 deg beams).
    - max_skip: 3: a cluster bridges up to two invalid (nan) beams, as hough / ransac; a no-return
      (+inf) beam always breaks it (open space: a doorway, or beyond range), as in every method.
    - end points farther than 3 sigma from the fitted line are trimmed (twice, refitting): they
      belong to a small neighbouring face the split threshold let in.
    - runs_z: 0 (off). When > 0, a line whose residual signs form ``runs_z`` standard deviations
      fewer runs than noise would (Wald-Wolfowitz runs test) is taken for an arc and dropped. At
      3 it lifts precision on the pillars world (~0.47 -> ~0.5-0.6) but on the real logs drops a
      third of the walls: real residuals are correlated along a wall (SICK range bias, surfaces
      not flat), so the test cannot be on by default.

    Raises:
        ConfigError: naming the field, when a value cannot work.
    """

    sigma: float = 0.005
    sigma_fit: float | None = None  # m; None: sigma
    breakpoint_lambda: float = float(np.deg2rad(10.0))  # rad
    split_threshold: float = 0.03  # m, least
    split_sigmas: float = 3.0
    merge_rms: float = 0.01  # m, least
    merge_sigmas: float = 2.0
    min_points: int = 8
    min_length: float = 0.15
    max_skip: int = 3
    runs_z: float = 0.0
    corners: CornerConfig = field(default_factory=CornerConfig)

    def __post_init__(self) -> None:
        check_split_fields(self, chord=False)

    @property
    def params(self) -> engine.SplitParams:
        """The kernels' typed record of this config (built once, in ``__post_init__``)."""
        return self._params  # type: ignore[attr-defined, no-any-return]


def check_split_fields(cfg: object, chord: bool) -> None:
    """The checks of a SplitMergeConfig or IepfConfig (ConfigError naming the field), then its
    numbers as plain ints and floats (``checks.plain_numbers``) and its kernels' record (``split_params``) kept on it as ``_params``."""
    checks.shared_fields(cfg)
    if cfg.sigma_fit is not None:
        checks.noise_sigma("sigma_fit", cfg.sigma_fit)  # 1e-300: every beam splits; 1e300: one line a scan
    checks.band("split_threshold", cfg.split_threshold)  # 1e300: one line across every corner, exit 0
    checks.sigmas("split_sigmas", cfg.split_sigmas)
    checks.between("merge_rms", cfg.merge_rms, 0.0, checks.MAX_BAND_M, "m")  # 0: the noise-following part alone
    checks.sigmas("merge_sigmas", cfg.merge_sigmas)
    checks.plain_numbers(cfg)  # after every check: they see (and quote) the values given
    object.__setattr__(cfg, "_params", split_params(cfg, chord))


_extract_scan = FixedTypeCall(engine.extract_scan)  # a Scan's types: read-only float64 arrays, floats
_extract_batch = FixedTypeCall(engine.extract_batch)  # stacked_ranges: a C-contiguous float64 (S, n) array


def thresholds(cfg: object) -> tuple[float, float]:
    """The split threshold and merge RMS (m) a SplitMergeConfig or IepfConfig applies:
    max(split_threshold, split_sigmas x sigma_fit) and max(merge_rms, merge_sigmas x sigma_fit),
    sigma_fit defaulting to sigma."""
    fit = float(cfg.sigma if cfg.sigma_fit is None else cfg.sigma_fit)
    # capped at the largest float: an overflowed merge RMS of inf let the merge pass count the
    # non-adjacent pairs' inf as mergeable while picking none, and loop forever
    return (min(max(float(cfg.split_threshold), float(cfg.split_sigmas) * fit), MAX_FLOAT),
            min(max(float(cfg.merge_rms), float(cfg.merge_sigmas) * fit), MAX_FLOAT))


def split_params(cfg: object, chord: bool) -> engine.SplitParams:
    """The kernels' record of a SplitMergeConfig or IepfConfig (the thresholds of ``thresholds``)."""
    split, merge = thresholds(cfg)
    return engine.SplitParams(
        float(cfg.sigma), float(cfg.breakpoint_lambda), split, merge,
        checks.beams(cfg.min_points), float(cfg.min_length), checks.beams(cfg.max_skip), float(cfg.runs_z), bool(chord),
    )


@lru_cache(maxsize=16)
def bearing_table(angle_min: float, increment: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(cos, sin) of the bearings of n beams from ``angle_min`` in steps of ``increment`` (rad,
    as ``lms200.Scan.angles``), read-only, computed once per geometry (``engine.bearing_table``)."""
    cos_b, sin_b = engine.bearing_table(angle_min + np.arange(n) * increment)
    cos_b.setflags(write=False)
    sin_b.setflags(write=False)
    return cos_b, sin_b


def run_pipeline(scan: Scan, cfg, method: str) -> FeatureSet:  # noqa: ANN001
    """Lines and corners of ``scan`` (sensor frame) by the split / merge pipeline of ``cfg``:
    splitting at the least-squares fit (a SplitMergeConfig) or the chord (an IepfConfig)."""
    lv, lb, cv, cb = _extract_scan(scan.ranges, *bearing_table(scan.angle_min, scan.angle_increment, scan.ranges.size),
                                   scan.range_min, scan.range_max, scan.angle_increment, cfg.params,
                                   cfg.corners.params)
    return FeatureSet.of(Lines(lv, lb), Corners(cv, cb), method)


def run_pipeline_many(scans: Sequence[Scan], cfg, method: str) -> list[FeatureSet]:  # noqa: ANN001
    """``run_pipeline`` of every scan (one geometry, checked), in one kernel call."""
    if not scans:
        return []
    scan = common_geometry(scans)
    rows = _extract_batch(stacked_ranges(scans), *bearing_table(scan.angle_min, scan.angle_increment, len(scan)),
                                scan.range_min, scan.range_max, scan.angle_increment, cfg.params, cfg.corners.params)
    return split_rows(*rows, method)


def run(scan: Scan, cfg: SplitMergeConfig) -> FeatureSet:
    """Extract lines and corners from ``scan`` (sensor frame) by split-and-merge."""
    return run_pipeline(scan, cfg, "split_merge")


def run_many(scans: Sequence[Scan], cfg: SplitMergeConfig) -> list[FeatureSet]:
    """``run`` of every scan of a batch of one geometry, in one kernel call."""
    return run_pipeline_many(scans, cfg, "split_merge")


register("split_merge", SplitMergeConfig, run, backend="numba", run_many=run_many, thread_safe=True)
