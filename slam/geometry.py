"""Rigid 2-D poses ``(x m, y m, theta rad)``: the one ``to_world``, composition and relative pose.

A pose maps points of its own frame into the parent (world) frame: ``w = R(theta) p + (x, y)``.
"""

from __future__ import annotations

import numpy as np

from .models import wrap


def rotation(theta: float) -> np.ndarray:
    """2x2 rotation matrix of ``theta`` rad."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def to_world(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (n, 2) of the frame of ``pose`` (x, y, theta) in the parent frame (n, 2)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    p = np.asarray(points, float).reshape(-1, 2)
    return p @ np.array([[c, s], [-s, c]]) + (pose[0], pose[1])


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose ``a * b``: pose b (given in the frame of a) in a's parent frame."""
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2])])


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose b in the frame of pose a (``a^-1 * b``)."""
    c, s = np.cos(a[2]), np.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2])])


def rotate_covariance(cov: np.ndarray, theta: float) -> np.ndarray:
    """A pose covariance (3, 3) turned by ``theta`` rad: its (x, y) block rotated, heading kept.
    From a pose's own frame (gtsam's tangent) to the world with the pose's heading; back with
    minus it."""
    A = np.eye(3)
    A[:2, :2] = rotation(theta)
    return A @ cov @ A.T


def adjoint(pose: np.ndarray) -> np.ndarray:
    """3x3 matrix that moves a covariance of a small pose change in the frame of ``pose`` into the
    parent frame (``Ad P Ad^T``)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return np.array([[c, -s, pose[1]], [s, c, -pose[0]], [0.0, 0.0, 1.0]])
