"""Bad input to the scores and helpers of features, slam.metrics and the simulator's tours (the API
hunt of 2026-12-04, session 33): an ``LmsbenchError`` naming the argument, never numba's
TypingError, Python's OverflowError / TypeError or a silent nan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from features.errors import ConfigError, ScanTypeError
from features.noise_estimate import neighbour_sigma, stacked_sigma
from features.realdata import truncated_normal_rms
from features.scoring import prf
from lms200 import LmsbenchError, Scan
from lms200.errors import InputError
from slam.metrics import rpe

SCAN = Scan.lms200(3.0 + 0.01 * np.sin(np.arange(361)))
T = np.linspace(0.0, 10.0, 50)
TRAJ = np.column_stack((T, np.cos(T), np.sin(T), np.zeros_like(T)))


@pytest.mark.parametrize("call, error, message", [
    (lambda: stacked_sigma(None, SCAN), InputError, r"^ranges: must be a \(k, 361\) array of real numbers"),  # TypingError
    (lambda: stacked_sigma(3.0, SCAN), InputError, r"^ranges: must be a \(k, 361\) array"),
    (lambda: stacked_sigma(SCAN.ranges, SCAN), InputError, r"^ranges: must be a \(k, 361\) array .* got shape \(361,\)$"),
    (lambda: stacked_sigma(np.ones((3, 100)), SCAN), InputError, r"^ranges: must be a \(k, 361\) array .* got shape \(3, 100\)$"),
    (lambda: stacked_sigma(np.ones((3, 361)), None), ScanTypeError, r"^stacked_sigma: expected an lms200\.Scan, got NoneType"),
    (lambda: stacked_sigma(np.ones((3, 361)), SCAN, fallback=math.nan), ConfigError, r"^fallback: must be a finite number > 0"),
    (lambda: prf(-1, 0, 0), InputError, r"^tp: must be a whole number >= 0 \(a count\), got -1$"),  # (nan, nan, nan)
    (lambda: prf(1, math.nan, 0), InputError, r"^fp: must be a whole number >= 0 \(a count\), got nan$"),
    (lambda: prf(1, 0, None), InputError, r"^fn: must be a whole number >= 0 \(a count\), got None$"),  # TypeError
    (lambda: prf("1", 0, 0), InputError, r"^tp: must be a whole number"),
    (lambda: rpe(TRAJ[:1], TRAJ), InputError, r"^rpe: fewer than 2 estimated poses fall inside"),  # nan scores, n 0
    (lambda: rpe(TRAJ, np.column_stack((np.ones_like(T), TRAJ[:, 1:]))), InputError, r"^rpe: fewer than 2"),  # one stamp
])
def test_scores_name_the_bad_argument(call, error: type, message: str) -> None:
    with pytest.raises(error, match=message) as info:
        call()
    assert isinstance(info.value, LmsbenchError) and "\n" not in str(info.value)


def test_scores_keep_their_valid_inputs() -> None:
    """Same numbers as before: counts as numpy ints or whole floats, nan precision of no detection
    (documented), rpe of a run shorter than delta (n 0); stacked_sigma of a list of rows is now
    read as its array (it was numba's TypingError)."""
    rows = np.stack([SCAN.ranges] * 3)
    assert stacked_sigma(rows.tolist(), SCAN) == stacked_sigma(rows, SCAN) == neighbour_sigma([SCAN] * 3)
    assert prf(np.int64(3), 1.0, 0) == (0.75, 1.0, pytest.approx(6 / 7))
    p, r, f = prf(0, 0, 2)
    assert math.isnan(p) and r == 0.0 and f == 0.0
    short = rpe(TRAJ, TRAJ, delta=100.0)
    assert short.n == 0 and math.isnan(short.trans_rmse)
    assert rpe(TRAJ, TRAJ).trans_rmse == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("sigma, tolerance", [(0.01, 1e308), (5e-324, 0.03)])
def test_truncated_normal_rms_of_no_truncation_is_sigma(sigma: float, tolerance: float) -> None:
    """A tolerance of 1e308 m (or a sigma of 5e-324 m) truncates nothing: the RMS is sigma, not
    nan (inf * phi(inf)); ordinary values are unchanged."""
    assert truncated_normal_rms(sigma, tolerance) == sigma
    assert truncated_normal_rms(0.01, 0.03) == pytest.approx(0.01 * math.sqrt(1 - 2 * 3 * math.exp(-4.5) / math.sqrt(2 * math.pi)
                                                                              / math.erf(3 / math.sqrt(2))))


@pytest.mark.parametrize("t, message", [
    (None, r"^t: must be a \(k, 1\) array of real numbers"),    # was the tour's end pose
    (math.nan, r"^t: must be finite \(s\); row 0 is not$"),      # was the tour's end pose
    ("1.0", r"^t: must be a \(k, 1\) array of real numbers"),   # was taken as 1 s
    (10**400, r"^t: must be a \(k, 1\) array of real numbers"),  # OverflowError
    (1 + 1j, r"^t: must be a \(k, 1\) array of real numbers"),  # TypeError
])
def test_tour_pose_at_names_bad_times(t: object, message: str) -> None:
    from sim import make_world, robot_tour

    tour = robot_tour(make_world("office", seed=0), seed=0, duration=10.0)
    for method in (tour.pose_at, tour.twist_at):
        with pytest.raises(InputError, match=message):
            method(t)
    assert tour.pose_at(1.0).shape == (1, 3) and tour.pose_at([1.0, 2.0]).shape == (2, 3)
    assert np.array_equal(tour.pose_at(np.array([[1.0], [2.0]])), tour.pose_at([1.0, 2.0]))
