"""The filterpy-based EKF with a growing state, data association and the rotation pre-alignment."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from slam import models
from slam.association import jcbb, nearest_neighbour
from slam.ekf import SlamEKF, stacked_H, stacked_h, stacked_residual
from slam.prealign import align, rotation_candidates
from slam.synthetic import CONVEX_ROOM, observe_walls


def grown_filter(rng: np.random.Generator) -> SlamEKF:
    ekf = SlamEKF((0.5, -0.2, 0.3), pose_sigma=0.05)
    ekf.x[3:5, 0] = (0.8, 0.3)
    for z in ([2.0, 0.3], [3.0, 1.9], [1.5, -1.4]):
        value, Gp, Gz = models.init_line(ekf.x[:3, 0], np.array(z))
        ekf.add_landmark(value, Gp, Gz, np.diag([0.01, 0.002]) ** 2)
    value, Gp, Gz = models.init_corner(ekf.x[:3, 0], np.array([2.0, 1.0]))
    ekf.add_landmark(value, Gp, Gz, np.eye(2) * 0.02**2)
    return ekf


def test_growing_state_keeps_filterpy_internals_consistent():
    ekf = grown_filter(np.random.default_rng(0))
    n = 5 + 2 * 4
    assert ekf.dim_x == n and ekf.n_landmarks == 4
    assert ekf.x.shape == (n, 1) and ekf.P.shape == (n, n)
    assert ekf.F.shape == ekf.Q.shape == ekf._I.shape == (n, n)
    assert ekf.K.shape == (n, 2) and ekf.x_prior.shape == (n, 1) and ekf.P_post.shape == (n, n)
    np.linalg.cholesky(ekf.P)
    np.testing.assert_allclose(ekf.P, ekf.P.T)
    ekf.remove_landmarks([7, 11])
    assert ekf.dim_x == 9 and ekf._I.shape == (9, 9) and ekf.F.shape == (9, 9)
    with pytest.raises(IndexError):
        ekf.remove_landmarks([3])


def test_fast_predict_and_update_equal_filterpy_methods():
    ekf = grown_filter(np.random.default_rng(1))
    ref = copy.deepcopy(ekf)
    ekf.set_motion(0.2, 1.0, 3.0, 0.1)
    ref.set_motion(0.2, 1.0, 3.0, 0.1)
    ekf.predict()
    ExtendedKalmanFilter.predict(ref)  # filterpy's own: predict_x() then F P F^T + Q on full matrices
    np.testing.assert_allclose(ekf.x, ref.x, atol=1e-12)
    np.testing.assert_allclose(ekf.P, ref.P, atol=1e-12)
    kinds, ids = ["line", "line", "corner"], [5, 9, 11]
    z = stacked_h(ekf.x, kinds, ids) + np.array([[0.01], [0.003], [-0.02], [-0.004], [0.01], [0.02]])
    z[3, 0] = models.wrap(z[3, 0])
    R = np.diag([0.01, 0.003, 0.01, 0.003, 0.02, 0.02]) ** 2
    args = dict(R=R, args=(kinds, ids), hx_args=(kinds, ids), residual=stacked_residual(kinds))
    ekf.update(z, stacked_H, stacked_h, **args)
    ExtendedKalmanFilter.update(ref, z, stacked_H, stacked_h, **args)  # Joseph form
    np.testing.assert_allclose(ekf.x, ref.x, atol=1e-10)
    np.testing.assert_allclose(ekf.P, ref.P, atol=1e-10)
    assert ekf.x.shape == (ekf.dim_x, 1)  # a (2m,) z must not broadcast the state to (n, 2m)


def test_residual_wraps_line_angles_only():
    res = stacked_residual(["line", "corner"])
    y = res(np.array([[1.0], [3.1], [0.0], [3.1]]), np.array([[1.0], [-3.1], [0.0], [-3.1]]))
    np.testing.assert_allclose(y[:, 0], [0.0, 6.2 - 2 * np.pi, 0.0, 6.2])


def test_nearest_neighbour_is_one_to_one_and_gated():
    d2 = np.array([[1.0, 0.5, 30.0], [0.2, 8.0, 30.0], [40.0, 50.0, 60.0]])
    assert nearest_neighbour(d2, 9.21) == [(0, 1), (1, 0)]


def test_jcbb_rejects_individually_but_not_jointly_compatible_pairs():
    # two observations, two landmarks; pairing (0,0),(1,1) is jointly consistent, the swapped
    # one is individually compatible but the innovations are correlated so that it is not.
    nu = {(0, 0): np.array([0.1, 0.0]), (1, 1): np.array([0.1, 0.0]), (0, 1): np.array([1.0, 0.0]), (1, 0): np.array([-1.0, 0.0])}
    d2 = np.array([[0.01, 1.0], [1.0, 0.01]])

    def S_fn(pairs):
        k = len(pairs)
        S = np.eye(2 * k)
        for a in range(k):
            for b in range(k):
                if a != b:
                    S[2 * a, 2 * b] = 0.9  # strongly correlated first components (a common pose error)
        return S

    pairs = jcbb(d2, 9.21, lambda o, l: nu[(o, l)], S_fn)
    assert pairs == [(0, 0), (1, 1)]


@pytest.mark.parametrize("turn_deg", [0.0, 35.0, -80.0, 90.0, 170.0])
def test_prealign_finds_large_turns_without_initial_guess(turn_deg):
    rng = np.random.default_rng(3)
    pose = np.array([4.0, 3.0, 0.4])
    world_lines = []
    for w in CONVEX_ROOM:  # map lines in the world frame
        d = w[2:] - w[:2]
        n = np.array([-d[1], d[0]]) / np.hypot(*d)
        R = n @ w[:2]
        world_lines.append((abs(R), np.arctan2(*(n * np.sign(R or 1))[::-1]), np.hypot(*d)))
    world_lines = np.array(world_lines)
    true = np.array([4.2, 3.1, models.wrap(0.4 + np.radians(turn_deg))])
    obs = observe_walls(CONVEX_ROOM, true, rng=rng)
    predicted = pose.copy()  # the previous pose: knows nothing of the turn
    a = align(obs.lines[:, 0], obs.lines[:, 1], obs.line_lengths, world_lines[:, 0], world_lines[:, 1], world_lines[:, 2], predicted)
    assert a is not None
    assert abs(models.wrap(a.pose[2] - true[2])) < np.radians(1.0)
    np.testing.assert_allclose(a.pose[:2], true[:2], atol=0.05)
    assert a.matched_length > 0.8 * a.total_length


def test_rotation_candidates_recover_a_pure_shift():
    alpha = np.radians([10.0, 100.0, 190.0, 235.0])
    w = np.array([3.0, 1.0, 2.0, 1.5])
    cands = rotation_candidates(alpha, w, alpha + np.radians(47.3), w, max_candidates=1)
    assert abs(np.degrees(models.wrap(cands[0])) - 47.3) < 0.2
