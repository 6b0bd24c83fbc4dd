"""Checks of the simulator's public arguments: each raises ``lms200.InputError`` (an
``LmsbenchError`` and a ``ValueError``) whose message starts with the argument's name. Found by
fuzzing the Python API: a nan pose scanned nothing (every beam +inf) and saw no face, silently;
a pose of two numbers or text was a bare unpacking error."""

from __future__ import annotations

import math

import numpy as np

from lms200.errors import InputError
from lms200.finite import check_instance as check_instance  # re-exported: their home before lms200 used them
from lms200.finite import check_number as check_number


def _numbers(value: object, count: int, name: str, what: str) -> tuple[float, ...]:
    try:
        items = tuple(float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: must be {count} finite numbers ({what}), got {value!r}") from None
    if len(items) != count or isinstance(value, (str, bytes)) or not all(math.isfinite(v) for v in items):
        raise InputError(f"{name}: must be {count} finite numbers ({what}), got {value!r}")
    return items


def check_pose(pose: object, name: str = "pose") -> tuple[float, float, float]:
    """``pose`` as three finite floats (x m, y m, theta rad)."""
    x, y, th = _numbers(pose, 3, name, "x m, y m, theta rad")
    return x, y, th


def check_twist(twist: object, name: str = "twist") -> tuple[float, float] | None:
    """``twist`` as None or two finite floats (v m/s, w rad/s)."""
    if twist is None:
        return None
    v, w = _numbers(twist, 2, name, "v m/s, w rad/s")
    return v, w


def check_beam_poses(beam_poses: object, n_beams: int) -> np.ndarray:
    """(n_beams, 3) finite float scanner poses, one a beam (x m, y m, theta rad)."""
    try:
        bp = np.asarray(beam_poses, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"beam_poses: must be ({n_beams}, 3) numbers x m, y m, theta rad ({exc})") from None
    if bp.shape != (n_beams, 3):
        raise InputError(f"beam_poses: must be ({n_beams}, 3) (x m, y m, theta rad a beam), got shape {bp.shape}")
    if not np.all(np.isfinite(bp)):
        raise InputError("beam_poses: must be finite")
    return bp
