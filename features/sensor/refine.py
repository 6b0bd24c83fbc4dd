"""Weighted least-squares refinement of (rho, alpha) for many lines at once, with the covariance
implied by the range noise (the paper's future work: a quality measure of the parameters).

Model: beam j (range d_j, bearing b_j) on the line x cos(alpha) + y sin(alpha) = rho has
d_j cos(b_j - alpha) - rho = 0. Range noise e_j (std sigma_r) moves this residual by
e_j cos(b_j - alpha), so the weight of beam j is 1 / (sigma_r cos(b_j - alpha))^2: the fit
minimises the squared range residuals, the maximum-likelihood estimate under range noise.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

MIN_COS = 0.05  # beams within ~87 deg of grazing incidence get no weight


class LineFit(NamedTuple):
    rho: np.ndarray  # (R,) m
    alpha: np.ndarray  # (R,) rad, not wrapped
    cov: np.ndarray  # (R, 2, 2) covariance of (rho, alpha): m^2, m rad, rad^2
    z: np.ndarray  # (N,) range residual / sigma_r of every stacked beam (inf where unseen)


def gauss_newton(
    d: np.ndarray,
    b: np.ndarray,
    run_id: np.ndarray,
    starts: np.ndarray,
    weight_mask: np.ndarray,
    rho: np.ndarray,
    alpha: np.ndarray,
    sigma_r: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One Gauss-Newton step of every run's (rho, alpha) on its masked beams.

    Returns the new rho, alpha and the (R, 2, 2) covariance at the new estimate's linearisation.
    """
    phi = b - alpha[run_id]
    c = np.cos(phi)
    ok = weight_mask & (c > MIN_COS)
    w = np.where(ok, 1.0 / (c * c), 0.0)
    g = d * np.sin(phi)  # d residual / d alpha
    r = d * c - rho[run_id]  # residual along the normal (m); d residual / d rho = -1
    wg = w * g
    sums = np.add.reduceat(np.stack((w, wg, wg * g, w * r, wg * r)), starts, axis=1)
    sw, swg, swgg, swr, swgr = sums
    # normal equations H delta = -J^T W r with J = [-1, g]
    det = sw * swgg - swg * swg
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_det = 1.0 / det
        d_rho = (swgg * swr - swg * swgr) * inv_det
        d_alpha = (swg * swr - sw * swgr) * inv_det
        cov = np.empty((starts.size, 2, 2))
        var = sigma_r * sigma_r * inv_det
        cov[:, 0, 0] = swgg * var
        cov[:, 0, 1] = swg * var
        cov[:, 1, 0] = swg * var
        cov[:, 1, 1] = sw * var
    return rho + d_rho, alpha + d_alpha, cov


def range_residuals(
    d: np.ndarray, b: np.ndarray, run_id: np.ndarray, rho: np.ndarray, alpha: np.ndarray, sigma_r: float
) -> np.ndarray:
    """(d_j - rho / cos(b_j - alpha)) / sigma_r for every stacked beam (inf where the beam
    cannot hit the line)."""
    c = np.cos(b - alpha[run_id])
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (d * c - rho[run_id]) / (sigma_r * c)
    z[~(c > MIN_COS)] = np.inf
    return z
