"""The typed configuration of a SLAM run (saved as YAML beside every result)."""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from features.baselines.checks import MAX_BEAMS
from lms200 import LmsbenchError
from lms200.finite import float_of, is_one_of, shown


class SlamConfigError(LmsbenchError, ValueError):
    """A SLAM configuration field is unknown or out of range."""


@dataclass(frozen=True)
class AlignmentConfig:
    """Scan matching (``slam.icp``): robust point-to-line ICP of a scan against the local map.

    Attributes:
        stride: every ``stride``-th valid beam of a scan is matched (1 = all); at most 16,384 (``MAX_BEAMS``),
            and a run refuses at its first scan one that keeps fewer than ``MIN_MATCH_POINTS`` of its beams.
        max_range: beams longer than this (m) are not matched (far points are sparse and noisy); in
            [0.1, 1e4] m.
        max_correspondence: a point further than this (m) from every map point is left out of a step...
        fine_correspondence: ...and once converged, further than this (m) (partial overlaps).
        huber: Huber threshold (m) of the point-to-line residuals (at least ``MIN_HUBER_M``, 1 um).
        max_iterations, fine_iterations: Gauss-Newton steps at most with the wide and then the
            narrow reach; a step below ``tolerance_xy`` (m) and ``tolerance_theta`` (rad) ends a stage.
        damping: Levenberg damping, a fraction of the Hessian's mean eigenvalue: an unconstrained
            direction (a corridor's axis) stays at the prediction.
        inlier_distance: a point this close (m) to a map point counts as explained. It and the two
            reaches above are at least 1 mm (``MIN_REACH_M``, the LMS200's quantum: 1e-300 paired no point).
        sigma_point: floor (m) of one point's point-to-line residual in the covariance (a
            near-perfect fit does not make a pose exact)...
        covariance_inflation: ...the match's covariance is the sandwich of its own residuals
            (``slam.icp.sandwich_information``) times this. Set once on simulated office runs
            (tuning seeds 100-102, 300 s at 10 scans/s, never the evaluation's seeds or logs):
            with the scans de-skewed and a 45-degree normal check, 3, 1.5 and 1 gave mean pose
            NEES of 0.3-0.4, 0.5-0.7 and 0.8-1.1 (3 dof; 3 is consistent): 1, no inflation (below
            1 the floor above would no longer be a floor); on the final code (67.5 degrees), 0.9-1.7.
            Before the de-skew, 3 compensated for the scan's own motion distortion. In [0.01, 100]
            (``MIN_COVARIANCE_INFLATION``, ``MAX_COVARIANCE_INFLATION``).
        retry_inliers: when the ICP from the prediction explains fewer than this fraction of the
            points, it is also run from standing still and from ``heading_hypotheses``.
        heading_hypotheses: heading offsets (rad) about the prediction tried on a retry (15, 30,
            60, 90 and 180 degrees: a fast turn between two scans); without odometry first only
            those within ``max_turn_rate`` times the time since the last scan plus 0.1 rad
            (``slam.scanslam.DISTINCT_THETA``) of the last heading, the search's bound (below),
            and all of them only when no pose within that bound fits. Empty (``[]``): the retry
            tries no turn, only standing still (and nothing with odometry or in a loop closure,
            which have no other start), as ``refine_hypotheses: 0`` refines no retry start.
        refine_hypotheses: how many of the retry starts (best first by their initial score) are refined.
        hypothesis_margin: a retry wins only with this much larger inlier fraction.
        min_inliers: a match explaining fewer points is not used (the pose follows the prediction).
        motion_prior: the match from the prediction is a MAP estimate with the prediction's
            std (``motion``: ``sigma_accel dt^2`` + floor, ``sigma_alpha dt^2`` + floor) as a
            prior: the prediction holds the directions the scan barely fixes (a corridor's axis),
            where the few points that constrain them would otherwise set the pose alone.
        deskew: undo the sensor's motion during a scan with the constant-velocity twist of the
            last two poses, so that the match estimates the pose at the scan's stamp (its first
            beam). Beam times are the LMS200's (``lms200.timing.beam_time_offsets``): a 1 deg scan
            is one 180 deg sweep (6.7 ms), a 0.5 deg scan two interlaced turns (odd beams 13.3 ms
            after the even ones; last beam at 20 ms). At 1 rad/s a point 8 m away moves up to
            16 cm during a 0.5 deg scan. Off for scans taken at one instant (the simulator's
            ``SensorConfig(interlaced=False)`` / ``.ideal()``), where it would add that motion
            instead of removing it (``lmsbench slam`` and sweeps switch it off there themselves).
            A scan no LMS200 could take (a resolution other than 1, 0.5 or 0.25 deg, or more than
            180 deg: ``lms200.timing.lms200_shaped``) is not de-skewed unless ``beam_time_increment``
            gives its timing (``lmsbench slam`` then switches deskew off and says so).
        beam_time_increment: s between consecutive beams of a scanner that sweeps them in beam
            order (a Hokuyo UTM-30LX: 25 ms a 1440-step turn, 1.736e-5 s; an URG-04LX: 100 ms a
            1024-step turn, 9.77e-5 s); de-skewing then uses these times for every scan instead of
            the LMS200's. 0 (default): the LMS200's timing, for scans of its shape only. At most
            ``MAX_BEAM_TIME_INCREMENT_S``.
        normal_agreement: a scan point (with a normal) is paired only with map points whose normal
            lies within this angle (rad) of its own: a point near a corner is not pulled onto the
            perpendicular wall (90 degrees off; along a corridor such pairs set the axis from a
            few points), while a chord normal blended across a corner (at most 45 degrees off
            either wall) still pairs: 67.5 degrees, halfway.
        normal_step, normal_gap, normal_gap_per_range: point normals from the chord
            ``normal_step`` beams either side, shorter than ``normal_gap`` m plus
            ``normal_gap_per_range`` m per m of range (beams spread apart with range).
        search: a guess-free correlative search (:mod:`slam.correlative`) when the motion since
            the last scan may lie beyond the ICP's reach: the prediction's std (``motion``, it
            grows with dt^2) times ``search_sigmas`` exceeds ``max_correspondence``, or the match
            from the prediction (and its retries) explains fewer than ``retry_inliers`` of the
            points or turned beyond ``max_turn_rate`` (below). Its window is the prediction +- ``search_sigmas`` std, at most
            ``search_xy`` m in x and y (and the whole turn at most); the ``search_candidates``
            best distinct poses are refined by the ICP and compete with the prediction's match,
            which stays unless one of them fits better by more than ``fit_margin``.
        search_sigmas, search_xy: see ``search`` (3 std, in [1, 10]; 2 m, twice the 1 m/s of an
            indoor robot over a second of prediction error; at least ``search_step``, at most 10 m).
        max_turn_rate: headings are searched only within this turn rate (rad/s) times the time
            since the last scan of the last pose's heading. The prediction's heading std grows
            with dt^2 (``motion.sigma_alpha``: 3 std pass half a turn from 0.5 s between scans
            on), a robot's turn does not: without the bound, a corridor seen half a turn the
            wrong way could win (csail-robotlaser1, 0.64 s apart, flipped twice: ATE 10 m). Half
            a turn a second (pi), above the fastest turns of the logs' corrected poses
            (csail-robotlaser1 2.1 rad/s, ACES 1.1, MIT CSAIL 1.9 at the 99th percentile); from
            1 s between scans on it allows the whole turn. In [0.01, 1e4] rad/s (``MAX_TURN_RATE``: 1e4
            allows any heading even at 100 scans/s; 100 allowed only 1.33 rad at the LMS200's 75).
        search_step, search_step_theta: the window's grid (m, rad): 0.2 m and 1 degree, well
            inside the ICP's 0.5 m reach (1 degree moves a point 10 m away by 0.17 m); at least
            1e-3 rad, a step at least ``search_resolution``, and a window of at most 4 million
            poses (headings x positions: 32 MB of scores; the default's 159,201).
        search_resolution, search_sigma: the likelihood field's cells (m, 0.01-1) and the std (m,
            1e-4 to 1) of its Gaussian about each map point (the window's step: a pose off by
            half a step still scores). The field covers at most 2,000 x 2,000 cells about the
            prediction (100 m square at 5 cm), whatever the map's extent.
        search_points: at most this many of the scan's valid points (evenly spread) are scored.
        search_candidates: how many distinct window poses (0.3 m or 0.1 rad apart) are refined
            (at most 32: each is an ICP run on every searched step).
        fit_sigma: a searched step's candidates are ranked by their fit, the mean over the points of
            ``exp(-r^2 / 2 fit_sigma^2)`` (r the point-to-line residual, m; 0 beyond
            ``fine_correspondence``): 3 cm, 1.5 ``sigma_point`` (1e-4 to 1 m). Unlike the inlier fraction
            (points within ``inlier_distance``) it tells a corridor seen half a turn the wrong way,
            its points near a wall, from the right pose, its points on it.
        fit_margin: candidates within this of the best fit are told apart by the prior (below; in [0, 1]).
        ambiguity_sigmas: a searched step is ambiguous when a distinct pose (0.3 m or 0.1 rad
            away) fits within ``fit_margin`` as well and the prior prefers the chosen pose
            by less than this many std (``consistency.max_ambiguous`` bounds their share; at most 100).
        see_through: (off by default) the search counts negative information against a pose: the
            share of the local map's points in the scan's view that its beams pass (a beam and both
            neighbours return from beyond the point by more than ``normal_gap`` +
            ``normal_gap_per_range`` x range, the chord test's tolerance for one surface;
            :func:`slam.correlative.see_through`). The window's best ``SEE_THROUGH_POOL`` (32)
            distinct poses are ranked by their score less that share, the best
            ``search_candidates`` refined, and every competitor's fit is less it too. The field and
            the fit count only the points that land on the map, and the map behind the robot is
            the richest: 3 s apart on 1-degree scans a corridor seen half a turn the wrong way
            out-scored the true pose even on a map placed by the logs' corrected poses. Off by
            default: fewer half-turn steps on Intel and ACES without odometry, but Intel's ATE
            worse (docs/slam.md).
        free_space: (off by default) the search's likelihood field also counts the known free
            space against a pose: a cell that a local-map keyframe's beam crossed, short of its
            return by the chord test's tolerance (``normal_gap`` + ``normal_gap_per_range`` x
            range) and more than ``normal_gap`` from every map point, scores -1 instead of the
            field's value (:func:`slam.correlative.free_space`), so the window ranks poses by hits
            less points in free space (points where no beam went say nothing); every competitor's
            fit is less the share of its points in such cells (:func:`slam.correlative.free_share`).
            Off by default: fewer bad steps on Intel and ACES without odometry, but Intel's ATE
            worse (docs/slam.md).
    """

    stride: int = 3
    max_range: float = 30.0
    max_correspondence: float = 0.5
    fine_correspondence: float = 0.15
    huber: float = 0.05
    max_iterations: int = 10
    fine_iterations: int = 5
    tolerance_xy: float = 5e-4
    tolerance_theta: float = 5e-4
    damping: float = 1e-8
    inlier_distance: float = 0.1
    sigma_point: float = 0.02
    covariance_inflation: float = 1.0
    retry_inliers: float = 0.7
    heading_hypotheses: tuple[float, ...] = (0.26, -0.26, 0.52, -0.52, 1.05, -1.05, 1.57, -1.57, 3.14)
    refine_hypotheses: int = 3
    hypothesis_margin: float = 0.05
    min_inliers: float = 0.3
    normal_step: int = 2
    normal_gap: float = 0.3
    normal_gap_per_range: float = 0.05
    motion_prior: bool = False
    deskew: bool = True
    beam_time_increment: float = 0.0
    normal_agreement: float = 1.178
    search: bool = True
    search_sigmas: float = 3.0
    search_xy: float = 2.0
    search_step: float = 0.2
    search_step_theta: float = 0.01745
    search_resolution: float = 0.1
    search_sigma: float = 0.2
    search_points: int = 200
    search_candidates: int = 4
    fit_sigma: float = 0.03
    fit_margin: float = 0.05
    ambiguity_sigmas: float = 3.0
    max_turn_rate: float = math.pi
    see_through: bool = False
    free_space: bool = False


