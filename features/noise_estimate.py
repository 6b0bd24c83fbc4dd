"""``sigma_r="auto"``: the range noise the extractors' thresholds should assume, from the data.

An extractor compares neighbouring beams, so what its noise-scaled thresholds must allow for is the
scatter of a range about a straight face *between neighbouring beams*: the sensor's noise, the
rounding of the range codes (1 cm steps in SICK cm mode: an error of variance q^2 / 12), and, at
0.5 and 0.25 deg, the offset between the interlaced 1 deg sweeps a moving scanner takes 13 ms
apart. :func:`neighbour_sigma` measures exactly that: the robust scale (median absolute deviation,
then clipped standard deviation) of the collinearity residuals of neighbouring beam triples
(``lms200.noise.line_residuals`` with stride 1 and ``robust_scale``: the estimator of
``lms200.noise``, used at the beam step the extractors see). Depth steps, corners and curved
surfaces are outliers of those residuals and do not enter the scale.

The estimate is compiled (``features.sensor.engine``, section 0: ``pooled_sigma``), since the sensor
method runs it on every cm-mode scan; it equals the numpy estimator of ``lms200.noise`` bit for bit.

Measured on the real logs of ../shared/data (pooled over each log): MIT CSAIL and the CSAIL
ROBOTLASER1 log (0.5 deg, cm codes) 12 mm, against 5.3 mm within one mirror turn; Intel (1 deg,
cm codes) 5.3 mm; ACES (1 deg) 25 mm.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Iterable

import numpy as np

from lms200 import Scan
from lms200.noise import MIN_RANGE_M

from .jit import FixedTypeCall

AUTO = "auto"
AUTO_FALLBACK = 0.005  # m: the noise assumed when a scan has too few usable triples


@lru_cache(maxsize=1)
def _engine() -> tuple[Any, FixedTypeCall]:
    """The sensor engine (imported on first use: its package imports this module) and its
    ``pooled_sigma`` called with fixed types ((S, n) float64 ranges, floats)."""
    from .sensor import engine  # noqa: PLC0415

    return engine, FixedTypeCall(engine.pooled_sigma)


@lru_cache(maxsize=64)
def twice_cos(increment: float) -> float:
    """2 cos(D) of a beam step D (rad), as numpy computes it (``lms200.noise.line_residuals``)."""
    return float(2.0 * np.cos(increment))


def scan_sigma(scan: Scan, fallback: float = AUTO_FALLBACK) -> float:
    """:func:`neighbour_sigma` of one scan (the sensor method's per-scan "auto"), in one compiled call."""
    return _engine()[1](scan.ranges.reshape(1, -1), twice_cos(scan.angle_increment), float(scan.range_min),
                         float(scan.range_max), float(fallback))


def stacked_sigma(ranges: np.ndarray, scan: Scan, fallback: float = AUTO_FALLBACK) -> float:
    """:func:`neighbour_sigma` of scans of ``scan``'s geometry stacked as rows of ``ranges`` (S, n)."""
    return _engine()[0].pooled_sigma(ranges, twice_cos(scan.angle_increment), float(scan.range_min), float(scan.range_max),
                        float(fallback))


def neighbour_sigma(scans: Scan | Iterable[Any], fallback: float = AUTO_FALLBACK) -> float:
    """Range scatter (m, 1 sigma) of neighbouring beams about straight faces, pooled over ``scans``
    (one Scan, or Scans or records with ``.scan``), at least the quantisation's q / sqrt(12) and
    ``features.sensor.engine.SIGMA_FLOOR_M`` (1 mm); ``fallback`` when fewer than
    ``features.sensor.engine.MIN_TRIPLES`` (20) triples are usable."""
    if isinstance(scans, Scan):
        return scan_sigma(scans, fallback)
    engine = _engine()[0]
    zs: list[np.ndarray] = []
    sample: list[np.ndarray] = []
    total = 0
    for item in scans:
        scan = getattr(item, "scan", item)
        r = scan.ranges
        z = np.empty(max(r.size - 2, 0))
        m = engine.neighbour_residuals(r, twice_cos(scan.angle_increment), max(float(scan.range_min), MIN_RANGE_M),
                                float(scan.range_max), z, 0)
        zs.append(z[:m])
        s = np.empty(r.size // engine.SAMPLE_STEP + 1)
        sample.append(s[: engine.finite_sample(r, s, 0)])
        total += m
        if total >= engine.MAX_TRIPLES:
            break
    z_all = np.concatenate(zs) if zs else np.empty(0)
    return float(engine.sigma_of_residuals(z_all, np.concatenate(sample) if sample else np.empty(0), float(fallback)))
