"""Defects a read-only review (session 32) reproduced in the CARMEN reader / writer, the Scan angle
snapping and the Record / LaserGeometry argument checks; each test failed on the code before its fix."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lms200 import LaserGeometry, Record, Scan, read_log, write_log
from lms200.errors import InputError, LogFormatError


def _scan() -> Scan:
    return Scan(np.ones(3), -0.1, 0.05, 0.0, 8.0)


@pytest.mark.parametrize("pose, message", [
    ((10**400, 0, 0), "odom: must be finite, got a int beyond float64's range"),
    ("123", "odom: must be None or three numbers (x m, y m, theta rad), got str '123'"),
    ((True, False, True), "odom: must be None or three numbers (x m, y m, theta rad), got bool True among them"),
    ((1.0, 2.0), "odom: must be None or three numbers (x m, y m, theta rad), got 2 items"),
])
def test_record_pose_refused_with_input_error_naming_the_field(pose, message):
    # was: raw OverflowError; "123" read as (1.0, 2.0, 3.0); (True, False, True) as (1.0, 0.0, 1.0)
    with pytest.raises(InputError) as err:
        Record(_scan(), odom=pose)
    assert str(err.value) == message
    with pytest.raises(InputError, match="^truth: "):
        Record(_scan(), truth=pose)
    assert Record(_scan(), odom=(np.float64(1), 2, np.int64(3))).odom == (1.0, 2.0, 3.0)


@pytest.mark.parametrize("kw, message", [
    (dict(fov=-1), r"fov: must be > 0, got -1 rad \(-57.2958 deg\)"),
    (dict(range_max=10**400), "range_max: must be finite, got a int beyond float64's range"),
    (dict(fov="3"), "fov: must be a number, got str '3'"),
    (dict(resolution=True), "resolution: must be a number, got bool True"),
])
def test_laser_geometry_refused_with_input_error_naming_the_field(kw, message):
    # was: plain ValueError, raw OverflowError; "3" and True accepted as 3 rad and 1 rad
    with pytest.raises(InputError, match=f"^{message}$"):
        LaserGeometry(**kw)
