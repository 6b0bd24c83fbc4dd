"""The default pipeline: motion measured from the scan, a keyframe pose graph with loop closures.

Per scan: predict the pose from the last two poses (constant velocity; or, with
``motion.use_odometry``, from the odometry's step since the previous scan), match the scan's
points against the local map of the newest keyframes (:mod:`slam.icp`), and take the matched
pose. A scan far enough from the current keyframe becomes a keyframe: a factor between it
and the previous keyframe enters the gtsam graph, and every ``loop_closure.every`` keyframes the
earlier keyframes near the estimate are matched for a loop closure. The output trajectory is the
graph's: every scan's pose relative to its keyframe, composed with the keyframe's optimised pose.
Pure: no I/O, no clocks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING, Iterator

import numpy as np

from dataclasses import replace

from .config import MAX_SEARCH_CANDIDATES, AlignmentConfig, KeyframeConfig, LoopClosureConfig, MotionConfig
from .models import chi2_quantile, wrap
from .geometry import between, compose, rotate_covariance
from .correlative import Field, fit, free_share, free_space, make_field, search, see_through
from .icp import Match, Reference, chord_normals, chord_normals_at, match, refine
from .keyframes import DISTINCT_THETA, DISTINCT_XY, Keyframe, LoopClosure, find_closure, find_closure_window, local_map
from .posegraph import PoseGraph, robust_noise
from .run import Column

if TYPE_CHECKING:
    from .run import SlamResult

__all__ = ["DISTINCT_THETA", "DISTINCT_XY", "SEE_THROUGH_POOL", "ScanSlam", "ScanStep", "run_scan_slam"]

#: ``alignment.see_through``: the correlative search's best distinct window poses re-ranked by their
#: score less the share of the map they see through, of which the ``search_candidates`` best are
#: refined (the most ``search_candidates`` allows, 32, each an ICP run)
SEE_THROUGH_POOL = MAX_SEARCH_CANDIDATES


@dataclass
class ScanStep:
    """What one scan did (diagnostics)."""

    keyframe: int  # key of the keyframe the pose is stored against
    inliers: float = float("nan")  # fraction of the scan's points explained by the local map
    rms: float = float("nan")  # m
    hypothesis: int = 0  # ICP start that won (0 = the prediction)
    matched: bool = False  # the match was used (else the pose follows the prediction)
    new_keyframe: bool = False
    jump_rejected: bool = False  # the match jumped from the prediction and failed the point check
    searched: bool = False  # the correlative search ran (the motion may lie beyond the ICP's reach)
    fit: float = float("nan")  # the chosen pose's fit (slam.correlative.fit) when searched; less its see-through share (alignment.see_through) and its free-space share (alignment.free_space)
    ambiguous: bool = False  # the search found a distinct pose that fits as well, which the prior barely tells apart
    odometry: bool = False  # the prediction was the odometry's step (motion.use_odometry)
    odometry_doubt: bool = False  # its match was poor and the constant-velocity prediction's clearly better
    weak: float = float("nan")  # points' worth holding the match's weakest position direction (Hessian eigenvalue)
    weak_sigma: float = float("nan")  # the match's own std along that direction (m)
    prediction_sigma: float = float("nan")  # std (m) of the step's prediction (motion model or odometry), the ICP's start
    factor_scale: float = 1.0  # a keyframe factor's covariance over its match's (keyframes.correlation_length)
    loop: LoopClosure | None = None


def weakest_direction(m: Match) -> tuple[float, float]:
    """The points' worth that hold ``m``'s weakest position direction (the smallest eigenvalue of
    its Hessian's position block: each point on a surface adds its unit normal's square, Huber
    weights below 1) and the match's own std (m) along that direction (its covariance). Along a
    bare corridor's axis a few points' worth, across it tens."""
    w, v = np.linalg.eigh(0.5 * (m.hessian[:2, :2] + m.hessian[:2, :2].T))
    axis = v[:, 0]
    return float(w[0]), float(np.sqrt(max(float(axis @ m.covariance[:2, :2] @ axis), 0.0)))


def degenerate_drift(infos: list[ScanStep], points: float) -> tuple[float, int | None]:
    """The largest drift (m) a stretch of degenerate matches can have left along its weak axis, and
    the index of the scan where that stretch reached it (None without one). A step is degenerate
    when its match's weakest position direction is held by fewer than ``points`` points' worth (a
    corridor's axis); a matched step that is not ends the stretch. Within a stretch each new
    keyframe adds its factor's std along that direction (the match's, times the square root of
    ``keyframes.correlation_length``'s scale where that is on; the keyframe factors carry the
    drift: between keyframes a scan is matched against the same local map), at most the
    predictions' stds summed over the steps since the previous keyframe (or since the stretch
    began): along an axis the scan does not fix the pose is where the prediction put it, so that is
    what holds it there (a free axis's match std is 1/sqrt(1e-9) = 31,623 m, ``Match.covariance``'s
    regularisation, not a distance). Summed, not in quadrature: along such an axis the matching
    objective itself is biased (the ICP started at the true pose slides 0.1-0.2 m, docs/slam.md),
    so the steps' errors need not cancel. A degenerate scan between keyframes counts what a
    keyframe there would have added (its pose is held to the last keyframe by its own match the
    same way), without adding it to the stretch: so a stretch that makes no keyframe, where the
    estimate stands still along a corridor while the robot drives on, is counted too."""
    drift = DegenerateDrift(points)
    for i in infos:
        drift.add(i)
    return drift.best, drift.at


class DegenerateDrift:
    """:func:`degenerate_drift` fed one step at a time (``add``, in scan order; ``best``, ``at``: its
    result so far), so that a run need not keep its ScanStep records (~600 B a scan) to compute it."""

    def __init__(self, points: float) -> None:
        self.points = points
        self.best, self.cur, self.held, self.k = 0.0, 0.0, 0.0, 0  # k: the steps added
        self.at: int | None = None

    def add(self, i: ScanStep) -> None:
        k, self.k = self.k, self.k + 1
        if np.isfinite(i.prediction_sigma):
            self.held += i.prediction_sigma
        if not i.matched:
            if i.new_keyframe:  # the motion model's guess: neither adds nor ends a stretch, counted by matched_fraction
                self.held = 0.0
            return
        if not i.weak < self.points:
            self.cur = self.held = 0.0  # the match holds every direction: the stretch, and what the predictions held, start again
            return
        if np.isfinite(i.weak_sigma):
            reached = self.cur + min(i.weak_sigma * float(np.sqrt(i.factor_scale)), self.held)
            if reached > self.best:
                self.best, self.at = reached, k
            if i.new_keyframe:
                self.cur = reached
        if i.new_keyframe:
            self.held = 0.0


def correlated_scale(points: np.ndarray, inliers: float, length: float) -> float:
    """``keyframes.correlation_length``: the explained points (``inliers`` of ``points``, (n, 2))
    over the squares of side ``length`` (m) the points occupy, at least 1. Points that close lie on
    one wall and share the error of the map's points there, so a square counts as one measurement."""
    p = np.asarray(points, float).reshape(-1, 2)
    if p.shape[0] == 0:
        return 1.0
    cells = np.unique(np.floor(p / length).astype(np.int64), axis=0).shape[0]
    return max(1.0, float(inliers) * p.shape[0] / cells)


