"""Weighted least-squares refinement of (rho, alpha) for many lines at once, with the covariance
implied by the range noise (the paper's future work: a quality measure of the parameters).

Model: beam j (range d_j, bearing b_j) on the line x cos(alpha) + y sin(alpha) = rho has
r_j = d_j cos(b_j - alpha) - rho = 0. Range noise e_j (std sigma_r) moves this residual by
e_j cos(b_j - alpha), so the weight of beam j is 1 / (sigma_r cos(b_j - alpha))^2: the fit
minimises the squared range residuals, the maximum-likelihood estimate under range noise, and
(J^T W J)^-1 is the covariance of (rho, alpha). Call under ``np.errstate(all="ignore")``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

MIN_COS = 0.05  # beams within ~3 deg of grazing the line get no weight


class Step(NamedTuple):
    rho: np.ndarray  # (R,) after the step (m)
    alpha: np.ndarray  # (R,) after the step (rad, not wrapped)
    cov: np.ndarray | None  # (R, 2, 2) covariance of (rho, alpha) at the step's linearisation
    z: np.ndarray | None  # (N,) range residual / sigma_r before the step (when inlier_tau is given)
    weight: np.ndarray  # (N,) 1/cos^2 weights used (0 for beams left out)


def gauss_newton(
    d: np.ndarray,
    b: np.ndarray,
    run_id: np.ndarray,
    starts: np.ndarray,
    mask: np.ndarray | None,
    rho: np.ndarray,
    alpha: np.ndarray,
    sigma_r: float,
    inlier_tau: float | None = None,
    with_cov: bool = True,
) -> Step:
    """One Gauss-Newton step of every run's (rho, alpha) on its beams.

    Args:
        d, b: (N,) range (m) and bearing (rad) of the stacked beams; run_id: (N,) their run.
        starts: (R,) first row of each run. mask: (N,) bool beams to use, or None for all.
        rho, alpha: (R,) current estimate. sigma_r: range noise std (m).
        inlier_tau: when given, only beams with |range residual| <= inlier_tau sigma_r at the
            current estimate are used (on top of ``mask``).
        with_cov: compute the covariance (else ``cov`` is None).
    """
    phi = b - alpha[run_id]
    c = np.cos(phi)
    r = d * c - rho[run_id]  # residual along the normal (m); d r / d rho = -1
    g = d * np.sin(phi)  # d r / d alpha
    use = c > MIN_COS
    if mask is not None:
        use &= mask
    z = None
    if inlier_tau is not None:
        z = r / (sigma_r * c)
        use &= np.abs(z) <= inlier_tau
    w = use / (c * c)
    buf = np.empty((5, d.size))
    buf[0] = w
    np.multiply(w, g, out=buf[1])
    np.multiply(buf[1], g, out=buf[2])
    np.multiply(w, r, out=buf[3])
    np.multiply(buf[1], r, out=buf[4])
    sw, swg, swgg, swr, swgr = np.add.reduceat(buf, starts, axis=1)
    # normal equations H delta = -J^T W r with J = [-1, g]
    inv_det = 1.0 / (sw * swgg - swg * swg)
    rho = rho + (swgg * swr - swg * swgr) * inv_det
    alpha = alpha + (swg * swr - sw * swgr) * inv_det
    if not with_cov:
        return Step(rho, alpha, None, z, w)
    var = (sigma_r * sigma_r) * inv_det
    cov = np.empty((starts.size, 2, 2))
    cov[:, 0, 0] = swgg * var
    cov[:, 0, 1] = cov[:, 1, 0] = swg * var
    cov[:, 1, 1] = sw * var
    return Step(rho, alpha, cov, z, w)
