"""The windowed loop-closure search (``loop_closure.search: window``, :func:`slam.keyframes.find_closure_window`):
a revisit metres and degrees off the estimate that the nearest-visit ICP cannot reach is closed, and a
corridor whose door recesses repeat a spacing away is refused rather than closed on the wrong door."""

from __future__ import annotations

import numpy as np
import pytest

from slam.config import AlignmentConfig, LoopClosureConfig
from slam.correlative import Field, search
from slam.geometry import compose
from slam.keyframes import Keyframe, find_closure, find_closure_window
from slam.models import wrap
from slam.scanslam import ScanPoints
from slam.synthetic import scan_points

ALIGN = AlignmentConfig()
LOOP = LoopClosureConfig(search="window")
VOXEL = 0.05


def _walls(corners) -> np.ndarray:
    c = np.asarray(corners, float)
    return np.column_stack((c[:-1], c[1:]))


def _keyframe(walls: np.ndarray, key: int, true: np.ndarray, estimate: np.ndarray, travelled: float,
              rng: np.random.Generator) -> tuple[Keyframe, ScanPoints]:
    sp = ScanPoints.from_points(scan_points(walls, true, n_beams=181, max_range=8.0, sigma=0.01, rng=rng), ALIGN)
    return Keyframe(key, key, float(key), np.asarray(estimate, float), *sp.surface(), travelled), sp


def _search(new: Keyframe, sp: ScanPoints, old: list[Keyframe], relative: np.ndarray, window: bool,
            nan_for: frozenset[int] = frozenset()):
    """``nan_for``: the keys whose relative covariance is given as NaN (the window search only)."""
    xy = np.array([kf.pose[:2] for kf in old])
    travel = np.array([kf.travelled for kf in old])
    if window:
        return find_closure_window(new, sp.matched, old, LOOP, ALIGN, VOXEL,
                                   lambda cand: np.full((3, 3), np.nan) if cand.key in nan_for else relative,
                                   xy, travel, sp.matched_normals)
    return find_closure(new, sp.matched, old, LoopClosureConfig(), ALIGN, VOXEL, 0.0,
                        lambda cand: LOOP.window_inflation * relative, xy, travel, sp.matched_normals)


def _room_walls() -> np.ndarray:
    """An irregular room (no symmetry) with a box in it."""
    room = _walls([(0, 0), (10, 0), (10, 4), (7, 4), (7, 7), (3, 7), (3, 5), (0, 5), (0, 0)])
    box = _walls([(4.5, 2.0), (5.5, 2.0), (5.5, 2.6), (4.5, 2.6), (4.5, 2.0)])
    return np.vstack((room, box))


def _room_revisit():
    """Five keyframes of a first visit at their true poses, a revisit whose estimate drifted 3 m and
    8 degrees (within 2 std of the relative covariance returned, times the 10 of ``window_inflation``)."""
    walls, rng = _room_walls(), np.random.default_rng(3)
    old = [_keyframe(walls, k, p, p, 0.5 * k, rng)[0]
           for k, p in enumerate(np.array([[1.0, 1.0, 0.2], [1.5, 1.2, 0.3], [2.0, 1.3, 0.4], [2.5, 1.5, 0.5],
                                           [3.0, 1.7, 0.5]]))]
    true = np.array([2.2, 1.1, 0.35])
    new, sp = _keyframe(walls, 40, true, compose(true, np.array([3.0, 0.0, np.radians(8.0)])), 30.0, rng)
    relative = np.diag([0.5**2, 0.5**2, 0.05**2])  # x10: 1.6 m and 9 degrees std
    return old, true, new, sp, relative


def test_a_revisit_metres_off_the_estimate_is_closed_where_the_icp_cannot_reach():
    """Five keyframes of a first visit at their true poses; the revisit's estimate has drifted
    3 m and 8 degrees (within 2 std of the relative covariance given, times the 10 of
    ``window_inflation``). The nearest-visit ICP starts at the estimate and reaches 0.5 m: no
    closure. The window search closes it, within 3 cm and 0.5 degree of the truth."""
    old, true, new, sp, relative = _room_revisit()
    assert _search(new, sp, old, relative, window=False) is None
    loop = _search(new, sp, old, relative, window=True)
    assert loop is not None
    closed = compose(old[loop.old].pose, loop.relative)
    assert np.hypot(*(closed[:2] - true[:2])) < 0.03
    assert abs(wrap(closed[2] - true[2])) < np.radians(0.5)


