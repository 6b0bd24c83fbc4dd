"""Records: what every scan source yields (a log reader, the simulator, the serial driver)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import InputError
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
    """``pose`` as an (x, y, theta) tuple of floats; InputError naming ``name`` otherwise."""
    try:
        x, y, th = (float(v) for v in pose)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InputError(f"{name}: must be None or three numbers (x m, y m, theta rad), got {pose!r}") from None
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
        raise InputError(f"{name}: must be finite (x m, y m, theta rad), got {pose!r}")
    return (x, y, th)
