"""The EKF on ``filterpy.kalman.ExtendedKalmanFilter`` with a state that grows and shrinks.

State ``x = [X, Y, Phi, V, w, l1a, l1b, l2a, l2b, ...]`` (column vector, filterpy's shape (n, 1)):
the robot (see :mod:`slam.models`) then two numbers per landmark.

filterpy fixes the size at construction; growing the state here resizes every internal that
depends on it (``x``, ``P``, ``F``, ``Q``, ``dim_x``, the private identity ``_I``, ``K``, the
prior / posterior copies), so filterpy's own ``predict()`` and ``update()`` stay valid on the
grown filter. The overrides below compute the same numbers faster by using the structure of the
problem (F is the identity on landmarks; P - K S K^T instead of the O(n^3) Joseph form); a test
checks them against filterpy's methods.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from . import models
from .models import ROBOT_DIM, wrap


class SlamEKF(ExtendedKalmanFilter):
    """EKF-SLAM filter. ``x`` is (n, 1), ``P`` (n, n); landmarks are addressed by the index of their
    first state entry (``ROBOT_DIM + 2 k``)."""

    F: np.ndarray  # filterpy's state transition and process noise, resized with the state
    Q: np.ndarray

    def __init__(self, pose: tuple[float, float, float] = (0.0, 0.0, 0.0), pose_sigma: float = 0.0,
                 velocity_sigma: tuple[float, float] = (0.5, 0.5)) -> None:
        super().__init__(dim_x=ROBOT_DIM, dim_z=2)
        self.velocity_sigma = (float(velocity_sigma[0]), float(velocity_sigma[1]))
        self.x = np.array([[pose[0]], [pose[1]], [pose[2]], [0.0], [0.0]])
        self.P = np.diag([pose_sigma**2, pose_sigma**2, pose_sigma**2, velocity_sigma[0] ** 2, velocity_sigma[1] ** 2])
        self.Q = np.zeros((ROBOT_DIM, ROBOT_DIM))
        self._motion: tuple | None = None
        self._sync_internals()

    # -- size management ----------------------------------------------------------------------
    @property
    def n_landmarks(self) -> int:
        return (self.dim_x - ROBOT_DIM) // 2

    def _sync_internals(self) -> None:
        """Make every size-dependent filterpy internal match ``x``."""
        n = self.x.shape[0]
        old = self.F.shape[0]
        F = np.eye(n)
        Q = np.zeros((n, n))
        k = min(old, n, ROBOT_DIM)
        F[:k, :k] = self.F[:k, :k]
        Q[:k, :k] = self.Q[:k, :k]
        self.F = F
        self.Q = Q
        self.dim_x = n
        self._I = np.eye(n)
        self.K = np.zeros((n, self.dim_z))
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()

    def add_landmark(self, value: np.ndarray, G_pose: np.ndarray, G_z: np.ndarray, R_z: np.ndarray) -> int:
        """Append a landmark initialised from an observation: value (2,), Jacobians of the inverse
        observation wrt the pose (2x3) and the observation (2x2), observation covariance (2x2).
        Returns the landmark's state index."""
        n = self.dim_x
        P = self.P
        P_lx = G_pose @ P[:3, :]  # (2, n) cross covariance with everything
        P_ll = G_pose @ P[:3, :3] @ G_pose.T + G_z @ R_z @ G_z.T
        newP = np.empty((n + 2, n + 2))
        newP[:n, :n] = P
        newP[n:, :n] = P_lx
        newP[:n, n:] = P_lx.T
        newP[n:, n:] = 0.5 * (P_ll + P_ll.T)
        self.P = newP
        self.x = np.vstack((self.x, np.asarray(value, dtype=float).reshape(2, 1)))
        self._sync_internals()
        return n

    def remove_landmarks(self, indices: list[int]) -> None:
        """Drop the landmarks whose state indices are given (marginalisation: delete rows/cols)."""
        if not indices:
            return
        drop = np.zeros(self.dim_x, bool)
        for i in indices:
            if i < ROBOT_DIM or i + 1 >= self.dim_x:
                raise IndexError(f"landmark index {i} outside the state of size {self.dim_x}")
            drop[i : i + 2] = True
        keep = ~drop
        self.x = self.x[keep]
        self.P = self.P[np.ix_(keep, keep)]
        self._sync_internals()

    # -- prediction ----------------------------------------------------------------------------
    def restart_velocity(self) -> None:
        """The velocity (V, w) set to zero with the uncertainty it started with, uncorrelated with
        the rest of the state (pose and landmarks kept): the motion restarts as at the first scan."""
        self.x[3:ROBOT_DIM, 0] = 0.0
        self.P[3:ROBOT_DIM, :] = 0.0
        self.P[:, 3:ROBOT_DIM] = 0.0
        self.P[3, 3], self.P[4, 4] = self.velocity_sigma[0] ** 2, self.velocity_sigma[1] ** 2
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()

    def set_motion(self, dt: float, sigma_accel: float, sigma_alpha: float, sigma_lateral: float = 0.0) -> None:
        """Constant-velocity step of ``dt`` s: sets the robot blocks of F (Jacobian) and Q."""
        r = self.x[:ROBOT_DIM, 0]
        self.F[:ROBOT_DIM, :ROBOT_DIM] = models.motion_jacobian(r, dt)
        self.Q[:ROBOT_DIM, :ROBOT_DIM] = models.motion_noise(r, dt, sigma_accel, sigma_alpha, sigma_lateral)
        self._motion = ("cv", dt)

    def set_odometry(self, delta: np.ndarray, dt: float, cov_delta: np.ndarray) -> None:
        """Odometry step: compound the increment (dx, dy, dphi) with covariance ``cov_delta``."""
        r = self.x[:ROBOT_DIM, 0]
        F, J = models.odometry_jacobians(r, delta)
        self.F[:ROBOT_DIM, :ROBOT_DIM] = F
        Q = J @ cov_delta @ J.T
        rate = 1.0 / dt if dt > 0 else 0.0
        Q[3, 3] += (0.5) ** 2 + cov_delta[0, 0] * rate**2  # V, w: re-set from the increment each step
        Q[4, 4] += (0.5) ** 2 + cov_delta[2, 2] * rate**2
        self.Q[:ROBOT_DIM, :ROBOT_DIM] = Q
        self._motion = ("odom", np.asarray(delta, float), dt)

    def predict_x(self, u: object = 0) -> None:
        """Nonlinear robot motion (filterpy's default is the linear ``F @ x``)."""
        if self._motion is None:
            raise RuntimeError("call set_motion() or set_odometry() before predict()")
        r = self.x[:ROBOT_DIM, 0]
        if self._motion[0] == "cv":
            new = models.motion(r, self._motion[1])
        else:
            new = models.odometry_motion(r, self._motion[1], self._motion[2])
        self.x[:ROBOT_DIM, 0] = new

    def predict(self, u: object = 0) -> None:
        """filterpy's predict (x = f(x), P = F P F^T + Q) using that F is the identity on landmarks."""
        Fr = self.F[:ROBOT_DIM, :ROBOT_DIM].copy()
        self.predict_x(u)
        P = self.P
        P[:ROBOT_DIM, :] = Fr @ P[:ROBOT_DIM, :]
        P[:, :ROBOT_DIM] = P[:, :ROBOT_DIM] @ Fr.T
        P[:ROBOT_DIM, :ROBOT_DIM] += self.Q[:ROBOT_DIM, :ROBOT_DIM]
        self.x_prior = self.x.copy()
        self.P_prior = P.copy()

    # -- update --------------------------------------------------------------------------------
    def update(self, z: np.ndarray, HJacobian: Callable, Hx: Callable, R: np.ndarray | None = None,
               args: tuple = (), hx_args: tuple = (), residual: Callable = np.subtract) -> None:
        """filterpy's update with the same arguments, in O(n^2 m): P -= K S K^T (symmetrised)."""
        if z is None:
            return
        if not isinstance(args, tuple):
            args = (args,)
        if not isinstance(hx_args, tuple):
            hx_args = (hx_args,)
        z = np.asarray(z, dtype=float).reshape(-1, 1)
        if R is None:
            R = self.R
        H = HJacobian(self.x, *args)
        PHT = self.P @ H.T
        self.S = H @ PHT + R
        self.SI = np.linalg.inv(self.S)
        self.K = PHT @ self.SI
        self.y = residual(z, Hx(self.x, *hx_args))
        self.x = self.x + self.K @ self.y
        self.P = self.P - self.K @ self.S @ self.K.T
        self.P = 0.5 * (self.P + self.P.T)
        self.z = z.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self._log_likelihood = self._likelihood = self._mahalanobis = None


