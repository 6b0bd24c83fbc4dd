"""Odometry-free EKF-SLAM with line and corner landmarks, and trajectory scoring.

``run_slam(records, config=SlamConfig()) -> SlamResult``; metrics in :mod:`slam.metrics`.
"""

from .config import SlamConfig, SlamConfigError
from .filter import SlamFilter
from .observations import Observations, from_features
from .run import SlamInputError, SlamResult, run_observations, run_slam, run_steps

__all__ = [
    "SlamConfig",
    "SlamConfigError",
    "SlamFilter",
    "SlamInputError",
    "SlamResult",
    "Observations",
    "from_features",
    "run_slam",
    "run_steps",
    "run_observations",
]
