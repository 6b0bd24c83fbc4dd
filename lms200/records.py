"""Records: what every scan source yields (a log reader, the simulator, the serial driver)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .codes import NOT_NUMBER_ITEMS
from .errors import InputError
from .finite import float_of
from .scan import Scan

Pose2D = tuple[float, float, float]  # (x m, y m, theta rad) in the world / odometry frame


@dataclass(frozen=True)
class Record:
    """One scan with what the source knows of the robot's pose at the scan's ``stamp``.

    Attributes:
        scan: the laser scan; ``scan.stamp`` is the source's timestamp (s).
        odom: raw odometry pose (x, y, theta) or None where the source has none.
        truth: true pose (x, y, theta) or None where the source has none.

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) naming the field: ``scan`` not a
            Scan, a pose that is not three finite numbers (poses are stored as tuples of floats).
    """

    scan: Scan
    odom: Pose2D | None = None
    truth: Pose2D | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.scan, Scan):
            raise InputError(f"scan: must be an lms200.Scan, got {type(self.scan).__name__}")
        for name in ("odom", "truth"):
            pose = getattr(self, name)
            if pose is not None:
                object.__setattr__(self, name, pose_of(name, pose))


def pose_of(name: str, pose: object) -> Pose2D:
    """``pose`` as an (x, y, theta) tuple of floats; InputError naming ``name`` otherwise: text
    (``"123"`` was read as (1.0, 2.0, 3.0)), bools (True is not 1 m), ints beyond float64
    (10**400 was a raw OverflowError), nan / inf. Found by a review's reproduction."""
    shape = f"{name}: must be None or three numbers (x m, y m, theta rad)"
    if isinstance(pose, (str, bytes)):
        raise InputError(f"{shape}, got {type(pose).__name__} {pose!r}")
    try:
        items: tuple[object, ...] = tuple(pose)  # type: ignore[arg-type]
    except TypeError:
        raise InputError(f"{shape}, got {type(pose).__name__}") from None
    if len(items) != 3:
        raise InputError(f"{shape}, got {len(items)} items")
    values = []
    for v in items:
        if isinstance(v, np.ndarray) and v.ndim == 0:
            v = v.item()
        if isinstance(v, NOT_NUMBER_ITEMS):
            raise InputError(f"{shape}, got {type(v).__name__} {v!r} among them")
        try:
            values.append(float_of(v, name, InputError))
        except (TypeError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"{shape}, got {type(v).__name__} among them") from None
    x, y, th = values
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
        raise InputError(f"{name}: must be finite (x m, y m, theta rad), got {pose!r}")
    return (x, y, th)