@dataclass
class ScanPoints:
    """A scan's points in the sensor frame: all valid ones in beam order (for the map), and the
    thinned subset that is matched."""

    valid: np.ndarray
    matched: np.ndarray
    cfg: AlignmentConfig

    @classmethod
    def from_points(cls, points: np.ndarray, cfg: AlignmentConfig) -> "ScanPoints":
        p = np.asarray(points, float).reshape(-1, 2)
        with np.errstate(over="ignore"):  # a point beyond 1e154 m squares to inf: beyond max_range, without numpy's warning
            p = p[np.isfinite(p[:, 0]) & (p[:, 0] ** 2 + p[:, 1] ** 2 <= cfg.max_range**2)]
        return cls(p, p[:: cfg.stride], cfg)

    @cached_property
    def _normals(self) -> tuple[np.ndarray, np.ndarray]:
        """Chord normals of the valid points (towards the sensor, so the map's two faces of a thin
        wall differ) and the mask of those on a surface (computed once per scan)."""
        cfg = self.cfg
        return chord_normals(self.valid, cfg.normal_step, cfg.normal_gap, cfg.normal_gap_per_range, True)

    def surface(self) -> tuple[np.ndarray, np.ndarray]:
        """The points that lie on a surface and their unit normals (towards the sensor), (p, 2) each."""
        n, ok = self._normals
        return self.valid[ok], n[ok]

    @cached_property
    def matched_normals(self) -> np.ndarray:
        """Unit normals (towards the sensor) of the matched points, (0, 0) where a point has none
        (its chord spans a depth jump): the chord normals of :meth:`surface`, at the matched
        beams only."""
        cfg = self.cfg
        p, k = self.valid, cfg.normal_step
        out = np.zeros_like(self.matched)
        idx = np.arange(0, p.shape[0], cfg.stride)
        inner = (idx >= k) & (idx < p.shape[0] - k)
        i = idx[inner]
        if i.size:
            n, ok = chord_normals_at(p, i, k, cfg.normal_gap, cfg.normal_gap_per_range, True)
            n[~ok] = 0.0
            out[inner] = n
        return out

    @cached_property
    def beams(self) -> tuple[np.ndarray, np.ndarray]:
        """Bearings (rad, ascending) and ranges (m) of the valid points (sensor frame), for
        :func:`slam.correlative.see_through`."""
        b = np.arctan2(self.valid[:, 1], self.valid[:, 0])
        order = np.argsort(b, kind="stable")
        return b[order], np.hypot(self.valid[order, 0], self.valid[order, 1])

    @property
    def points(self) -> np.ndarray:
        return self.surface()[0]

    @property
    def normals(self) -> np.ndarray:
        return self.surface()[1]


