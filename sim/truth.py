"""Exact ground truth seen from a pose: the visible parts of the world's straight faces and the
corners whose two faces are both visible next to them, in the sensor frame, with their beams.

Computed in 2-D from the world description alone (no ray casting): faces are culled when seen
from their solid side, clipped to the field of view and to range_max, and split where a nearer
face or circle shadows them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .checks import check_instance, check_pose
from .sensor import SensorConfig
from .world import World

_ANGLE_TOL = 1e-9  # rad
_POINT_TOL = 1e-6  # m


@dataclass(frozen=True)
class VisibleTruth:
    """Ground truth for one scan, sensor frame (x ahead, y left), metres and radians.

    Attributes:
        segments: (k, 4) x1, y1, x2, y2: visible part of each straight face, p1 at the lower
            bearing, rows in beam order.
        segment_beams: (k, 2) int: first and last beam index (inclusive) whose bearing falls on
            the visible part.
        corners: (m, 4) x, y, angle_rad, convex: corners whose two faces are both visible next to
            the corner (angle and convex as in ``World.corners``).
        corner_beams: (m,) int: the beam whose bearing is nearest the corner.
        segment_faces: (k,) int: index of each segment's face in ``World.walls``.
        corner_ids: (m,) int: index of each corner in ``World.corners``.
    """

    segments: np.ndarray
    segment_beams: np.ndarray
    corners: np.ndarray
    corner_beams: np.ndarray
    segment_faces: np.ndarray
    corner_ids: np.ndarray


def to_sensor_frame(points: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
    """(n, 2) world points -> sensor frame of the scanner at pose (x, y, theta)."""
    x, y, th = pose
    c, s = np.cos(th), np.sin(th)
    d = np.asarray(points, dtype=float).reshape(-1, 2) - (x, y)
    return np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]))


def _clip_halfplane(p: np.ndarray, q: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Clip segments (p, q: (n, 2)) to normal . x >= 0; returns (n, 4) with nan rows if empty."""
    dp, dq = p @ normal, q @ normal
    out = np.column_stack((p, q))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = dp / (dp - dq)
        cut = p + t[:, None] * (q - p)
    out[:, :2] = np.where((dp < 0)[:, None], cut, p)
    out[:, 2:] = np.where((dq < 0)[:, None], cut, q)
    out[(dp < 0) & (dq < 0)] = np.nan
    return out


def _clip_disc(p: np.ndarray, q: np.ndarray, radius: float) -> np.ndarray:
    """Clip segments to the disc |x| <= radius; (n, 4), nan rows if empty."""
    d = q - p
    a = (d * d).sum(1)
    b = 2 * (p * d).sum(1)
    c = (p * p).sum(1) - radius**2
    disc = b * b - 4 * a * c
    out = np.full((len(p), 4), np.nan)
    ok = disc > 0
    sq = np.sqrt(np.where(ok, disc, 0.0))
    t0 = np.clip((-b - sq) / (2 * a), 0, 1)
    t1 = np.clip((-b + sq) / (2 * a), 0, 1)
    ok &= t1 > t0
    out[ok, :2] = p[ok] + t0[ok, None] * d[ok]
    out[ok, 2:] = p[ok] + t1[ok, None] * d[ok]
    return out