def _corridor_walls() -> np.ndarray:
    """A corridor 2 m wide and 60 m long along x, a door recess (0.8 m wide, 0.3 m deep) every
    2 m on both walls: seen from any two poses 2 m apart along it, the scans are the same."""
    segs = []
    for y, depth in ((-1.0, -0.3), (1.0, 0.3)):
        for x0 in np.arange(-30.0, 30.0, 2.0):
            segs += [(x0, y, x0 + 0.6, y), (x0 + 0.6, y, x0 + 0.6, y + depth), (x0 + 0.6, y + depth, x0 + 1.4, y + depth),
                     (x0 + 1.4, y + depth, x0 + 1.4, y), (x0 + 1.4, y, x0 + 2.0, y)]
    return np.array(segs, float)


@pytest.mark.parametrize("offset", [2.0, 4.0])
def test_a_door_spacing_away_along_an_aliased_corridor_is_refused(offset):
    """The revisit stands where a first visit's keyframe stood, its estimate ``offset`` m further
    along the corridor (one or two door spacings). The nearest-visit ICP from the estimate fits
    the aliased doors and closes the loop ``offset`` m wrong; the window (which holds both
    places) sees two distinct poses fit alike and refuses."""
    walls, rng = _corridor_walls(), np.random.default_rng(5)
    old = [_keyframe(walls, k, p, p, 0.5 * k, rng)[0]
           for k, p in enumerate(np.array([[x, 0.0, 0.0] for x in np.arange(-6.0, 13.0, 1.0)]))]
    true = np.array([1.0, 0.0, 0.0])
    new, sp = _keyframe(walls, 60, true, true + np.array([offset, 0.0, 0.0]), 40.0, rng)
    relative = np.diag([0.5**2, 0.5**2, 0.03**2])
    wrong = _search(new, sp, old, relative, window=False)
    assert wrong is not None  # the old search closes it, on the wrong door
    closed = compose(old[wrong.old].pose, wrong.relative)
    assert abs(closed[0] - true[0] - offset) < 0.1
    assert _search(new, sp, old, relative, window=True) is None


def test_a_candidate_without_a_finite_relative_covariance_is_passed_over():
    """A NaN relative covariance (a graph gone singular) leaves no window: that candidate is passed
    over (it was a ValueError, NaN to integer) and the next keyframe of the visit is searched; with
    none finite, no closure."""
    old, true, new, sp, relative = _room_revisit()
    first = _search(new, sp, old, relative, window=True)
    assert first is not None
    loop = _search(new, sp, old, relative, window=True, nan_for=frozenset({first.old}))
    assert loop is not None and loop.old != first.old
    closed = compose(old[loop.old].pose, loop.relative)
    assert np.hypot(*(closed[:2] - true[:2])) < 0.03
    assert _search(new, sp, old, relative, window=True, nan_for=frozenset(kf.key for kf in old)) is None


def test_the_peaks_search_gives_another_place_as_runner_up_not_a_shoulder_of_the_best():
    """A hand-built field (0.1 m cells): a wide bump (1 at (1, 1), 0.5 m std) and a narrow second
    peak (0.7 at (2.5, 1), 0.05 m std) 1.5 m away; one scan point at the sensor's origin, so a
    pose scores the field at its position. The best 2 poses 0.3 m apart are the bump and its
    shoulder 0.3 m off (exp(-0.18) = 0.84 > 0.7); the best 2 local maxima are the bump and the
    second peak."""
    res = 0.1
    origin = np.array([-0.5, -0.5])
    x, y = np.meshgrid(origin[0] + res * np.arange(41), origin[1] + res * np.arange(31), indexing="ij")
    values = np.maximum(np.exp(-0.5 * ((x - 1.0) ** 2 + (y - 1.0) ** 2) / 0.5**2),
                        0.7 * np.exp(-0.5 * ((x - 2.5) ** 2 + (y - 1.0) ** 2) / 0.05**2))
    field = Field(values, origin, res)
    args = (np.zeros((1, 2)), field, np.array([1.5, 1.0, 0.0]), 1.5, 0.0, res, 0.01, 2, 0.3, 0.1)
    best, shoulder = search(*args)
    np.testing.assert_allclose(best.pose, [1.0, 1.0, 0.0], atol=1e-9)
    assert abs(np.hypot(*(shoulder.pose[:2] - best.pose[:2])) - 0.3) < 1e-9
    assert shoulder.score == pytest.approx(np.exp(-0.18))
    best, second = search(*args, peaks=True)
    np.testing.assert_allclose(best.pose, [1.0, 1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(second.pose, [2.5, 1.0, 0.0], atol=1e-9)
    assert second.score == pytest.approx(0.7)
