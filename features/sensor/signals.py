"""Per-beam signals of the paper, vectorised over a whole scan: AD_ik (eq. 4), the slope estimate
theta_i (eq. 6-7 as corrected in NOTES.md), psi_i = theta_i - theta_{i+k}, and their noise std.

Beam i has bearing b_i = angle_min + i*D. Inverse ranges u_i = 1/d_i of a straight line are a
sinusoid in i, which is why every test here works on u. Noise propagation is first order in the
range noise ``sigma_r`` (m): u_j = 1/(d_j + e_j) ~ u_j - u_j**2 e_j.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from lms200 import Scan

TWO_PI = 2.0 * np.pi


class WindowConstants(NamedTuple):
    ones: np.ndarray  # (2k+1,) kernel of the AD window sum (eq. 4)
    signed: np.ndarray  # (2k+1,) kernel of the slope sum (eq. 6): -1 before i, +1 from i on
    ad_line: float  # 1 + 2 sum_{j=1..k} cos(jD): AD on any straight line (eq. 4)
    two_sin_sum: float  # 2 sum_{m=1..k} sin(mD): the slope denominator (NOTES, eq. 7)


@lru_cache(maxsize=64)
def window_constants(k: int, increment: float) -> WindowConstants:
    """The constants of the AD and slope windows for half-width k beams and step D (rad)."""
    j = np.arange(1, k + 1)
    ones = np.ones(2 * k + 1)
    signed = np.concatenate((-np.ones(k), np.ones(k + 1)))
    for a in (ones, signed):
        a.setflags(write=False)
    return WindowConstants(
        ones,
        signed,
        float(1.0 + 2.0 * np.cos(j * increment).sum()),
        float(2.0 * np.sin(j * increment).sum()),
    )


def wrap(angle: np.ndarray | float) -> np.ndarray | float:
    """Angles wrapped to (-pi, pi] (rad)."""
    return np.pi - np.mod(np.pi - angle, TWO_PI)


class BeamSignals(NamedTuple):
    """Per-beam arrays (length n, nan where a window is incomplete or holds an invalid beam)."""

    valid: np.ndarray  # bool: finite range inside [max(range_min, min_range), range_max]
    u: np.ndarray  # inverse range 1/d (1/m), nan where not valid
    AD: np.ndarray  # eq. 4 over the window i-k..i+k
    AD_sigma: np.ndarray  # std of AD from range noise
    ad: np.ndarray  # eq. 6 over the window
    theta: np.ndarray  # slope estimate: normal angle of the local line (rad, wrapped)
    theta_sigma: np.ndarray  # its std from range noise (rad)
    psi: np.ndarray  # theta_i - theta_{i+k}, wrapped (rad)
    psi_sigma: np.ndarray  # its std (rad)
    ad_line: float  # AD on a straight line


def compute(
    ranges: np.ndarray,
    bearings: np.ndarray,
    increment: float,
    k: int,
    sigma_r: float,
    range_lo: float,
    range_hi: float,
) -> BeamSignals:
    """All per-beam signals of one scan; never raises on special values (they become nan)."""
    n = ranges.size
    const = window_constants(k, increment)
    with np.errstate(all="ignore"):
        valid = (ranges >= range_lo) & (ranges <= range_hi)
        u = np.where(valid, 1.0 / ranges, np.nan)
        nan = np.full(n, np.nan)
        AD, AD_var, ad, ad_var = nan, nan, nan, nan
        if n >= 2 * k + 1:
            # window sums; a nan inside a window makes that window nan (np.correlate is direct)
            s1 = np.correlate(u, const.ones, "valid")
            s4 = np.correlate(u * u * u * u, const.ones, "valid")
            sd = np.correlate(u, const.signed, "valid")
            uc = u[k : n - k]
            u2 = uc * uc
            other = (s4 - u2 * u2) / u2  # sum_{j != i} (d AD / d e_j)^2, same for ad
            AD = nan.copy()
            ad = nan.copy()
            AD_var = nan.copy()
            ad_var = nan.copy()
            AD[k : n - k] = s1 / uc  # eq. 4
            ad[k : n - k] = sd / uc  # eq. 6
            AD_var[k : n - k] = other + (AD[k : n - k] - 1.0) ** 2 * u2
            ad_var[k : n - k] = other + (ad[k : n - k] - 1.0) ** 2 * u2
        tan_psi = (ad - 1.0) / const.two_sin_sum  # psi = alpha - b_i (NOTES eq. 7)
        cos2 = 1.0 / (1.0 + tan_psi * tan_psi)
        theta = wrap(bearings + np.arctan(tan_psi))
        AD_sigma = sigma_r * np.sqrt(AD_var)
        theta_sigma = sigma_r * np.sqrt(ad_var) / const.two_sin_sum * cos2
        psi = nan.copy()
        psi_sigma = nan.copy()
        if n > k:
            psi[: n - k] = wrap(theta[: n - k] - theta[k:])
            psi_sigma[: n - k] = np.hypot(theta_sigma[: n - k], theta_sigma[k:])
    return BeamSignals(valid, u, AD, AD_sigma, ad, theta, theta_sigma, psi, psi_sigma, const.ad_line)


def signals(scan: Scan, k: int = 3, sigma_r: float = 0.005, min_range: float = 0.02) -> dict:
    """The paper's intermediate signals of ``scan`` for its figures 4-6.

    Args:
        scan: the laser scan.
        k: half-width of the window in beams (the paper's figures use k = 10).
        sigma_r: range noise std (m), for the ``*_sigma`` entries.
        min_range: ranges below this (or the scan's range_min) are invalid (m).

    Returns:
        dict of numpy arrays, one value per beam, nan where the window is incomplete or holds an
        invalid beam: ``ad`` = AD_ik (eq. 4), ``theta`` = slope estimate theta_i (rad, normal angle
        of the local line, eq. 7 corrected), ``psi`` = theta_i - theta_{i+k} (rad, wrapped),
        ``ad_slope`` = ad_ik (eq. 6), ``ad_sigma``, ``theta_sigma``, ``psi_sigma`` (noise std),
        ``bearing`` (rad), ``valid`` (bool); and the float ``ad_line`` = 1 + 2 sum cos(jD).
    """
    s = compute(
        np.asarray(scan.ranges, dtype=float),
        np.asarray(scan.angles, dtype=float),
        scan.angle_increment,
        int(k),
        float(sigma_r),
        max(scan.range_min, min_range),
        scan.range_max,
    )
    return {
        "ad": s.AD,
        "theta": s.theta,
        "psi": s.psi,
        "ad_slope": s.ad,
        "ad_sigma": s.AD_sigma,
        "theta_sigma": s.theta_sigma,
        "psi_sigma": s.psi_sigma,
        "bearing": np.asarray(scan.angles, dtype=float),
        "valid": s.valid,
        "ad_line": s.ad_line,
    }