def _range_on_lines(phi: np.ndarray, rho: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Range along bearing phi to lines x cos(alpha) + y sin(alpha) = rho."""
    with np.errstate(divide="ignore"):
        return rho / np.cos(phi - alpha)


def visible_truth(world: World, pose: tuple[float, float, float], sensor: SensorConfig | None = None) -> VisibleTruth:
    """The faces and corners of ``world`` visible from scanner pose (x, y, theta), sensor frame.
    InputError naming the argument for a world that is no World, a sensor that is no SensorConfig, a
    pose that is not three finite numbers (a nan pose saw no face, silently)."""
    check_instance(world, World, "world", optional=False)
    check_instance(sensor, SensorConfig, "sensor")
    pose = check_pose(pose)
    s = sensor if sensor is not None else SensorConfig()
    a_min, inc, n = s.angle_min, s.angle_increment, s.n_beams
    a_max = a_min + (n - 1) * inc
    walls = world.walls
    n_faces = len(walls)
    glass = world.glass
    both = np.vstack((walls, glass)) if len(glass) else walls  # glass: occluders, never faces
    p, q = to_sensor_frame(both[:, :2], pose), to_sensor_frame(both[:, 2:], pose)
    d = q - p
    front = d[:, 0] * (-p[:, 1]) - d[:, 1] * (-p[:, 0]) < -1e-12  # sensor on the free (right) side
    front[n_faces:] = np.abs(d[n_faces:, 0] * p[n_faces:, 1] - d[n_faces:, 1] * p[n_faces:, 0]) > 1e-12
    seg = np.full((len(both), 4), np.nan)
    seg[front] = np.column_stack((p[front], q[front]))
    for normal in (np.array([-np.sin(a_min), np.cos(a_min)]), np.array([np.sin(a_max), -np.cos(a_max)])):
        seg = _clip_halfplane(seg[:, :2], seg[:, 2:], normal)
    seg = _clip_disc(seg[:, :2], seg[:, 2:], s.range_max)
    live = np.flatnonzero(np.isfinite(seg[:, 0]))
    seg = seg[live]
    is_glass = live >= n_faces
    phi1 = np.arctan2(seg[:, 1], seg[:, 0])
    phi2 = np.arctan2(seg[:, 3], seg[:, 2])
    lo, hi = np.minimum(phi1, phi2), np.maximum(phi1, phi2)
    # normal form of each face line, sensor frame
    u = seg[:, 2:] - seg[:, :2]
    nrm = np.column_stack((u[:, 1], -u[:, 0]))
    nrm /= np.hypot(nrm[:, 0], nrm[:, 1])[:, None]
    rho = (nrm * seg[:, :2]).sum(1)
    nrm[rho < 0] *= -1
    rho = np.abs(rho)
    alpha = np.arctan2(nrm[:, 1], nrm[:, 0])
    circles = world.circles
    cc = to_sensor_frame(circles[:, :2], pose) if len(circles) else np.zeros((0, 2))
    cd = np.hypot(cc[:, 0], cc[:, 1])
    cr = circles[:, 2] if len(circles) else np.zeros(0)
    cbeta = np.arctan2(cc[:, 1], cc[:, 0])
    chalf = np.arcsin(np.clip(cr / np.maximum(cd, 1e-12), 0, 1))

    out_seg: list = []
    out_beams: list = []
    out_face: list = []
    vis_ends: dict = {}
    for k in range(len(seg)):
        if is_glass[k] or hi[k] - lo[k] < _ANGLE_TOL:
            continue
        shadows = []
        o_lo, o_hi = np.maximum(lo, lo[k]), np.minimum(hi, hi[k])
        cand = np.flatnonzero(o_hi - o_lo > _ANGLE_TOL)
        cand = cand[cand != k]
        if cand.size:
            mid = (o_lo[cand] + o_hi[cand]) / 2
            nearer = _range_on_lines(mid, rho[cand], alpha[cand]) < _range_on_lines(mid, rho[k], alpha[k])
            shadows += list(zip(o_lo[cand][nearer], o_hi[cand][nearer]))
        if len(circles):
            c_lo, c_hi = np.maximum(cbeta - chalf, lo[k]), np.minimum(cbeta + chalf, hi[k])
            cidx = np.flatnonzero(c_hi - c_lo > _ANGLE_TOL)
            if cidx.size:
                mid = (c_lo[cidx] + c_hi[cidx]) / 2
                off = mid - cbeta[cidx]
                front_r = cd[cidx] * np.cos(off) - np.sqrt(np.maximum(cr[cidx] ** 2 - (cd[cidx] * np.sin(off)) ** 2, 0))
                nearer = front_r < _range_on_lines(mid, rho[k], alpha[k])
                shadows += list(zip(c_lo[cidx][nearer], c_hi[cidx][nearer]))
        cursor = lo[k]
        pieces = []
        for a, b in sorted(shadows):
            if a > cursor + _ANGLE_TOL:
                pieces.append((cursor, a))
            cursor = max(cursor, b)
        if hi[k] > cursor + _ANGLE_TOL:
            pieces.append((cursor, hi[k]))
        face = int(live[k])
        for a, b in pieces:
            ra, rb = _range_on_lines(np.array([a, b]), rho[k], alpha[k])
            pa, pb = ra * np.array([np.cos(a), np.sin(a)]), rb * np.array([np.cos(b), np.sin(b)])
            vis_ends.setdefault(face, []).extend([pa, pb])
            first = int(np.ceil((a - a_min) / inc - 1e-6))
            last = int(np.floor((b - a_min) / inc + 1e-6))
            if last >= first:
                out_seg.append(np.concatenate((pa, pb)))
                out_beams.append((first, last))
                out_face.append(face)

    order = np.lexsort((np.array([sg[1] for sg in out_seg]) if out_seg else np.zeros(0),
                        np.array([b[0] for b in out_beams], dtype=int)))
    segments = np.array(out_seg, dtype=float).reshape(-1, 4)[order]
    beams = np.array(out_beams, dtype=int).reshape(-1, 2)[order]
    faces = np.array(out_face, dtype=int)[order] if out_face else np.zeros(0, dtype=int)

    corners, corner_beams, corner_ids = [], [], []
    if len(world.corners):
        cpts = to_sensor_frame(world.corners[:, :2], pose)
        for cid, ((i, j), cp) in enumerate(zip(world.corner_faces, cpts)):
            if _touches(vis_ends.get(int(i)), cp) and _touches(vis_ends.get(int(j)), cp):
                b = int(np.rint((np.arctan2(cp[1], cp[0]) - a_min) / inc))
                corners.append((cp[0], cp[1], world.corners[cid, 2], world.corners[cid, 3]))
                corner_beams.append(min(max(b, 0), n - 1))
                corner_ids.append(cid)
    corder = np.argsort(np.array(corner_beams, dtype=int), kind="stable")
    return VisibleTruth(
        segments=segments,
        segment_beams=beams,
        corners=np.array(corners, dtype=float).reshape(-1, 4)[corder],
        corner_beams=np.array(corner_beams, dtype=int)[corder],
        segment_faces=faces,
        corner_ids=np.array(corner_ids, dtype=int)[corder],
    )


def _touches(ends: list[np.ndarray] | None, point: np.ndarray) -> bool:
    if not ends:
        return False
    e = np.array(ends)
    return bool(np.min(np.hypot(e[:, 0] - point[0], e[:, 1] - point[1])) < _POINT_TOL)
