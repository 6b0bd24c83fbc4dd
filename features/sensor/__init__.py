"""The paper's extractor in sensor coordinates, registered as method "sensor".

Pipeline (all in range-bearing space, ``engine``): per-beam AD_ik and slope theta_i -> runs of
beams on straight lines -> Log-Hough search in a narrow band around each run's slope -> weighted
least-squares refinement with covariance from the range noise -> merged segments -> corners where
two segments meet. ``signals`` gives the per-beam signals of the paper's figures 4-6.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from lms200 import Scan

from ..registry import register
from ..batch import common_geometry, split_rows, stacked_ranges
from ..errors import not_a_scan
from ..types import Corners, FeatureSet, Lines
from ..jit import FixedTypeCall
from ..noise_estimate import AUTO, AUTO_FALLBACK
from . import engine
from .config import SensorMethodConfig
from .grid import bearings_of, grid_constants, window_sums

__all__ = ["SensorMethodConfig", "extract_sensor", "extract_sensor_many", "signals"]

METHOD = "sensor"
_extract_scan = FixedTypeCall(engine.extract_scan)  # a Scan's types: read-only float64 arrays, floats, a bool
_extract_batch = FixedTypeCall(engine.extract_batch)  # stacked_ranges: a read-only C-contiguous float64 (S, n) array


def extract_sensor(scan: Scan, cfg: SensorMethodConfig) -> FeatureSet:
    """Lines and corners of ``scan`` in its sensor frame (the registered run function); a noise of
    "auto" is estimated from the scan in the same compiled call."""
    p = cfg.params
    grid = grid_constants(p.k, scan.angle_increment, p.hough_subdiv)
    bearings = bearings_of(scan.angle_min, scan.angle_increment, len(scan))
    range_lo = float(max(scan.range_min, cfg.min_range))
    sigma = cfg.sigma_for(scan.range_max)
    auto = sigma == AUTO
    lv, lb, cv, cb = _extract_scan(scan.ranges, bearings, scan.angle_min, scan.angle_increment, range_lo, scan.range_max,
                                   0.0 if auto else float(sigma), auto, float(scan.range_min), AUTO_FALLBACK, grid, p)
    return FeatureSet.of(Lines(lv, lb), Corners(cv, cb), METHOD)


def extract_sensor_many(scans: Sequence[Scan], cfg: SensorMethodConfig) -> list[FeatureSet]:
    """``extract_sensor`` of every scan (one geometry, checked), in one kernel call: the same
    lines and corners, scan by scan; a noise of "auto" is estimated from each scan itself, as a
    single call does (to use one noise for a whole log, as ``lmsbench compare`` does, pass it:
    ``sigma_r_cm=features.noise_estimate.neighbour_sigma(scans)``)."""
    if not scans:
        return []
    scan = common_geometry(scans)
    p = cfg.params
    grid = grid_constants(p.k, scan.angle_increment, p.hough_subdiv)
    ranges = stacked_ranges(scans)
    sigma = cfg.sigma_for(scan.range_max)
    rows = _extract_batch(
        ranges, bearings_of(scan.angle_min, scan.angle_increment, len(scan)), scan.angle_min,
        scan.angle_increment, float(max(scan.range_min, cfg.min_range)), scan.range_max,
        0.0 if sigma == AUTO else float(sigma), sigma == AUTO, float(scan.range_min), AUTO_FALLBACK, grid, p,
    )
    return split_rows(*rows, METHOD)


def signals(scan: Scan, k: int = 3, sigma_r: float = 0.005, min_range: float = 0.02) -> dict:
    """The paper's intermediate signals of ``scan`` for its figures 4-6 (computed by the extractor).

    Args:
        scan: the laser scan.
        k: half-width of the window in beams (the paper's figures use k = 10).
        sigma_r: range noise std (m), for the ``*_sigma`` entries.
        min_range: ranges below this (or the scan's range_min) are invalid (m).

    Returns:
        dict of numpy arrays, one value per beam, nan where the window is incomplete or holds an
        invalid beam: ``ad`` = AD_ik (eq. 4), ``theta`` = slope estimate theta_i (rad, normal angle
        of the local line, eq. 7 corrected, wrapped to (-pi, pi]), ``psi`` = theta_i - theta_{i+k}
        (rad, wrapped), ``ad_slope`` = ad_ik (eq. 6), ``ad_sigma``, ``theta_sigma``, ``psi_sigma``
        (noise std), ``bearing`` (rad), ``valid`` (bool); and the float ``ad_line`` = 1 + 2 sum cos(jD).
    """
    if not isinstance(scan, Scan):  # was an AttributeError ('Record' object has no attribute 'angle_increment')
        raise not_a_scan(scan, "signals")
    cfg = SensorMethodConfig(k=k, sigma_r=sigma_r, min_range=min_range)  # checks the values
    ad_line, two_sin_sum = window_sums(cfg.params.k, scan.angle_increment)
    valid, _, AD, AD_var, ad, theta, theta_var, psi, psi_var = engine.beam_signals(
        scan.ranges, scan.angles, cfg.params.k, max(scan.range_min, cfg.min_range), scan.range_max,
        float(sigma_r), two_sin_sum,
    )
    from lms200.angles import wrap  # noqa: PLC0415

    with np.errstate(invalid="ignore"):  # a variance rounded below 0 on a degenerate window reads nan, as before
        ad_sigma, theta_sigma, psi_sigma = sigma_r * np.sqrt(AD_var), np.sqrt(theta_var), np.sqrt(psi_var)
    return {
        "ad": AD,
        "theta": wrap(theta),
        "psi": psi,
        "ad_slope": ad,
        "ad_sigma": ad_sigma,
        "theta_sigma": theta_sigma,
        "psi_sigma": psi_sigma,
        "bearing": np.asarray(scan.angles, dtype=float),
        "valid": valid,
        "ad_line": ad_line,
    }


register(METHOD, SensorMethodConfig, extract_sensor, backend="numba", run_many=extract_sensor_many, thread_safe=True)