# --- stacked observation functions for filterpy's update(z, HJacobian, Hx) -------------------------
def stacked_h(x: np.ndarray, kinds: list[str], indices: list[int]) -> np.ndarray:
    """Expected observations (2m, 1) of the landmarks at ``indices`` (``kinds``: "line"/"corner")."""
    pose = x[:3, 0]
    out = np.empty((2 * len(indices), 1))
    for k, (kind, i) in enumerate(zip(kinds, indices)):
        lm = x[i : i + 2, 0]
        out[2 * k : 2 * k + 2, 0] = models.observe_line(pose, lm) if kind == "line" else models.observe_corner(pose, lm)
    return out


def stacked_H(x: np.ndarray, kinds: list[str], indices: list[int]) -> np.ndarray:
    """Jacobian (2m, n) of :func:`stacked_h`."""
    pose = x[:3, 0]
    H = np.zeros((2 * len(indices), x.shape[0]))
    for k, (kind, i) in enumerate(zip(kinds, indices)):
        lm = x[i : i + 2, 0]
        Hp, Hl = (models.observe_line_jacobians if kind == "line" else models.observe_corner_jacobians)(pose, lm)
        H[2 * k : 2 * k + 2, :3] = Hp
        H[2 * k : 2 * k + 2, i : i + 2] = Hl
    return H


def stacked_residual(kinds: list[str]) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """Residual z - h(x) with the angle of every line observation wrapped to (-pi, pi]."""
    angle_rows = np.array([2 * k + 1 for k, kind in enumerate(kinds) if kind == "line"], dtype=int)

    def residual(z: np.ndarray, hx: np.ndarray) -> np.ndarray:
        y = np.asarray(z, float).reshape(-1, 1) - np.asarray(hx, float).reshape(-1, 1)
        if angle_rows.size:
            y[angle_rows, 0] = wrap(y[angle_rows, 0])
        return y

    return residual
