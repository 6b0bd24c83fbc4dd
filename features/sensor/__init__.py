"""The paper's extractor in sensor coordinates, registered as method "sensor".

Pipeline (all in range-bearing space): per-beam AD_ik and slope theta_i (``signals``) -> runs of
beams on straight lines -> Log-Hough search in a narrow band around each run's slope (``hough``)
-> weighted least-squares refinement with covariance from the range noise (``refine``) -> merged
segments (``segments``) -> corners where two segments meet (``corners``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from lms200 import Scan

from ..backends import BACKENDS, numba_available as _numba_available
from ..registry import register
from ..types import FeatureSet, new_line
from .config import SensorMethodConfig
from .corners import find_corners
from .lines import find_lines
from .segments import endpoints, merge_neighbours, resolve_overlaps
from .signals import compute, signals

__all__ = ["BACKENDS", "SensorMethodConfig", "extract_sensor", "resolve_backend", "signals"]

METHOD = "sensor"


_CHECKED: dict[int, SensorMethodConfig] = {}  # id -> config already checked (kept alive here)


def _check(cfg: SensorMethodConfig) -> SensorMethodConfig:
    """Raise ValueError naming the field when the configuration cannot work (once per config
    object: hashing a 30-field dataclass on every scan would cost more than the check)."""
    if _CHECKED.get(id(cfg)) is cfg:
        return cfg
    if not isinstance(cfg.k, (int, np.integer)) or cfg.k < 1:
        raise ValueError(f"k: must be an integer >= 1, got {cfg.k!r}")
    if not cfg.sigma_r > 0:
        raise ValueError(f"sigma_r: must be > 0 m, got {cfg.sigma_r!r}")
    if not cfg.sigma_r_cm > 0:
        raise ValueError(f"sigma_r_cm: must be > 0 m, got {cfg.sigma_r_cm!r}")
    if not isinstance(cfg.hough_subdiv, (int, np.integer)) or cfg.hough_subdiv < 1:
        raise ValueError(f"hough_subdiv: must be an integer >= 1, got {cfg.hough_subdiv!r}")
    if not isinstance(cfg.hough_angles, (int, np.integer)) or cfg.hough_angles < 1 or cfg.hough_angles % 2 == 0:
        raise ValueError(f"hough_angles: must be an odd integer >= 1, got {cfg.hough_angles!r}")
    if cfg.min_points < 3:
        raise ValueError(f"min_points: must be >= 3, got {cfg.min_points!r}")
    if cfg.backend not in BACKENDS:
        raise ValueError(f"backend: must be one of {', '.join(BACKENDS)}, got {cfg.backend!r}")
    if cfg.backend == "numba" and not _numba_available():
        raise ValueError("backend: 'numba' asked for but numba is not installed (pip install numba)")
    if len(_CHECKED) > 64:
        _CHECKED.clear()
    _CHECKED[id(cfg)] = cfg
    return cfg


CM_MODE_RANGE_MAX = 10.0  # m: a scan with a larger range_max comes in SICK cm codes (1 cm steps)
_CM_CONFIGS: dict[int, tuple[SensorMethodConfig, SensorMethodConfig]] = {}


def _for_scan(cfg: SensorMethodConfig, scan: Scan) -> SensorMethodConfig:
    """The config with ``sigma_r`` set for the scan's range units: ``sigma_r_cm`` for cm codes."""
    if scan.range_max <= CM_MODE_RANGE_MAX or cfg.sigma_r_cm == cfg.sigma_r:
        return cfg
    hit = _CM_CONFIGS.get(id(cfg))
    if hit is None or hit[0] is not cfg:
        if len(_CM_CONFIGS) > 64:
            _CM_CONFIGS.clear()
        hit = (cfg, dataclasses.replace(cfg, sigma_r=cfg.sigma_r_cm))
        _CM_CONFIGS[id(cfg)] = hit
    return hit[1]


def resolve_backend(backend: str) -> str:
    """The backend a config's ``backend`` field runs on: "auto" is "numba" when importable."""
    if backend == "auto":
        return "numba" if _numba_available() else "numpy"
    return backend


def extract_sensor(scan: Scan, cfg: SensorMethodConfig) -> FeatureSet:
    """Lines and corners of ``scan`` in its sensor frame (the registered run function); the
    config's ``backend`` picks the compiled kernels or the numpy reference (same results)."""
    _check(cfg)
    cfg = _for_scan(cfg, scan)
    if resolve_backend(cfg.backend) == "numba":  # IEEE arithmetic inside: no errstate needed
        return _compiled()(scan, cfg, max(scan.range_min, cfg.min_range))
    with np.errstate(all="ignore"):
        return _extract(scan, cfg)


_COMPILED: list = []


def _compiled():  # noqa: ANN202
    """``compiled.extract_numba``, imported (with numba) on first use."""
    if not _COMPILED:
        from .compiled import extract_numba  # noqa: PLC0415

        _COMPILED.append(extract_numba)
    return _COMPILED[0]


def _extract(scan: Scan, cfg: SensorMethodConfig) -> FeatureSet:
    ranges = scan.ranges
    bearings = scan.angles
    sig = compute(
        ranges, bearings, scan.angle_increment, int(cfg.k), max(scan.range_min, cfg.min_range), scan.range_max,
        cfg.sigma_r,
    )
    table = find_lines(sig, ranges, bearings, scan.angle_min, scan.angle_increment, cfg)
    if table.rho.size == 0:
        return FeatureSet([], [], METHOD)
    if table.rho.size > 1:
        invalid_cum = np.concatenate(([0], np.cumsum(~sig.valid)))
        table = merge_neighbours(table, invalid_cum, cfg)
    first, last = table.first.copy(), table.last.copy()
    resolve_overlaps(first, last)
    n_lines = first.size
    ends = endpoints(np.tile(table.rho, 2), np.tile(table.alpha, 2), ranges, bearings, np.concatenate((first, last)))
    p0, p1 = ends[:n_lines], ends[n_lines:]
    d = p1 - p0
    keep = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] >= cfg.min_length * cfg.min_length  # nan -> dropped
    idx = np.flatnonzero(keep)
    rho = table.rho[idx].tolist()
    alpha = table.alpha[idx].tolist()
    first_l = first[idx].tolist()
    last_l = last[idx].tolist()
    n_pts = np.minimum(table.n_points, last - first + 1)[idx].tolist()
    start = list(map(tuple, p0[idx].tolist()))
    end = list(map(tuple, p1[idx].tolist()))
    covs = table.cov[idx]
    lines = [
        new_line(rho[m], alpha[m], start[m], end[m], first_l[m], last_l[m], covs[m], n_pts[m])
        for m in range(len(rho))
    ]
    corners = []
    if cfg.corners and len(lines) > 1:
        corners = find_corners(
            rho, alpha, first_l, last_l, start, end, sig.psi, ranges, bearings, sig.valid,
            scan.angle_min, scan.angle_increment, cfg,
        )
    return FeatureSet(lines, corners, METHOD)


register(METHOD, SensorMethodConfig, extract_sensor)
