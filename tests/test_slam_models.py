"""Models of the SLAM filter: Jacobians against central finite differences, the covariance
prediction against a Monte-Carlo propagation, and the sign flip of the line observation."""

from __future__ import annotations

import numpy as np
import pytest

from slam import models as m


def finite_difference(f, x: np.ndarray, eps: float = 1e-6, angle_rows=()) -> np.ndarray:
    f0 = f(x)
    J = np.zeros((f0.size, x.size))
    for i in range(x.size):
        d = np.zeros_like(x)
        d[i] = eps
        diff = f(x + d) - f(x - d)
        for r in angle_rows:
            diff[r] = m.wrap(diff[r])
        J[:, i] = diff / (2 * eps)
    return J


RNG = np.random.default_rng(42)
CASES = [(RNG.normal(0, 3, 3), np.array([abs(RNG.normal(0, 5)) + 0.5, RNG.uniform(-3, 3)])) for _ in range(8)]


@pytest.mark.parametrize("pose,landmark", CASES)
def test_line_observation_jacobians_match_finite_differences(pose, landmark):
    Hp, Hl = m.observe_line_jacobians(pose, landmark)
    np.testing.assert_allclose(Hp, finite_difference(lambda p: m.observe_line(p, landmark), pose, angle_rows=(1,)), atol=1e-7)
    np.testing.assert_allclose(Hl, finite_difference(lambda l: m.observe_line(pose, l), landmark, angle_rows=(1,)), atol=1e-7)


@pytest.mark.parametrize("pose,landmark", CASES)
def test_corner_and_inverse_observation_jacobians(pose, landmark):
    Hp, Hl = m.observe_corner_jacobians(pose, landmark)
    np.testing.assert_allclose(Hp, finite_difference(lambda p: m.observe_corner(p, landmark), pose), atol=1e-7)
    np.testing.assert_allclose(Hl, finite_difference(lambda l: m.observe_corner(pose, l), landmark), atol=1e-7)
    z = np.array([landmark[0], m.wrap(landmark[1] - 1.0)])
    _, Gp, Gz = m.init_line(pose, z)
    np.testing.assert_allclose(Gp, finite_difference(lambda p: m.init_line(p, z)[0], pose, angle_rows=(1,)), atol=1e-7)
    np.testing.assert_allclose(Gz, finite_difference(lambda zz: m.init_line(pose, zz)[0], z, angle_rows=(1,)), atol=1e-7)
    _, Gp, Gz = m.init_corner(pose, landmark)
    np.testing.assert_allclose(Gp, finite_difference(lambda p: m.init_corner(p, landmark)[0], pose), atol=1e-7)
    np.testing.assert_allclose(Gz, finite_difference(lambda zz: m.init_corner(pose, zz)[0], landmark), atol=1e-7)


@pytest.mark.parametrize("pose,_", CASES[:4])
def test_motion_and_odometry_jacobians(pose, _):
    robot = np.r_[pose, RNG.normal(0, 1, 2)]
    np.testing.assert_allclose(m.motion_jacobian(robot, 0.21), finite_difference(lambda r: m.motion(r, 0.21), robot, angle_rows=(2,)), atol=1e-7)
    delta = np.array([0.3, -0.05, 0.4])
    F, J = m.odometry_jacobians(robot, delta)
    fd_F = finite_difference(lambda r: m.odometry_motion(r, delta, 0.2), robot, angle_rows=(2,))
    fd_J = finite_difference(lambda d: m.odometry_motion(robot, d, 0.2), delta, angle_rows=(2,))
    np.testing.assert_allclose(F[:3], fd_F[:3], atol=1e-7)
    np.testing.assert_allclose(J[:3], fd_J[:3], atol=1e-7)


def test_observation_round_trip_and_sign_flip():
    # the line x = 2 (R=2, theta=0) seen from (5, 0) facing +x lies behind: rho = 3, alpha = pi
    z = m.observe_line(np.array([5.0, 0.0, 0.0]), np.array([2.0, 0.0]))
    np.testing.assert_allclose(z, [3.0, np.pi], atol=1e-12)
    # from (1, 1) heading 90 deg: rho = 1, alpha = -90 deg
    np.testing.assert_allclose(m.observe_line(np.array([1.0, 1.0, np.pi / 2]), np.array([2.0, 0.0])), [1.0, -np.pi / 2], atol=1e-12)
    pose = np.array([1.0, -2.0, 0.7])
    for lm in ([3.0, 0.2], [1.0, 2.5], [0.5, -2.0]):
        z = m.observe_line(pose, np.array(lm))
        back, _, _ = m.init_line(pose, z)
        np.testing.assert_allclose(back, lm, atol=1e-12)
        assert z[0] >= 0


def test_wrap_range():
    a = m.wrap(np.array([np.pi, -np.pi, 3 * np.pi, 0.1, -7.0]))
    assert np.all(a > -np.pi) and np.all(a <= np.pi)
    np.testing.assert_allclose(a[:4], [np.pi, np.pi, np.pi, 0.1])


def test_covariance_prediction_matches_monte_carlo():
    rng = np.random.default_rng(7)
    x0 = np.array([1.0, 2.0, 0.6, 1.2, 0.8])
    P0 = np.diag([0.02, 0.03, 0.01, 0.3, 0.3]) ** 2
    P0[0, 2] = P0[2, 0] = 0.5 * 0.02 * 0.01
    dt, sa, sal, sl = 0.5, 0.3, 0.5, 0.05
    F = m.motion_jacobian(x0, dt)
    predicted = F @ P0 @ F.T + m.motion_noise(x0, dt, sa, sal, sl)
    n = 40000
    xs = rng.multivariate_normal(x0, P0, n)
    noise = rng.normal(0, 1, (n, 3)) * [sa, sal, sl]
    out = np.array([m.motion(x, dt, w) for x, w in zip(xs, noise)])
    mc = np.cov(out.T)
    sd = np.sqrt(np.diag(predicted))
    corr_err = (mc - predicted) / np.outer(sd, sd)
    assert np.abs(corr_err).max() < 0.04, corr_err
    # the classic mistake G^T P G (transposed Jacobians) does not pass this test
    wrong = F.T @ P0 @ F + m.motion_noise(x0, dt, sa, sal, sl)
    assert np.abs((mc - wrong) / np.outer(sd, sd)).max() > 0.1


def test_chi2_quantile_matches_scipy():
    from scipy.stats import chi2

    for p, k in [(0.99, 2), (0.999, 1), (0.999, 3), (0.95, 10), (0.5, 4)]:
        assert m.chi2_quantile(p, k) == pytest.approx(chi2.ppf(p, k), rel=1e-10)
