"""The SLAM loop: predict, pre-align, associate, update, manage the map. Pure: no I/O, no clocks."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from features.baselines.checks import finite, is_real
from lms200.errors import InputError, LmsbenchError
from lms200.finite import shown
from lms200.records import pose_of

from .models import chi2_quantile

from . import association as assoc
from . import models
from .config import SlamConfig
from .ekf import SlamEKF, stacked_H, stacked_h, stacked_residual
from .models import ROBOT_DIM, wrap
from .observations import Observations
from .pointalign import align_to_previous, beam_normals, point_to_line_translation
from .prealign import align


class SlamInputError(LmsbenchError, ValueError):
    """The records cannot be processed (no scans, time going backwards)."""


def checked_step(k: int, t: object, obs: object, odom: object, truth: object) -> tuple[float, Any, Any]:
    """Step ``k``'s stamp as a float, its odometry and true poses as float tuples (or None);
    SlamInputError naming the scan otherwise. Found by fuzzing the Python API: a nan or inf stamp
    was "cannot convert float NaN to integer" deep in the filter, text numpy's ValueError, an
    item that is no Observations an AttributeError, a true pose of text an IndexError."""
    if not (is_real(t) and finite(t)):
        # shown: one line, cut past 60 characters (an Observations' repr was 187 lines)
        raise SlamInputError(f"scan {k}: its stamp must be a finite number (s), got {shown(t)}")
    stamp = float(t)  # type: ignore[arg-type]  # a real number: is_real
    if not isinstance(obs, Observations):
        raise SlamInputError(f"scan {k}: its observations must be a slam.Observations, got {type(obs).__name__}")
    try:
        return stamp, None if odom is None else pose_of("odometry", odom), None if truth is None else pose_of("truth", truth)
    except InputError as exc:
        raise SlamInputError(f"scan {k}: {exc}") from None


def out_of_order(k: int, t: float, previous: float) -> SlamInputError:
    """The error of scan ``k`` stamped ``t`` s, before the scan ahead of it (``previous`` s), saying
    how to go on: Intel's corrected log has 4 such scans, and ``run_slam(read_log(...))`` stopped
    there with no word of what to do (a library walkthrough; ``lmsbench slam --skip-bad-lines``
    drops them)."""
    return SlamInputError(f"scan {k}: timestamp {t} is earlier than the previous one ({previous}); SLAM needs scans in "
                          "time order: drop those out of order (experiments.commands.slam.in_time_order(stamps) gives "
                          "the indices of the most scans in order, which lmsbench slam --skip-bad-lines keeps)")


_MIN_DT = 1e-3  # s: a turn-rate widening never divides by a shorter interval
_INFORMATION_FLOOR = 1e-3  # 1/m^2: keeps a corridor's information invertible (no direction fixed)
_MIN_REFERENCE_POINTS = 10  # a scan with fewer valid points is no reference for the next one


@dataclass
class Landmark:
    """Bookkeeping of one landmark; its value lives in the filter state."""

    kind: str  # "line" or "corner"
    born: int  # scan number of creation
    hits: int = 1
    confirmed: bool = False
    extent: tuple[float, float] = (np.inf, -np.inf)  # lines: min, max of s along (-sin, cos)(theta)


@dataclass
class StepInfo:
    """What one scan did to the filter (diagnostics)."""

    n_lines: int = 0
    n_matched: int = 0
    n_new: int = 0
    nis: float = 0.0
    nis_dof: int = 0
    prealign_used: bool = False
    prealign_shift: float = 0.0  # rad, heading change the alignment applied to the prediction
    scan_velocity: float = float("nan")  # m/s, forward speed measured against the previous scan
    point_score: float = float("nan")  # fraction of the scan's points on the previous scan's at the estimate
    n_unobserved: int = 0  # lines and corners beyond observations.max_lines (not observed)
    n_unadded: int = 0  # observations that would have started a landmark beyond landmarks.max_landmarks
    n_dropped: int = 0  # pairs left out of the update by the joint check (association.joint_check)


class SlamFilter:
    """EKF-SLAM over line (and optionally corner) landmarks; call :meth:`step` once per scan."""

    def __init__(self, config: SlamConfig = SlamConfig(), initial_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        """Raises:
            SlamInputError: ``config`` is no SlamConfig, ``initial_pose`` not three finite numbers
                (None was an AttributeError inside, a pair an IndexError, nan a filter of nan poses
                without a word; found by fuzzing the Python API).
        """
        if not isinstance(config, SlamConfig):
            raise SlamInputError(f"config: must be a slam.SlamConfig, got {type(config).__name__}")
        try:
            initial_pose = pose_of("initial_pose", initial_pose, optional=False)  # None is refused: "must be None or" was self-contradictory
        except InputError as exc:
            raise SlamInputError(str(exc)) from None
        self.config = config
        self.ekf = SlamEKF(initial_pose)
        self.landmarks: list[Landmark] = []
        self.scan_no = -1
        self.stamp: float | None = None
        self.odom: tuple[float, float, float] | None = None
        self.gate = float(chi2_quantile(config.association.gate_probability, 2))
        self.new_gate = float(chi2_quantile(config.association.new_landmark_probability, 2))
        self._previous_points: cKDTree | None = None
        self._previous_world = np.zeros((0, 2))
        # reference scans of the scan velocity: (stamp s, pose, tree, world points, normals), oldest first
        self._references: list[tuple[float, np.ndarray, cKDTree, np.ndarray, np.ndarray]] = []
        self._heading_before = float(initial_pose[2])
        self._dt = 0.0
        self.restarts: list[int] = []  # scans after a step longer than motion.max_gap (the velocity restarted)

    # -- state views ---------------------------------------------------------------------------
    @property
    def pose(self) -> np.ndarray:
        return self.ekf.x[:3, 0].copy()

    def _indices(self, kind: str) -> tuple[np.ndarray, np.ndarray]:
        """(positions in self.landmarks, state indices) of the landmarks of one kind."""
        pos = np.array([k for k, lm in enumerate(self.landmarks) if lm.kind == kind], dtype=int)
        return pos, ROBOT_DIM + 2 * pos

    # -- one scan ------------------------------------------------------------------------------
    def step(self, stamp: float, obs: Observations, odom: tuple[float, float, float] | None = None) -> StepInfo:
        """Process the observations of the scan taken at ``stamp`` (s), no earlier than the last one's.

        Raises:
            SlamInputError: a stamp that is no finite number or earlier than the last step's,
                an update whose innovation covariance is singular in float64 (hand-built observations),
                ``obs`` no Observations, ``odom`` neither None nor three finite numbers (checked as
                run_steps checks them: called directly, a nan stamp was "cannot convert float NaN to
                integer" inside, a stamp going backwards or a nan odometry was taken without a word).
        """
        stamp, odom, _ = checked_step(self.scan_no + 1, stamp, obs, odom, None)
        if self.stamp is not None and stamp < self.stamp:
            raise out_of_order(self.scan_no + 1, stamp, self.stamp)
        cfg = self.config
        self.scan_no += 1
        info = StepInfo(n_lines=obs.lines.shape[0])
        obs = capped(obs, cfg.observations.max_lines, info)
        self._heading_before = float(self.ekf.x[2, 0])
        self._dt = 0.0
        if self.stamp is not None:
            self._predict(stamp - self.stamp, odom)
        self.stamp = stamp
        if odom is not None:
            self.odom = odom
        if cfg.prealign.enabled and self.scan_no > 0:
            self._prealign(obs, info)
        if cfg.prealign.scan_velocity and self.scan_no > 0 and not cfg.motion.use_odometry:
            self._scan_velocity(obs, info)
        pairs_l, new_l = self._associate_lines(obs)
        pairs_c, new_c = self._associate_corners(obs)
        try:
            pairs_l = self._update(obs, pairs_l, pairs_c, info)  # the pairs it kept
        except np.linalg.LinAlgError:  # numpy's "Singular matrix", raw (fuzz round 10): from_features' observations
            # carry a variance floor, so only observations built by hand reach it
            raise SlamInputError(f"scan {self.scan_no}: the filter's innovation covariance is singular in float64: the "
                                 "observations' covariances (line_cov, corner_cov) are too close to singular against "
                                 "the map's; give each a variance the filter can invert, as from_features' floor "
                                 "(observations.sigma_rho, sigma_alpha_obs); the filter is left mid-step") from None
        self._extend(obs, pairs_l)
        self._manage()  # before the room is counted: the tentative landmarks it prunes make room this scan
        room = max(cfg.landmarks.max_landmarks - len(self.landmarks), 0)  # the map's bound (memory: P is n^2)
        new_l, new_c = list(new_l), list(new_c)
        info.n_unadded = max(len(new_l) + len(new_c) - room, 0)
        new_l = new_l[:room]
        new_c = new_c[: room - len(new_l)]
        for o in new_l:
            self._add("line", obs.lines[o], obs.line_cov[o], obs.line_ends[o])
        for o in new_c:
            self._add("corner", obs.corners[o], obs.corner_cov[o], None)
        info.n_new = len(new_l) + len(new_c)
        verify = self._verifier(obs.points)
        if verify is not None:
            info.point_score = verify(self.ekf.x[:3, 0])
        self._remember_points(obs.points)
        return info

    def _predict(self, dt: float, odom: tuple[float, float, float] | None) -> None:
        cfg = self.config
        dt = max(float(dt), 0.0)
        self._dt = dt
        if cfg.motion.use_odometry and odom is not None and self.odom is not None:
            delta = models.odometry_delta(self.odom, odom)
            dist = float(np.hypot(delta[0], delta[1]))
            a_t, a_r, a_rt = cfg.motion.odom_noise
            var_t = (a_t * dist) ** 2 + 1e-6
            var_r = (a_r * abs(delta[2]) + a_rt * dist) ** 2 + 1e-6
            self.ekf.set_odometry(delta, dt, np.diag([var_t, var_t, var_r]))
            self.ekf.predict()
            return
        if dt > cfg.motion.max_gap:  # no constant velocity over it: integrated, it diverged (1e11 s: x of 1e18 m)
            self.ekf.restart_velocity()
            self.restarts.append(self.scan_no)
            return
        n = max(1, min(int(np.ceil(dt / cfg.motion.max_dt)), MAX_PREDICT_STEPS))
        for _ in range(n):
            self.ekf.set_motion(dt / n, cfg.motion.sigma_accel, cfg.motion.sigma_alpha, cfg.motion.sigma_lateral)
            self.ekf.predict()

    def _prealign(self, obs: Observations, info: StepInfo) -> None:
        """Heading (and after a missed turn, position) of the scan against the map's lines, or,
        for a scan with too few lines, against the previous scan's points."""
        cfg = self.config
        x = self.ekf.x[:, 0].copy()
        max_turn = cfg.prealign.max_turn_rate * self._dt + cfg.prealign.turn_margin
        a = self._line_alignment(obs, x, max_turn) if obs.lines.shape[0] else None
        if a is not None and a.matched_length > 0 and a.matched_length >= cfg.prealign.min_fraction * a.total_length:
            self._apply_alignment(a.pose, a.information, x, info)
            return
        if not cfg.prealign.point_fallback or self._previous_points is None or obs.points.shape[0] < cfg.prealign.min_points:
            return
        cands = align_to_previous(obs.points, self._previous_world, self._previous_points, x[:3],
                                  self._heading_before, max_turn, cfg.prealign.verify_tolerance)
        near = [c for c in cands if abs(wrap(c[1][2] - x[2])) <= cfg.prealign.near_heading]
        far = [c for c in cands if abs(wrap(c[1][2] - x[2])) > cfg.prealign.near_heading]
        chosen = near[0] if near else None
        if far and (chosen is None or far[0][0] > chosen[0] + cfg.prealign.verify_margin):
            chosen = far[0]
        if chosen is not None and chosen[0] >= cfg.prealign.point_min_score:
            self._apply_alignment(chosen[1], np.eye(2) if cfg.prealign.point_xy else None, x, info, always_xy=cfg.prealign.point_xy)

    def _line_alignment(self, obs: Observations, x: np.ndarray, max_turn: float):
        pos, idx = self._indices("line")
        if pos.size == 0:
            return None
        R, th = x[idx], x[idx + 1]
        ends = self._extent_points(R, th, pos)
        near = _point_segment_distance(x[:2], ends) <= self.config.prealign.radius
        if not near.any():
            return None
        lengths = np.hypot(ends[:, 2] - ends[:, 0], ends[:, 3] - ends[:, 1])
        return align(obs.lines[:, 0], obs.lines[:, 1], obs.line_lengths, R[near], th[near],
                     np.maximum(lengths[near], self.config.prealign.min_map_line_length), x[:3], scan_ends=obs.line_ends, map_ends=ends[near],
                     reference_heading=self._heading_before, max_turn=max_turn,
                     verify=self._verifier(obs.points), verify_margin=self.config.prealign.verify_margin)

    def _apply_alignment(self, pose: np.ndarray, information: np.ndarray | None, x: np.ndarray, info: StepInfo,
                         always_xy: bool = False) -> None:
        """Pose pseudo-measurement: the heading always; the position along the matched line
        normals (``information``) only after a turn the prediction missed."""
        cfg = self.config
        nu = pose - x[:3]
        nu[2] = wrap(nu[2])
        P = self.ekf.P
        var_phi = cfg.prealign.sigma_phi**2
        if nu[2] ** 2 > chi2_quantile(cfg.prealign.widen_probability, 1) * (P[2, 2] + var_phi):
            # the constant-velocity prior cannot explain the turn the scan shows: widen it
            P[2, 2] += nu[2] ** 2
            P[4, 4] += cfg.prealign.turn_rate_widening * (nu[2] / max(self._dt, _MIN_DT)) ** 2
        rows = [2]
        if information is not None:
            # position: only along the normals of the matched lines (a corridor fixes one direction);
            # the line update fixes the position once the heading is right, so the alignment's
            # position is used only after a turn the prediction missed (it double-counts the lines)
            R_xy = cfg.prealign.sigma_xy**2 * np.linalg.inv(information + _INFORMATION_FLOOR * np.eye(2))
            S_xy = P[:2, :2] + R_xy
            if (always_xy or abs(nu[2]) > cfg.prealign.xy_turn) and nu[:2] @ np.linalg.solve(S_xy, nu[:2]) < chi2_quantile(cfg.prealign.xy_probability, 2):
                rows = [0, 1, 2]
        Rm = np.zeros((len(rows), len(rows)))
        Rm[-1, -1] = var_phi
        if len(rows) == 3:
            Rm[:2, :2] = R_xy
        H = np.zeros((len(rows), self.ekf.dim_x))
        H[np.arange(len(rows)), rows] = 1.0
        self.ekf.update(pose[rows].reshape(-1, 1), lambda _x: H, lambda xx: xx[rows],
                        R=Rm, residual=_pose_residual)
        info.prealign_used = True
        info.prealign_shift = float(nu[2])

    def _verifier(self, points: np.ndarray):
        """``verify(pose)``: fraction of this scan's points within ``verify_tolerance`` of the
        previous scan's points (world frame); None without points on either side."""
        tree = self._previous_points
        if tree is None or points.shape[0] < _MIN_REFERENCE_POINTS:
            return None
        tol = self.config.prealign.verify_tolerance

        def verify(pose: np.ndarray) -> float:
            c, s = np.cos(pose[2]), np.sin(pose[2])
            w = points @ np.array([[c, s], [-s, c]]) + pose[:2]
            d, _ = tree.query(w, distance_upper_bound=tol)
            return float(np.mean(np.isfinite(d)))

        return verify

    def _remember_points(self, points: np.ndarray) -> None:
        X, Y, Phi = self.ekf.x[:3, 0]
        if points.shape[0] < _MIN_REFERENCE_POINTS:
            self._previous_points = None
            self._references = []
            return
        c, s = np.cos(Phi), np.sin(Phi)
        self._previous_world = points @ np.array([[c, s], [-s, c]]) + (X, Y)
        self._previous_points = cKDTree(self._previous_world)
        if self.config.prealign.scan_velocity and self.stamp is not None:
            normals, ok = beam_normals(self._previous_world)
            if ok.sum() < _MIN_REFERENCE_POINTS:
                self._references = []
                return
            ref = (float(self.stamp), np.array([X, Y, Phi]), cKDTree(self._previous_world[ok]), self._previous_world[ok], normals[ok])
            self._references.append(ref)
            # the next scan picks the newest reference at least scan_velocity_baseline before it
            while len(self._references) > 1 and self._references[1][0] <= self.stamp - self.config.prealign.scan_velocity_baseline + 1e-9:
                self._references.pop(0)

    def _scan_velocity(self, obs: Observations, info: StepInfo) -> None:
        """Forward speed from the scan's points against the previous scan's (point-to-line,
        translation only, heading as estimated): a pseudo-measurement of V over the scan interval,
        used only when the matched points' normals constrain the forward direction (a wall ahead, a
        door frame): in a corridor the lines fix only the sideways position."""
        cfg = self.config
        if not self._references or self._dt <= 0 or obs.points.shape[0] < cfg.prealign.min_points or self.stamp is None:
            return
        old_enough = [r for r in self._references if r[0] <= self.stamp - cfg.prealign.scan_velocity_baseline + 1e-9]
        ref_stamp, ref_pose, tree, prev, normals = old_enough[-1] if old_enough else self._references[0]
        interval = float(self.stamp) - ref_stamp
        if interval <= 0:
            return
        x = self.ekf.x[:, 0]
        c, s = np.cos(x[2]), np.sin(x[2])
        rotated = obs.points @ np.array([[c, s], [-s, c]])
        best: tuple[np.ndarray, float, np.ndarray] | None = None
        for start in (x[:2], ref_pose[:2]):  # the prediction, and standing still
            t, score, A = point_to_line_translation(rotated, tree, prev, normals, start, cfg.prealign.verify_tolerance)
            if best is None or score > best[1] + 1e-9:
                best = (t, score, A)
        assert best is not None
        t, score, A = best
        if score < cfg.prealign.scan_velocity_min_score:
            return
        phi_mid = ref_pose[2] + 0.5 * wrap(x[2] - ref_pose[2])
        u = np.array([np.cos(phi_mid), np.sin(phi_mid)])
        n_matched = max(np.trace(A), 1.0)
        fraction = float(u @ A @ u) / n_matched
        if fraction < cfg.prealign.scan_velocity_min_fraction:
            return
        v = float((t - ref_pose[:2]) @ u) / interval
        var = (cfg.prealign.scan_velocity_sigma**2 / fraction) / interval**2 + cfg.prealign.scan_velocity_floor**2
        P = self.ekf.P
        if (v - x[3]) ** 2 > chi2_quantile(cfg.prealign.scan_velocity_prior_probability, 1) * (P[3, 3] + var):
            # the prior is far off (a missed stop or start): widen it rather than fight it
            P[3, 3] += (v - x[3]) ** 2
        H = np.zeros((1, self.ekf.dim_x))
        H[0, 3] = 1.0
        self.ekf.update(np.array([[v]]), lambda _x: H, lambda xx: xx[3:4], R=np.array([[var]]))
        self.ekf.x[2, 0] = wrap(self.ekf.x[2, 0])
        info.scan_velocity = v

    def _extent_points(self, R: np.ndarray, th: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """(L, 4) world endpoints of line landmarks from their extents."""
        ext = np.array([self.landmarks[k].extent for k in pos]).reshape(-1, 2)
        c, s = np.cos(th), np.sin(th)
        return np.column_stack((R * c - ext[:, 0] * s, R * s + ext[:, 0] * c, R * c - ext[:, 1] * s, R * s + ext[:, 1] * c))

    def _world_ends(self, ends: np.ndarray) -> np.ndarray:
        X, Y, Phi = self.ekf.x[:3, 0]
        c, s = np.cos(Phi), np.sin(Phi)
        out = np.empty_like(ends)
        out[:, 0] = X + c * ends[:, 0] - s * ends[:, 1]
        out[:, 1] = Y + s * ends[:, 0] + c * ends[:, 1]
        out[:, 2] = X + c * ends[:, 2] - s * ends[:, 3]
        out[:, 3] = Y + s * ends[:, 2] + c * ends[:, 3]
        return out

    # -- association ---------------------------------------------------------------------------
    def _associate(self, kind: str, z: np.ndarray, Rz: np.ndarray, extra_mask: np.ndarray | None = None):
        pos, idx = self._indices(kind)
        if z.shape[0] == 0:
            return [], []
        if pos.size == 0:
            return [], list(range(z.shape[0]))
        x, P = self.ekf.x[:, 0], self.ekf.P
        lm = np.column_stack((x[idx], x[idx + 1]))
        zhat, Hp, Hl = (assoc.predict_lines if kind == "line" else assoc.predict_corners)(x[:3], lm)
        HPH = assoc.innovation_covariances(P, idx, Hp, Hl)
        cand = assoc.candidates(z, Rz, zhat, HPH, 1 if kind == "line" else None)
        d2 = cand.d2.copy()
        if extra_mask is not None:
            # extents veto every pairing outside the landmark's extent grown by the margin and the
            # pose uncertainty, also when the landmark is the only one in the gate (MIT CSAIL scan
            # 453: a corridor's first cross line paired 6.5 m outside a lone candidate's extent)
            d2[~extra_mask] = np.inf
        if self.config.association.method == "jcbb":
            def nu_fn(o, l):
                return cand.nu[o, l]

            def S_fn(pairs):
                ids = [int(idx[l]) for _, l in pairs]
                H = stacked_H(self.ekf.x, [kind] * len(pairs), ids)
                S = H @ P @ H.T
                for k, (o, _) in enumerate(pairs):
                    S[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] += Rz[o]
                return S

            pairs = assoc.jcbb(d2, self.gate, nu_fn, S_fn, self.config.association.gate_probability)
        else:
            pairs = assoc.nearest_neighbour(d2, self.gate, self.config.association.reject_ambiguous)
        paired = {p[0] for p in pairs}
        new = [o for o in range(z.shape[0]) if np.min(cand.d2[o]) > self.new_gate and o not in paired]
        return [(o, int(pos[l])) for o, l in pairs], new

    def _associate_lines(self, obs: Observations):
        pos, idx = self._indices("line")
        mask = None
        if pos.size and obs.lines.shape[0] and np.isfinite(self.config.association.extent_margin):
            x = self.ekf.x[:, 0]
            th = x[idx + 1]
            d = np.column_stack((-np.sin(th), np.cos(th)))  # (L, 2) line directions
            w = self._world_ends(obs.line_ends)
            s0 = w[:, :2] @ d.T
            s1 = w[:, 2:] @ d.T  # (m, L)
            ext = np.array([self.landmarks[k].extent for k in pos]).reshape(-1, 2)
            a = self.config.association
            sigma_xy = float(np.sqrt(max(np.linalg.eigvalsh(self.ekf.P[:2, :2]).max(), 0.0)))
            m = a.extent_margin + a.extent_sigmas * sigma_xy
            mask = (np.maximum(s0, s1) >= ext[None, :, 0] - m) & (np.minimum(s0, s1) <= ext[None, :, 1] + m)
        return self._associate("line", obs.lines, obs.line_cov, mask)

    def _associate_corners(self, obs: Observations):
        if not self.config.observations.use_corners:
            return [], []
        return self._associate("corner", obs.corners, obs.corner_cov)

    # -- update and map management ---------------------------------------------------------------
    def _update(self, obs: Observations, pairs_l, pairs_c, info: StepInfo) -> list[tuple[int, int]]:
        """The EKF update with the scan's pairs (observation, landmark); returns the line pairs used."""
        if self.config.association.joint_check:
            pairs_l, pairs_c = self._jointly_compatible(obs, pairs_l, pairs_c, info)
        if not pairs_l and not pairs_c:
            return pairs_l
        kinds, ids, z, R = _stacked(obs, pairs_l, pairs_c)
        self.ekf.update(z.reshape(-1, 1), stacked_H, stacked_h, R=R, args=(kinds, ids), hx_args=(kinds, ids),
                        residual=stacked_residual(kinds))
        self.ekf.x[2, 0] = wrap(self.ekf.x[2, 0])
        line_rows = [i + 1 for i, k in zip(ids, kinds) if k == "line"]
        self.ekf.x[line_rows, 0] = wrap(self.ekf.x[line_rows, 0])
        y = self.ekf.y[:, 0]
        info.nis = float(y @ self.ekf.SI @ y)
        info.nis_dof = y.size
        info.n_matched = len(kinds)
        for _, k in pairs_l + pairs_c:
            lm = self.landmarks[k]
            lm.hits += 1
        return pairs_l

    def _jointly_compatible(self, obs: Observations, pairs_l, pairs_c, info: StepInfo):
        """The pairs of one update, made jointly compatible: while the stacked innovation's NIS
        exceeds the ``association.gate_probability`` chi-square quantile of its dof (2 a pair),
        the pair whose removal leaves the smallest NIS is dropped (``info.n_dropped``). Each pair
        passed its own gate; together they may not (MIT CSAIL step 453: three pairs, NIS 29.6 on
        6 dof, moved the robot 2.4 m along a corridor)."""
        n_lines, n = len(pairs_l), len(pairs_l) + len(pairs_c)
        if n < 2:
            return pairs_l, pairs_c
        x, P = self.ekf.x, self.ekf.P
        kinds, ids, z, R = _stacked(obs, pairs_l, pairs_c)
        H = stacked_H(x, kinds, ids)
        S = H @ P @ H.T + R
        y = stacked_residual(kinds)(z, stacked_h(x, kinds, ids))[:, 0]
        p = self.config.association.gate_probability

        def nis(keep: list[int]) -> float:
            rows = np.concatenate([[2 * j, 2 * j + 1] for j in keep])
            try:
                return float(y[rows] @ np.linalg.solve(S[np.ix_(rows, rows)], y[rows]))
            except np.linalg.LinAlgError:
                return np.inf

        keep = list(range(n))  # the stacked pairs' indices: the lines', then the corners'
        while len(keep) > 1 and nis(keep) > chi2_quantile(p, 2 * len(keep)):
            trials = [(nis([j for j in keep if j != drop]), drop) for drop in keep]
            keep.remove(min(trials)[1])
        if len(keep) == 1 and nis(keep) > chi2_quantile(p, 2):  # (each pair passed its gate: not reached)
            keep = []
        info.n_dropped = n - len(keep)
        return [pairs_l[j] for j in keep if j < n_lines], [pairs_c[j - n_lines] for j in keep if j >= n_lines]

    def _extend(self, obs: Observations, pairs_l) -> None:
        if not pairs_l:
            return
        w = self._world_ends(obs.line_ends)
        for o, k in pairs_l:
            th = self.ekf.x[ROBOT_DIM + 2 * k + 1, 0]
            d = np.array([-np.sin(th), np.cos(th)])
            s = (w[o, :2] @ d, w[o, 2:] @ d)
            lo, hi = self.landmarks[k].extent
            self.landmarks[k].extent = (min(lo, *s), max(hi, *s))

    def _add(self, kind: str, z: np.ndarray, Rz: np.ndarray, ends: np.ndarray | None) -> None:
        pose = self.ekf.x[:3, 0]
        value, Gp, Gz = (models.init_line if kind == "line" else models.init_corner)(pose, z)
        self.ekf.add_landmark(value, Gp, Gz, Rz)
        lm = Landmark(kind, born=self.scan_no, confirmed=self.config.landmarks.confirm_hits <= 1)
        if ends is not None:
            w = self._world_ends(ends.reshape(1, 4))[0]
            d = np.array([-np.sin(value[1]), np.cos(value[1])])
            s = (w[:2] @ d, w[2:] @ d)
            lm.extent = (min(s), max(s))
        self.landmarks.append(lm)

    def _manage(self) -> None:
        cfg = self.config
        drop = []
        for k, lm in enumerate(self.landmarks):
            if lm.confirmed:
                continue
            if lm.hits >= cfg.landmarks.confirm_hits:
                lm.confirmed = True
            elif self.scan_no - lm.born >= cfg.landmarks.tentative_window:
                drop.append(k)
        if drop:
            self.ekf.remove_landmarks([ROBOT_DIM + 2 * k for k in drop])
            keep = set(range(len(self.landmarks))) - set(drop)
            self.landmarks = [lm for k, lm in enumerate(self.landmarks) if k in keep]

    # -- output --------------------------------------------------------------------------------
    def map_lines(self, confirmed_only: bool = True) -> np.ndarray:
        """(k, 7) world lines: R, theta, x0, y0, x1, y1, hits."""
        pos, idx = self._indices("line")
        keep = np.array([self.landmarks[k].confirmed or not confirmed_only for k in pos], bool).reshape(-1)
        pos, idx = pos[keep], idx[keep]
        x = self.ekf.x[:, 0]
        R, th = x[idx], x[idx + 1]
        ends = self._extent_points(R, th, pos)
        hits = np.array([self.landmarks[k].hits for k in pos], float)
        return np.column_stack((R, th, ends, hits)).reshape(-1, 7)

    def map_corners(self, confirmed_only: bool = True) -> np.ndarray:
        """(k, 3) world corners: x, y, hits."""
        pos, idx = self._indices("corner")
        keep = np.array([self.landmarks[k].confirmed or not confirmed_only for k in pos], bool).reshape(-1)
        pos, idx = pos[keep], idx[keep]
        x = self.ekf.x[:, 0]
        hits = np.array([self.landmarks[k].hits for k in pos], float)
        return np.column_stack((x[idx], x[idx + 1], hits)).reshape(-1, 3)

    def healthy(self, full: bool = False) -> bool:
        """State finite and covariance symmetric positive (semi-)definite (robot block, or all if
        ``full``); the first pose defines the frame, so a zero pose covariance is legitimate."""
        if not np.all(np.isfinite(self.ekf.x)):
            return False
        P = self.ekf.P if full else self.ekf.P[:ROBOT_DIM, :ROBOT_DIM]
        if not np.all(np.isfinite(P)) or not np.allclose(P, P.T, atol=1e-9):
            return False
        try:
            np.linalg.cholesky(P + 1e-12 * np.eye(P.shape[0]))
        except np.linalg.LinAlgError:
            return False
        return True


def _stacked(obs: Observations, pairs_l, pairs_c) -> tuple[list[str], list[int], np.ndarray, np.ndarray]:
    """One update's stacked measurement of its pairs (observation, landmark), lines first: their kinds,
    each landmark's first state row, z (2m,) and the block-diagonal R (2m, 2m); at least one pair."""
    kinds = ["line"] * len(pairs_l) + ["corner"] * len(pairs_c)
    ids = [ROBOT_DIM + 2 * k for _, k in pairs_l] + [ROBOT_DIM + 2 * k for _, k in pairs_c]
    z = np.concatenate([obs.lines[o] for o, _ in pairs_l] + [obs.corners[o] for o, _ in pairs_c])
    covs = [obs.line_cov[o] for o, _ in pairs_l] + [obs.corner_cov[o] for o, _ in pairs_c]
    R = np.zeros((2 * len(covs), 2 * len(covs)))
    for k, c in enumerate(covs):
        R[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = c
    return kinds, ids, z, R


def capped(obs: Observations, most: int, info: StepInfo) -> Observations:
    """``obs`` with at most ``most`` lines (its longest, in their order) and ``most`` corners (its
    first); ``info.n_unobserved`` counts the rest. A scan of 20,000 lines ran over 60 s in one step
    of the filter, its innovation covariance and the grown state's toward 12.8 GB."""
    m, c = obs.lines.shape[0], obs.corners.shape[0]
    if m <= most and c <= most:
        return obs
    keep = np.sort(np.argsort(-obs.line_lengths, kind="stable")[:most])
    info.n_unobserved = (m - keep.size) + max(c - most, 0)
    return Observations._built(obs.lines[keep], obs.line_cov[keep], obs.line_ends[keep], obs.corners[:most],
                               obs.corner_cov[:most], obs.points)


def _pose_residual(z: np.ndarray, h: np.ndarray) -> np.ndarray:
    """z - h for stacked pose measurements whose last row is a heading (wrapped)."""
    y = np.asarray(z, float).reshape(-1, 1) - np.asarray(h, float).reshape(-1, 1)
    y[-1, 0] = wrap(y[-1, 0])
    return y


def _point_segment_distance(p: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Distance (m) from point p (2,) to segments (L, 4)."""
    a, b = seg[:, :2], seg[:, 2:]
    ab = b - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    t = np.where(L2 > 0, np.einsum("ij,ij->i", p - a, ab) / np.where(L2 > 0, L2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    q = a + t[:, None] * ab
    return np.hypot(*(p - q).T)


#: most constant-velocity steps a time gap is integrated in (paper preset): a gap longer than
#: MAX_PREDICT_STEPS * max_dt (5,000 s at the default 0.5 s) takes steps longer than max_dt; a 1e9 s
#: gap in a log's stamps was 2e9 steps, a hang
MAX_PREDICT_STEPS = 10_000
