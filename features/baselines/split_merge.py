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

from dataclasses import dataclass, field

import numpy as np

from lms200 import Scan

from ..registry import register
from ..types import FeatureSet
from . import checks
from .common import (BACKENDS, CornerConfig, PrefixFit, breakpoints, build_lines, feature_set, straight_enough, trim_ends,
                     use_numba, valid_points)
from .splitting import _ragged, merge_collinear, split, unshare


@dataclass(frozen=True)
class SplitMergeConfig:
    """Defaults, for the LMS200 (sigma = 5 mm in mm mode):

    - sigma: range noise (m) for breakpoints and line covariances.
    - breakpoint_lambda_deg: 10 deg, Borges & Aldon (2004)'s value for their adaptive breakpoint
      detector.
    - split_threshold: 0.03 m = 6 sigma: the largest residual of a true line of ~100 points stays
      below ~4 sigma, so genuine lines are not split; a 10 deg bend over 1 m legs exceeds it.
    - merge_rms: 0.01 m = 2 sigma RMS residual for merging neighbours (Nguyen et al. 2007 merge
      collinear neighbours after splitting).
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
    """

    sigma: float = 0.005
    breakpoint_lambda_deg: float = 10.0
    split_threshold: float = 0.03
    merge_rms: float = 0.01
    min_points: int = 8
    min_length: float = 0.15
    max_skip: int = 3
    runs_z: float = 0.0
    corners: CornerConfig = field(default_factory=CornerConfig)
    backend: str = "auto"  # "numba" (compiled kernels), "numpy" (the reference), "auto": numba when importable

    def __post_init__(self) -> None:
        """Raise ValueError naming the field when a value cannot work."""
        checks.shared_fields(self)
        checks.positive("split_threshold", self.split_threshold, "m")
        checks.non_negative("merge_rms", self.merge_rms, "m")
        checks.choice("backend", self.backend, BACKENDS)


def segment_lines(scan: Scan, sigma: float, lam_deg: float, threshold: float, merge_rms: float,
                  min_points: int, min_length: float, max_skip: int, runs_z: float, chord: bool):
    """The split / merge / refit pipeline shared with ``iepf``; returns beam-ordered Lines."""
    pts = valid_points(scan)
    if pts.idx.size < 2:
        return []
    fitter = PrefixFit(pts.x, pts.y)
    clusters = breakpoints(pts, scan.angle_increment, np.deg2rad(lam_deg), sigma, max_skip)
    segs = split(pts, fitter, clusters, threshold, min_points, chord)
    if merge_rms > 0:
        segs = merge_collinear(fitter, segs, merge_rms)
    segs = unshare(segs)
    segs = segs[(segs[:, 1] - segs[:, 0] + 1) >= min_points]
    if segs.size == 0:
        return []
    s, e = segs[:, 0], segs[:, 1]
    rho, alpha, n, mx, my, along = fitter.fit(s, e)
    for _ in range(2):  # drop end points off the fitted line (a neighbouring small face), refit
        pos, _, offsets = _ragged(s, e)
        lo, hi = trim_ends(pts.x[pos], pts.y[pos], offsets, rho, alpha, 3.0 * sigma, min_points)
        if np.array_equal(pos[lo], s) and np.array_equal(pos[hi], e):
            break
        s, e = pos[lo], pos[hi]
        rho, alpha, n, mx, my, along = fitter.fit(s, e)
    if runs_z > 0:
        pos, _, offsets = _ragged(s, e)
        ok = straight_enough(pts.x[pos], pts.y[pos], offsets, rho, alpha, runs_z, 0.5 * sigma)
        s, e, rho, alpha, n, mx, my, along = (v[ok] for v in (s, e, rho, alpha, n, mx, my, along))
    lines = build_lines(pts, s, e, rho, alpha, n, mx, my, along, sigma)
    return [l for l in lines if l.length >= min_length]


def run_pipeline(scan: Scan, cfg, method: str, chord: bool) -> FeatureSet:  # noqa: ANN001
    """Lines and corners of ``scan`` (sensor frame) by the split / merge pipeline, splitting at the
    least-squares fit (``chord=False``, split_merge) or the chord (``chord=True``, iepf), on the
    backend the config (``SplitMergeConfig`` or ``IepfConfig``) names."""
    if use_numba(cfg.backend):
        from .compiled import extract_numba  # noqa: PLC0415  (numba is imported on first use)

        return extract_numba(scan, cfg, method, chord=chord)
    lines = segment_lines(scan, cfg.sigma, cfg.breakpoint_lambda_deg, cfg.split_threshold,
                          cfg.merge_rms, cfg.min_points, cfg.min_length, cfg.max_skip, cfg.runs_z, chord=chord)
    return feature_set(lines, cfg.corners, method, scan.angle_increment)


def run(scan: Scan, cfg: SplitMergeConfig) -> FeatureSet:
    """Extract lines and corners from ``scan`` (sensor frame) by split-and-merge."""
    return run_pipeline(scan, cfg, "split_merge", chord=False)


register("split_merge", SplitMergeConfig, run)
