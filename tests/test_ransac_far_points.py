"""RANSAC on points too far for float64 least squares (their squares overflow)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from features import extract
from lms200 import Scan


@pytest.mark.parametrize("distance", [1e154, 1.3e154, 1e160, 1e300])
def test_a_wall_too_far_to_square_gives_no_line_and_no_runtime_warning(distance: float) -> None:
    """A wall 1e160 m or more away (valid under range_max 1e308) gave ransac 27 RuntimeWarnings
    ("overflow encountered in multiply": x * x of its least-squares moments; found by
    tests/test_fuzz_extract.py) on stderr, and no line; split_merge, iepf and sensor give no line
    silently. Now such a fit is no line, without a warning."""
    a = np.deg2rad(np.arange(-30, 30.5, 0.5))
    scan = Scan(distance / np.cos(a), a[0], np.deg2rad(0.5), 0.0, 1e308)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fs = extract(scan, method="ransac")
    assert len(fs.lines) == 0 and len(fs.corners) == 0


def test_points_at_the_origin_and_beyond_1e154_m_give_no_warning() -> None:
    """The fuzz's case: beams alternating 5e-324 m and 1e300 m."""
    scan = Scan(np.array([5e-324, 1e300] * 6 + [5e-324]), 0.0, 0.5, 0.0, 1e308)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # breakpoint_lambda above the 0.5 rad step (the default 10 deg is not: a ConfigError, registry.step_problem),
        # the corner step's own too (checked alike)
        from features.baselines.common import CornerConfig

        assert len(extract(scan, method="ransac", breakpoint_lambda=1.0,
                           corners=CornerConfig(breakpoint_lambda=1.0)).lines) == 0


def test_a_near_wall_beside_a_far_one_is_still_found() -> None:
    """A wall at 2 m on the right half, one at 1e200 m on the left: ransac finds the near one."""
    a = np.deg2rad(np.arange(-30, 30.5, 0.5))
    r = np.where(a < 0, 2.0 / np.cos(a), 1e200 / np.cos(a))
    scan = Scan(r, a[0], np.deg2rad(0.5), 0.0, 1e308)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lines = extract(scan, method="ransac").lines
    assert len(lines) == 1
    np.testing.assert_allclose([lines.rho[0], lines.alpha[0]], [2.0, 0.0], atol=1e-9)
