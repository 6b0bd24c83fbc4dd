"""The typed configuration of a SLAM run (saved as YAML beside every result)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from lms200 import LmsbenchError


class SlamConfigError(LmsbenchError, ValueError):
    """A SLAM configuration field is unknown or out of range."""


@dataclass(frozen=True)
class SlamConfig:
    """Parameters of :func:`slam.run_slam`. Units: metres, radians, seconds.

    Motion and noise:
        sigma_accel: white forward acceleration noise (m/s^2) of the constant-velocity model.
        sigma_alpha: white angular acceleration noise (rad/s^2).
        sigma_lateral: white sideways velocity noise (m/s): covers a scanner mounted off the
            turning axis and the arc that the Euler step of the notes' model leaves out.
        use_odometry: use the log's odometry increments as the motion input instead (comparison).
        odom_noise: (trans m/m, rot rad/rad, rot rad/m) odometry error factors.
        max_dt: longest step integrated at once (s); longer gaps are split.
    Observations:
        extractor, extractor_params: ``features.extract(scan, method=extractor, **extractor_params)``.
        min_line_points, min_line_length: lines with fewer beams or shorter (m) are ignored.
        sigma_rho, sigma_alpha_obs: floor of the line observation noise (m, rad), added to the
            extractor's covariance (or used alone where it gives none).
        use_corners: add corner landmarks (x, y); sigma_corner (m) their noise.
    Association:
        gate_probability: chi-square (2 dof) gate of individual compatibility.
        new_landmark_probability: an observation further than this quantile from every landmark
            starts a new one; between the two it is ignored as ambiguous.
        association: "nn" (nearest neighbour) or "jcbb" (joint compatibility branch and bound).
        extent_margin: an observation must overlap the landmark's extent grown by this (m).
        reject_ambiguous: (nn) leave an observation unpaired when two landmarks pass its gate.
    Map management:
        confirm_hits: sightings (including the first) that confirm a tentative landmark...
        tentative_window: ...within this many scans of its creation, else it is pruned.
    Pre-alignment:
        prealign: find the scan's heading (and position) against the map's lines before the update.
        prealign_radius: map lines within this distance (m) of the predicted position take part.
        prealign_sigma_xy, prealign_sigma_phi: std of the resulting pose pseudo-measurement.
        prealign_xy_turn: the alignment's position is used (besides its heading) only when its
            heading differs from the prediction by more than this (rad).
        prealign_min_fraction: the alignment is used only when it explains this fraction of line length.
        point_stride, verify_tolerance: pre-alignment candidates are checked by the fraction of the
            scan's points (every ``point_stride``-th beam) within ``verify_tolerance`` m of the
            previous scan's points; ``verify_margin``: a candidate far from the prediction must
            beat the one near it by this fraction.
        point_fallback, point_min_score: a scan whose lines do not align falls back to its points:
            normal-histogram headings against the previous scan, accepted when this fraction of
            the points lands on the previous scan's.
        max_turn_rate: fastest turn considered possible (rad/s): headings further from the previous
            one than this times the scan interval (+10 deg) are rejected (corridor 180-degree flips).
    Scan velocity (along a corridor the lines fix only the sideways position):
        scan_velocity: measure the forward speed V from the scan's points against an earlier
            scan's (point-to-line least squares, translation only, heading as pre-aligned, started
            from the prediction and from standing still), as a pseudo-measurement of V; a speed far
            outside the prior (a missed stop or start) widens the prior's V variance. Off by
            default: it fixes the simulated corridor runs but makes MIT CSAIL less stable.
        scan_velocity_baseline: the earlier scan is the newest one at least this old (s): at high
            scan rates a longer baseline measures the speed more precisely.
        scan_velocity_min_score: used only when this fraction of the points lands within
            ``verify_tolerance`` of the earlier scan's points...
        scan_velocity_min_fraction: ...and the matched normals' weight along the heading is at
            least this fraction of their total (a wall ahead, door frames; not a bare corridor).
        scan_velocity_sigma: std (m) of the displacement along a fully constraining direction;
            divided by sqrt(fraction) and the baseline, plus ``scan_velocity_floor`` (m/s).
    Consistency:
        nis_window, nis_divergence: the filter is flagged as diverged when the mean normalised
            innovation squared per degree of freedom over the last ``nis_window`` scans exceeds this.
    """

    sigma_accel: float = 1.0
    sigma_alpha: float = 4.0
    sigma_lateral: float = 0.1
    use_odometry: bool = False
    odom_noise: tuple[float, float, float] = (0.1, 0.1, 0.05)
    max_dt: float = 0.5
    extractor: str = "sensor"
    extractor_params: dict[str, Any] = field(default_factory=dict)
    min_line_points: int = 8
    min_line_length: float = 0.3
    sigma_rho: float = 0.02
    sigma_alpha_obs: float = 0.01
    use_corners: bool = False
    sigma_corner: float = 0.05
    gate_probability: float = 0.99
    new_landmark_probability: float = 0.9999
    association: str = "nn"
    extent_margin: float = 1.0
    reject_ambiguous: bool = True
    confirm_hits: int = 3
    tentative_window: int = 6
    prealign: bool = True
    prealign_radius: float = 12.0
    prealign_sigma_xy: float = 0.1
    prealign_sigma_phi: float = 0.03
    prealign_min_fraction: float = 0.3
    prealign_xy_turn: float = 0.1
    max_turn_rate: float = 8.0
    point_stride: int = 2
    verify_tolerance: float = 0.1
    verify_margin: float = 0.1
    point_fallback: bool = True
    point_min_score: float = 0.5
    point_xy: bool = False
    scan_velocity: bool = False
    scan_velocity_min_score: float = 0.4
    scan_velocity_min_fraction: float = 0.05
    scan_velocity_sigma: float = 0.01
    scan_velocity_floor: float = 0.05
    scan_velocity_baseline: float = 0.15
    nis_window: int = 20
    nis_divergence: float = 5.0

    def __post_init__(self) -> None:
        if self.association not in ("nn", "jcbb"):
            raise SlamConfigError(f"association: must be 'nn' or 'jcbb', got {self.association!r}")
        for name in ("sigma_accel", "sigma_alpha", "sigma_lateral", "sigma_rho", "sigma_alpha_obs", "sigma_corner", "max_dt",
                     "prealign_sigma_xy", "prealign_sigma_phi"):
            if not getattr(self, name) > 0:
                raise SlamConfigError(f"{name}: must be > 0, got {getattr(self, name)}")
        for name in ("gate_probability", "new_landmark_probability"):
            if not 0 < getattr(self, name) < 1:
                raise SlamConfigError(f"{name}: must be in (0, 1), got {getattr(self, name)}")
        if self.new_landmark_probability < self.gate_probability:
            raise SlamConfigError("new_landmark_probability: must be >= gate_probability")
        if self.confirm_hits < 1 or self.tentative_window < 1:
            raise SlamConfigError("confirm_hits and tentative_window: must be >= 1")
        object.__setattr__(self, "odom_noise", tuple(float(v) for v in self.odom_noise))

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["odom_noise"] = list(self.odom_noise)
        return d

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> "SlamConfig":
        """Build from a mapping (e.g. parsed YAML); unknown keys raise SlamConfigError."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise SlamConfigError(f"unknown SLAM config field(s) {unknown}; known: {sorted(known)}")
        return cls(**values)
