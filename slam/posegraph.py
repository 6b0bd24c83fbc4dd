"""A keyframe pose graph on gtsam (iSAM2): odometry-like factors between consecutive keyframes from
the scan matcher, loop-closure factors under a robust kernel, one prior on the first keyframe.

Poses are ``(x m, y m, theta rad)`` in the world frame; covariances of a relative pose are in the
frame of its second pose (gtsam's Pose2 tangent space: x, y along the pose's axes, then theta).
"""

from __future__ import annotations

import gtsam
import numpy as np


def _pose2(p: np.ndarray) -> gtsam.Pose2:
    return gtsam.Pose2(float(p[0]), float(p[1]), float(p[2]))


def _array(p: gtsam.Pose2) -> np.ndarray:
    return np.array([p.x(), p.y(), p.theta()])


def robust_noise(noise: np.ndarray, kernel: str, width: float) -> gtsam.noiseModel.Base:
    """Gaussian noise under a Cauchy or Huber kernel of ``width`` (whitened units): ``noise`` is a
    (3, 3) covariance, or (3,) sigmas (m, m, rad) of a diagonal one."""
    noise = np.asarray(noise, float)
    base: gtsam.noiseModel.Base
    if noise.ndim == 1:
        base = gtsam.noiseModel.Diagonal.Sigmas(noise)
    else:
        base = gtsam.noiseModel.Gaussian.Covariance(0.5 * (noise + noise.T) + 1e-12 * np.eye(3))
    est = (gtsam.noiseModel.mEstimator.Cauchy if kernel == "cauchy" else gtsam.noiseModel.mEstimator.Huber).Create(width)
    return gtsam.noiseModel.Robust.Create(est, base)


class PoseGraph:
    """Keyframe poses keyed 0, 1, 2... in insertion order."""

    def __init__(self, first: np.ndarray, prior_sigma: float = 1e-4) -> None:
        params = gtsam.ISAM2Params()
        self.isam = gtsam.ISAM2(params)
        graph = gtsam.NonlinearFactorGraph()
        values = gtsam.Values()
        graph.add(gtsam.PriorFactorPose2(0, _pose2(first), gtsam.noiseModel.Isotropic.Sigma(3, prior_sigma)))
        values.insert(0, _pose2(first))
        self.isam.update(graph, values)
        self.size = 1
        self.loops: list[tuple[int, int]] = []

    def add(self, relative: np.ndarray, covariance: np.ndarray, initial: np.ndarray) -> int:
        """Append a keyframe ``relative`` to the newest one (covariance 3x3, second pose's frame),
        starting at ``initial`` (world); returns its key."""
        key = self.size
        graph = gtsam.NonlinearFactorGraph()
        values = gtsam.Values()
        cov = 0.5 * (covariance + covariance.T) + 1e-12 * np.eye(3)
        graph.add(gtsam.BetweenFactorPose2(key - 1, key, _pose2(relative), gtsam.noiseModel.Gaussian.Covariance(cov)))
        values.insert(key, _pose2(initial))
        self.isam.update(graph, values)
        self.size += 1
        return key

    def close(self, i: int, j: int, relative: np.ndarray, noise: gtsam.noiseModel.Base, iterations: int = 3) -> None:
        """Add a loop closure: pose j ``relative`` to pose i; re-optimise."""
        graph = gtsam.NonlinearFactorGraph()
        graph.add(gtsam.BetweenFactorPose2(i, j, _pose2(relative), noise))
        self.isam.update(graph, gtsam.Values())
        for _ in range(iterations - 1):
            self.isam.update()
        self.loops.append((i, j))

    def poses(self) -> np.ndarray:
        """(n, 3) current estimate of every keyframe pose."""
        est = self.isam.calculateEstimate()
        return np.array([_array(est.atPose2(k)) for k in range(self.size)]).reshape(-1, 3)

    def pose(self, key: int) -> np.ndarray:
        return _array(self.isam.calculateEstimate().atPose2(key))

    def relative_covariance(self, old: int, new: int) -> np.ndarray:
        """Covariance (3, 3) of pose ``new`` relative to pose ``old`` (the error of
        ``old^-1 * new``, in the frame of ``new``) from their joint marginal: what a closure between
        them may correct, the correlation of the two kept."""
        joint = self.isam.jointMarginalCovariance([old, new])
        s_oo, s_on, s_nn = (np.asarray(joint.at(a, b)) for a, b in ((old, old), (old, new), (new, new)))
        rel = self.isam.calculateEstimatePose2(new).between(self.isam.calculateEstimatePose2(old))  # old in new's frame
        B = np.asarray(rel.AdjointMap())  # old's tangent -> new's
        cov = s_nn - B @ s_on - s_on.T @ B.T + B @ s_oo @ B.T
        return 0.5 * (cov + cov.T)

    def covariance(self, key: int) -> np.ndarray:
        """Marginal covariance (3x3) of a keyframe pose, in its own frame."""
        return np.asarray(self.isam.marginalCovariance(key))