@dataclass(frozen=True)
class MotionConfig:
    """Motion: the constant-velocity model (section 4.1; both presets) and, for the default
    pipeline, the check that keeps a match from jumping. No odometry unless ``use_odometry``.

    Attributes:
        sigma_accel: std of the white forward acceleration (m/s^2) of the constant-velocity model...
        sigma_alpha: ...and of the angular acceleration (rad/s^2). Default pipeline: over a scan
            interval dt the prediction's std is ``sigma * dt^2`` (+ ``sigma_floor_xy`` m,
            ``sigma_floor_theta`` rad; floors in [1e-6, 1000], sigmas at most 1000, so that the std
            and its inverse square stay finite).
        sigma_lateral: (paper preset) white sideways velocity noise (m/s): covers a scanner
            mounted off the turning axis and the arc that the Euler step leaves out.
        max_dt: (paper preset) longest step integrated at once (s); longer gaps are split, in at most
            ``slam.filter.MAX_PREDICT_STEPS`` (10,000) steps.
        max_gap: a step between scans longer than this (s; a pause in the recording, two logs
            joined, a clock jump) is not predicted by the constant-velocity model, which knows
            nothing of it (the paper preset's filter, integrating a 1e11 s gap, put the robot
            1e18 m away): the motion restarts as at the first scan, from the last pose with zero
            velocity (the paper preset: its velocity's uncertainty as at the start, the pose's and
            the map's kept; the default pipeline: its match starts at the last pose). Steps the
            odometry predicts (``use_odometry``) are not affected. Above every gap of the Intel,
            ACES and MIT CSAIL logs (at most 37.7 s). At least ``MIN_MAX_GAP_S`` (0.01 s: 1e-300
            made every step a gap, and the model never ran).
        use_odometry: the log's odometry increments drive the prediction instead (never the
            default; the paper preset's filter, or the default pipeline's matcher: its start,
            the heading hypotheses it may try and the search's window); ``odom_noise``: (trans
            m/m, rot rad/rad, rot rad/m) odometry error factors, each in [0, 10]: a step of d m
            and dtheta rad has std ``a_t d`` m and ``a_r |dtheta| + a_rt d`` rad (+ the floors
            above in the default pipeline).
        odom_max_turn_error: (default pipeline, ``use_odometry``) a retry of the match tries the
            heading hypotheses (``alignment.heading_hypotheses``) within this many rad of the
            odometry's heading, or within ``alignment.search_sigmas`` of its std where that is
            wider; in [0, pi]. A wheel odometry can be a few tenths of a radian off over a step
            (a slip, a late stamp: MIT CSAIL's by up to 0.74 rad), not the half turn that
            matches a corridor backwards. 1.5: every hypothesis below a quarter turn. Set on the
            logs after 3 std alone lost MIT CSAIL's slips (0.6 measured alike; docs/slam.md,
            "With odometry", says how each rule was reached on Intel, ACES and MIT CSAIL).
        odom_retry_gate: (default pipeline, ``use_odometry``; off) a retry whose heading stays
            within the odometry's ``jump_probability`` chi-square gate (1 dof) found no heading slip,
            and must keep its position within the same gate of the odometry's step (2 dof); one
            that found a slip may go anywhere. On Intel and ACES it takes the steps off the
            corrected poses by more than 0.3 m from 19 to 6 and 33 to 9, but not the ATE (the
            closures then decide it; docs/slam.md, "Why Intel and ACES end metres off").
        jump_probability: a match further from the prediction than this chi-square quantile
            (3 dof, of the prediction's std) is a jump...
        jump_margin: ...and replaced by the narrow-reach match started at the prediction when
            that explains this fraction more of the scan's points (the point check).
    """

    sigma_accel: float = 1.0
    sigma_alpha: float = 4.0
    sigma_floor_xy: float = 0.01
    sigma_floor_theta: float = 0.005
    jump_probability: float = 0.999
    jump_margin: float = 0.02
    sigma_lateral: float = 0.1
    max_dt: float = 0.5
    max_gap: float = 60.0
    use_odometry: bool = False
    odom_noise: tuple[float, float, float] = (0.1, 0.1, 0.05)
    odom_max_turn_error: float = 1.5
    odom_retry_gate: bool = False


