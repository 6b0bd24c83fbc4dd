"""Feature types shared by every extractor: lines, corners and the FeatureSet they come in.

All geometry is in the sensor frame of the scan (x ahead, y left, metres, radians CCW).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Line:
    """A line segment ``x cos(alpha) + y sin(alpha) = rho``.

    Attributes:
        rho: distance of the infinite line from the sensor origin (m, >= 0).
        alpha: normal angle of the line (rad, in (-pi, pi]).
        start: (x, y) endpoint at the first beam (m), the projection of that beam's point on the line.
        end: (x, y) endpoint at the last beam (m).
        first: index of the first beam assigned to the line (inclusive).
        last: index of the last beam assigned to the line (inclusive).
        cov: 2x2 covariance of (rho, alpha) in (m^2, m rad, rad^2).
        n_points: number of valid beams that support the line.
    """

    rho: float
    alpha: float
    start: tuple[float, float]
    end: tuple[float, float]
    first: int
    last: int
    cov: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    n_points: int = 0

    @property
    def length(self) -> float:
        """Length of the segment between its endpoints (m)."""
        return float(np.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1]))


def new_line(rho: float, alpha: float, start: tuple[float, float], end: tuple[float, float], first: int,
             last: int, cov: np.ndarray, n_points: int) -> Line:
    """``Line(...)`` built without the frozen dataclass' per-field setattr (the same object, ~3x
    faster): for extractors that build many Lines per scan from values already of the right types."""
    line = object.__new__(Line)
    line.__dict__.update(
        rho=rho, alpha=alpha, start=start, end=end, first=first, last=last, cov=cov, n_points=n_points
    )
    return line


@dataclass(frozen=True)
class Corner:
    """A corner where two extracted lines meet.

    Attributes:
        x, y: position in the sensor frame (m).
        angle: angle between the two lines (rad, in (0, pi)); pi/2 for a right-angle corner.
        index: beam index of the corner.
        lines: indices of the two lines in ``FeatureSet.lines`` (beam order).
    """

    x: float
    y: float
    angle: float
    index: int
    lines: tuple[int, int]


@dataclass(frozen=True)
class FeatureSet:
    """The features extracted from one scan."""

    lines: list[Line] = field(default_factory=list)
    corners: list[Corner] = field(default_factory=list)
    method: str = ""

    def line_array(self) -> np.ndarray:
        """(n, 8) array: rho, alpha, x0, y0, x1, y1, first, last (for tables and plots)."""
        if not self.lines:
            return np.empty((0, 8))
        return np.array(
            [(l.rho, l.alpha, *l.start, *l.end, l.first, l.last) for l in self.lines], dtype=float
        )

    def corner_array(self) -> np.ndarray:
        """(m, 4) array: x, y, angle, index."""
        if not self.corners:
            return np.empty((0, 4))
        return np.array([(c.x, c.y, c.angle, c.index) for c in self.corners], dtype=float)
