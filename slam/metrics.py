"""Trajectory and map scores: ATE after a 2-D rigid alignment, RPE, map error against true walls,
and the relations metric of Kummerle et al. 2009 ("On measuring the accuracy of SLAM algorithms").

Trajectories are (n, 4) arrays ``t s, x m, y m, theta rad``. Pure functions, plus one reader.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from lms200 import InputError, LmsbenchError, LogFormatError
from lms200.codes import real_rows, real_vector
from lms200.finite import shown
from lms200.logs import regular_file, row_lines, row_numbers
from lms200.records import angle_problem, pose_problem, poses_problem, stamp_problem
from lms200.tum import MAX_TILT_DEG, TILT_NOTE_DEG, tilt_of_roll_pitch_deg
from features.baselines.checks import positive

from .models import wrap


def checked_trajectory(traj: object, name: str, finite_poses: bool = True) -> np.ndarray:
    """``traj`` as a float64 (n >= 1, 4) trajectory (t s, x m, y m, theta rad) whose stamps are
    finite and do not decrease, its positions within +-MAX_COORD_M (as read_tum reads them); with
    ``finite_poses`` its poses finite too (a reference's must be; an estimate of a lost run may
    hold nan poses, which its scores then read as nan)."""
    a = real_rows(traj, name, 4, "t s, x m, y m, theta rad", finite=False)
    if a.shape[0] == 0:
        raise InputError(f"{name}: has no poses")
    t = a[:, 0]
    if not np.isfinite(t).all():
        raise InputError(f"{name}: its stamps (column 0) must be finite; row {int(np.nonzero(~np.isfinite(t))[0][0])} is not")
    if np.any(np.diff(t) < 0):
        k = int(np.nonzero(np.diff(t) < 0)[0][0]) + 1
        raise InputError(f"{name}: stamps must not decrease (row {k}: {t[k].item()!r} s after {t[k - 1].item()!r} s)")
    if finite_poses and not np.isfinite(a[:, 1:]).all():
        raise InputError(f"{name}: its poses must be finite; row {int(np.nonzero(~np.isfinite(a[:, 1:]).all(1))[0][0])} is not")
    problem = poses_problem(a[:, 1:], "pose")  # nan poses (a lost estimate) are not beyond the bounds
    if problem is not None:  # 1e300 m overflowed ate's squares, its RMSE inf; a heading of 1e300 rad is no angle,
        raise InputError(f"{name}: row {problem[0]}: {problem[1]}")  # its wrap noise scored as a heading error
    return a


def interpolate_poses(traj: np.ndarray, stamps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poses (k, 3) of ``traj`` at ``stamps`` (linear in x, y; shortest arc in theta) and a mask of
    the stamps inside the trajectory's time span (poses outside are nan, and so are those next to a
    pose that is not finite: a lost run's)."""
    traj = checked_trajectory(traj, "trajectory", finite_poses=False)
    stamps = real_vector(stamps, "stamps", "s", finite=False)
    t = traj[:, 0]
    inside = (stamps >= t[0] - 1e-9) & (stamps <= t[-1] + 1e-9)
    out = np.full((stamps.size, 3), np.nan)
    if traj.shape[0] == 1:
        out[inside] = traj[0, 1:]
        return out, inside
    s = np.clip(stamps[inside], t[0], t[-1])
    i = np.clip(np.searchsorted(t, s, side="right") - 1, 0, t.size - 2)
    span = t[i + 1] - t[i]
    f = np.where(span > 0, (s - t[i]) / np.where(span > 0, span, 1.0), 0.0)
    a, b = traj[i, 1:], traj[i + 1, 1:]
    out[inside, :2] = a[:, :2] + f[:, None] * (b[:, :2] - a[:, :2])
    out[inside, 2] = wrap(a[:, 2] + f * wrap(b[:, 2] - a[:, 2]))
    return out, inside


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose b in the frame of pose a, row-wise for (k, 3) arrays."""
    d = b[:, :2] - a[:, :2]
    c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
    return np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], wrap(b[:, 2] - a[:, 2])))


# --- ATE --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Alignment2D:
    """x_truth = R(rotation) x_est + translation (rotation about z only)."""

    rotation: float
    translation: tuple[float, float]

    def apply(self, xy: np.ndarray) -> np.ndarray:
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        xy = np.asarray(xy, float).reshape(-1, 2)
        return xy @ np.array([[c, s], [-s, c]]) + np.asarray(self.translation)


def align_2d(est_xy: np.ndarray, true_xy: np.ndarray) -> tuple[Alignment2D, float]:
    """Least-squares rigid 2-D alignment (Umeyama without scale) of est onto truth, restricted to
    a proper rotation; also returns the RMSE of the best *reflection*, to detect a mirrored estimate.
    ``est_xy`` and ``true_xy``: (n >= 1, 2) finite real arrays (m) of one n, within +-MAX_COORD_M, else an
    InputError naming the argument (a list was "AttributeError: 'list' object has no attribute 'mean'",
    unequal lengths numpy's matmul ValueError, no points an alignment of nan, a nan "SVD did not converge")."""
    from lms200.logs import MAX_COORD_M

    est_xy = real_rows(est_xy, "est_xy", 2, "x m, y m")
    true_xy = real_rows(true_xy, "true_xy", 2, "x m, y m")
    for name, xy in (("est_xy", est_xy), ("true_xy", true_xy)):
        if xy.shape[0] == 0:
            raise InputError(f"{name}: has no points")
        if np.abs(xy).max() > MAX_COORD_M:  # it said "x or y beyond +-1e+09 m": not the value, nor that it is a bound
            k = int(np.nonzero((np.abs(xy) > MAX_COORD_M).any(1))[0][0])
            raise InputError(f"{name}: row {k}: x and y must be within +-{MAX_COORD_M:g} m, got "
                             f"({xy[k, 0]:.6g}, {xy[k, 1]:.6g}) m")
    if est_xy.shape[0] != true_xy.shape[0]:
        raise InputError(f"est_xy and true_xy: must hold one point each for the other, got {est_xy.shape[0]} and "
                         f"{true_xy.shape[0]}")
    mu_e, mu_t = est_xy.mean(0), true_xy.mean(0)
    E, T = est_xy - mu_e, true_xy - mu_t
    U, _, Vt = np.linalg.svd(E.T @ T)
    Rp = (U @ np.diag([1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0]) @ Vt).T  # proper rotation
    Rm = (U @ np.diag([1.0, -np.sign(np.linalg.det(U @ Vt)) or -1.0]) @ Vt).T  # reflection
    rot = float(np.arctan2(Rp[1, 0], Rp[0, 0]))
    al = Alignment2D(rot, tuple(mu_t - Rp @ mu_e))
    mirror_err = T - E @ Rm.T
    return al, float(np.sqrt(np.mean(np.sum(mirror_err**2, axis=1))))


@dataclass(frozen=True)
class AteResult:
    """Absolute trajectory error (m) after 2-D rigid alignment; heading error (rad)."""

    rmse: float
    mean: float
    median: float
    max: float
    heading_rmse: float
    n: int
    rotation: float
    translation: tuple[float, float]
    mirror_rmse: float  # RMSE of the best reflection (m); inf with align=False (no alignment, none looked for)
    # the best reflection fits with under half the rotation's RMSE (mirror_rmse < 0.5 rmse): the estimate
    # is probably mirrored; a reflection that fits only somewhat better (a short, straight run) is not flagged
    mirrored: bool

    def as_dict(self) -> dict:
        return asdict(self)


def ate(estimate: np.ndarray, truth: np.ndarray, align: bool = True) -> AteResult:
    """ATE of ``estimate`` against ``truth`` (both (n, 4) t, x, y, theta); the truth is
    interpolated at the estimate's stamps (stamps outside its span are left out). An estimate
    with a pose that is not finite (a lost run) scores nan (``n`` counts its poses).

    Raises:
        InputError: ``estimate`` or ``truth`` is no (n, 4) trajectory with finite stamps that do
            not decrease (the truth's poses finite too), or fewer than 2 estimated poses fall
            inside the truth's time span, or ``align`` is not a bool.
    """
    if not isinstance(align, (bool, np.bool_)):  # align="no" is true, and aligned silently
        raise InputError(f"ate: align must be True or False, got {align!r}")
    est = checked_trajectory(estimate, "estimate", finite_poses=False)
    tru, inside = interpolate_poses(checked_trajectory(truth, "truth"), est[:, 0])
    est, tru = est[inside], tru[inside]
    if est.shape[0] < 2:
        raise InputError("ate: fewer than 2 estimated poses fall inside the ground truth's time span")
    if not np.isfinite(est).all():  # the SVD of a nan estimate was numpy's LinAlgError
        nan = math.nan
        return AteResult(nan, nan, nan, nan, nan, int(est.shape[0]), nan, (nan, nan), nan, False)
    if align:
        al, mirror = align_2d(est[:, 1:3], tru[:, :2])
    else:
        al, mirror = Alignment2D(0.0, (0.0, 0.0)), np.inf
    xy = al.apply(est[:, 1:3])
    e = np.hypot(*(xy - tru[:, :2]).T)
    he = wrap(est[:, 3] + al.rotation - tru[:, 2])
    rmse = float(np.sqrt(np.mean(e**2)))
    return AteResult(rmse, float(e.mean()), float(np.median(e)), float(e.max()), float(np.sqrt(np.mean(he**2))),
                     int(e.size), al.rotation, (float(al.translation[0]), float(al.translation[1])), mirror,
                     bool(mirror < 0.5 * rmse))


# --- RPE --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RpeResult:
    """Relative pose error over a travelled distance ``delta`` (m): translation (m), rotation (rad)."""

    delta: float
    trans_rmse: float
    trans_mean: float
    trans_max: float
    rot_rmse: float
    rot_mean: float
    n: int

    def as_dict(self) -> dict:
        return asdict(self)


#: Pairing rules of :func:`rpe`.
RPE_PAIRS = ("every", "evo")


def rpe(estimate: np.ndarray, truth: np.ndarray, delta: float = 1.0, pairs: str = "every") -> RpeResult:
    """Relative pose error over ``delta`` m of true travel; needs no alignment. The truth is
    interpolated at the estimate's stamps (poses outside its time span are dropped).

    Pairing rule ``pairs``:

    - ``"every"`` (default): every pose i is paired with the first pose j whose true travel since
      i is at least ``delta``: overlapping pairs, one per pose that has such a j.
    - ``"evo"``: evo_rpe's rule for ``--delta D --delta_unit m`` (its defaults: consecutive
      pairs, pairs from the estimate): walking along the *estimated* path from the first pose, a
      pose is kept whenever the path travelled since the last kept pose reaches ``delta``;
      consecutive kept poses are paired, a chain of non-overlapping pairs (so far fewer pairs,
      each spanning a little more than delta).

    Either way the error of a pair is E = (T_i^-1 T_j)^-1 (P_i^-1 P_j) (T truth, P estimate):
    translation |t(E)| (m, evo's ``translation_part``), rotation |theta(E)| (rad).

    With no pair (the truth travels less than ``delta``) ``n`` is 0 and the errors are nan; an
    estimate with a pose that is not finite (a lost run) scores nan.

    Raises:
        InputError: ``estimate`` or ``truth`` is no (n, 4) trajectory with finite stamps that do
            not decrease (the truth's poses finite too), fewer than 2 estimated poses fall inside
            the truth's time span (one pose scored nan, silently), an unknown ``pairs`` or a
            ``delta`` that is no finite number > 0.
    """
    if not isinstance(pairs, str) or pairs not in RPE_PAIRS:
        raise InputError(f"pairs: must be one of {', '.join(RPE_PAIRS)}, got {shown(pairs)}")
    positive("delta", delta, "m of true travel")  # nan, 0 or -1 paired every pose with itself
    est = checked_trajectory(estimate, "estimate", finite_poses=False)
    tru, inside = interpolate_poses(checked_trajectory(truth, "truth"), est[:, 0])
    est, tru = est[inside, 1:], tru[inside]
    if est.shape[0] < 2:
        raise InputError("rpe: fewer than 2 estimated poses fall inside the ground truth's time span")
    steps = np.hypot(*np.diff(tru[:, :2], axis=0).T)
    if pairs == "evo":
        kept, path = [0], 0.0
        for k, step in enumerate(np.hypot(*np.diff(est[:, :2], axis=0).T).tolist(), start=1):
            path += step
            if path >= delta:
                kept.append(k)
                path = 0.0
        i, j = np.asarray(kept[:-1], dtype=int), np.asarray(kept[1:], dtype=int)
    else:
        travelled = np.concatenate(([0.0], np.cumsum(steps)))
        # the first pose past i that has travelled at all: a delta below the spacing of floats at
        # the distance travelled (1e-300 m) is lost in travelled + delta, which paired a pose with itself
        j = np.maximum(np.searchsorted(travelled, travelled + delta), np.searchsorted(travelled, travelled, side="right"))
        ok = j < travelled.size
        i, j = np.nonzero(ok)[0], j[ok]
    if i.size == 0:
        return RpeResult(delta, np.nan, np.nan, np.nan, np.nan, np.nan, 0)
    de, dt = relative(est[i], est[j]), relative(tru[i], tru[j])
    err = relative(dt, de)  # (truth relative)^-1 (estimate relative)
    te, re = np.hypot(err[:, 0], err[:, 1]), np.abs(err[:, 2])
    return RpeResult(delta, float(np.sqrt(np.mean(te**2))), float(te.mean()), float(te.max()),
                     float(np.sqrt(np.mean(re**2))), float(re.mean()), int(i.size))


# --- map against true walls -------------------------------------------------------------------------
@dataclass(frozen=True)
class MapError:
    """Map lines against the true walls: perpendicular distance of segment endpoints (m) and
    direction error (rad) to the matched wall; ``matched`` of ``n_lines`` lines found a wall (the
    distances and angle are nan when none did: no line, or none near a wall in place and direction)."""

    n_lines: int
    matched: int
    distance_mean: float
    distance_rmse: float
    angle_mean: float
    wall_coverage: float  # fraction of the total true wall length overlapped by matched map lines

    def as_dict(self) -> dict:
        return asdict(self)


#: numbers a (map lines x walls) array of :func:`map_error` holds at most (8 bytes each; a few
#: such arrays live at once): the walls are taken a chunk at a time
MAP_ERROR_CHUNK = 1 << 18


def _segment_wall_terms(sa: np.ndarray, sb: np.ndarray, sd: np.ndarray, wa: np.ndarray, wd: np.ndarray,
                        wn: np.ndarray) -> tuple[np.ndarray, ...]:
    """Of segments (ends sa, sb, direction sd) against walls (start wa, direction wd, normal wn),
    broadcast over their leading axes: the direction error mod pi (rad), the ends' distances da,
    db from the wall's line (m) and the segment's span lo, hi along the wall from its start (m).
    Element by element (no matrix product), so a pair's numbers do not depend on what else is
    computed beside it (a chunk of walls, or the matched pairs alone)."""
    ang = np.arccos(np.clip(np.abs(sd[..., 0] * wd[..., 0] + sd[..., 1] * wd[..., 1]), 0.0, 1.0))
    wan = wa[..., 0] * wn[..., 0] + wa[..., 1] * wn[..., 1]
    wad = wa[..., 0] * wd[..., 0] + wa[..., 1] * wd[..., 1]
    da = np.abs(sa[..., 0] * wn[..., 0] + sa[..., 1] * wn[..., 1] - wan)
    db = np.abs(sb[..., 0] * wn[..., 0] + sb[..., 1] * wn[..., 1] - wan)
    ta = sa[..., 0] * wd[..., 0] + sa[..., 1] * wd[..., 1] - wad
    tb = sb[..., 0] * wd[..., 0] + sb[..., 1] * wd[..., 1] - wad
    return ang, da, db, np.minimum(ta, tb), np.maximum(ta, tb)


def map_error(map_segments: np.ndarray, walls: np.ndarray, alignment: Alignment2D | None = None,
              max_angle: float = np.radians(10.0), max_distance: float = 0.5) -> MapError:
    """Match each map segment (k, 4: x0, y0, x1, y1, map frame) to the true wall (n, 4) nearest in
    mean endpoint distance among those within ``max_angle`` in direction that it overlaps; the map
    is first moved into the truth frame by ``alignment`` (e.g. the ATE's).

    Raises:
        InputError: segments or walls that are no (k, 4) arrays (walls finite; a lost run's segments
            may hold nan: they match no wall), a wall of zero length (its
            direction was nan), an ``alignment`` that is no Alignment2D, or a ``max_angle`` /
            ``max_distance`` that is not a finite number > 0.
    """
    seg = real_rows(map_segments, "map_segments", 4, "x0, y0, x1, y1 m", finite=False)  # a lost run's nan lines: unmatched
    walls = real_rows(walls, "walls", 4, "x0, y0, x1, y1 m")
    if alignment is not None and not isinstance(alignment, Alignment2D):
        raise InputError(f"alignment: must be a slam.metrics.Alignment2D or None, got {type(alignment).__name__}")
    positive("max_angle", max_angle, "rad")
    positive("max_distance", max_distance, "m")
    if walls.size and not np.all(np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1]) > 0):
        raise InputError("walls: every wall must have two distinct ends (a wall of zero length has no direction)")
    if alignment is not None and seg.size:
        seg = np.column_stack((alignment.apply(seg[:, :2]), alignment.apply(seg[:, 2:])))
    if seg.shape[0] == 0 or walls.shape[0] == 0:
        return MapError(seg.shape[0], 0, np.nan, np.nan, np.nan, 0.0)
    wa, wb = walls[:, :2], walls[:, 2:]
    wlen = np.hypot(*(wb - wa).T)
    wd = (wb - wa) / wlen[:, None]  # (n, 2) wall directions
    wn = np.column_stack((-wd[:, 1], wd[:, 0]))
    sa, sb = seg[:, :2], seg[:, 2:]
    sd = (sb - sa) / np.maximum(np.hypot(*(sb - sa).T), 1e-12)[:, None]
    # the walls a chunk at a time, so that no (lines x walls) array holds more than MAP_ERROR_CHUNK
    # numbers: a world.json within its 32 MB may hold a million walls, (lines x walls) was unbounded
    n_seg = seg.shape[0]
    step = max(1, MAP_ERROR_CHUNK // n_seg)
    best = np.zeros(n_seg, dtype=np.int64)
    best_cost = np.full(n_seg, np.inf)
    for w0 in range(0, walls.shape[0], step):
        w = slice(w0, w0 + step)
        ang, da, db, lo, hi = _segment_wall_terms(sa[:, None, :], sb[:, None, :], sd[:, None, :],
                                                  wa[None, w], wd[None, w], wn[None, w])
        dist = 0.5 * (da + db)
        overlap = np.minimum(hi, wlen[None, w]) - np.maximum(lo, 0.0)
        ok = (ang < max_angle) & (overlap > 0) & (dist < max_distance)
        cost = np.where(ok, dist, np.inf)
        j = np.argmin(cost, axis=1)  # the first wall of least cost, as argmin over all walls took it
        c = cost[np.arange(n_seg), j]
        better = c < best_cost  # strictly: an earlier chunk's wall keeps a tie
        best[better], best_cost[better] = w0 + j[better], c[better]
    matched = np.isfinite(best_cost)
    if not matched.any():
        return MapError(seg.shape[0], 0, np.nan, np.nan, np.nan, 0.0)
    k = np.nonzero(matched)[0]
    bk = best[k]
    ang_k, da_k, db_k, lo_k, hi_k = _segment_wall_terms(sa[k], sb[k], sd[k], wa[bk], wd[bk], wn[bk])
    dk = np.concatenate((da_k, db_k))
    covered = np.zeros(walls.shape[0])
    order = np.argsort(bk, kind="stable")  # the matched lines grouped by wall, in line order within one
    groups = np.split(order, np.nonzero(np.diff(bk[order]))[0] + 1)
    for g in groups:  # union of overlaps per wall
        wi = int(bk[g[0]])
        iv = sorted((max(float(lo_k[i]), 0.0), min(float(hi_k[i]), float(wlen[wi]))) for i in g)
        total, end = 0.0, -np.inf
        for a, b in iv:
            if b > end:
                total += b - max(a, end)
                end = b
        covered[wi] = total
    return MapError(seg.shape[0], int(k.size), float(dk.mean()), float(np.sqrt(np.mean(dk**2))),
                    float(ang_k.mean()), float(covered.sum() / wlen.sum()))


# --- relations (Kummerle et al. 2009) ----------------------------------------------------------------
#: how far from 1 the norm of a row's last four numbers may be for them to read as a TUM quaternion
QUATERNION_NORM_TOLERANCE = 1e-4
#: m: a relation's z up to this is taken as 0 (a planar relation's is 0; a 3-D dataset's text rounding or
#: noise on a relation of no x, y motion is no climb); beyond it, the motion's climb over its x, y part,
#: atan2(|z|, hypot(x, y)), is held to the tilt bounds (``lms200.tum.MAX_TILT_DEG``, ``TILT_NOTE_DEG``):
#: a row of z = 5 m over 0.3 m was scored on its x and y, silently
RELATION_Z_FLOOR_M = 0.01
#: m: a climb beyond MAX_TILT_DEG refuses the file only where z is beyond this too; below it (a turn on the
#: spot with z = 2 cm climbs 90 deg) the row is scored and counted in the warning: a z left out of the score
#: hides at most that much error, a few times the relations metric's typical centimetres
RELATION_Z_REFUSE_M = 0.1


def _not_relations(path: str | Path) -> str:
    """What :func:`read_relations` says of a TUM trajectory given as a relations file."""
    return (f"{path}: a TUM trajectory (t x y z qx qy qz qw: the last four numbers of every row a unit quaternion), "
            "not a relations file (t1 t2 x y z roll pitch yaw a line: the pairs of stamps and the true motion between them)")


def read_relations(path: str | Path) -> np.ndarray:
    """Read a relations file (``t1 t2 x y z roll pitch yaw`` a line) into (m, 5): t1, t2, x, y, yaw.

    Raises:
        LogFormatError: a row that is not 8 finite numbers (no ``_`` in a number), x or y beyond
            +-``lms200.logs.MAX_COORD_M``, roll, pitch or yaw beyond +-``lms200.logs.MAX_HEADING_RAD`` (1e6 rad), a line longer than ``lms200.logs.MAX_ROW_CHARS``, naming file and line.
        LmsbenchError: a file without rows, or a TUM trajectory (``t x y z qx qy qz qw``, also 8 numbers
            a row): every row's last four numbers of norm 1 and some row's z, roll or pitch (qx, qy, qz)
            not 0 (a 2-D relation's z, roll, pitch and yaw are (0, 0, 0, yaw)).
        LogFormatError: a row whose roll and pitch tilt it by more than ``lms200.tum.MAX_TILT_DEG`` (30 deg; acos(cos roll cos pitch)),
            or whose z (beyond ``RELATION_Z_REFUSE_M``, 10 cm) climbs more than that over its x, y motion:
            a motion out of the plane (its x, y and yaw were scored, silently), naming file and line.

    Warns:
        LmsbenchWarning: once for a file with rows tilted or climbing by more than ``lms200.tum.TILT_NOTE_DEG``
            (5 deg) and up to 30 deg, naming how many and the line of the largest (as ``read_tum``): scored on
            their x, y and yaw.
    """
    rows: list[tuple[float, float, float, float, float]] = []
    unit_quaternions = 0  # rows whose last four numbers have norm 1, as a TUM row's quaternion has
    turned = False  # a row with z, roll or pitch (a TUM row's qx, qy, qz) not 0
    tilted: tuple[int, str] | None = None  # the first row tilted or climbing by more than MAX_TILT_DEG, and why
    noted, most = 0, (0.0, 0)  # rows off the plane by more than TILT_NOTE_DEG, and the largest angle with its line
    for no, line in row_lines(path, regular_file(path, "relations file"), "a relations file"):  # a 3 GB line was read whole: MemoryError
        s = line.split()
        if not s or s[0].startswith("#"):
            continue
        if len(s) != 8:
            raise LogFormatError(path, no, f"relation rows need 8 numbers (t1 t2 x y z roll pitch yaw), got {len(s)}")
        v = row_numbers(path, no, s, "relation row")
        if not all(math.isfinite(x) for x in v):  # a nan made the mean error null, silently
            raise LogFormatError(path, no, f"relation row has a non-finite number: {line.strip()[:60]!r}")
        unit = abs(math.hypot(*v[4:8]) - 1.0) <= QUATERNION_NORM_TOLERANCE
        problem = stamp_problem(v[0], "relation row's t1") or stamp_problem(v[1], "relation row's t2")
        if problem is not None:
            # a TUM row's x or y read as a stamp (a slam run's trajectory.tum): every row so far a unit quaternion,
            # and one of them turned (its qx, qy or qz not 0); a relation of yaw +-1 rad alone has norm 1 too
            if unit and unit_quaternions == len(rows) and (turned or any(v[4:7])):
                raise LmsbenchError(_not_relations(path))  # was "t2 -0.000217 s is outside 0 .. 2^32 s" (round 7)
            raise LogFormatError(path, no, problem)
        problem = (pose_problem(v[2], v[3], 0.0, "relation row's motion")
                   or angle_problem(v[7], "relation row's yaw")  # a yaw of 1e300 scored 138.6 deg, exit 0
                   or angle_problem(v[5], "relation row's roll") or angle_problem(v[6], "relation row's pitch"))
        if problem is not None:
            raise LogFormatError(path, no, problem)
        rows.append((v[0], v[1], v[2], v[3], v[7]))
        unit_quaternions += unit
        turned |= any(v[4:7])  # a TUM row's qz of a pose turned from the first; a 2-D relation's z, roll, pitch are 0
        # tilted as read_tum and the bags measure it; roll and pitch both near +-pi tilt it by ~0 but turn its
        # heading by pi (its yaw would be scored half a turn off): a planar relation's are near 0
        tilt = tilt_of_roll_pitch_deg(v[5], v[6])
        climb = math.degrees(math.atan2(abs(v[4]), math.hypot(v[2], v[3]))) if abs(v[4]) > RELATION_Z_FLOOR_M else 0.0
        if tilted is None and (tilt > MAX_TILT_DEG or math.cos(v[5]) < 0):
            tilted = (no, f"relation row's roll and pitch tilt it by more than {MAX_TILT_DEG:g} deg, or are not near 0: "
                          f"not a planar motion, whose x, y and yaw could be scored: {line.strip()[:60]!r}")
        elif tilted is None and climb > MAX_TILT_DEG and abs(v[4]) > RELATION_Z_REFUSE_M:
            tilted = (no, f"relation row's z {v[4]:g} m climbs {climb:.1f} deg over its x, y motion of "
                          f"{math.hypot(v[2], v[3]):.3g} m (at most {MAX_TILT_DEG:g} deg where z is beyond "
                          f"{RELATION_Z_REFUSE_M:g} m): not a planar motion, whose x, y and yaw could be "
                          f"scored: {line.strip()[:60]!r}")
        if max(tilt, climb) > TILT_NOTE_DEG:
            noted += 1
            most = max(most, (max(tilt, climb), -no))  # the largest, the first line of it
    if not rows:  # an empty file gave "none of the 0 relations falls inside the run" after the run
        raise LmsbenchError(f"{path}: no relations (t1 t2 x y z roll pitch yaw a line)")
    if unit_quaternions == len(rows) and turned:  # a TUM file (slam --relations RUN/groundtruth.tum) scored 1.42 m, exit 0
        raise LmsbenchError(_not_relations(path))
    if tilted is not None:  # a 3-D relation's motion read as its x, y and yaw, silently (as read_tum refuses a tilted pose)
        raise LogFormatError(path, tilted[0], tilted[1])
    if noted:  # as read_tum says of poses tilted by 5 to 30 deg
        import warnings

        from lms200.errors import LmsbenchWarning

        warnings.warn(f"{path}: {noted} of its {len(rows)} relation{'s' if len(rows) != 1 else ''} {'leave' if noted != 1 else 'leaves'} the plane by more than {TILT_NOTE_DEG:g} deg "
                      f"(roll / pitch tilt, or a z beyond {RELATION_Z_FLOOR_M:g} m climbing over the x, y motion; up to {most[0]:.1f} deg, line "
                      f"{-most[1]}): scored on their x, y and yaw", LmsbenchWarning, stacklevel=2)
    return np.array(rows, float).reshape(-1, 5)


#: relations whose poses lie further apart than this (s) are scored on their own as well
#: (``RelationsResult.trans_mean_far``): MIT CSAIL has 97 of its 1,172
FAR_APART_S = 200.0


@dataclass(frozen=True)
class RelationsResult:
    """Mean and std of the absolute translational (m) and rotational (deg) relation errors; the
    median translational error (m); and the mean translational error (m) over the relations whose
    two poses lie more than ``far_apart_s`` apart (the README's MIT CSAIL columns "median" and
    "> 200 s apart, mean": a drift no loop closure bounds shows there)."""

    trans_mean: float
    trans_std: float
    rot_mean_deg: float
    rot_std_deg: float
    n: int
    n_skipped: int  # relations outside the trajectory's time span
    trans_median: float = math.nan
    far_apart_s: float = FAR_APART_S
    trans_mean_far: float = math.nan  # nan where no scored relation is that far apart
    n_far: int = 0  # scored relations whose stamps t1, t2 lie more than far_apart_s apart

    def as_dict(self) -> dict:
        return asdict(self)


def relations_error(trajectory: np.ndarray, relations: np.ndarray, far_apart_s: float = FAR_APART_S) -> RelationsResult:
    """Kummerle et al.'s metric: for each relation (t1, t2, x, y, yaw), the estimated motion from
    t1 to t2 (poses interpolated at the stamps) against the true one; eps = true^-1 * estimated.
    A trajectory with a pose that is not finite (a lost run) scores nan where a relation meets it.
    Besides the means and stds: the median translational error, and the mean over the relations
    whose stamps lie more than ``far_apart_s`` (s) apart, with their count (nan and 0 where none is).

    Raises:
        InputError: a ``trajectory`` that is no (n, 4) trajectory with finite stamps that do not
            decrease, ``relations`` that are no finite (m, 5) array (``read_relations``'s), no
            relation inside the trajectory's time span, or a ``far_apart_s`` that is no finite number > 0.
    """
    positive("far_apart_s", far_apart_s, "s between a relation's stamps")
    rel = real_rows(relations, "relations", 5, "t1 s, t2 s, x m, y m, yaw rad")
    trajectory = checked_trajectory(trajectory, "trajectory", finite_poses=False)
    p1, in1 = interpolate_poses(trajectory, rel[:, 0])
    p2, in2 = interpolate_poses(trajectory, rel[:, 1])
    ok = in1 & in2
    if not ok.any():
        raise InputError("relations_error: no relation falls inside the trajectory's time span")
    est = relative(p1[ok], p2[ok])
    err = relative(rel[ok, 2:5], est)
    te = np.hypot(err[:, 0], err[:, 1])
    re = np.degrees(np.abs(err[:, 2]))
    far = np.abs(rel[ok, 1] - rel[ok, 0]) > far_apart_s
    return RelationsResult(float(te.mean()), float(te.std()), float(re.mean()), float(re.std()), int(ok.sum()),
                           int((~ok).sum()), float(np.median(te)), float(far_apart_s),
                           float(te[far].mean()) if far.any() else math.nan, int(far.sum()))
