"""Angles wrapped to (-pi, pi] (rad), the range of every angle the extractors return."""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap(angle: np.ndarray | float) -> np.ndarray:
    """Angles wrapped to (-pi, pi] (rad); -pi itself (and what rounds to it) becomes pi."""
    w = np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), TWO_PI)
    return np.where(w <= -np.pi, w + TWO_PI, w)
