"""Angles wrapped to (-pi, pi] (rad), the range of every angle the extractors return."""

from __future__ import annotations

import math

import numpy as np

from .jit import kernel

TWO_PI = 2.0 * math.pi


def wrap(angle: np.ndarray | float) -> np.ndarray:
    """Angles wrapped to (-pi, pi] (rad); -pi itself (and what rounds to it) becomes pi."""
    w = np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), TWO_PI)
    return np.where(w <= -np.pi, w + TWO_PI, w)


@kernel
def wrap_one(a: float) -> float:
    """One angle wrapped to (-pi, pi] (rad), for the compiled extractors: pi - (pi - a) mod 2 pi,
    the modulo skipped where it changes nothing (0 <= pi - a < 2 pi, the common case)."""
    t = math.pi - a
    w = math.pi - t if 0.0 <= t < TWO_PI else math.pi - t % TWO_PI
    return w + TWO_PI if w <= -math.pi else w