@dataclass(frozen=True)
class ObservationConfig:
    """Which extracted features become observations, and their noise floor.

    Attributes:
        min_line_points, min_line_length: lines with fewer beams or shorter (m) are ignored.
        sigma_rho, sigma_alpha_obs: (paper preset) floor of the line observation noise (m, rad),
            added to the extractor's covariance (or used alone where it gives none).
        use_corners: (paper preset) add corner landmarks (x, y); ``sigma_corner`` (m) their noise.
        point_stride: (paper preset) every ``point_stride``-th beam's point checks a pre-alignment.
        max_lines: (paper preset) the most lines, and apart the most corners, of one scan the filter
            observes: a scan with more keeps its longest lines (its first corners) and the rest are
            not observed (``diagnostics["n_unobserved"]``; ``run_slam`` warns, ``lmsbench slam`` once a run, naming it). It bounds a step's
            work and memory: a scan of 20,000 lines ran over 60 s in one step, toward a 12.8 GB
            covariance (the LMS200's scans have at most a few dozen; 100 keeps every line of the
            four real logs).
    """

    min_line_points: int = 8
    min_line_length: float = 0.3
    sigma_rho: float = 0.02
    sigma_alpha_obs: float = 0.01
    use_corners: bool = False
    sigma_corner: float = 0.05
    point_stride: int = 2
    max_lines: int = 100


@dataclass(frozen=True)
class AssociationConfig:
    """Data association of the paper preset's EKF.

    Attributes:
        gate_probability: chi-square (2 dof) gate of individual compatibility.
        new_landmark_probability: an observation further than this quantile from every landmark
            starts a new one; between the two it is ignored as ambiguous.
        method: "nn" (nearest neighbour) or "jcbb" (joint compatibility branch and bound).
        extent_margin: an observation must overlap the landmark's extent grown by this (m)...
        extent_sigmas: ...plus this many std of the predicted robot position, always, even when
            the landmark is the only one in the gate (a corridor's first cross line).
        reject_ambiguous: (nn) leave an observation unpaired when two landmarks pass its gate.
        joint_check: (off) before the update, while the scan's pairs together exceed the
            ``gate_probability`` chi-square quantile of their stacked dof, the pair whose removal
            leaves the smallest joint NIS is dropped (each pair passed its own gate; together they
            may not). Off: with ``prealign.scan_velocity`` it took MIT CSAIL's relations error
            from 0.17 to 1.68 m (docs/slam.md, "The paper preset").
    """

    gate_probability: float = 0.99
    new_landmark_probability: float = 0.9999
    method: str = "nn"
    extent_margin: float = 1.0
    extent_sigmas: float = 3.0
    reject_ambiguous: bool = True
    joint_check: bool = False


@dataclass(frozen=True)
class LandmarkConfig:
    """Map management of the paper preset's EKF.

    Attributes:
        confirm_hits: sightings (including the first) that confirm a tentative landmark...
        tentative_window: ...within this many scans of its creation, else it is pruned.
        max_landmarks: the most landmarks (tentative and confirmed) the map holds: an observation
            that would start one more is not added (``diagnostics["n_unadded"]``; ``run_slam``
            warns); the tentative landmarks a scan prunes make room, that scan already. It bounds the
            filter's memory and time: its covariance is (5 + 2 n)^2 float64, 128 MB at the default
            2,000 landmarks (paper preset), 3.2 GB at the largest allowed, 10,000.
    """

    confirm_hits: int = 3
    tentative_window: int = 6
    max_landmarks: int = 2000


@dataclass(frozen=True)
class PrealignConfig:
    """The paper preset's heading search before each update (``slam.prealign``, ``slam.pointalign``).

    Attributes:
        enabled: find the scan's heading (and position) against the map's lines before the update
            (the heading search alone: ``scan_velocity`` is a switch of its own, on whatever this says).
        radius: map lines within this distance (m) of the predicted position take part.
        sigma_xy, sigma_phi: std of the resulting pose pseudo-measurement (m, rad).
        xy_turn: the alignment's position is used (besides its heading) only when its heading
            differs from the prediction by more than this (rad).
        min_fraction: the alignment is used only when it explains this fraction of line length.
        verify_tolerance: candidates are checked by the fraction of the scan's points within this
            (m) of the previous scan's points; ``verify_margin``: a candidate far from the
            prediction must beat the one near it by this fraction.
        near_heading: a candidate within this (rad) of the predicted heading counts as near.
        turn_margin: headings further from the previous one than ``max_turn_rate`` (rad/s) times
            the scan interval plus this (rad) are rejected (corridor 180-degree flips).
        widen_probability: a heading innovation beyond this chi-square quantile (1 dof) widens the
            heading and turn-rate prior instead of being fought; ``xy_probability`` (2 dof) gates
            the position part.
        turn_rate_widening: the turn-rate variance grows by this times (heading jump / dt)^2.
        point_fallback, point_min_score, point_xy, min_points: a scan whose lines do not align
            (with at least ``min_points`` points) falls back to its points: normal-histogram
            headings against the previous scan, accepted when this fraction of the points lands
            on the previous scan's; with ``point_xy`` its position is used too.
        scan_velocity...: measure the forward speed V from the scan's points against an earlier
            scan's, a pseudo-measurement of V where the matched normals hold the direction of
            travel (on: along a corridor whose lines fix only the sideways position, the
            constant-velocity speed sagged and the filter diverged on MIT CSAIL; docs/slam.md,
            "The paper preset"): baseline (s), min_score, min_fraction, sigma (m), floor (m/s),
            prior_probability (1 dof, a speed this far out widens the prior). Independent of
            ``enabled``; not used with ``motion.use_odometry`` (the odometry gives the speed).
    """

    enabled: bool = True
    radius: float = 12.0
    sigma_xy: float = 0.1
    sigma_phi: float = 0.03
    min_fraction: float = 0.3
    xy_turn: float = 0.1
    max_turn_rate: float = 8.0
    turn_margin: float = 0.1745
    near_heading: float = 0.1745
    verify_tolerance: float = 0.1
    verify_margin: float = 0.1
    widen_probability: float = 0.999
    xy_probability: float = 0.999
    turn_rate_widening: float = 0.25
    min_map_line_length: float = 0.3
    point_fallback: bool = True
    point_min_score: float = 0.5
    point_xy: bool = False
    min_points: int = 20
    scan_velocity: bool = True
    scan_velocity_min_score: float = 0.4
    scan_velocity_min_fraction: float = 0.05
    scan_velocity_sigma: float = 0.01
    scan_velocity_floor: float = 0.05
    scan_velocity_baseline: float = 0.15
    scan_velocity_prior_probability: float = 0.9999