@dataclass
class ScanSlam:
    """Keyframe scan-matching SLAM; call :meth:`step` once per scan, then :meth:`trajectory`."""

    alignment: AlignmentConfig = field(default_factory=AlignmentConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    keyframes_cfg: KeyframeConfig = field(default_factory=KeyframeConfig)
    loop_cfg: LoopClosureConfig = field(default_factory=LoopClosureConfig)

    def __post_init__(self) -> None:
        self.keyframes: list[Keyframe] = []
        self.graph: PoseGraph | None = None
        self.ref: Reference | None = None
        self.pose = np.zeros(3)
        self.last: list[tuple[float, np.ndarray]] = []  # (stamp, pose) of the last two scans
        # per scan, in numpy blocks (slam.run.Column: 104 B a scan, where a list of a tuple, an int and two
        # arrays a scan held ~430 B): its keyframe's key, its pose in that keyframe's frame, the covariance of
        # its match (world frame); read as lists, as before the blocks, through :attr:`anchors` and :attr:`covariances`
        self.anchor_keys, self.anchor_poses = Column(np.int64), Column(np.float64, (3,))
        self._covariances = Column(np.float64, (3, 3))
        self.loops: list[LoopClosure] = []
        self._kf_xy = np.zeros((0, 2))  # keyframe positions (current estimates) and path lengths, as arrays
        self._kf_travel = np.zeros(0)
        self.travelled = 0.0
        self._since_search = 0
        self._closed_at = 0.0  # path length (m) at the last loop closure
        self._jump_gate = chi2_quantile(self.motion.jump_probability, 3)
        self._retry_gate = chi2_quantile(self.motion.jump_probability, 2)
        self._heading_gate = chi2_quantile(self.motion.jump_probability, 1)
        self._narrow = replace(self.alignment, max_iterations=0)
        self.predict_velocity = True
        self._field_cache: tuple[Reference, Field] | None = None
        self._odom: np.ndarray | None = None  # the previous scan's odometry pose (motion.use_odometry)
        self.restarts: list[int] = []  # scans after a step longer than motion.max_gap (the motion restarted)

    # -- one scan -------------------------------------------------------------------------------
    def predict(self, stamp: float) -> np.ndarray:
        """Constant-velocity prediction from the last two poses (the previous pose if fewer)."""
        if not self.last:
            return np.zeros(3)
        t1, p1 = self.last[-1]
        if len(self.last) < 2:
            return p1.copy()
        t0, p0 = self.last[-2]
        if t1 - t0 <= 0:
            return p1.copy()
        f = (stamp - t1) / (t1 - t0)
        d = between(p0, p1) * f
        return compose(p1, d)

    def velocity(self) -> np.ndarray:
        """(3,) twist (m/s, m/s, rad/s) in the sensor frame from the last two poses (zeros if fewer)."""
        if len(self.last) < 2 or self.last[1][0] <= self.last[0][0]:
            return np.zeros(3)
        (t0, p0), (t1, p1) = self.last
        return between(p0, p1) / (t1 - t0)

    def deskew(self, points: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """The scan's points (n, 2) in the sensor frame at the stamp (its first beam): beam i was
        measured ``offsets[i]`` s later, from where the constant-velocity motion had moved the
        sensor by then (first order in the motion over the scan's 6.7-20 ms)."""
        v = self.velocity()
        tau = np.asarray(offsets, float)
        a = v[2] * tau
        c, s = np.cos(a), np.sin(a)
        x, y = points[:, 0], points[:, 1]
        return np.column_stack((c * x - s * y + v[0] * tau, s * x + c * y + v[1] * tau))

    def step(self, stamp: float, points: np.ndarray, offsets: np.ndarray | None = None,
             odom: np.ndarray | None = None) -> ScanStep:
        """Process the scan taken at ``stamp`` (s, its first beam) with points (n, 2) in the sensor
        frame, in beam order (invalid beams as nan rows); ``offsets`` (n,), each beam's time (s)
        after the first (:func:`lms200.timing.beam_time_offsets`), undoes the motion during the
        scan when ``alignment.deskew`` is on. ``odom``: the odometry pose (x m, y m, theta rad, in
        the odometry's own frame) at the scan, or None; with ``motion.use_odometry`` its increment
        since the previous scan's is the prediction (:meth:`odometry_prediction`) wherever both
        scans have one and the step is one the search could check, else the constant-velocity
        model is."""
        if self.last and stamp - self.last[-1][0] > self.motion.max_gap:
            # a gap (a pause, two logs joined): no velocity across it; the motion restarts at the last pose
            self.last = self.last[-1:]
            self.restarts.append(self._covariances.size)  # this scan's index
        if offsets is not None and self.alignment.deskew and len(self.last) >= 2:
            points = self.deskew(np.asarray(points, float).reshape(-1, 2), offsets)
        sp = ScanPoints.from_points(points, self.alignment)
        odom_now = None if odom is None or not self.motion.use_odometry else np.asarray(odom, float).reshape(3)
        odom_before, self._odom = self._odom, odom_now
        if self.graph is None:
            return self._first(stamp, sp)
        dt = stamp - self.last[-1][0]
        predicted = None
        if odom_now is not None and odom_before is not None:
            predicted = self.odometry_prediction(odom_before, odom_now)
        by_odometry = predicted is not None
        if predicted is not None:
            pred, (sxy, sth) = predicted
        else:
            pred, (sxy, sth) = self.predict(stamp), self._motion_sigma(dt)
        info = ScanStep(keyframe=self.keyframes[-1].key, odometry=by_odometry, prediction_sigma=sxy)
        m: Match | None = None
        if sp.matched.shape[0] >= 10 and self.ref is not None:
            if by_odometry:  # the odometry's increment, not a guess: no start at the last pose
                starts = [pred]
            else:
                starts = [pred, self.last[-1][1]] if self.predict_velocity else [self.last[-1][1], pred]
                if len(self.last) < 2:  # the prediction is the last pose: one start
                    starts = starts[:1]
            prior = np.diag([sxy**-2, sxy**-2, sth**-2]) if self.alignment.motion_prior else None
            qn = sp.matched_normals if self.alignment.normal_agreement < np.pi else None
            # a wheel odometry may be tenths of a radian off over a step (a slip, a late stamp), not the half
            # turn that matches a corridor backwards: the retry's heading hypotheses stay within that
            reach = max(self.alignment.search_sigmas * sth, self.motion.odom_max_turn_error) if by_odometry else np.inf
            turn = None if by_odometry else self._turn_bound(dt)
            # motion.odom_retry_gate: a retry that found no heading slip keeps its position within the odometry's gate
            within = self._odometry_gate(pred, sxy, sth) if by_odometry and self.motion.odom_retry_gate else None
            m = match(sp.matched, self.ref, starts, self.alignment, reach, prior=prior, normals=qn, turn=turn,
                      within=within)
            m = self._check_jump(sp.matched, m, pred, sxy, sth, info, qn)
            # the search looks for motion beyond the ICP's reach; within the odometry's reach it runs only when
            # the odometry-held match fails (a wheel slip), not to trade the odometry for a better-fitting slide
            retry = self.alignment.min_inliers if by_odometry else self.alignment.retry_inliers
            turned = turn is not None and abs(wrap(m.pose[2] - turn[0])) > turn[1]
            if self.alignment.search and (self._beyond_reach(sxy) or m.inliers < retry or turned):
                m = self._search(sp, m, pred, sxy, sth, dt, info, qn, by_odometry)
            if turn is not None and abs(wrap(m.pose[2] - turn[0])) > turn[1]:
                # no pose within the bound fits (the search found none, or did not run): the scan says the robot
                # turned faster than a robot does, so the stamps do not time the motion; the retry as without it
                m = match(sp.matched, self.ref, starts, self.alignment, reach, prior=prior, normals=qn)
                m = self._check_jump(sp.matched, m, pred, sxy, sth, info, qn)
            al = self.alignment
            if by_odometry and (info.searched or m.inliers < al.retry_inliers):
                # the constant-velocity prediction's match, with the same heading reach (no match backwards)
                alt = match(sp.matched, self.ref, [self.predict(stamp)], al, reach, normals=qn)
                better = alt.inliers > m.inliers + al.hypothesis_margin
                if info.searched:
                    # the ICP found nothing at the odometry's step (the search had to run): it may be a glitch
                    # (a reset, a slip within its std), so that match competes as a retry does
                    if better:
                        m = alt
                else:
                    # a poor match from the odometry's step that one from the constant-velocity prediction
                    # beats clearly: the odometry may be wrong (frozen, reversed, a spike). Only said, not
                    # acted on: on the keyframe logs, whose odometry is right, that prediction slides along
                    # corridors (switching took Intel and ACES to 2.6 and 4.5 m), and it does not repair a
                    # wrong odometry either (simulated, 1.3-4.1 m)
                    info.odometry_doubt = better and alt.inliers >= al.retry_inliers
            info.inliers, info.rms, info.hypothesis = m.inliers, m.rms, m.start
            info.weak, info.weak_sigma = weakest_direction(m)
        if m is not None and m.inliers >= self.alignment.min_inliers:
            pose, cov = m.pose, m.covariance
            info.matched = True
        elif by_odometry:  # no match: the odometry's step, with its own uncertainty
            pose, cov = pred, np.diag([sxy, sxy, sth]) ** 2
        else:
            pose, cov = pred, np.diag([0.1, 0.1, 0.03]) ** 2
        self.travelled += float(np.hypot(*(pose[:2] - self.last[-1][1][:2])))
        kf = self.keyframes[-1]
        rel = between(kf.pose, pose)
        kc = self.keyframes_cfg
        if np.hypot(rel[0], rel[1]) >= kc.distance or abs(rel[2]) >= kc.angle or (
                info.matched and info.inliers < kc.min_inliers):
            moved = self._new_keyframe(stamp, sp, pose, rel, cov, info)
            if info.loop is not None:  # the closure moved the graph: move the previous pose along with
                t_prev, p_prev = self.last[-1]  # this one, so that the velocity has no jump
                self.last[-1] = (t_prev, compose(moved, between(pose, p_prev)))
            pose = moved
        self.pose = pose
        self._anchor(self.keyframes[-1].key, between(self.keyframes[-1].pose, pose), cov)
        self.last = [self.last[-1], (stamp, pose)]
        return info

    def _check_jump(self, points: np.ndarray, m: Match, pred: np.ndarray, sxy: float, sth: float, info: ScanStep,
                    normals: np.ndarray | None = None) -> Match:
        """The point check: a match further from the prediction than the prediction's std (``sxy``
        m, ``sth`` rad) allows is compared with a narrow-reach match started at the prediction
        (which cannot slide to an aliased place along a corridor); the jump stands unless that one
        explains clearly more of the scan's points."""
        mc = self.motion
        e = m.pose - pred
        e[2] = wrap(e[2])
        if (e[0] ** 2 + e[1] ** 2) / sxy**2 + e[2] ** 2 / sth**2 <= self._jump_gate:
            return m
        assert self.ref is not None
        near = refine(points, self.ref, pred, self._narrow, normals=normals)
        if near.inliers <= m.inliers + mc.jump_margin:
            return m
        info.jump_rejected = True
        return near

    def _odometry_gate(self, pred: np.ndarray, sxy: float, sth: float):
        """``within(pose)`` for a retry of an odometry-predicted match (a heading hypothesis): a pose
        whose heading lies outside the odometry's ``jump_probability`` chi-square gate (1 dof of
        ``sth`` rad) found a heading slip, and a slip leaves the odometry's step in doubt too, so any
        position goes; a pose whose heading agrees with the odometry's found no slip, so its
        position must agree as well (the same gate, 2 dof of ``sxy`` m): beyond it, it has slid to
        an aliased place along a corridor, which explains a few more points of a partial overlap."""
        bound_xy, bound_th = self._retry_gate * sxy**2, self._heading_gate * sth**2

        def within(pose: np.ndarray) -> bool:
            if wrap(float(pose[2] - pred[2])) ** 2 > bound_th:
                return True
            return float(np.sum((pose[:2] - pred[:2]) ** 2)) <= bound_xy

        return within

    def _turn_bound(self, dt: float) -> tuple[float, float] | None:
        """(last heading, rad) and the turn a robot makes at most in ``dt`` s (``max_turn_rate``,
        plus ``DISTINCT_THETA``), the search's bound; None when it allows the whole turn."""
        max_turn = self.alignment.max_turn_rate * max(dt, 0.0)
        return None if max_turn >= np.pi else (float(self.last[-1][1][2]), max_turn + DISTINCT_THETA)

    def _beyond_reach(self, sxy: float) -> bool:
        """The prediction's position std ``sxy`` (m) times ``search_sigmas`` exceeds the ICP's reach."""
        return self.alignment.search_sigmas * sxy > self.alignment.max_correspondence

    def _search(self, sp: ScanPoints, m: Match, pred: np.ndarray, sxy: float, sth: float, dt: float, info: ScanStep,
                normals: np.ndarray | None, by_odometry: bool = False) -> Match:
        """The correlative search (:mod:`slam.correlative`) about the prediction, and about the
        last pose when that lies outside the window: its best distinct poses, each refined by the
        ICP held near it (a prior of the window's step: the ICP does not slide along a corridor),
        compete with ``m``, the match from the prediction (or from one of its heading hypotheses).

        Headings are searched only within ``max_turn_rate * dt`` rad of the last pose's (``dt``
        s since it): the constant-velocity prediction's std grows with dt^2 (3 std of heading
        pass half a turn from 0.5 s on), a robot's turn rate does not. ``m`` stays unless a
        search pose fits (:func:`slam.correlative.fit`) better by more than ``fit_margin``, or it
        turned beyond that bound (plus ``DISTINCT_THETA``);
        then, among the search poses within ``fit_margin`` of the best fit, the one nearest the
        prediction or the last pose wins (Mahalanobis, the prediction's std truncated to the
        window: a half turn costs 9, a metre at most 2.25). ``info.ambiguous``: a pose
        ``DISTINCT_XY`` m or ``DISTINCT_THETA`` rad from the chosen one fits within
        ``fit_margin`` of the best and the prior prefers the chosen one by less than
        ``ambiguity_sigmas`` std.

        ``by_odometry`` (the prediction is the odometry's step): the search is about the
        prediction alone, its headings within ``search_sigmas`` std (the odometry's heading std)
        of the prediction's, and the prior is the prediction's (the last pose is no rival: the
        odometry says how far the robot went)."""
        al = self.alignment
        assert self.ref is not None
        info.searched = True
        half_xy = min(al.search_sigmas * sxy, al.search_xy)
        half_th = min(al.search_sigmas * sth, np.pi)
        if by_odometry:
            last = pred
            max_turn = half_th
        else:
            last = self.last[-1][1]
            max_turn = al.max_turn_rate * max(dt, 0.0)
        turn = (float(last[2]), max_turn) if max_turn < np.pi else None
        centres = [pred]
        if np.any(np.abs(last[:2] - pred[:2]) > half_xy):
            centres.append(last)
        field = self._field(pred, al.max_range + half_xy + float(np.hypot(*(last[:2] - pred[:2]))))
        pts = sp.valid[:: max(1, -(-sp.valid.shape[0] // al.search_points))]
        hold = np.diag([al.search_step**-2, al.search_step**-2, al.search_step_theta**-2])
        results = [m]
        for c in centres:
            cands = search(pts, field, c, half_xy, half_th, al.search_step, al.search_step_theta,
                           SEE_THROUGH_POOL if al.see_through else al.search_candidates, DISTINCT_XY, DISTINCT_THETA,
                           turn)
            if al.see_through:  # the window's best poses, less the share of the map each sees through
                score = [cd.score - self._see_through(sp, cd.pose) for cd in cands]
                cands = [cands[i] for i in np.argsort(-np.array(score), kind="stable")[:al.search_candidates]]
            for cand in cands:
                r = refine(sp.matched, self.ref, cand.pose, al, prior=hold, normals=normals)
                if turn is not None and abs(wrap(r.pose[2] - last[2])) > max_turn + DISTINCT_THETA:
                    continue  # the refinement turned it beyond reach
                results.append(Match(r.pose, r.information, r.inliers, r.rms, r.n_points, r.hessian, -1))
        min_cos = float(np.cos(al.normal_agreement))
        fits = [fit(sp.matched, normals, self.ref, r.pose, al.fine_correspondence, al.fit_sigma, min_cos)
                for r in results]
        if al.see_through:  # the share of the map in view that the scan sees through counts against a pose
            fits = [f - self._see_through(sp, r.pose) for f, r in zip(fits, results)]
        if al.free_space:  # the share of the scan's points in space the map's beams crossed counts against it
            fits = [f - free_share(sp.matched, field, r.pose) for f, r in zip(fits, results)]
        best = max(fits)
        close = [i for i, f in enumerate(fits) if f >= best - al.fit_margin]
        wxy, wth = half_xy / al.search_sigmas, half_th / al.search_sigmas  # the prior, truncated to the window

        def distance(r: Match) -> float:
            out = np.inf
            for c in (pred, last):
                e = r.pose - c
                out = min(out, float((e[0] ** 2 + e[1] ** 2) / wxy**2 + wrap(e[2]) ** 2 / wth**2))
            return out

        prior = {i: distance(results[i]) for i in close}
        # the prediction's match unless clearly beaten, and only within the turn bound (it may come
        # from a heading hypothesis up to half a turn off, which the search's candidates may not)
        keep = 0 in close and not (turn is not None and abs(wrap(m.pose[2] - last[2])) > max_turn + DISTINCT_THETA)
        k = 0 if keep else min(close, key=prior.__getitem__)
        chosen = results[k]
        info.fit = fits[k]
        for i in close:
            r = results[i]
            if (np.hypot(*(r.pose[:2] - chosen.pose[:2])) > DISTINCT_XY or abs(wrap(r.pose[2] - chosen.pose[2])) >
                    DISTINCT_THETA) and prior[i] - prior[k] < al.ambiguity_sigmas**2:
                info.ambiguous = True
        return chosen

    def _see_through(self, sp: ScanPoints, pose: np.ndarray) -> float:
        """The share of the local map's points in the scan's view at ``pose`` that its beams pass
        (:func:`slam.correlative.see_through`, with the chord test's tolerance for one surface)."""
        al = self.alignment
        assert self.ref is not None
        bearings, ranges = sp.beams
        return see_through(self.ref.points, pose, bearings, ranges, al.normal_gap, al.normal_gap_per_range,
                           al.max_range)

    def _field(self, centre: np.ndarray, radius: float) -> Field:
        """The likelihood field of the local map about ``centre`` (kept while the map is unchanged)."""
        al = self.alignment
        assert self.ref is not None
        if self._field_cache is None or self._field_cache[0] is not self.ref:
            fld = make_field(self.ref.points, al.search_resolution, al.search_sigma, centre, radius)
            if al.free_space:
                kfs = self.keyframes[-self.keyframes_cfg.local_map:]
                fld = free_space(fld, np.array([kf.pose[:2] for kf in kfs]), [kf.world()[0] for kf in kfs],
                                 al.normal_gap, al.normal_gap_per_range, al.search_sigma)
            self._field_cache = (self.ref, fld)
        return self._field_cache[1]

    def odometry_prediction(self, odom_before: np.ndarray,
                            odom_now: np.ndarray) -> tuple[np.ndarray, tuple[float, float]] | None:
        """The pose the odometry predicts (the last pose composed with the odometry's increment
        between two scans, in the robot's frame) and the std of that step (m, rad):
        ``a_t d + sigma_floor_xy`` and ``a_r |dtheta| + a_rt d + sigma_floor_theta`` for a step of
        ``d`` m and ``dtheta`` rad (``motion.odom_noise`` = (a_t, a_r, a_rt), the paper preset's
        odometry model). None for a step no match could check: one longer than
        ``alignment.max_range`` (the two scans would share nothing), one whose ``search_sigmas``
        std is wider than ``alignment.search_xy`` (with the defaults a step over 6.6 m between two
        scans: an odometry reset or a glitch; a 1 km jump made a 100 m std, which the pose graph
        could not solve), or one that is not finite."""
        delta = between(odom_before, odom_now)
        dist, turn = float(np.hypot(delta[0], delta[1])), abs(float(delta[2]))
        a_t, a_r, a_rt = self.motion.odom_noise
        mc, al = self.motion, self.alignment
        sxy, sth = a_t * dist + mc.sigma_floor_xy, a_r * turn + a_rt * dist + mc.sigma_floor_theta
        if not (np.isfinite(sth) and dist <= al.max_range and al.search_sigmas * sxy <= al.search_xy):
            return None
        return compose(self.last[-1][1], delta), (sxy, sth)

    def _motion_sigma(self, dt: float) -> tuple[float, float]:
        """Std (m, rad) of the constant-velocity prediction over ``dt`` s."""
        mc = self.motion
        dt2 = max(dt, 0.0) ** 2
        return mc.sigma_accel * dt2 + mc.sigma_floor_xy, mc.sigma_alpha * dt2 + mc.sigma_floor_theta

    def _anchor(self, key: int, pose: np.ndarray, cov: np.ndarray) -> None:
        """Keep the scan's keyframe ``key``, its ``pose`` in that keyframe's frame and its match's ``cov``."""
        self.anchor_keys.append(key)
        self.anchor_poses.append(pose)
        self._covariances.append(cov)

    def _first(self, stamp: float, sp: ScanPoints) -> ScanStep:
        self.graph = PoseGraph(np.zeros(3), self.loop_cfg.prior_sigma)
        self.keyframes.append(Keyframe(0, 0, stamp, np.zeros(3), *sp.surface(), 0.0))
        self._kf_xy, self._kf_travel = np.zeros((1, 2)), np.zeros(1)
        self.ref = local_map(self.keyframes, self.keyframes_cfg.voxel)
        self._anchor(0, np.zeros(3), np.zeros((3, 3)))
        self.last = [(stamp, np.zeros(3))]
        return ScanStep(keyframe=0, new_keyframe=True)

    def _new_keyframe(self, stamp: float, sp: ScanPoints, pose: np.ndarray, rel: np.ndarray, cov: np.ndarray,
                      info: ScanStep) -> np.ndarray:
        """Add the scan as a keyframe (and perhaps close a loop); returns its pose after optimisation."""
        assert self.graph is not None
        if info.matched and self.keyframes_cfg.correlation_length > 0:
            info.factor_scale = correlated_scale(sp.matched, info.inliers, self.keyframes_cfg.correlation_length)
            cov = cov * info.factor_scale
        key = self.graph.add(rel, rotate_covariance(cov, -pose[2]), pose)  # world -> frame of pose
        kf = Keyframe(key, self.anchor_keys.size, stamp, pose.copy(), *sp.surface(), self.travelled)
        self.keyframes.append(kf)
        self._kf_xy = np.vstack((self._kf_xy, pose[:2]))
        self._kf_travel = np.append(self._kf_travel, self.travelled)
        info.new_keyframe = True
        info.keyframe = key
        self._since_search += 1
        lc = self.loop_cfg
        if lc.enabled and self._since_search >= lc.every and sp.matched.shape[0] >= 10:
            self._since_search = 0
            normals = sp.matched_normals if self.alignment.normal_agreement < np.pi else None
            loop: LoopClosure | None
            if lc.search == "window":
                graph = self.graph
                loop = find_closure_window(
                    kf, sp.matched, self.keyframes[:-1], lc, self.alignment, self.keyframes_cfg.voxel,
                    lambda cand: rotate_covariance(graph.relative_covariance(cand.key, kf.key), kf.pose[2]),
                    self._kf_xy[:-1], self._kf_travel[:-1], normals)
            else:
                loop = find_closure(kf, sp.matched, self.keyframes[:-1], lc, self.alignment, self.keyframes_cfg.voxel,
                                    self.travelled - self._closed_at, self._drift(kf), self._kf_xy[:-1],
                                    self._kf_travel[:-1], normals)
            if loop is not None:
                self._closed_at = self.travelled
                noise = robust_noise(loop.covariance, lc.kernel, lc.kernel_width)
                self.graph.close(loop.old, loop.new, loop.relative, noise)
                self.loops.append(loop)
                info.loop = loop
                poses = self.graph.poses()
                for k, p in enumerate(poses):
                    self.keyframes[k].pose = p
                self._kf_xy = poses[:, :2].copy()
        self.ref = local_map(self.keyframes[-self.keyframes_cfg.local_map:], self.keyframes_cfg.voxel)
        return self.keyframes[-1].pose.copy()

    def _drift(self, new: Keyframe):
        """``drift(candidate)``: world-frame covariance (3, 3) of the error of ``new``'s estimate
        relative to the candidate's, times ``loop_closure.drift_inflation``: from the graph's
        marginals of both (``drift: marginals``, their correlation left out, which can only widen
        the gate), or from their joint marginal (``drift: joint``)."""
        assert self.graph is not None
        graph = self.graph
        scale = self.loop_cfg.drift_inflation
        if self.loop_cfg.drift == "joint":
            return lambda cand: scale * rotate_covariance(graph.relative_covariance(cand.key, new.key), new.pose[2])
        own: list[np.ndarray] = []  # computed at the first candidate (most searches have none)

        def drift(cand: Keyframe) -> np.ndarray:
            if not own:
                own.append(rotate_covariance(graph.covariance(new.key), new.pose[2]))
            dx, dy = new.pose[0] - cand.pose[0], new.pose[1] - cand.pose[1]
            J = np.array([[1.0, 0.0, -dy], [0.0, 1.0, dx], [0.0, 0.0, 1.0]])  # the candidate's heading error moves new
            return scale * (own[0] + J @ rotate_covariance(graph.covariance(cand.key), cand.pose[2]) @ J.T)

        return drift

    # -- output ---------------------------------------------------------------------------------
    def keyframe_poses(self) -> np.ndarray:
        assert self.graph is not None
        return self.graph.poses()

    def pose_covariances(self) -> np.ndarray:
        """(n, 3, 3) world-frame covariance of every scan's pose in :meth:`trajectory`: its
        keyframe's marginal from the graph (relative to the first keyframe) composed with the
        scan's match covariance against the local map."""
        assert self.graph is not None
        kp = self.keyframe_poses()
        kcov = [rotate_covariance(self.graph.covariance(k), kp[k][2]) for k in range(len(kp))]
        out = np.empty((self.anchor_keys.size, 3, 3))
        for i, (k, rel, cov) in enumerate(self._anchors()):
            p = compose(kp[k], rel)
            J = np.array([[1.0, 0.0, -(p[1] - kp[k][1])], [0.0, 1.0, p[0] - kp[k][0]], [0.0, 0.0, 1.0]])
            out[i] = J @ kcov[k] @ J.T + (cov if rel.any() else 0.0)
        return out

    def trajectory(self) -> np.ndarray:
        """(n, 3) world pose of every scan: its keyframe's optimised pose composed with the scan's
        pose relative to that keyframe."""
        kp = self.keyframe_poses()
        out = np.empty((self.anchor_keys.size, 3))
        for i, (k, rel, _) in enumerate(self._anchors()):
            out[i] = compose(kp[k], rel)
        return out

    def _anchors(self) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """Every scan's keyframe key, pose in that keyframe's frame and match covariance, in scan order."""
        for keys, poses, covs in zip(self.anchor_keys.blocks(), self.anchor_poses.blocks(), self._covariances.blocks()):
            yield from zip(keys.tolist(), poses, covs)

    @property
    def anchors(self) -> list[tuple[int, np.ndarray]]:
        """Every scan's (keyframe key, (3,) pose (m, m, rad) in that keyframe's frame), in scan order: a
        list built from the blocks at each read (a copy: changing it changes nothing in the run)."""
        return [(k, rel.copy()) for k, rel, _ in self._anchors()]

    @property
    def covariances(self) -> list[np.ndarray]:
        """Every scan's (3, 3) match covariance (world frame), in scan order: a list built from the
        blocks at each read (a copy, as :attr:`anchors`); :meth:`pose_covariances` adds the graph's."""
        return [cov.copy() for _, _, cov in self._anchors()]


#: the ScanStep fields a run keeps per scan (its diagnostics), with their dtypes
STEP_COLUMNS = {"inliers": np.float64, "matched": np.bool_, "keyframe": np.int64, "hypothesis": np.int64,
                "ambiguous": np.bool_, "weak": np.float64, "weak_sigma": np.float64, "searched": np.bool_,
                "fit": np.float64, "odometry": np.bool_, "odometry_doubt": np.bool_}


def run_scan_slam(steps, config) -> "SlamResult":
    """The default pipeline over (stamp s, scan, odometry pose or None, true pose or None) steps; see
    :func:`slam.run_slam`. The odometry is used only with ``config.motion.use_odometry``.

    The trajectory and the keyframes come from the optimised pose graph; the map is the lines
    extracted on the keyframes (``features.extract_many``, once at the end), placed by their
    optimised poses and merged (:mod:`slam.linemap`).
    """
    from .linemap import merge_lines
    from .filter import SlamInputError, out_of_order
    from .run import SlamResult, extract_all, lost_against_scan, pose_nees

    slam = ScanSlam(config.alignment, config.motion, config.keyframes, config.loop_closure)
    cc = config.consistency
    # per scan, in numpy blocks (Column), not a list of its ScanStep, stamp and truth (~990 B a scan at the
    # peak of a run, 6.4 GB at MAX_SLAM_SCANS): its stamp, true pose (nan: none) and the diagnostics kept
    stamps, truths, has_truth = Column(np.float64), Column(np.float64, (3,)), Column(np.bool_)
    steps_kept = {name: Column(kind) for name, kind in STEP_COLUMNS.items()}
    drifts = DegenerateDrift(cc.degenerate_points)
    kf_scans: dict[int, object] = {}  # keyframe key -> its scan, for the map's lines
    previous = None
    for k, (t, scan, odom, truth) in enumerate(steps):
        t = float(t)
        if previous is not None and t < previous:
            raise out_of_order(k, t, previous)
        previous = t
        info = slam.step(t, scan.points, _offsets(scan, config.alignment), odom)
        if info.new_keyframe:
            kf_scans[info.keyframe] = scan
        stamps.append(t)
        truths.append(np.nan if truth is None else truth)
        has_truth.append(truth is not None)
        for name, column in steps_kept.items():
            column.append(getattr(info, name))
        drifts.add(info)
    if not stamps.size:
        raise SlamInputError("no scans in the input")
    poses = slam.trajectory()
    kposes = slam.keyframe_poses()
    t_all = stamps.taken()
    traj = np.column_stack((t_all, poses))
    covs = slam.pose_covariances()
    keys = list(kf_scans)
    fsets = extract_all([kf_scans[k] for k in keys], config)  # one compiled call over the keyframes
    segs = [_place(kposes[key], seg) for key, fs in zip(keys, fsets) if (seg := _segments(fs, config)).size]
    lines = merge_lines(np.concatenate(segs) if segs else np.zeros((0, 4)))
    kept = {name: column.taken() for name, column in steps_kept.items()}
    inliers, matched = kept["inliers"], kept["matched"]
    true_poses = truths.taken()
    nees = pose_nees(traj, covs, (row if has else None for row, has in zip(true_poses, has_truth.taken())))
    diverged_at = None
    for k in range(len(t_all)):
        if lost_against_scan(inliers[:k + 1], cc):
            diverged_at = float(t_all[k])
            break
    finite = nees[np.isfinite(nees)]
    ambiguous = kept["ambiguous"]
    drift, drift_at = drifts.best, drifts.at
    ambiguous_fraction = float(ambiguous[1:].mean()) if ambiguous.size > 1 else 0.0
    matched_fraction = float(matched[1:].mean()) if matched.size > 1 else 1.0
    diag = {
        "inliers": inliers, "matched": matched, "nees": nees,
        "keyframe": kept["keyframe"], "hypothesis": kept["hypothesis"],
        "n_keyframes": len(slam.keyframes), "n_loops": len(slam.loops),
        "loops": [{"old": lp.old, "new": lp.new, "inliers": lp.inliers, "rms": lp.rms, "correction": lp.correction,
                   "old_stamp": slam.keyframes[lp.old].stamp, "new_stamp": slam.keyframes[lp.new].stamp}
                  for lp in slam.loops],
        "keyframes": np.column_stack(([kf.stamp for kf in slam.keyframes], kposes)),
        "diverged": diverged_at is not None, "diverged_at": diverged_at,
        "healthy": (bool(np.all(np.isfinite(poses))) and diverged_at is None
                    and ambiguous_fraction <= config.consistency.max_ambiguous
                    and matched_fraction >= config.consistency.min_matched_fraction
                    and not cc.degenerate_stretch_flagged(drift)),
        "weak": kept["weak"], "weak_sigma": kept["weak_sigma"],
        "degenerate_fraction": float(np.mean(matched[1:] & (kept["weak"][1:] < cc.degenerate_points)))
        if len(t_all) > 1 else 0.0,
        "degenerate_drift": drift, "degenerate_drift_at": None if drift_at is None else float(t_all[drift_at]),
        "searched": kept["searched"], "ambiguous": ambiguous, "fit": kept["fit"],
        "searched_fraction": float(np.mean(kept["searched"][1:])) if len(t_all) > 1 else 0.0,
        "ambiguous_fraction": ambiguous_fraction,
        "mean_nis_per_dof": float("nan"), "mean_nees": float(finite.mean()) if finite.size else float("nan"),
        "matched_fraction": matched_fraction,
    }
    if config.motion.use_odometry:  # the steps the odometry predicted (the rest: no odometry, or a step beyond the search)
        diag["odometry_fraction"] = float(np.mean(kept["odometry"][1:])) if len(t_all) > 1 else 0.0
        doubt = kept["odometry_doubt"]
        diag["odometry_doubt"] = doubt
        diag["odometry_doubt_fraction"] = float(doubt[1:].mean()) if len(t_all) > 1 else 0.0
        diag["healthy"] = diag["healthy"] and diag["odometry_doubt_fraction"] <= config.consistency.max_odometry_doubt
    return SlamResult(traj, covs, lines, np.zeros((0, 3)), diag)


def _offsets(scan, alignment: AlignmentConfig | None = None) -> np.ndarray | None:
    """Each beam's time after the scan's first beam (s): ``alignment.beam_time_increment`` apart in
    beam order where it is set, else the LMS200's interlaced mirror timing where the scan has an
    LMS200's shape, else None (no de-skew: the scanner and its clock are unknown). The LMS200's timing
    was used for every scan: a 1081-beam 270 deg Hokuyo scan at 0.25 deg was de-skewed as four
    interlaced turns, neighbours 13 ms apart, which bent what it was meant to straighten (ATE
    0.9 -> 4.3 cm on a simulated run, docs/slam.md). ``alignment`` None: the default config's."""
    increment = alignment.beam_time_increment if alignment is not None else 0.0
    return _beam_times(scan.ranges.shape[0], float(scan.angle_increment), increment)


@lru_cache(maxsize=8)
def _beam_times(n_beams: int, angle_increment: float, increment: float) -> np.ndarray | None:
    from lms200.timing import beam_time_offsets, lms200_shaped

    if increment > 0:
        return np.arange(n_beams) * increment
    return beam_time_offsets(n_beams, angle_increment) if lms200_shaped(n_beams, angle_increment) else None


def _segments(fs, config) -> np.ndarray:
    """(k, 4) sensor-frame segments of the extracted lines long and well supported enough."""
    ln, obs = fs.lines, config.observations
    keep = ~((ln.n_points > 0) & (ln.n_points < obs.min_line_points)) & ~(ln.length < obs.min_line_length)
    return np.asarray(ln.values[keep, 2:6], float).reshape(-1, 4)


def _place(pose: np.ndarray, seg: np.ndarray) -> np.ndarray:
    from .geometry import to_world

    return np.column_stack((to_world(pose, seg[:, :2]), to_world(pose, seg[:, 2:])))
