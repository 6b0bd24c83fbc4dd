"""Value checks for the baseline configs: each raises ValueError with a message that starts with the
field's name (as the sensor method's config does), so a bad sweep value fails at config time with
what to fix instead of deep inside an extractor (a ZeroDivisionError, a numpy shape error)."""

from __future__ import annotations

import math

import numpy as np


def is_real(value: object) -> bool:
    """A plain or numpy number, not a bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def integer(name: str, value: object, minimum: int) -> None:
    """``value`` must be an integer (not a bool) >= ``minimum``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name}: must be an integer >= {minimum}, got {value!r}")


def positive(name: str, value: object, unit: str) -> None:
    """``value`` must be a finite number > 0 (in ``unit``)."""
    if not is_real(value) or not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name}: must be a finite number > 0 {unit}, got {value!r}")


def non_negative(name: str, value: object, unit: str = "") -> None:
    """``value`` must be a finite number >= 0 (in ``unit``)."""
    if not is_real(value) or not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{name}: must be a finite number >= 0{' ' + unit if unit else ''}, got {value!r}")


def angle_deg(name: str, value: object, high: float) -> None:
    """``value`` must be an angle in (0, ``high``] degrees."""
    if not is_real(value) or not (0 < value <= high):
        raise ValueError(f"{name}: must be an angle in (0, {high:g}] deg, got {value!r}")


def choice(name: str, value: object, allowed: tuple[str, ...]) -> None:
    """``value`` must be one of ``allowed``."""
    if value not in allowed:
        raise ValueError(f"{name}: must be one of {', '.join(allowed)}, got {value!r}")


def shared_fields(cfg: object) -> None:
    """The fields every baseline has: sigma, breakpoint_lambda_deg, min_points, min_length,
    max_skip, runs_z."""
    positive("sigma", cfg.sigma, "m")
    angle_deg("breakpoint_lambda_deg", cfg.breakpoint_lambda_deg, 90.0)
    integer("min_points", cfg.min_points, 2)
    non_negative("min_length", cfg.min_length, "m")
    integer("max_skip", cfg.max_skip, 1)
    non_negative("runs_z", cfg.runs_z)
