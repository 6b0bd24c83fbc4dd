"""Typed configuration of the paper's sensor-coordinate extractor (method "sensor")."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SensorMethodConfig:
    """Parameters of the sensor-coordinate line and corner extractor.

    Windows and counts are in beams, distances in metres, angles in radians. The noise-scaled
    thresholds (``*_tau``) are in standard deviations of the quantity they test, derived from the
    range noise ``sigma_r``.
    """

    k: int = 3  # half-width of the AD / slope window (eq. 4, 6), beams
    sigma_r: float = 0.005  # range noise std of the sensor, m (SICK mm mode: range_max <= 10 m)
    sigma_r_cm: float = 0.02  # range noise std used instead when range_max > 10 m (SICK cm mode, 1 cm codes), m
    min_range: float = 0.02  # ranges below this (or below the scan's range_min) are invalid, m
    ad_tau: float = 4.0  # |AD - (1 + 2 sum cos jD)| <= ad_tau * sigma_AD(beam) marks a line beam
    psi_split: float = 0.2  # a slope change |psi| above this splits a run (rad) ...
    psi_tau: float = 4.0  # ... when it also exceeds psi_tau * its noise std
    hough_subdiv: int = 4  # Log-Hough angle step = angle_increment / hough_subdiv
    hough_angles: int = 7  # number of normal angles searched in each run's band
    band_tau: float = 4.0  # band half-width in std of the run's mean slope estimate
    band_min: float = 0.004  # smallest band half-width, rad
    bin_tau: float = 3.0  # Log-Hough log-range bin half-width in range-noise std
    inlier_tau: float = 3.0  # |range residual| <= inlier_tau * sigma_r after the weighted fit
    max_chi2: float = 3.0  # largest mean squared normalised residual of an accepted line
    min_inlier_fraction: float = 0.7  # fraction of a run's beams the line must explain
    curvature_tau: float = 4.0  # reject a line whose residuals bend (parabola t-statistic) more
    min_points: int = 8  # fewest supporting beams of a line
    min_length: float = 0.3  # shortest line segment kept, m
    merge_gap: int = 4  # neighbouring lines at most this many beams apart may merge ...
    merge_tau: float = 3.0  # ... when their (rho, alpha) agree within merge_tau std
    bridge_invalid: int = 0  # invalid (+inf, nan) beams a merge may bridge; 0: they break segments
    corners: bool = True  # extract corners
    corner_min_turn: float = 0.35  # smallest change of line direction that makes a corner, rad
    corner_psi: float = 0.35  # psi must reach this fraction of the line-to-line turn near the corner
    corner_max_gap: int = 1  # most beams between the two lines' facing ends
    corner_max_dist: float = 0.15  # the intersection must lie this close to both facing ends, m
    acute_check: bool = True  # the paper's remedy: reject a corner when the variance of the ranges
    acute_min_var: float = 1.0  # of the beams within k of it is below acute_min_var * sigma_r**2
    backend: str = "auto"  # "numba" (compiled kernels), "numpy" (the reference), "auto": numba when importable
