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
    """Per-beam arrays (length n, nan where a window is incomplete or holds an invalid beam).
    Variances are per unit range noise: multiply by sigma_r**2 for m-based units."""

    valid: np.ndarray  # bool: finite range inside [max(range_min, min_range), range_max]
    u: np.ndarray  # inverse range 1/d (1/m), nan where not valid
    AD: np.ndarray  # eq. 4 over the window i-k..i+k
    AD_var: np.ndarray  # variance of AD per sigma_r**2 (1/m^2)
    ad: np.ndarray  # eq. 6 over the window
    theta: np.ndarray  # slope estimate: normal angle of the local line (rad, b_i + arctan, unwrapped)
    theta_var: np.ndarray  # its variance (rad^2)
    psi: np.ndarray  # theta_i - theta_{i+k}, wrapped (rad); nan for the last k beams
    psi_var: np.ndarray  # its variance (rad^2)
    ad_line: float  # AD on a straight line


@lru_cache(maxsize=64)
def _nan_pad(k: int) -> np.ndarray:
    pad = np.full(k, np.nan)
    pad.setflags(write=False)
    return pad


def compute(
    ranges: np.ndarray,
    bearings: np.ndarray,
    increment: float,
    k: int,
    range_lo: float,
    range_hi: float,
    sigma_r: float = 0.005,
) -> BeamSignals:
    """All per-beam signals of one scan in a handful of whole-scan operations.

    Special values become nan, never exceptions; call under ``np.errstate(all="ignore")``.
    Noise propagation: d AD / d e_j = -u_j^2 / u_i (j != i) and (AD - 1) u_i (j = i), the same
    for ad, so var(AD) / sigma_r^2 = (sum_j u_j^4 - u_i^4) / u_i^2 + (AD - 1)^2 u_i^2. The std of
    theta = b + arctan(T) is taken as the half-difference of arctan over T +- std(T), which stays
    right at grazing incidence, where the slope of arctan changes within the noise of T.
    """
    n = ranges.size
    const = window_constants(k, increment)
    valid = (ranges >= range_lo) & (ranges <= range_hi)
    u = np.where(valid, 1.0 / ranges, np.nan)
    if n >= 2 * k + 1:
        pad = _nan_pad(k)
        up = np.concatenate((pad, u, pad))  # windows at the ends hold a nan: they come out nan
        up2 = up * up
        s1 = np.correlate(up, const.ones, "valid")  # nan wherever the window holds a nan
        sd = np.correlate(up, const.signed, "valid")
        s4 = np.correlate(up2 * up2, const.ones, "valid")
    else:
        s1 = sd = s4 = np.full(n, np.nan)
        up2 = np.full(n + 2 * k, np.nan)
    u2 = up2[k : k + n]
    AD = s1 / u  # eq. 4
    ad = sd / u  # eq. 6
    other = s4 / u2 - u2  # sum over j != i of u_j^4 / u_i^2
    ad1 = ad - 1.0
    AD1 = AD - 1.0
    AD_var = other + AD1 * AD1 * u2
    tan_psi = ad1 / const.two_sin_sum  # psi = alpha - b_i (NOTES eq. 7)
    theta = bearings + np.arctan(tan_psi)
    tan_sd = np.sqrt(other + ad1 * ad1 * u2) * (sigma_r / const.two_sin_sum)
    theta_sd = 0.5 * (np.arctan(tan_psi + tan_sd) - np.arctan(tan_psi - tan_sd))
    theta_var = theta_sd * theta_sd
    psi = np.full(n, np.nan)
    psi_var = np.full(n, np.nan)
    if n > k:
        dpsi = theta[: n - k] - theta[k:]
        psi[: n - k] = dpsi - TWO_PI * np.rint(dpsi / TWO_PI)  # wrapped to [-pi, pi]
        psi_var[: n - k] = theta_var[: n - k] + theta_var[k:]
    return BeamSignals(valid, u, AD, AD_var, ad, theta, theta_var, psi, psi_var, const.ad_line)


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
    with np.errstate(all="ignore"):
        s = compute(
            np.asarray(scan.ranges, dtype=float),
            np.asarray(scan.angles, dtype=float),
            scan.angle_increment,
            int(k),
            max(scan.range_min, min_range),
            scan.range_max,
            float(sigma_r),
        )
        theta = wrap(s.theta)
        ad_sigma = sigma_r * np.sqrt(s.AD_var)
        theta_sigma, psi_sigma = np.sqrt(s.theta_var), np.sqrt(s.psi_var)
    return {
        "ad": s.AD,
        "theta": theta,
        "psi": s.psi,
        "ad_slope": s.ad,
        "ad_sigma": ad_sigma,
        "theta_sigma": theta_sigma,
        "psi_sigma": psi_sigma,
        "bearing": np.asarray(scan.angles, dtype=float),
        "valid": s.valid,
        "ad_line": s.ad_line,
    }
