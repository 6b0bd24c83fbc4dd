"""The project's one angle wrap: angles (rad) to (-pi, pi].

One formula, ``pi - (pi - a) mod 2 pi`` with -pi (and what rounds to it) moved to +pi, written
once (:func:`wrap_formula`; :func:`wrap_scalar` is it for one float) and used three ways:
:func:`wrap` for Python floats and numpy arrays, and ``features.jit.wrap_one``, :func:`wrap_scalar`
compiled, for the kernels of the extractors and the scan matcher (compiled there: importing
``lms200`` loads no numba, so that a command's help and ``--version`` stay quick). ``mod`` is the
floored remainder (Python's ``%``, ``np.mod``, numba's ``%``: the same fmod-based result in all
three), so a compiled kernel and numpy wrap an angle to the same bits.
"""

from __future__ import annotations

import math
from typing import overload

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_formula(angle):  # noqa: ANN001, ANN201  (a float, a numpy array or a compiled float)
    """``angle`` (rad) wrapped to (-pi, pi]: the formula behind :func:`wrap` and :func:`wrap_scalar`."""
    w = math.pi - (math.pi - angle) % TWO_PI
    return w + TWO_PI * (w <= -math.pi)  # mod can round up to 2 pi: w = -pi then becomes +pi


def wrap_scalar(angle: float) -> float:
    """One angle (rad) wrapped to (-pi, pi]: :func:`wrap_formula` for one float, the modulo skipped
    where it changes nothing (0 <= pi - angle < 2 pi, the common case: a branch, where the
    formula's modulo is a call of fmod, ~20 ns in a kernel's inner loop)."""
    t = math.pi - angle
    w = math.pi - t if 0.0 <= t < TWO_PI else math.pi - t % TWO_PI
    return w + TWO_PI if w <= -math.pi else w



@overload
def wrap(angle: float) -> float: ...


@overload
def wrap(angle: np.ndarray) -> np.ndarray: ...


def wrap(angle: np.ndarray | float) -> np.ndarray | float:
    """Angles (rad) wrapped to (-pi, pi]: a float for a scalar, an array (float64) for an array."""
    if isinstance(angle, (float, int)) and not isinstance(angle, bool):
        return wrap_scalar(float(angle))
    w = wrap_formula(np.asarray(angle, dtype=float))
    return float(w) if np.ndim(w) == 0 else w