@dataclass(frozen=True)
class ConsistencyConfig:
    """Divergence checks.

    Attributes:
        nis_window, nis_divergence: (paper preset) diverged when the mean normalised innovation
            squared per degree of freedom over the last ``nis_window`` scans exceeds this.
        point_window, point_min_score: diverged when, for ``point_window`` scans in a row, fewer
            than ``point_min_score`` of the scan's points land on the map at the estimated pose
            (a NEES-like check against the scan itself: both presets).
        max_ambiguous: (default pipeline) not healthy when more than this share of the steps are
            ambiguous (``alignment.ambiguity_sigmas``: a distinct pose fitted as well and only the
            motion model chose). 0: one such step is enough, since one wrong choice breaks the
            map. On simulated office runs at 0.5 scans/s (seeds 0-7) the 3 runs that lost track
            (ATE 0.56-2.7 m) had 1-3 ambiguous steps each (a share of 2.3-6.8 %, so a 5 % bound
            missed two of them); of the 5 that tracked (ATE 0.6-1.7 cm), 2 had one ambiguous step
            (flagged though right) and 3 none. Set after these measurements.
        min_matched_fraction: (default pipeline) not healthy when fewer than this share of the
            steps were matched (an unmatched step's pose is the motion model's guess): the four
            shared logs match 0.98-1.0 of their steps; a log of 3-beam scans matched none and was
            reported healthy. (Paper preset: below it ``lmsbench slam`` warns, and ``healthy``
            stays the filter's own state; MIT CSAIL pairs a line on 0.98 of its steps.)
        max_odometry_doubt: (default pipeline, ``motion.use_odometry``) not healthy when more than
            this share of the steps doubt the odometry: the match from the odometry's step explained
            fewer than ``alignment.retry_inliers`` of the points, and one from the constant-velocity
            prediction explained at least that and ``hypothesis_margin`` more. 0, as
            ``max_ambiguous``: on simulated runs at 0.5 scans/s with the simulator's odometry no step
            doubts it (seeds 0, 1, 3, 7, 11, 21, 22), while an odometry frozen, constant, reversed or
            with a 1.6 rad spike gave 1-9 such steps a run, and ATE 1.8-4.3 m reported healthy before.
        degenerate_points, max_degenerate_drift: (default pipeline) not healthy when a stretch of
            degenerate matches may have drifted more than ``max_degenerate_drift`` (m) along its weak
            axis (``degenerate_drift``: a match is degenerate when its weakest position direction is
            held by fewer than ``degenerate_points`` points' worth, a corridor's axis; over a stretch
            of them, each new keyframe's std along that axis, its factor's (the match's own
            covariance, times ``keyframes.correlation_length``'s scale when on), at most the
            predictions' stds summed since the previous keyframe (what holds the pose along an axis
            the scan does not fix; a scan between keyframes counts what a keyframe there would
            reach, so a stretch that makes no keyframe counts too), summed as if every error had the same sign, since along such an
            axis the matching objective itself is biased). ``degenerate_points`` in [1, 8192] (0
            marked no step degenerate); ``max_degenerate_drift`` in [0.001, 1e6] m, and 1e6, its
            largest, turns the check off. Fixed before they were measured: 10 points' worth is where the
            MIT-like corridor's stall sat (7-13, against 30 at the median of tracked steps,
            docs/slam.md), and 0.3 m is ``slam.scanslam.DISTINCT_XY``, the distance at which two
            poses are told apart. Simulated corridor worlds at 1 degree lost track (ATE 0.2-3.2 m)
            and were reported healthy before.
    """

    nis_window: int = 20
    nis_divergence: float = 5.0
    point_window: int = 10
    point_min_score: float = 0.3
    max_ambiguous: float = 0.0
    min_matched_fraction: float = 0.9
    max_odometry_doubt: float = 0.0
    degenerate_points: float = 10.0
    max_degenerate_drift: float = 0.3

    def degenerate_stretch_flagged(self, drift: float) -> bool:
        """Whether a run whose ``degenerate_drift`` is ``drift`` (m) fails the degenerate-stretch
        check: above ``max_degenerate_drift``, unless that is its largest value (the check off)."""
        return drift > self.max_degenerate_drift and self.max_degenerate_drift < MAX_DEGENERATE_DRIFT_M


@dataclass(frozen=True)
class KeyframeConfig:
    """Keyframes of the default pipeline and the local map the scans are matched against.

    Attributes:
        distance, angle: a scan becomes a keyframe when it is this far (m) or turned this much (rad)
            from the current keyframe...
        min_inliers: ...or when it explains fewer than this fraction of its points on the local map.
        local_map: the local map holds the points of the newest this many keyframes (20 beat 10
            on the tuning runs, seeds 100-105 at 5 and 37.5 scans/s: mean ATE 2.6 against 3.4 cm)...
        voxel: ...thinned to one point per square of this side (m).
        correlation_length: (m; 0, the default, off) a keyframe factor's covariance (its match's)
            is multiplied by the explained points over the squares of this side that the matched
            points occupy (at least 1): points that close share the error of the map's wall they
            lie on, so they count as one. The factors are over-confident on the keyframe logs (a
            median whitened chi-square of 27-31 against 2.4). 1 m, fixed first and the only value
            tried, scales them by 1.1-8 (median 2.5 on Intel, 4.4 on MIT CSAIL); not the default:
            MIT CSAIL without odometry 0.0283 -> 0.0284 m, Intel without odometry worse (docs/slam.md).
    """

    distance: float = 0.3
    angle: float = 0.2
    min_inliers: float = 0.8
    local_map: int = 20
    voxel: float = 0.05
    correlation_length: float = 0.0


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
        max_sigma_xy: ...and fix the position to this std (m, from ``alignment.sigma_point``
            before the inflation) in every direction (a bare corridor does not fix its axis and
            cannot close a loop).
        gate_probability: ...and move the new keyframe by no more than the drift since the
            candidate allows: the correction's Mahalanobis distance against that drift (``drift``,
            below) plus the match's own covariance within this
            chi-square quantile (3 dof); only heading hypotheses inside that gate are tried (an
            aliased place half a turn or a door's spacing away is refused).
        kernel: robust loss of the closure factors, "cauchy" or "huber"...
        kernel_width: ...its width in whitened units (std of the closure's own noise, which is
            the closure match's covariance: its Hessian over its residual variance, as for the
            keyframe factors, so no global factor sets the balance between the two).
        prior_sigma: std of the first keyframe's prior (m and rad).
        drift: the drift the gate allows: "marginals" (the graph's marginals of the two keyframes
            added, their correlation left out: far from the start it allows metres even between
            keyframes a few apart) or "joint" (the covariance of the new keyframe relative to the
            candidate, from their joint marginal: the drift of the path between them, less what
            the closures in between fixed)...
        drift_inflation: ...times this (in [1, 1e6]). The keyframe factors and the closures are
            the matches' covariances, over-confident where the scans are 1 degree apart (Intel and
            ACES: a median chi-square of 27-31 against 2.4, 3 dof), and scaling them all scales the
            joint marginal alike.
        search: how a candidate is matched: "nearest" (the ICP from the new keyframe's estimate,
            reaching ``alignment.max_correspondence`` from it, against the nearest ``candidates``
            visits) or "window" (:func:`slam.keyframes.find_closure_window`: a correlative search
            over the window the two keyframes' relative uncertainty allows, accepted only when
            unambiguous; ``drift`` and ``drift_inflation`` are then not used)...
        window_inflation: ...whose window is ``sqrt(chi2(gate_probability, 3))`` std of the joint
            relative covariance times this (the keyframe factors' measured over-confidence on
            1-degree scans: a median chi-square of 27-31 per 3 dof, about 10)...
        window_xy, window_theta: ...at most this (m either side in x and y, rad either side)...
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
    max_sigma_xy: float = 0.016
    gate_probability: float = 0.999
    kernel: str = "huber"
    kernel_width: float = 1.0
    prior_sigma: float = 1e-4
    drift: str = "marginals"
    drift_inflation: float = 1.0
    search: str = "nearest"
    window_inflation: float = 10.0
    window_xy: float = 6.0
    window_theta: float = 0.26


