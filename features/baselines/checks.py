"""Value checks for the extractors' configs: each raises ConfigError with a message that starts
with the field's name, so a bad sweep value fails when the config is built, with what to fix,
instead of deep inside an extractor (a ZeroDivisionError, a numpy shape error)."""

from __future__ import annotations

import math

import numpy as np

from lms200.finite import is_number as is_real  # a plain or numpy number, not a bool

from ..errors import ConfigError

MAX_BEAMS = 1 << 14  # most beams of a scan the extractors take (bounds the memory of one call)
#: largest range noise sigma (m) a baseline takes: a line's covariance is sigma^2 over the scatter
#: of its points, and sigma = 1e300 m overflowed it to inf (fuzzing: 6 of 4,000 calls)
MAX_SIGMA_M = 1000.0
#: most rounds in a row without a line (hough, ransac max_failures): each is a full search over the
#: points left, and max_failures = 1.7e8 ran for hours (a 542-beam scan: 34 ms a round at 16,384 beams)
MAX_FAILURES = 100
#: beam counts (min_points, max_skip, max_gap_beams) are capped here before the kernels' int64
#: fields: any count beyond a scan's beams means the same, and 10**30 no longer overflows
BEAM_COUNT_CAP = 2**31


def beams(n: int) -> int:
    """A beam count for the kernels: ``n`` capped at BEAM_COUNT_CAP."""
    return min(int(n), BEAM_COUNT_CAP)


def fail(name: str, requirement: str, value: object) -> None:
    """Raise the ConfigError ``"<name>: <requirement>, got <value>"``."""
    raise ConfigError(f"{name}: {requirement}, got {value!r}")


def finite(value: object) -> bool:
    """``math.isfinite(value)``, False for an int beyond float64 (10**400 raised OverflowError)."""
    try:
        return math.isfinite(value)  # type: ignore[arg-type]
    except OverflowError:
        return False


def integer(name: str, value: object, minimum: int, maximum: int | None = None) -> None:
    """``value`` must be an integer (not a bool) >= ``minimum`` (and <= ``maximum``, if given)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum \
            or (maximum is not None and value > maximum):
        fail(name, f"must be an integer >= {minimum}" + (f" and <= {maximum}" if maximum is not None else ""), value)


def positive(name: str, value: object, unit: str) -> None:
    """``value`` must be a finite number > 0 (in ``unit``)."""
    if not is_real(value) or not (finite(value) and value > 0):
        fail(name, f"must be a finite number > 0 {unit}", value)


def non_negative(name: str, value: object, unit: str = "") -> None:
    """``value`` must be a finite number >= 0 (in ``unit``)."""
    if not is_real(value) or not (finite(value) and value >= 0):
        fail(name, f"must be a finite number >= 0{' ' + unit if unit else ''}", value)


def real_at_least(name: str, value: object, minimum: float) -> None:
    """``value`` must be a finite number >= ``minimum``."""
    if not is_real(value) or not (finite(value) and value >= minimum):
        fail(name, f"must be a finite number >= {minimum:g}", value)


def between(name: str, value: object, low: float, high: float, unit: str = "") -> None:
    """``value`` must be a number in [low, high] (in ``unit``)."""
    if not is_real(value) or not (low <= value <= high):
        fail(name, f"must be a number in [{low:g}, {high:g}]{' ' + unit if unit else ''}", value)


def angle(name: str, value: object, high: float, low_open: bool = True) -> None:
    """``value`` must be an angle in (0, ``high``] rad (``low_open``) or [0, high) rad."""
    ok = is_real(value) and ((0 < value <= high) if low_open else (0 <= value < high))
    if not ok:
        fail(name, f"must be an angle in {'(0' if low_open else '[0'}, {high:.6g}{']' if low_open else ')'} rad", value)


def flag(name: str, value: object) -> None:
    """``value`` must be a bool."""
    if not isinstance(value, (bool, np.bool_)):
        fail(name, "must be True or False", value)


def choice(name: str, value: object, allowed: tuple[str, ...]) -> None:
    """``value`` must be one of ``allowed``."""
    if value not in allowed:
        fail(name, f"must be one of {', '.join(allowed)}", value)


def shared_fields(cfg: object) -> None:
    """The fields every baseline has: sigma, breakpoint_lambda, min_points, min_length, max_skip,
    runs_z, corners."""
    positive("sigma", cfg.sigma, "m")
    if cfg.sigma > MAX_SIGMA_M:
        fail("sigma", f"must be a range noise std in (0, {MAX_SIGMA_M:g}] m", cfg.sigma)
    angle("breakpoint_lambda", cfg.breakpoint_lambda, math.pi / 2)
    integer("min_points", cfg.min_points, 2)
    non_negative("min_length", cfg.min_length, "m")
    integer("max_skip", cfg.max_skip, 1)
    non_negative("runs_z", cfg.runs_z)
    from .common import CornerConfig  # noqa: PLC0415 (common imports this module)

    if not isinstance(cfg.corners, CornerConfig):
        fail("corners", "must be a CornerConfig", cfg.corners)
