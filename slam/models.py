"""Pure motion and observation models of the EKF-SLAM with their Jacobians (NOTES.md, section 4.1).

Frames: the world (map) frame is the frame of the first scan; the robot state is the pose of the
scanner ``(X m, Y m, Phi rad)`` with forward speed ``V`` (m/s) and turn rate ``w`` (rad/s).
A line landmark is ``(R m, theta rad)``, the line ``x cos(theta) + y sin(theta) = R`` in the world
frame; a corner landmark is ``(x m, y m)`` in the world frame. Angles are wrapped to (-pi, pi].
"""

from __future__ import annotations

import numpy as np

from lms200.angles import wrap as wrap  # the project's one wrap, re-exported for slam's modules

ROBOT_DIM = 5  # X, Y, Phi, V, w


def chi2_quantile(probability: float, dof: int) -> float:
    """Quantile of the chi-square distribution (``scipy.stats.chi2.ppf`` without importing
    scipy.stats, which takes a second): ``2 * gammaincinv(dof / 2, p)``."""
    from scipy.special import gammaincinv

    return float(2.0 * gammaincinv(0.5 * dof, probability))


# --- motion: constant velocity, white acceleration noise (NOTES.md: cos(Phi), not cos(w)) ----------
def motion(robot: np.ndarray, dt: float, noise: np.ndarray | None = None) -> np.ndarray:
    """Robot state after ``dt`` s. ``noise`` = (a_v m/s^2, a_w rad/s^2, v_lat m/s): forward and
    angular accelerations held over the step, and a sideways velocity (a scanner off the turning
    axis, skid, or the arc the Euler step ignores) held over the step."""
    X, Y, Phi, V, w = robot
    av, aw, vl = (0.0, 0.0, 0.0) if noise is None else noise
    c, s = np.cos(Phi), np.sin(Phi)
    h = 0.5 * dt * dt
    ds = V * dt + av * h
    return np.array(
        [X + ds * c - vl * dt * s, Y + ds * s + vl * dt * c, wrap(Phi + w * dt + aw * h), V + av * dt, w + aw * dt]
    )


def motion_jacobian(robot: np.ndarray, dt: float) -> np.ndarray:
    """d motion / d robot state (5x5) at zero acceleration."""
    _, _, Phi, V, _ = robot
    c, s = np.cos(Phi), np.sin(Phi)
    F = np.eye(ROBOT_DIM)
    F[0, 2], F[0, 3] = -V * s * dt, c * dt
    F[1, 2], F[1, 3] = V * c * dt, s * dt
    F[2, 4] = dt
    return F


def motion_noise(robot: np.ndarray, dt: float, sigma_accel: float, sigma_alpha: float,
                 sigma_lateral: float = 0.0) -> np.ndarray:
    """Process noise Q (5x5) of a piecewise-constant white acceleration of std ``sigma_accel``
    (m/s^2, along the heading), angular acceleration ``sigma_alpha`` (rad/s^2) and sideways
    velocity ``sigma_lateral`` (m/s) over ``dt`` s: ``G diag(sigma^2) G^T`` with G = d motion / d noise."""
    Phi = robot[2]
    c, s = np.cos(Phi), np.sin(Phi)
    h = 0.5 * dt * dt
    G = np.array([[h * c, 0.0, -dt * s], [h * s, 0.0, dt * c], [0.0, h, 0.0], [dt, 0.0, 0.0], [0.0, dt, 0.0]])
    return G @ np.diag([sigma_accel**2, sigma_alpha**2, sigma_lateral**2]) @ G.T


# --- motion from odometry increments (comparison mode) ---------------------------------------------
def odometry_delta(prev: tuple[float, float, float], cur: tuple[float, float, float]) -> np.ndarray:
    """Increment (dx, dy, dphi) of ``cur`` in the frame of ``prev`` (m, m, rad)."""
    dx, dy = cur[0] - prev[0], cur[1] - prev[1]
    c, s = np.cos(prev[2]), np.sin(prev[2])
    return np.array([c * dx + s * dy, -s * dx + c * dy, wrap(cur[2] - prev[2])])


def odometry_motion(robot: np.ndarray, delta: np.ndarray, dt: float) -> np.ndarray:
    """Robot state after compounding the odometry increment; V and w set to the increment's rates."""
    X, Y, Phi = robot[:3]
    c, s = np.cos(Phi), np.sin(Phi)
    dx, dy, dphi = delta
    rate = 1.0 / dt if dt > 0 else 0.0
    return np.array([X + c * dx - s * dy, Y + s * dx + c * dy, wrap(Phi + dphi), np.hypot(dx, dy) * rate, dphi * rate])