@dataclass(frozen=True)
class SlamConfig:
    """Parameters of :func:`slam.run_slam`, in nested sections (each its own docstring). Units:
    metres, radians, seconds.

    preset: "default" (motion from scan matching, keyframe pose graph with loop closures, see
        :mod:`slam.scanslam`) or "paper" (the paper's EKF of section 4.1: constant-velocity model,
        line landmarks, :mod:`slam.filter`).
    extractor, extractor_params: ``features.extract(scan, method=extractor, **extractor_params)``;
        the method must be registered (``features.available_methods()``) and the params build its
        config, both checked here.
    motion, observations: both presets. alignment, keyframes, loop_closure: the default pipeline.
    association, landmarks, prealign: the paper preset's EKF. consistency: divergence checks.
    """

    preset: str = "default"
    extractor: str = "sensor"
    extractor_params: dict[str, Any] = field(default_factory=dict)
    motion: MotionConfig = field(default_factory=MotionConfig)
    observations: ObservationConfig = field(default_factory=ObservationConfig)
    alignment: AlignmentConfig = field(default_factory=AlignmentConfig)
    keyframes: KeyframeConfig = field(default_factory=KeyframeConfig)
    loop_closure: LoopClosureConfig = field(default_factory=LoopClosureConfig)
    association: AssociationConfig = field(default_factory=AssociationConfig)
    landmarks: LandmarkConfig = field(default_factory=LandmarkConfig)
    prealign: PrealignConfig = field(default_factory=PrealignConfig)
    consistency: ConsistencyConfig = field(default_factory=ConsistencyConfig)

    def __post_init__(self) -> None:
        if not is_one_of(self.preset, PRESETS):
            raise SlamConfigError(f"preset: must be one of {list(PRESETS)}, got {self.preset!r}")
        if not isinstance(self.extractor, str) or not self.extractor.strip():
            raise SlamConfigError(f"extractor: must be an extraction method's name, got {self.extractor!r}")
        if not isinstance(self.extractor_params, dict) or not all(isinstance(k, str) for k in self.extractor_params):
            raise SlamConfigError(f"extractor_params: must be a mapping of the method's config fields, "
                                  f"got {self.extractor_params!r}")
        _check_extractor(self.extractor, self.extractor_params)
        for name, cls in SECTIONS.items():
            value = getattr(self, name)
            if isinstance(value, dict):
                value = _section(cls, name, value)
            elif not isinstance(value, cls):
                raise SlamConfigError(f"{name}: expected a mapping of {cls.__name__} fields, got {value!r}")
            object.__setattr__(self, name, _checked_fields(value, name))
        if self.loop_closure.kernel not in ("cauchy", "huber"):
            raise SlamConfigError(f"loop_closure.kernel: must be 'cauchy' or 'huber', got {self.loop_closure.kernel!r}")
        if self.loop_closure.drift not in ("marginals", "joint"):
            raise SlamConfigError(f"loop_closure.drift: must be 'marginals' or 'joint', got {self.loop_closure.drift!r}")
        if self.loop_closure.search not in ("nearest", "window"):
            raise SlamConfigError(f"loop_closure.search: must be 'nearest' or 'window', got {self.loop_closure.search!r}")
        # every number's own interval (FIELD_RANGES, the probabilities, the shares) was checked by
        # _checked_fields above; what stays here depends on more than one field, or is no single number
        al = self.alignment
        _check_search(al)
        if len(al.heading_hypotheses) > MAX_HEADING_HYPOTHESES:  # 200,000 were taken: each retry scores them all
            raise SlamConfigError(f"alignment.heading_hypotheses: at most {MAX_HEADING_HYPOTHESES} offsets (one a degree "
                                  f"of a whole turn; each is scored on every retry), got {len(al.heading_hypotheses):,}")
        if any(abs(h) > 2 * math.pi for h in al.heading_hypotheses):  # 1e300 overflowed; a half turn may read 3.1416
            raise SlamConfigError(f"alignment.heading_hypotheses: offsets must be within +-2 pi rad, "
                                  f"got {shown(list(al.heading_hypotheses))}")
        voxel = self.keyframes.voxel
        if not (voxel == 0 or MIN_VOXEL_M <= voxel <= MAX_VOXEL_M):  # 1e-12: the cell grid's size overflowed
            raise SlamConfigError(f"keyframes.voxel: must be 0 (no thinning) or in [{MIN_VOXEL_M:g}, {MAX_VOXEL_M:g}] m, "
                                  f"got {voxel}")
        corr = self.keyframes.correlation_length
        if not (corr == 0 or MIN_VOXEL_M <= corr <= MAX_MATCH_RANGE_M):  # 1e-300: the squares' indices overflowed
            raise SlamConfigError(f"keyframes.correlation_length: must be 0 (off) or in [{MIN_VOXEL_M:g}, "
                                  f"{MAX_MATCH_RANGE_M:g}] m, got {corr}")
        a, m, lm = self.association, self.motion, self.landmarks
        if a.method not in ("nn", "jcbb"):
            raise SlamConfigError(f"association.method: must be 'nn' or 'jcbb', got {a.method!r}")
        if a.new_landmark_probability < a.gate_probability:
            raise SlamConfigError("association.new_landmark_probability: must be >= gate_probability")
        if lm.confirm_hits > lm.tentative_window + 1:  # 7 of a window of 6 confirmed no landmark: an empty map
            raise SlamConfigError(f"landmarks.confirm_hits: must be at most tentative_window + 1 "
                                  f"({lm.tentative_window + 1}, the sightings a landmark can have before it is "
                                  f"pruned), got {lm.confirm_hits}")
        if len(m.odom_noise) != 3:
            raise SlamConfigError(f"motion.odom_noise: must be 3 numbers (x, y, theta), got {len(m.odom_noise):,}: "
                                  f"{shown(list(m.odom_noise))}")  # 200,000 numbers were echoed whole, a 1 MB line
        # in [0, MAX_ODOM_NOISE], checked above (1e300: the std's square overflowed)
        noise = cast(tuple[float, float, float], tuple(float(v) for v in m.odom_noise))
        object.__setattr__(self, "motion", dataclasses.replace(m, odom_noise=noise))

    def to_dict(self) -> dict[str, Any]:
        """Plain nested mappings and lists (for YAML)."""
        d = dataclasses.asdict(self)
        d["motion"]["odom_noise"] = list(self.motion.odom_noise)
        d["alignment"]["heading_hypotheses"] = list(self.alignment.heading_hypotheses)
        return d

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> "SlamConfig":
        """Build from a mapping (e.g. parsed YAML); unknown keys raise SlamConfigError, and so does
        ``values`` that is no mapping (None, a number, a list: Python's TypeError "object is not
        iterable", or a list of names read as unknown fields; found by fuzzing the Python API)."""
        if not isinstance(values, Mapping):
            raise SlamConfigError(f"SlamConfig.from_dict: expected a mapping of SLAM config fields (section: fields), "
                                  f"got {type(values).__name__}")
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known, key=str)  # YAML keys may be null, numbers, true
        if unknown:
            raise SlamConfigError(f"unknown SLAM config field(s) {unknown}; known: {sorted(known)}")
        return cls(**values)


def _check_extractor(method: str, params: dict[str, Any]) -> None:
    """``method`` is registered in ``features.registry`` and ``params`` build its config: checked
    when the SlamConfig is built (``extractor="nope"`` was taken and failed when the run started).
    A user's ``MODULE:FUNCTION`` extractor must be registered first (the command line does that)."""
    from features.registry import UnknownMethodError, available_methods, is_method, make_config

    if not is_method(method):
        raise SlamConfigError(f"extractor: unknown extraction method {method!r}; registered methods "
                              f"(features.registry): {', '.join(available_methods())}")
    if not params:  # a method's default config is built and checked when it registers
        return
    try:
        make_config(method, **params)
    except UnknownMethodError as exc:  # "unknown parameter(s) [...] for method ...; known: [...]"
        raise SlamConfigError(f"extractor_params: {exc}") from None
    except LmsbenchError as exc:  # a ConfigError, whose message starts with the field's name
        raise SlamConfigError(f"extractor_params.{exc}") from None
    except (TypeError, ValueError) as exc:  # a user method's own config type
        raise SlamConfigError(f"extractor_params: {' '.join(str(exc).split())}") from None


def _check_search(al: AlignmentConfig) -> None:
    """The correlative search's fields (``slam.correlative``), whose memory grows as the inverse
    square of the steps: each within its bounds, and the window within ``MAX_SEARCH_POSES``."""
    # (name, low, high, unit, (why below, why above)): the same interval for every value outside it
    # (-1 and 0 said "must be > 0", 1e300 the interval), with the reason of the side it is on
    for name, lo, hi, unit, why in (
            ("search_sigmas", 1.0, MAX_SEARCH_SIGMAS, "std of the prediction", ("", "")),
            ("search_step_theta", MIN_SEARCH_STEP_THETA, math.pi, "rad", ("finer needs more memory than the search "
                                                                           "is worth", "at most half a turn")),
            ("search_resolution", MIN_SEARCH_RESOLUTION_M, MAX_SEARCH_RESOLUTION_M, "m",
             ("finer needs more memory than the search is worth", "coarser cells cannot place a candidate")),
            ("search_sigma", MIN_FIELD_SIGMA_M, MAX_SEARCH_SIGMA_M, "m",
             ("narrower, the field's d / sigma overflows", "the field grows by 3 of it on every side")),
            ("fit_sigma", MIN_FIELD_SIGMA_M, MAX_FIT_SIGMA_M, "m",
             ("narrower, r / sigma overflows", "wider, it cannot tell a loose fit from a tight one")),
            ("search_step", al.search_resolution, MAX_SEARCH_XY_M, "m",
             ("the window's step is at least one cell of search_resolution", "the window's widest half-side")),
            ("search_xy", al.search_step, MAX_SEARCH_XY_M, "m",
             ("the window's half-side is at least one search_step", "10 m/s for a second")),
            ("fit_margin", 0.0, 1.0, "", ("a fit is a share of points", "a fit is a share of points")),
            ("ambiguity_sigmas", 0.0, MAX_AMBIGUITY_SIGMAS, "std",
             ("", f"the prior tells poses apart by a few times search_sigmas (<= {MAX_SEARCH_SIGMAS:g}) std at most")),
            ("search_candidates", 1, MAX_SEARCH_CANDIDATES, "",
             ("each is refined by the ICP on every searched step",) * 2)):
        value = getattr(al, name)
        if not lo <= value <= hi:  # an empty reason is left out (fit_margin -1 printed "()")
            reason = why[0] if value < lo else why[1]
            raise SlamConfigError(f"alignment.{name}: {interval_text(lo, hi, unit, reason)}, got {short_number(value)}")
    poses = search_window_poses(al)
    if poses > MAX_SEARCH_POSES:
        raise SlamConfigError(f"alignment.search_xy / search_step / search_step_theta: the search window would hold "
                              f"{poses:,} poses (headings x positions), more than {MAX_SEARCH_POSES:,} (memory); make "
                              f"the steps coarser or search_xy smaller")


