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

Measured on the real logs of ../shared/data (pooled over each log): MIT CSAIL and the CSAIL
ROBOTLASER1 log (0.5 deg, cm codes) 12 mm, against 5.3 mm within one mirror turn; Intel (1 deg,
cm codes) 5.3 mm; ACES (1 deg) 25 mm.
"""

from __future__ import annotations

import math
from typing import Any, Iterable

import numpy as np

from lms200 import Scan
from lms200.noise import estimate_quantum, line_residuals, robust_scale

AUTO = "auto"
SIGMA_FLOOR_M = 0.001  # smallest noise assumed (m): noiseless synthetic scans still get finite thresholds
MIN_TRIPLES = 20  # fewer usable triples than this: the scale cannot be had (see ``fallback``)
MAX_TRIPLES = 1_000_000  # memory bound when pooling a whole log


def neighbour_sigma(scans: Scan | Iterable[Any], fallback: float = 0.005) -> float:
    """Range scatter (m, 1 sigma) of neighbouring beams about straight faces, pooled over ``scans``
    (one Scan, or Scans or records with ``.scan``), at least the quantisation's q / sqrt(12) and
    ``SIGMA_FLOOR_M``; ``fallback`` when fewer than ``MIN_TRIPLES`` triples are usable."""
    zs: list[np.ndarray] = []
    sample: list[np.ndarray] = []
    total = 0
    for item in [scans] if isinstance(scans, Scan) else scans:
        scan = getattr(item, "scan", item)
        z, _, _ = line_residuals(scan.ranges, scan.angle_increment, scan.range_min, scan.range_max, stride=1)
        zs.append(z)
        r = scan.ranges
        sample.append(r[np.isfinite(r)][::5])
        total += z.size
        if total >= MAX_TRIPLES:
            break
    if total < MIN_TRIPLES:
        return float(fallback)
    _, scale, _ = robust_scale(np.concatenate(zs))
    quantum = estimate_quantum(np.concatenate(sample))
    floor = max(quantum / math.sqrt(12.0), SIGMA_FLOOR_M)
    return float(max(scale, floor)) if np.isfinite(scale) else float(fallback)
