"""The typed configuration of a SLAM run (saved as YAML beside every result)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from lms200 import LmsbenchError


class SlamConfigError(LmsbenchError, ValueError):
    """A SLAM configuration field is unknown or out of range."""


@dataclass(frozen=True)
class AlignmentConfig:
    """Scan matching (``slam.icp``): robust point-to-line ICP of a scan against the local map.

    Attributes:
        stride: every ``stride``-th valid beam of a scan is matched (1 = all).
        max_range: beams longer than this (m) are not matched (far points are sparse and noisy).
        max_correspondence: a point further than this (m) from every map point is left out of a step...
        fine_correspondence: ...and once converged, further than this (m) (partial overlaps).
        huber: Huber threshold (m) of the point-to-line residuals.
        max_iterations: Gauss-Newton steps at most; ``tolerance_xy`` (m) and ``tolerance_theta``
            (rad) stop earlier.
        damping: Levenberg damping, a fraction of the Hessian's mean eigenvalue: an unconstrained
            direction (a corridor's axis) stays at the prediction.
        inlier_distance: a point this close (m) to a map point counts as explained.
        sigma_point: std of one point-to-line residual (m) in the covariance...
        covariance_inflation: ...whose variance is multiplied by this: neighbouring points of a
            scan and the map are not independent (calibrated once on simulated runs, seeds 100-102).
        retry_inliers: when the ICP from the prediction explains fewer than this fraction of the
            points, it is also run from standing still and from ``heading_hypotheses``.
        heading_hypotheses: heading offsets (rad) about the prediction tried on a retry (15, 30,
            60, 90 and 180 degrees: a fast turn between two scans).
        refine_hypotheses: how many of the retry starts (best first by their initial score) are refined.
        hypothesis_margin: a retry wins only with this much larger inlier fraction.
        min_inliers: a match explaining fewer points is not used (the pose follows the prediction).
        normal_step, normal_gap, normal_gap_per_range: point normals from the chord
            ``normal_step`` beams either side, shorter than ``normal_gap`` m plus
            ``normal_gap_per_range`` m per m of range (beams spread apart with range).
    """

    stride: int = 2
    max_range: float = 30.0
    max_correspondence: float = 0.5
    fine_correspondence: float = 0.15
    huber: float = 0.05
    max_iterations: int = 20
    tolerance_xy: float = 1e-4
    tolerance_theta: float = 1e-4
    damping: float = 1e-8
    inlier_distance: float = 0.1
    sigma_point: float = 0.02
    covariance_inflation: float = 10.0
    retry_inliers: float = 0.7
    heading_hypotheses: tuple[float, ...] = (0.26, -0.26, 0.52, -0.52, 1.05, -1.05, 1.57, -1.57, 3.14)
    refine_hypotheses: int = 3
    hypothesis_margin: float = 0.05
    min_inliers: float = 0.3
    normal_step: int = 2
    normal_gap: float = 0.3
    normal_gap_per_range: float = 0.05


@dataclass(frozen=True)
class KeyframeConfig:
    """Keyframes of the default pipeline and the local map the scans are matched against.

    Attributes:
        distance, angle: a scan becomes a keyframe when it is this far (m) or turned this much (rad)
            from the current keyframe...
        min_inliers: ...or when it explains fewer than this fraction of its points on the local map.
        local_map: the local map holds the points of the newest this many keyframes...
        voxel: ...thinned to one point per square of this side (m).
    """

    distance: float = 0.3
    angle: float = 0.2
    min_inliers: float = 0.8
    local_map: int = 10
    voxel: float = 0.05


@dataclass(frozen=True)
class LoopClosureConfig:
    """Loop closures on the keyframe pose graph (gtsam). Fixed defaults, set before any evaluation.

    Attributes:
        enabled: search for closures at all.
        every: search at every ``every``-th keyframe.
        search_radius: earlier keyframes within this distance (m) of the estimate, plus
            ``search_growth`` m per m of path since the last closure (drift grows), are candidates...
        min_travel: ...when the path since them is at least this long (m) (not the local map)...
        candidates: ...the nearest of them in this many different visits are matched (keyframes
            less than ``visit_gap`` keys apart belong to one visit).
        submap: a candidate's map is its keyframe and this many keyframes either side.
        min_inliers: a closure must explain this fraction of the scan's points...
        max_rms: ...with an rms point-to-line residual below this (m)...
        max_sigma_xy: ...and fix the position to this std (m) in every direction (a bare corridor
            does not fix its axis and cannot close a loop).
        kernel: robust loss of the closure factors, "cauchy" or "huber"...
        kernel_width: ...its width in whitened units (std of the closure's own noise).
        sigma_xy, sigma_theta: noise of a closure (m, rad) in the graph.
        prior_sigma: std of the first keyframe's prior (m and rad).
    """

    enabled: bool = True
    every: int = 2
    search_radius: float = 5.0
    search_growth: float = 0.05
    min_travel: float = 8.0
    candidates: int = 3
    visit_gap: int = 20
    submap: int = 2
    min_inliers: float = 0.65
    max_rms: float = 0.04
    max_sigma_xy: float = 0.05
    kernel: str = "cauchy"
    kernel_width: float = 1.0
    sigma_xy: float = 0.03
    sigma_theta: float = 0.01
    prior_sigma: float = 1e-4


@dataclass(frozen=True)
class SlamConfig:
    """Parameters of :func:`slam.run_slam`. Units: metres, radians, seconds.

    preset: "default" (motion from scan matching, keyframe pose graph with loop closures, see
        :mod:`slam.scanslam`) or "paper" (the paper's EKF of section 4.1: constant-velocity model,
        line landmarks; the flat fields below).
    alignment, keyframes, loop_closure: the default pipeline's sections (their own docstrings).

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

    preset: str = "default"
    alignment: AlignmentConfig = field(default_factory=AlignmentConfig)
    keyframes: KeyframeConfig = field(default_factory=KeyframeConfig)
    loop_closure: LoopClosureConfig = field(default_factory=LoopClosureConfig)
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
        if self.preset not in PRESETS:
            raise SlamConfigError(f"preset: must be one of {list(PRESETS)}, got {self.preset!r}")
        for name, cls in SECTIONS.items():
            value = getattr(self, name)
            if isinstance(value, dict):
                object.__setattr__(self, name, _section(cls, name, value))
            elif not isinstance(value, cls):
                raise SlamConfigError(f"{name}: expected a mapping of {cls.__name__} fields, got {value!r}")
        if self.loop_closure.kernel not in ("cauchy", "huber"):
            raise SlamConfigError(f"loop_closure.kernel: must be 'cauchy' or 'huber', got {self.loop_closure.kernel!r}")
        for sec, name in (("alignment", "stride"), ("alignment", "max_iterations"), ("keyframes", "local_map"),
                          ("loop_closure", "every"), ("loop_closure", "candidates")):
            if getattr(getattr(self, sec), name) < 1:
                raise SlamConfigError(f"{sec}.{name}: must be >= 1, got {getattr(getattr(self, sec), name)}")
        for sec, name in (("alignment", "max_correspondence"), ("alignment", "huber"), ("alignment", "sigma_point"),
                          ("alignment", "covariance_inflation"), ("alignment", "inlier_distance"),
                          ("keyframes", "distance"), ("keyframes", "angle"), ("loop_closure", "sigma_xy"),
                          ("loop_closure", "sigma_theta"), ("loop_closure", "kernel_width"),
                          ("loop_closure", "prior_sigma")):
            if not getattr(getattr(self, sec), name) > 0:
                raise SlamConfigError(f"{sec}.{name}: must be > 0, got {getattr(getattr(self, sec), name)}")
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
        d["alignment"]["heading_hypotheses"] = list(self.alignment.heading_hypotheses)
        return d

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> "SlamConfig":
        """Build from a mapping (e.g. parsed YAML); unknown keys raise SlamConfigError."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise SlamConfigError(f"unknown SLAM config field(s) {unknown}; known: {sorted(known)}")
        return cls(**values)


PRESETS = ("default", "paper")
SECTIONS: dict[str, type] = {"alignment": AlignmentConfig, "keyframes": KeyframeConfig, "loop_closure": LoopClosureConfig}


def _section(cls: type, name: str, values: dict[str, Any]) -> Any:
    """A section dataclass from a mapping; unknown keys raise SlamConfigError."""
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - known)
    if unknown:
        raise SlamConfigError(f"unknown field(s) {unknown} in SLAM config section {name!r}; known: {sorted(known)}")
    values = dict(values)
    if "heading_hypotheses" in values:
        values["heading_hypotheses"] = tuple(float(v) for v in values["heading_hypotheses"])
    return cls(**values)