def odometry_jacobians(robot: np.ndarray, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F 5x5 wrt the robot state, J 5x3 wrt the increment) of :func:`odometry_motion`
    (V and w are overwritten by the increment, so their rows of F are zero)."""
    Phi = robot[2]
    c, s = np.cos(Phi), np.sin(Phi)
    dx, dy, _ = delta
    F = np.zeros((ROBOT_DIM, ROBOT_DIM))
    F[0, 0] = F[1, 1] = F[2, 2] = 1.0
    F[0, 2] = -s * dx - c * dy
    F[1, 2] = c * dx - s * dy
    J = np.zeros((ROBOT_DIM, 3))
    J[0, 0], J[0, 1], J[1, 0], J[1, 1], J[2, 2] = c, -s, s, c, 1.0
    return F, J


# --- line landmarks (NOTES.md: dot-product form, sign flip for negative distances) ---------------
def observe_line(pose: np.ndarray, landmark: np.ndarray) -> np.ndarray:
    """Expected observation (rho m >= 0, alpha rad) of world line (R, theta) from pose (X, Y, Phi)."""
    X, Y, Phi = pose[:3]
    R, theta = landmark
    rho = R - (X * np.cos(theta) + Y * np.sin(theta))
    alpha = theta - Phi
    if rho < 0:
        rho, alpha = -rho, alpha + np.pi
    return np.array([rho, wrap(alpha)])


def observe_line_jacobians(pose: np.ndarray, landmark: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H_pose 2x3 wrt X, Y, Phi; H_landmark 2x2 wrt R, theta) of :func:`observe_line`."""
    X, Y, _ = pose[:3]
    R, theta = landmark
    c, s = np.cos(theta), np.sin(theta)
    sign = 1.0 if R - (X * c + Y * s) >= 0 else -1.0
    Hp = np.array([[-sign * c, -sign * s, 0.0], [0.0, 0.0, -1.0]])
    Hl = np.array([[sign, sign * (X * s - Y * c)], [0.0, 1.0]])
    return Hp, Hl


def init_line(pose: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World line (R >= 0, theta) from observation z = (rho, alpha) at pose; with Jacobians
    (G_pose 2x3, G_z 2x2)."""
    X, Y, Phi = pose[:3]
    rho, alpha = z
    theta = alpha + Phi
    c, s = np.cos(theta), np.sin(theta)
    R = rho + X * c + Y * s
    dR_dtheta = -X * s + Y * c
    Gp = np.array([[c, s, dR_dtheta], [0.0, 0.0, 1.0]])
    Gz = np.array([[1.0, dR_dtheta], [0.0, 1.0]])
    if R < 0:
        R, theta = -R, theta + np.pi
        Gp[0] *= -1.0
        Gz[0] *= -1.0
    return np.array([R, wrap(theta)]), Gp, Gz


# --- corner landmarks ----------------------------------------------------------------------------
def observe_corner(pose: np.ndarray, landmark: np.ndarray) -> np.ndarray:
    """Expected (x, y) of world point ``landmark`` in the sensor frame at pose (X, Y, Phi)."""
    X, Y, Phi = pose[:3]
    c, s = np.cos(Phi), np.sin(Phi)
    dx, dy = landmark[0] - X, landmark[1] - Y
    return np.array([c * dx + s * dy, -s * dx + c * dy])


def observe_corner_jacobians(pose: np.ndarray, landmark: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H_pose 2x3, H_landmark 2x2) of :func:`observe_corner`."""
    X, Y, Phi = pose[:3]
    c, s = np.cos(Phi), np.sin(Phi)
    dx, dy = landmark[0] - X, landmark[1] - Y
    Hl = np.array([[c, s], [-s, c]])
    Hp = np.array([[-c, -s, -s * dx + c * dy], [s, -c, -c * dx - s * dy]])
    return Hp, Hl


def init_corner(pose: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World point from sensor-frame observation z = (x, y) at pose; with (G_pose 2x3, G_z 2x2)."""
    X, Y, Phi = pose[:3]
    c, s = np.cos(Phi), np.sin(Phi)
    zx, zy = z
    p = np.array([X + c * zx - s * zy, Y + s * zx + c * zy])
    Gp = np.array([[1.0, 0.0, -s * zx - c * zy], [0.0, 1.0, c * zx - s * zy]])
    Gz = np.array([[c, -s], [s, c]])
    return p, Gp, Gz