def search_window_poses(al: AlignmentConfig) -> int:
    """The most poses a correlative search window of ``al`` scores: headings (the whole turn at
    ``search_step_theta``) times positions (``search_xy`` either side at ``search_step``, in whole
    cells of ``search_resolution``); as ``slam.correlative.search`` lays them out."""
    cells = max(1, int(round(al.search_step / al.search_resolution)))
    side = 2 * int(math.floor(al.search_xy / (cells * al.search_resolution))) + 1
    headings = max(int(math.ceil(2 * math.pi / al.search_step_theta)),
                   2 * int(math.floor(math.pi / al.search_step_theta)) + 1)
    return headings * side * side


PRESETS = ("default", "paper")
MIN_SEARCH_STEP_THETA = 1e-3  # rad: at most 6,284 headings in a window
MIN_SEARCH_RESOLUTION_M = 0.01  # m: the likelihood field's finest cell (its raster is capped, slam.correlative)
MAX_SEARCH_RESOLUTION_M = 1.0  # m: twice the ICP's reach; coarser cells cannot place a candidate
MAX_SEARCH_XY_M = 10.0  # m: the window's widest half-side (10 m/s for a second)
MAX_SEARCH_SIGMA_M = 1.0  # m: the field's widest Gaussian (the field grows by 3 of it on every side)
MIN_FIELD_SIGMA_M = 1e-4  # m: the narrowest Gaussian of the likelihood field and of the fit (0.1 mm)
MAX_FIT_SIGMA_M = 1.0  # m: the fit's widest Gaussian (twice the ICP's reach)
MAX_AMBIGUITY_SIGMAS = 100.0  # std: the prior's window is at most search_sigmas (10) std wide
MIN_SIGMA_FLOOR = 1e-6  # m and rad: the prediction's std floor (its information, sigma^-2, stays finite)
MIN_NOISE_SIGMA, MAX_NOISE_SIGMA = 1e-6, 1e3  # m and rad: the noise stds of FIELD_RANGES (as the motion floors)
MIN_HUBER_M = 1e-6  # m: alignment.huber (1e-30 and below: gtsam's indeterminate system; the LMS200's quantum is 1 mm)
#: alignment.covariance_inflation: 1e4 and more left a 120 s office run 2.5-3.5 m off (0.007 m at 1 to 1000)
MIN_COVARIANCE_INFLATION, MAX_COVARIANCE_INFLATION = 0.01, 100.0
MAX_BEAM_TIME_INCREMENT_S = 0.01  # s between beams: a 1081-beam scan would take 10.8 s
MAX_HEADING_HYPOTHESES = 360  # alignment.heading_hypotheses: one a degree of a whole turn (the default 9)
MAX_ICP_ITERATIONS = 1000  # alignment.max_iterations / fine_iterations (defaults 10 / 5)
MAX_SIGMA_FLOOR = 1e3  # m and rad: a floor this wide leaves no motion model
MAX_SIGMA_MOTION = 1e3  # m/s^2 and rad/s^2: the constant-velocity model's widest acceleration std
#: m/s^2 and rad/s^2: its narrowest, a rigid constant velocity (1e-300 was 0 in all but name: the
#: default pipeline's floor-only prediction, the paper preset's rigid model; 1e-3 is both already)
MIN_SIGMA_MOTION = 1e-3
MAX_ODOM_NOISE = 10.0  # m/m, rad/rad, rad/m: ten times the motion itself, as the simulator's odometry alphas (sim.records)
MAX_SEARCH_SIGMAS = 10.0  # std: the window's half-width is search_sigmas std, its prior that width / search_sigmas
MAX_SEARCH_CANDIDATES = 32  # distinct poses refined per searched step (each an ICP run; the default 4)
MAX_SEARCH_POSES = 4_000_000  # poses of one window: 32 MB of scores (the default: 159,201)
SEARCH_CELL_M = 0.5  # m: cell of the scan matcher's search grid, the farthest a correspondence can reach
MAX_PRIOR_SIGMA = 1.0  # m and rad: loosest prior on the first keyframe that still anchors the graph
MIN_MATCH_RANGE_M = 0.1  # alignment.max_range: at least 10 cm (as the command line's --laser-range-max)
MIN_REACH_M = 1e-3  # m: alignment's correspondence reaches and inlier_distance, the LMS200's range quantum
MAX_MATCH_RANGE_M = 1e4  # alignment.max_range: at most 10 km (as the command line's --laser-range-max)
MIN_VOXEL_M, MAX_VOXEL_M = 1e-3, 10.0  # keyframes.voxel: a local map's cells (m), when thinned
MAX_DEGENERATE_DRIFT_M = 1e6  # consistency.max_degenerate_drift at this value: the degenerate-stretch check is off
MIN_MAX_GAP_S = 0.01  # s: motion.max_gap; the LMS200 scans at most 75 times a second, a Hokuyo 40
MIN_MAX_DT_S = 1e-3  # s: finest prediction step of the paper preset (a 10 s gap: at most 10,000 steps)
PI = math.pi
#: every numeric scalar field's accepted interval, checked when the config is built (SlamConfigError
#: "section.field: must be in [lo, hi] unit (why), got V", the same interval for a negative value as
#: for any other): (low, high, unit, low_open, why). Each is a physical bound, wide around the
#: default; beyond them a run did no useful work and ended exit 0 with at most a "not healthy"
#: warning (alignment.stride 1e12 matched one point a scan, damping 1e300 never moved a pose,
#: motion.sigma_accel 1e-300 was 0 in all but name). Fields missing here are checked by their own
#: rule in SlamConfig (the search window's, which depend on one another).
FieldRange = tuple[float, float, str, bool, str]
#: points of a scan the default pipeline's ICP needs at least (alignment.stride): 13, what stride 30 kept of a
#: 361-beam LMS200 scan, where a 10 s office run stayed healthy; 40 (10 points) left 40 % of its steps
#: unmatched, 60 (7) every one, exit 0 with a "not healthy" warning (the ICP itself takes 4: 3 dof)
MIN_MATCH_POINTS = 13
#: rad/s: alignment / prealign.max_turn_rate's widest; the turn allowed between scans is max_turn_rate * dt (and
#: prealign's turn_margin), so 1e4 allows any heading (100 rad) even at 100 scans/s, faster than any scanner's
MAX_TURN_RATE = 1e4
TURN_RATE_WHY = "the turn allowed between scans is it times their interval: 1e4 allows any heading at 100 scans/s"
NOISE_WHY = "a std whose square and inverse square stay finite"
FIELD_RANGES: dict[str, FieldRange] = {
    # alignment (the default pipeline's ICP)
    # up to the most beams a scan may have: 1e12 matched one point a scan; a stride that leaves fewer than
    # MIN_MATCH_POINTS of the first scan's beams is refused when the run starts (slam.run.check_first_scan)
    "alignment.stride": (1, MAX_BEAMS, "beams", False, "the most beams of a scan the extractors take"),
    "alignment.max_range": (MIN_MATCH_RANGE_M, MAX_MATCH_RANGE_M, "m", False, ""),
    "alignment.max_correspondence": (MIN_REACH_M, SEARCH_CELL_M, "m", False, "the LMS200's range quantum to the cell "
                                     "of the scan matcher's search grid"),
    "alignment.fine_correspondence": (MIN_REACH_M, SEARCH_CELL_M, "m", False, "the LMS200's range quantum to the cell "
                                      "of the scan matcher's search grid"),
    "alignment.huber": (MIN_HUBER_M, 1.0, "m", False, "a residual's scale: below it every point's weight vanishes; "
                        "beyond the 0.5 m reach every residual is quadratic alike"),
    "alignment.max_iterations": (1, MAX_ICP_ITERATIONS, "Gauss-Newton steps", False, ""),
    "alignment.fine_iterations": (0, MAX_ICP_ITERATIONS, "Gauss-Newton steps", False, ""),
    "alignment.tolerance_xy": (0, 0.1, "m", False, "a step below it ends a stage: 0.1 m, a fifth of the reach"),
    "alignment.tolerance_theta": (0, 0.1, "rad", False, "a step below it ends a stage"),
    "alignment.damping": (0, 1, "of the Hessian's mean eigenvalue", False, "1e300 held every pose at its prediction"),
    "alignment.inlier_distance": (MIN_REACH_M, 1.0, "m", False, "a shorter one pairs no point"),
    "alignment.sigma_point": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "m", False, NOISE_WHY),
    "alignment.covariance_inflation": (MIN_COVARIANCE_INFLATION, MAX_COVARIANCE_INFLATION, "", False,
                                       "a factor on the match's covariance; 1, the default, is none"),
    "alignment.retry_inliers": (0, 1, "", False, "a share of points"),
    "alignment.refine_hypotheses": (0, 100, "", False, "retry starts refined, each an ICP run"),
    "alignment.hypothesis_margin": (0, 1, "", False, "a share of points"),
    "alignment.min_inliers": (0, 1, "", False, "a share of points"),
    "alignment.normal_step": (1, 100, "beams", False, ""),
    "alignment.normal_gap": (MIN_REACH_M, 10, "m", False, ""),
    "alignment.normal_gap_per_range": (0, 1, "m per m of range", False, ""),
    "alignment.beam_time_increment": (0, MAX_BEAM_TIME_INCREMENT_S, "s between beams", False,
                                      "0: the LMS200's timing"),
    "alignment.normal_agreement": (0, PI, "rad", True, "pi: no normal check"),
    "alignment.search_points": (1, 16384, "points", False, "the most beams of a scan the extractors take"),
    # the headings searched are within max_turn_rate * dt (slam.scanslam): 100 rad/s allowed only 1.33 rad between
    # scans at 75 scans/s; MAX_TURN_RATE allows every heading (100 rad) even at 100 scans/s
    "alignment.max_turn_rate": (0.01, MAX_TURN_RATE, "rad/s", False, TURN_RATE_WHY),
    # motion
    "motion.sigma_accel": (MIN_SIGMA_MOTION, MAX_SIGMA_MOTION, "m/s^2", False,
                           "the prediction's std and its inverse square stay finite"),
    "motion.sigma_alpha": (MIN_SIGMA_MOTION, MAX_SIGMA_MOTION, "rad/s^2", False,
                           "the prediction's std and its inverse square stay finite"),
    "motion.sigma_floor_xy": (MIN_SIGMA_FLOOR, MAX_SIGMA_FLOOR, "m", False,
                              "the prediction's std and its inverse square stay finite"),
    "motion.sigma_floor_theta": (MIN_SIGMA_FLOOR, MAX_SIGMA_FLOOR, "rad", False,
                                 "the prediction's std and its inverse square stay finite"),
    "motion.jump_margin": (0, 1, "", False, "a share of points"),
    "motion.sigma_lateral": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "m/s", False, NOISE_WHY),
    "motion.max_dt": (MIN_MAX_DT_S, 3600, "s", False, "a gap is integrated in steps of at most max_dt"),
    "motion.max_gap": (MIN_MAX_GAP_S, 1e6, "s", False, "100 scans/s, faster than any scanner's, to about 12 days: "
                       "a shorter gap makes every step a gap"),
    "motion.odom_max_turn_error": (0, PI, "rad", False, ""),
    # observations (a min_line_points above the first scan's beams is refused when the run starts: slam.run.check_first_scan)
    "observations.min_line_points": (0, 16384, "beams", False, "the most beams of a scan the extractors take"),
    "observations.min_line_length": (0, 100, "m", False, ""),
    "observations.sigma_rho": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "m", False, NOISE_WHY),
    "observations.sigma_alpha_obs": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "rad", False, NOISE_WHY),
    "observations.sigma_corner": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "m", False, NOISE_WHY),
    "observations.point_stride": (1, 100, "beams", False, ""),
    "observations.max_lines": (1, 16384, "lines", False, ""),
    # association, landmarks (the paper preset)
    "association.extent_margin": (0, 100, "m", False, ""),
    "association.extent_sigmas": (0, 100, "std", False, ""),
    "landmarks.confirm_hits": (1, 1000, "sightings", False, ""),
    "landmarks.tentative_window": (1, 1000, "scans", False, ""),
    "landmarks.max_landmarks": (1, 10000, "landmarks", False, "the covariance is (5 + 2 n)^2 float64: 3.2 GB at 10,000"),
    # prealign (the paper preset)
    "prealign.radius": (0.1, 1000, "m", False, ""),
    "prealign.sigma_xy": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "m", False, NOISE_WHY),
    "prealign.sigma_phi": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "rad", False, NOISE_WHY),
    "prealign.min_fraction": (0, 1, "", False, "a share of line length"),
    "prealign.xy_turn": (0, PI, "rad", False, ""),
    "prealign.max_turn_rate": (0.01, MAX_TURN_RATE, "rad/s", False, TURN_RATE_WHY),
    "prealign.turn_margin": (0, PI, "rad", False, ""),
    "prealign.near_heading": (0, PI, "rad", False, ""),
    "prealign.verify_tolerance": (MIN_REACH_M, 1, "m", False, ""),
    "prealign.verify_margin": (0, 1, "", False, "a share of points"),
    "prealign.turn_rate_widening": (0, 100, "", False, ""),
    "prealign.min_map_line_length": (0, 100, "m", False, ""),
    "prealign.point_min_score": (0, 1, "", False, "a share of points"),
    "prealign.min_points": (1, 16384, "points", False, ""),
    "prealign.scan_velocity_min_score": (0, 1, "", False, "a share of points"),
    "prealign.scan_velocity_min_fraction": (0, 1, "", False, "a share of points"),
    "prealign.scan_velocity_sigma": (MIN_NOISE_SIGMA, MAX_NOISE_SIGMA, "m", False, NOISE_WHY),
    "prealign.scan_velocity_floor": (0, 100, "m/s", False, ""),
    "prealign.scan_velocity_baseline": (0, 100, "s", False, ""),
    # consistency
    "consistency.nis_window": (1, 100_000, "scans", False, ""),
    "consistency.nis_divergence": (1, 1e6, "per degree of freedom", False, "a consistent filter's is 1"),
    "consistency.point_window": (1, 100_000, "scans", False, ""),
    "consistency.point_min_score": (0, 1, "", False, "a share of points"),
    "consistency.max_ambiguous": (0, 1, "", False, "a share of steps"),
    "consistency.min_matched_fraction": (0, 1, "", False, "a share of steps"),
    "consistency.max_odometry_doubt": (0, 1, "", False, "a share of steps"),
    # 0 made no step degenerate (the check off, silently), 1e300 every matched one: the weaker of two directions
    # holds at most half of a scan's points (16384 beams at most)
    "consistency.degenerate_points": (1, 8192, "points' worth", False, "half the most beams of a scan"),
    # 0 flagged any degenerate keyframe; the largest, 1e6, turns the check off (ConsistencyConfig.degenerate_stretch_flagged)
    "consistency.max_degenerate_drift": (MIN_REACH_M, MAX_DEGENERATE_DRIFT_M, "m", False,
                                         f"{MAX_DEGENERATE_DRIFT_M:g}: the check off"),
    # keyframes (the default pipeline)
    "keyframes.distance": (MIN_REACH_M, 100, "m", False, ""),
    "keyframes.angle": (1e-3, PI, "rad", False, ""),
    "keyframes.min_inliers": (0, 1, "", False, "a share of points"),
    "keyframes.local_map": (1, 1000, "keyframes", False, "its points are matched at every scan"),
    # loop closures (the default pipeline)
    "loop_closure.every": (1, 1000, "keyframes", False, ""),
    "loop_closure.search_radius": (0.1, 1000, "m", False, ""),
    "loop_closure.search_growth": (0, 1, "m per m of path", False, ""),
    "loop_closure.min_travel": (0, 1e5, "m", False, ""),
    "loop_closure.candidates": (1, 100, "visits", False, ""),
    "loop_closure.visit_gap": (0, 100_000, "keyframes", False, ""),
    "loop_closure.submap": (0, 100, "keyframes", False, ""),
    "loop_closure.min_inliers": (0, 1, "", False, "a share of points"),
    "loop_closure.max_rms": (MIN_FIELD_SIGMA_M, 1, "m", False, ""),
    "loop_closure.max_sigma_xy": (MIN_FIELD_SIGMA_M, 10, "m", False, ""),
    "loop_closure.kernel_width": (0.01, 100, "std", False, ""),
    "loop_closure.prior_sigma": (MIN_NOISE_SIGMA, MAX_PRIOR_SIGMA, "m and rad", False,
                                 "a looser prior leaves the graph without an anchor"),
    "loop_closure.drift_inflation": (1, 1e6, "", False, "a factor on the drift the closure gate allows"),
    "loop_closure.window_inflation": (1, 1e6, "", False, "a factor on the relative covariance the closure window covers"),
    "loop_closure.window_xy": (0.1, 10, "m", False, ""),
    "loop_closure.window_theta": (0.01, PI, "rad", False, ""),
}
#: fields checked by their own rule in SlamConfig (``_check_search``: bounds that depend on one
#: another, or each side with its reason); their negative values are left to that rule too
OWN_RULE = frozenset({"alignment.search_sigmas", "alignment.search_step_theta", "alignment.search_resolution",
                      "alignment.search_sigma", "alignment.fit_sigma", "alignment.search_step", "alignment.search_xy",
                      "alignment.fit_margin", "alignment.ambiguity_sigmas", "alignment.search_candidates",
                      "keyframes.voxel", "keyframes.correlation_length"})


