"""``iepf``: iterative end-point fit. Clusters (adaptive breakpoints, Borges & Aldon 2004) are split
recursively at the point farthest from the chord between the segment's end points (Duda & Hart
1973; Douglas & Peucker 1973), then each final segment is refitted by least squares. As in Nguyen
et al. (2007), IEPF is split-and-merge with the chord in place of the fit; collinear neighbours are
merged before the refit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from lms200 import Scan

from ..registry import register
from ..types import FeatureSet
from .common import CornerConfig
from .engine import SplitParams
from .split_merge import check_split_fields, run_pipeline, run_pipeline_many


@dataclass(frozen=True)
class IepfConfig:
    """Defaults, for the LMS200 (sigma = 5 mm in mm mode):

    - split_threshold, split_sigmas: 0.04 m (8 sigma of the LMS200's 5 mm) and 4: the split
      threshold is max(split_threshold, split_sigmas x sigma_fit), a third above
      split_merge's (0.03 m, 3), as a chord between two noisy end points is itself off by
      their noise at each end.
    - the rest as ``split_merge`` (sigma_fit, None: sigma; breakpoint_lambda 10 deg in rad,
      Borges & Aldon 2004; merge RMS max(0.01 m, 2 sigma_fit);
      8 points and 0.15 m per line, Nguyen et al. 2007's P_min / L_min; up to two invalid beams
      bridged, none with no return; runs test off, ``runs_z`` = 0).
    """

    sigma: float = 0.005
    sigma_fit: float | None = None  # m; None: sigma
    breakpoint_lambda: float = float(np.deg2rad(10.0))  # rad
    split_threshold: float = 0.04  # m, least
    split_sigmas: float = 4.0
    merge_rms: float = 0.01  # m, least
    merge_sigmas: float = 2.0
    min_points: int = 8
    min_length: float = 0.15
    max_skip: int = 3
    runs_z: float = 0.0
    corners: CornerConfig = field(default_factory=CornerConfig)

    def __post_init__(self) -> None:
        """Raise ConfigError naming the field when a value cannot work."""
        check_split_fields(self, chord=True)

    @property
    def params(self) -> SplitParams:
        """The kernels' typed record of this config (built once, in ``__post_init__``)."""
        return self._params  # type: ignore[attr-defined, no-any-return]


def run(scan: Scan, cfg: IepfConfig) -> FeatureSet:
    """Extract lines and corners from ``scan`` (sensor frame) by iterative end-point fit."""
    return run_pipeline(scan, cfg, "iepf")


def run_many(scans: Sequence[Scan], cfg: IepfConfig) -> list[FeatureSet]:
    """``run`` of every scan of a batch of one geometry, in one kernel call."""
    return run_pipeline_many(scans, cfg, "iepf")


register("iepf", IepfConfig, run, backend="numba", run_many=run_many, thread_safe=True)
