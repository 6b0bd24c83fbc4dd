"""The numba backend of the sensor method: the compiled kernels of ``kernels`` behind the same
``(scan, config) -> FeatureSet`` call as the numpy reference. Imported (and numba with it) only
when the backend is first used (``features.backends`` tells whether numba is there)."""

from __future__ import annotations

import numpy as np

from lms200 import Scan

from ..types import Corner, FeatureSet, new_line
from . import kernels as kn
from .config import SensorMethodConfig
from .hough import logcos_template
from .segments import MERGE_FLOOR_VAR
from .signals import window_constants

METHOD = "sensor"
_FLOOR = (float(MERGE_FLOOR_VAR[0]), float(MERGE_FLOOR_VAR[1]))  # merge model-error floor (m^2, rad^2)
_PARAMS: dict[tuple[int, float], tuple[SensorMethodConfig, np.ndarray, np.ndarray, np.ndarray]] = {}


def params(cfg: SensorMethodConfig, increment: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Float and int parameter vectors of the kernels and the Log-Hough template, for a config
    and beam step (rad); scalar products are formed as the numpy reference forms them."""
    key = (id(cfg), increment)
    hit = _PARAMS.get(key)
    if hit is not None and hit[0] is cfg:
        return hit[1], hit[2], hit[3]
    const = window_constants(int(cfg.k), increment)
    step = increment / cfg.hough_subdiv
    template, zero = logcos_template(step)
    s2 = cfg.sigma_r * cfg.sigma_r
    fp = np.empty(kn.N_FLOAT)
    fp[kn.F_SIGMA_R] = cfg.sigma_r
    fp[kn.F_AD_C] = cfg.ad_tau * cfg.ad_tau * s2
    fp[kn.F_PSI_SPLIT2] = cfg.psi_split * cfg.psi_split
    fp[kn.F_PSI_TAU2] = cfg.psi_tau * cfg.psi_tau
    fp[kn.F_BAND_TAU] = cfg.band_tau
    fp[kn.F_BAND_MIN] = cfg.band_min
    fp[kn.F_BIN_TAU] = cfg.bin_tau
    fp[kn.F_INLIER_TAU] = cfg.inlier_tau
    fp[kn.F_MAX_CHI2] = cfg.max_chi2
    fp[kn.F_MIN_INLIER_FRACTION] = cfg.min_inlier_fraction
    fp[kn.F_CURV2] = cfg.curvature_tau * cfg.curvature_tau
    fp[kn.F_MIN_LENGTH] = cfg.min_length
    fp[kn.F_MERGE_TAU2] = cfg.merge_tau**2
    fp[kn.F_MIN_TURN] = cfg.corner_min_turn
    fp[kn.F_CORNER_MAX_DIST] = cfg.corner_max_dist
    fp[kn.F_CORNER_PSI] = cfg.corner_psi
    fp[kn.F_ACUTE_VAR] = cfg.acute_min_var * cfg.sigma_r**2
    fp[kn.F_AD_LINE] = const.ad_line
    fp[kn.F_TWO_SIN_SUM] = const.two_sin_sum
    fp[kn.F_SUBDIV_STEP] = step
    ip = np.empty(kn.N_INT, np.int64)
    ip[kn.I_K] = int(cfg.k)
    ip[kn.I_SUBDIV] = int(cfg.hough_subdiv)
    ip[kn.I_ANGLES] = int(cfg.hough_angles)
    ip[kn.I_MIN_POINTS] = int(np.ceil(cfg.min_points))  # n_in >= min_points for an integer n_in
    ip[kn.I_MERGE_GAP] = int(np.floor(cfg.merge_gap))  # gap > merge_gap for an integer gap
    ip[kn.I_BRIDGE] = int(np.floor(cfg.bridge_invalid))
    ip[kn.I_CORNERS] = int(bool(cfg.corners))
    ip[kn.I_MAX_GAP] = int(np.floor(cfg.corner_max_gap))
    ip[kn.I_ACUTE] = int(bool(cfg.acute_check))
    ip[kn.I_ZERO] = zero
    if len(_PARAMS) > 64:
        _PARAMS.clear()
    _PARAMS[key] = (cfg, fp, ip, template)
    return fp, ip, template


def extract_numba(scan: Scan, cfg: SensorMethodConfig, range_lo: float) -> FeatureSet:
    """Lines and corners of ``scan`` (sensor frame) by the compiled kernels; ``cfg`` already has
    the scan's ``sigma_r``, ``range_lo`` = max(scan.range_min, cfg.min_range) (m)."""
    ranges = np.ascontiguousarray(scan.ranges, dtype=np.float64)
    bearings = np.ascontiguousarray(scan.angles, dtype=np.float64)
    fp, ip, template = params(cfg, scan.angle_increment)
    rho, alpha, cov, first, last, npts, p0, p1, cf, ci = kn.extract(
        ranges, bearings, float(scan.angle_min), float(scan.angle_increment), float(range_lo),
        float(scan.range_max), template, fp, ip, _FLOOR[0], _FLOOR[1],
    )
    if rho.size == 0:
        return FeatureSet([], [], METHOD)
    rho_l, alpha_l = rho.tolist(), alpha.tolist()
    first_l, last_l, n_l = first.tolist(), last.tolist(), npts.tolist()
    start = list(map(tuple, p0.tolist()))
    end = list(map(tuple, p1.tolist()))
    lines = [
        new_line(rho_l[m], alpha_l[m], start[m], end[m], first_l[m], last_l[m], cov[m], n_l[m])
        for m in range(len(rho_l))
    ]
    found = [Corner(x, y, a, index, (i, i + 1)) for (x, y, a), (index, i) in zip(cf.tolist(), ci.tolist())]
    return FeatureSet(lines, found, METHOD)