def field_range_text(where: str) -> str:
    """``"must be in [lo, hi] unit (why)"`` for the field ``where`` of FIELD_RANGES."""
    lo, hi, unit, lo_open, why = FIELD_RANGES[where]
    return interval_text(lo, hi, unit, why, lo_open)


def interval_text(lo: float, hi: float, unit: str, why: str, lo_open: bool = False) -> str:
    """``"must be in [lo, hi] unit (why)"``; no unit or reason where they are empty."""
    interval = f"{'(' if lo_open else '['}{lo:g}, {'pi' if hi == PI else f'{hi:g}'}]"
    return f"must be in {interval}{' ' + unit if unit else ''}{f' ({why})' if why else ''}"


def short_number(value: float) -> str:
    """A number for a message: ``1e+300`` taken as a whole number is not echoed with its 301 digits."""
    return f"{float(value):.6g}" if isinstance(value, int) and abs(value) >= 1e15 else str(value)


def in_range(where: str, value: float) -> bool:
    """Whether ``value`` lies in the field ``where``'s interval (FIELD_RANGES)."""
    lo, hi, _, lo_open, _ = FIELD_RANGES[where]
    return (lo < value if lo_open else lo <= value) and value <= hi


SECTIONS: dict[str, type] = {"motion": MotionConfig, "observations": ObservationConfig, "alignment": AlignmentConfig,
                             "keyframes": KeyframeConfig, "loop_closure": LoopClosureConfig,
                             "association": AssociationConfig, "landmarks": LandmarkConfig,
                             "prealign": PrealignConfig, "consistency": ConsistencyConfig}


