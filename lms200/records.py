"""Records: what every scan source yields (a log reader, the simulator, the serial driver)."""

from __future__ import annotations

from dataclasses import dataclass

from .scan import Scan

Pose2D = tuple[float, float, float]  # (x m, y m, theta rad) in the world / odometry frame


@dataclass(frozen=True)
class Record:
    """One scan with what the source knows of the robot's pose at the scan's ``stamp``.

    Attributes:
        scan: the laser scan; ``scan.stamp`` is the source's timestamp (s).
        odom: raw odometry pose (x, y, theta) or None where the source has none.
        truth: true pose (x, y, theta) or None where the source has none.
    """

    scan: Scan
    odom: Pose2D | None = None
    truth: Pose2D | None = None