UNIT_FRACTION_SUFFIXES = ("_fraction", "min_inliers", "retry_inliers", "min_score")  # shares of points, in [0, 1]
STEP_SHARES = ("max_ambiguous", "min_matched_fraction", "max_odometry_doubt")  # consistency: shares of a run's steps, in [0, 1]
SIGNED_TUPLES = ("heading_hypotheses",)  # rad: offsets either way; the other tuple, motion.odom_noise, holds factors
ODOM_NOISE_TEXT = f"must be factors in [0, {MAX_ODOM_NOISE:g}] (m/m, rad/rad, rad/m)"


def _checked_fields(section: Any, name: str) -> Any:
    """``section`` with every field checked against its annotated type (SlamConfigError naming
    ``name.field``): bools are bools, strings strings, ints whole numbers >= 0, floats finite and
    >= 0 (every scalar is a distance, angle, time, sigma, count or share), shares of points in
    [0, 1], probabilities in (0, 1), tuples finite numbers; numbers are stored as int / float. Range checks that involve
    more than one field stay in :class:`SlamConfig`."""
    hints = typing.get_type_hints(type(section))
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(section):
        where, value, kind = f"{name}.{f.name}", getattr(section, f.name), hints[f.name]
        origin = typing.get_origin(kind) or kind
        if kind is bool:
            if not isinstance(value, (bool, np.bool_)):
                raise SlamConfigError(f"{where}: must be true or false, got {value!r}")
            changes[f.name] = bool(value)
        elif kind is str:
            if not isinstance(value, str):
                raise SlamConfigError(f"{where}: must be a string, got {value!r}")
        elif kind in (int, float):
            number = _finite_number(where, value)
            if where in FIELD_RANGES and not in_range(where, number):  # the real interval, for -1 as for 1e300
                raise SlamConfigError(f"{where}: {field_range_text(where)}, got {value!r}")
            if f.name.endswith("_probability") and not 0 < number < 1:  # -1 too (it said "must be >= 0")
                raise SlamConfigError(f"{where}: a probability, must be in (0, 1), got {value!r}")
            if number < 0 and where not in OWN_RULE:
                raise SlamConfigError(f"{where}: must be >= 0, got {value!r}")
            if kind is int:
                if number != int(number):
                    raise SlamConfigError(f"{where}: must be a whole number, got {value!r}")
                number = int(number)
            elif f.name in STEP_SHARES and number > 1:
                raise SlamConfigError(f"{where}: a share of steps, must be in [0, 1], got {value!r}")
            elif f.name.endswith(UNIT_FRACTION_SUFFIXES) and number > 1:
                raise SlamConfigError(f"{where}: a share of points, must be in [0, 1], got {value!r}")
            changes[f.name] = number
        elif origin is tuple:
            if isinstance(value, (str, bytes, dict)) or not isinstance(value, (tuple, list, np.ndarray)):
                raise SlamConfigError(f"{where}: must be a list of numbers, got {value!r}")
            numbers = tuple(_finite_number(where, v) for v in value)
            if f.name not in SIGNED_TUPLES and not all(0 <= v <= MAX_ODOM_NOISE for v in numbers):
                # -1 said "must hold numbers >= 0" and 1e300 "factors of at most 10": one interval
                raise SlamConfigError(f"{where}: {ODOM_NOISE_TEXT}, got {shown(list(value))}")
            changes[f.name] = numbers
    return dataclasses.replace(section, **changes)


def _finite_number(where: str, value: Any) -> float:
    """``value`` as a finite float, or SlamConfigError naming ``where`` (bools are not numbers)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SlamConfigError(f"{where}: must be a number, got {value!r}")
    number = float_of(value, where, SlamConfigError)  # 10**400 was an OverflowError
    if not math.isfinite(number):
        raise SlamConfigError(f"{where}: must be finite, got {value!r}")
    return number


def _section(cls: type, name: str, values: dict[str, Any]) -> Any:
    """A section dataclass from a mapping; unknown keys raise SlamConfigError."""
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - known, key=str)
    if unknown:
        raise SlamConfigError(f"unknown field(s) {unknown} in SLAM config section {name!r}; known: {sorted(known)}")
    return cls(**values)  # types are checked by _checked_fields
