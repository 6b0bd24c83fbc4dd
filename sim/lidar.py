"""The emulated LMS200: PyBullet ray casting against a world's solids plus the sensor model.

One PyBullet DIRECT client per simulator object; every PyBullet call names it. Ranges come from
the hit positions (not ``hitFraction * length``).
"""

from __future__ import annotations

import ctypes
import os
import sys
from itertools import chain
from operator import itemgetter
from contextlib import contextmanager
from typing import Iterator

import numpy as np

from lms200 import Scan

from .geometry import rectangle_corners
from .sensor import OUTLIER_RANGE_SHARE, SensorConfig
from .world import World

_STREAM_SENSOR = 2
_FIRST, _POSITION = itemgetter(0), itemgetter(3)  # rayTestBatch result: body id, hit position


def _flush_c_stdout() -> None:
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # pragma: no cover - no C library handle
        pass


@contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence fds 1 and 2 (PyBullet prints a build banner from C on import and connect)."""
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        _flush_c_stdout()  # the banner may sit in C's stdio buffer: flush it into /dev/null
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved + [devnull]:
            os.close(fd)


with _quiet_stdout():
    import pybullet as pb


class LMS200Sim:
    """An emulated SICK LMS200 in a world.

    Args:
        world: the world whose solids are loaded into a private PyBullet DIRECT client.
        sensor: the sensor model.
        seed: seed of the noise / dropout generator (numpy, stream 2 of the seed).
    """

    def __init__(self, world: World, sensor: SensorConfig | None = None, seed: int = 0) -> None:
        self.world = world
        self.sensor = sensor if sensor is not None else SensorConfig()
        self.rng = np.random.default_rng([int(seed), _STREAM_SENSOR])
        with _quiet_stdout():
            self.client = pb.connect(pb.DIRECT)
        self._load(world)
        s = self.sensor
        self._angles = s.angles
        self._offsets = s.beam_time_offsets
        self._ray_length = s.range_max + 0.01
        self._half_width = np.deg2rad(s.beam_width_deg) / 2

    def _load(self, world: World) -> None:
        """Load each solid as a static triangle-mesh body (Bullet's ray test against meshes is
        exact in double precision, while its convex cast against primitive boxes and cylinders is
        off by up to 2 cm near edges). Cylinders are prisms circumscribing the circle; a hit on
        one is moved onto the exact circle, and a hit Bullet accepts just outside a box's edge
        (its ray-triangle test tolerates 1e-4 x the triangle's width) is rejected (see
        :meth:`cast`)."""
        cid = self.client
        bodies: list[tuple[int, int, int]] = []  # body id, kind (0 box, 1 cylinder), index
        for k, box in enumerate(world.boxes):
            verts, faces = _box_mesh(box[None, :])
            shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=verts.tolist(), indices=faces.ravel().tolist(),
                                            physicsClientId=cid)
            bodies.append((pb.createMultiBody(0.0, shape, -1, [0, 0, 0], physicsClientId=cid), 0, k))
        for k, (cx, cy, r, z0, z1) in enumerate(world.cylinders):
            verts, faces = _prism_mesh(cx, cy, r, z0, z1)
            shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=verts.tolist(), indices=faces.ravel().tolist(),
                                            physicsClientId=cid)
            bodies.append((pb.createMultiBody(0.0, shape, -1, [0, 0, 0], physicsClientId=cid), 1, k))
        size = max([b[0] for b in bodies], default=-1) + 2
        self._kind_of_body = np.full(size, -1, dtype=np.int64)  # index by body id; last slot = no hit
        self._index_of_body = np.zeros(size, dtype=np.int64)
        for body, kind, k in bodies:
            self._kind_of_body[body], self._index_of_body[body] = kind, k
        self._boxes = np.asarray(world.boxes, dtype=float)
        self._box_cos, self._box_sin = np.cos(self._boxes[:, 2]), np.sin(self._boxes[:, 2])
        self._circles = np.asarray(world.cylinders[:, :3], dtype=float)

    # -- lifetime -----------------------------------------------------------------------------
    def close(self) -> None:
        """Disconnect the PyBullet client (idempotent)."""
        if getattr(self, "client", None) is not None:
            try:
                pb.disconnect(physicsClientId=self.client)
            except Exception:  # already gone (e.g. at interpreter shutdown)
                pass
            self.client = None

    def __enter__(self) -> "LMS200Sim":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()

    def reseed(self, seed: int | np.random.Generator) -> None:
        """Restart the noise generator (an int seed, or a Generator to draw from directly)."""
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng([int(seed), _STREAM_SENSOR])

    # -- ray casting --------------------------------------------------------------------------
    def cast(self, origins: np.ndarray, headings: np.ndarray, _depth: int = 0) -> np.ndarray:
        """Exact ranges (m) of horizontal rays at scan height from (n, 2) origins along (n,)
        world headings (rad); +inf where nothing is hit within range_max."""
        n = len(headings)
        start = np.empty((n, 3))
        start[:, :2] = origins
        start[:, 2] = self.world.scan_height
        ux, uy = np.cos(headings), np.sin(headings)
        end = start.copy()
        end[:, 0] += self._ray_length * ux
        end[:, 1] += self._ray_length * uy
        hits = pb.rayTestBatch(start, end, physicsClientId=self.client)
        body = np.fromiter(map(_FIRST, hits), dtype=np.int64, count=n)
        pos = np.fromiter(chain.from_iterable(map(_POSITION, hits)), dtype=float, count=3 * n).reshape(n, 3)
        ranges = np.hypot(pos[:, 0] - start[:, 0], pos[:, 1] - start[:, 1])
        kind = self._kind_of_body[body]  # body -1 reads the last slot: -1
        ranges[kind < 0] = np.inf
        index = self._index_of_body[body]
        again = np.zeros(n, dtype=bool)
        on_box = np.flatnonzero(kind == 0)
        if on_box.size:  # reject hits outside the true box (Bullet's edge tolerance)
            k = index[on_box]
            bx, c, s = self._boxes[k], self._box_cos[k], self._box_sin[k]
            dx, dy = pos[on_box, 0] - bx[:, 0], pos[on_box, 1] - bx[:, 1]
            outside = (np.abs(c * dx + s * dy) > bx[:, 3] + _BOX_TOL_M) | (np.abs(-s * dx + c * dy) > bx[:, 4] + _BOX_TOL_M)
            if outside.any():  # the ray may still meet that box just beside the false hit: exact entry
                out = on_box[outside]
                entry = _ray_box_entry(origins[out], ux[out], uy[out], bx[outside], c[outside], s[outside])
                meets = np.isfinite(entry)
                ranges[out[meets]] = entry[meets]
                again[out[~meets]] = True
        on_cyl = np.flatnonzero(kind == 1)
        if on_cyl.size:  # move onto the exact circle; grazing the prism but missing the circle: again
            circle = self._circles[index[on_cyl]]
            fx, fy = origins[on_cyl, 0] - circle[:, 0], origins[on_cyl, 1] - circle[:, 1]
            b = fx * ux[on_cyl] + fy * uy[on_cyl]
            disc = b * b - (fx * fx + fy * fy - circle[:, 2] ** 2)
            hit = disc >= 0
            ranges[on_cyl[hit]] = -b[hit] - np.sqrt(disc[hit])
            again[on_cyl[~hit]] = True
        redo = np.flatnonzero(again)
        if redo.size:
            if _depth >= _MAX_RECASTS:
                ranges[redo] = np.inf
            else:  # go on from just past the false hit
                skip = ranges[redo] + _RECAST_STEP_M
                u = np.column_stack((ux[redo], uy[redo]))
                ranges[redo] = skip + self.cast(origins[redo] + skip[:, None] * u, headings[redo], _depth + 1)
        if _depth == 0 and len(self.world.glass):
            ranges = np.where(_glass_range(origins, ux, uy, self.world.glass) < ranges, np.inf, ranges)
        ranges[ranges > self.sensor.range_max] = np.inf
        return ranges

    def beam_poses(self, pose: tuple[float, float, float], twist: tuple[float, float] | None = None) -> np.ndarray:
        """(n_beams, 3) scanner pose at each beam's time for a scan starting at ``pose`` and moving
        with a constant twist (v m/s, w rad/s) when interlaced; else ``pose`` for every beam."""
        x, y, th = (float(v) for v in pose)
        n = self.sensor.n_beams
        if twist is None or not self.sensor.interlaced or (twist[0] == 0 and twist[1] == 0):
            return np.tile([x, y, th], (n, 1))
        v, w = float(twist[0]), float(twist[1])
        t = self._offsets
        dth = w * t
        if abs(w) < 1e-12:
            dx, dy = v * t * np.cos(th), v * t * np.sin(th)
        else:
            dx = v / w * (np.sin(th + dth) - np.sin(th))
            dy = -v / w * (np.cos(th + dth) - np.cos(th))
        return np.column_stack((x + dx, y + dy, th + dth))

    def exact_ranges(self, beam_poses: np.ndarray) -> np.ndarray:
        """Noise-free ranges (m) of every beam from its own scanner pose ((n_beams, 3))."""
        bp = np.asarray(beam_poses, dtype=float)
        return self.cast(bp[:, :2], bp[:, 2] + self._angles)

    def scan_at(self, pose: tuple[float, float, float], stamp: float = 0.0,
                twist: tuple[float, float] | None = None) -> Scan:
        """One emulated scan from scanner pose (x m, y m, theta rad) in the world frame at the
        time of its first beam ``stamp`` (s); ``twist`` = (v, w) moves the scanner during the
        scan when the sensor is interlaced."""
        return self.scan_from_beam_poses(self.beam_poses(pose, twist), stamp)

    def scan_from_beam_poses(self, beam_poses: np.ndarray, stamp: float = 0.0) -> Scan:
        """One emulated scan whose beam i is taken from ``beam_poses[i]`` (x, y, theta)."""
        s = self.sensor
        bp = np.asarray(beam_poses, dtype=float)
        ranges = self.exact_ranges(bp)
        if s.mixed_pixels:
            ranges = self._mix_edges(bp, ranges)
        noise = self.rng.standard_normal(s.n_beams)
        dropped = self.rng.random(s.n_beams) < s.dropout_prob
        finite = np.isfinite(ranges)
        r = np.where(finite, ranges, 0.0)
        if s.outlier_prob > 0:  # extra draws only when asked for: the datasheet model's stream is unchanged
            spurious = finite & (self.rng.random(s.n_beams) < s.outlier_prob)
            lo, hi = OUTLIER_RANGE_SHARE
            r = np.where(spurious, r * self.rng.uniform(lo, hi, s.n_beams), r)
        sigma = s.sigma_at(r) if s.noise_sigma_per_m else s.noise_sigma
        if s.noise_tail_prob > 0:
            sigma = np.where(self.rng.random(s.n_beams) < s.noise_tail_prob, s.noise_tail_sigma, sigma)
        r = r + sigma * noise
        if s.quantise:
            r = np.rint(r / s.unit_m) * s.unit_m
        r = np.maximum(r, 0.0)
        r = np.where(finite & (r < s.range_max), r, np.inf)
        if s.no_return_prob > 0:
            r[self.rng.random(s.n_beams) < s.no_return_prob] = np.inf
        r[dropped] = np.nan
        if s.max_reading is not None:  # the logger's cap: no-returns and farther echoes read as it
            with np.errstate(invalid="ignore"):
                r[np.isposinf(r) | (r > s.max_reading)] = s.max_reading
        return Scan(r, s.angle_min, s.angle_increment, 0.0, s.range_max, stamp)

    def _mix_edges(self, bp: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """Mixed pixels. Each beam's spot is sampled at 5 bearings (-w/2, -w/4, 0, +w/4, +w/2 of
        beam width w): the centre is the beam's own ray; the half facing a neighbour across a
        depth step (> mixed_gap, or return / no return) gets two sub-rays from the beam's own pose,
        the other half is taken as the centre's surface. Where the samples split into a near and a
        far group, the beam returns their mean (with a far group at no return, the near mean when
        the near group holds the larger share, else no return)."""
        gap = self.sensor.mixed_gap
        with np.errstate(invalid="ignore"):
            step = np.abs(np.diff(ranges))
        g = np.flatnonzero((step > gap) | (np.isfinite(ranges[1:]) != np.isfinite(ranges[:-1])))
        if g.size == 0:
            return ranges
        hw = self._half_width
        right = np.array([hw / 2, hw])  # beam g looks towards g + 1
        left = np.array([-hw, -hw / 2])  # beam g + 1 looks towards g
        origins = np.vstack((np.repeat(bp[g, :2], 2, axis=0), np.repeat(bp[g + 1, :2], 2, axis=0)))
        heads = np.concatenate((((bp[g, 2] + self._angles[g])[:, None] + right).ravel(),
                                ((bp[g + 1, 2] + self._angles[g + 1])[:, None] + left).ravel()))
        sub = self.cast(origins, heads)
        samples = np.repeat(ranges[:, None], 5, axis=1)
        samples[g, 3:5] = sub[: 2 * g.size].reshape(-1, 2)
        samples[g + 1, 0:2] = sub[2 * g.size :].reshape(-1, 2)
        idx = np.union1d(g, g + 1)
        smp = samples[idx]
        near = smp.min(axis=1)
        far = ~(smp <= (near + gap)[:, None])  # +inf counts as far
        n_far = far.sum(axis=1)
        finite = np.isfinite(smp).all(axis=1)
        with np.errstate(invalid="ignore"):
            near_mean = np.where(far, 0.0, smp).sum(axis=1) / np.maximum(5 - n_far, 1)
            mixed = np.where(finite, smp.mean(axis=1) if finite.any() else 0.0,
                             np.where(2 * n_far > 5, np.inf, near_mean))
        out = ranges.copy()
        split = (n_far > 0) & np.isfinite(near)
        out[idx[split]] = mixed[split]
        return out


def _ray_box_entry(origins: np.ndarray, ux: np.ndarray, uy: np.ndarray, boxes: np.ndarray, c: np.ndarray,
                   s: np.ndarray) -> np.ndarray:
    """Distance (m) at which each ray enters its box (slab method, box frame); +inf if it misses."""
    ox, oy = origins[:, 0] - boxes[:, 0], origins[:, 1] - boxes[:, 1]
    lo_x, lo_y = c * ox + s * oy, -s * ox + c * oy
    dx, dy = c * ux + s * uy, -s * ux + c * uy
    with np.errstate(divide="ignore", invalid="ignore"):
        tx1, tx2 = (-boxes[:, 3] - lo_x) / dx, (boxes[:, 3] - lo_x) / dx
        ty1, ty2 = (-boxes[:, 4] - lo_y) / dy, (boxes[:, 4] - lo_y) / dy
    t_in = np.maximum(np.fmin(tx1, tx2), np.fmin(ty1, ty2))
    t_out = np.minimum(np.fmax(tx1, tx2), np.fmax(ty1, ty2))
    return np.where((t_in <= t_out) & (t_in > 0), t_in, np.inf)


def _glass_range(origins: np.ndarray, ux: np.ndarray, uy: np.ndarray, glass: np.ndarray) -> np.ndarray:
    """Distance (m) along each ray to the nearest glass segment it crosses (+inf for none)."""
    ax, ay = glass[:, 0], glass[:, 1]
    ex, ey = glass[:, 2] - ax, glass[:, 3] - ay
    wx, wy = ax[None, :] - origins[:, 0:1], ay[None, :] - origins[:, 1:2]
    den = ux[:, None] * ey[None, :] - uy[:, None] * ex[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (wx * ey[None, :] - wy * ex[None, :]) / den  # along the ray
        s = (wx * uy[:, None] - wy * ux[:, None]) / den  # along the glass, 0..1
    hit = (np.abs(den) > 1e-12) & (t > 0) & (s >= 0) & (s <= 1)
    return np.where(hit, t, np.inf).min(axis=1)


_PRISM_TOLERANCE_M = 2e-4  # largest gap between a cylinder and its circumscribed prism


def _prism_sides(r: np.ndarray | float) -> np.ndarray:
    """Sides of a circumscribed prism whose faces stay within _PRISM_TOLERANCE_M of the circle."""
    r = np.asarray(r, dtype=float)
    return np.maximum(12, np.ceil(np.pi / np.arccos(r / (r + _PRISM_TOLERANCE_M)))).astype(int)


_MAX_TRIANGLE_WIDTH_M = np.inf  # side faces are two triangles each (false hits are rejected)
_BOX_TOL_M = 1e-7  # a box hit farther than this outside the box is Bullet's edge tolerance
_RECAST_STEP_M = 1e-4  # a rejected hit's ray goes on from this far past it
_MAX_RECASTS = 4


def _box_mesh(boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of boxes (n, 7: cx, cy, yaw, hx, hy, z0, z1): side faces cut into
    columns at most _MAX_TRIANGLE_WIDTH_M wide, plus top and bottom."""
    verts: list[tuple[float, float, float]] = []
    tris: list[tuple[int, int, int]] = []
    for cx, cy, yaw, hx, hy, z0, z1 in boxes:
        xy = rectangle_corners(cx, cy, yaw, hx, hy)
        for k in range(4):
            a, b = xy[k], xy[(k + 1) % 4]
            cols = max(1, int(np.ceil(np.hypot(*(b - a)) / _MAX_TRIANGLE_WIDTH_M)))
            ring = a + np.linspace(0, 1, cols + 1)[:, None] * (b - a)
            base = len(verts)
            verts += [(x, y, z0) for x, y in ring] + [(x, y, z1) for x, y in ring]
            top = cols + 1
            for i in range(cols):
                tris += [(base + i, base + i + 1, base + top + i + 1), (base + i, base + top + i + 1, base + top + i)]
        base = len(verts)
        verts += [(x, y, z0) for x, y in xy] + [(x, y, z1) for x, y in xy]
        tris += [(base + 3, base + 2, base + 1), (base + 3, base + 1, base), (base + 4, base + 5, base + 6),
                 (base + 4, base + 6, base + 7)]
    return np.array(verts, dtype=float), np.array(tris, dtype=int)


def _prism_mesh(cx: float, cy: float, r: float, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
    """A regular prism circumscribing the cylinder (its faces touch the circle)."""
    n = int(_prism_sides(r))
    rc = r / np.cos(np.pi / n)
    a = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack((cx + rc * np.cos(a), cy + rc * np.sin(a)))
    verts = np.vstack([np.column_stack((ring, np.full(n, z0))), np.column_stack((ring, np.full(n, z1))),
                       [[cx, cy, z0], [cx, cy, z1]]])
    tris = []
    for i in range(n):
        j = (i + 1) % n
        tris += [(i, j, n + j), (i, n + j, n + i), (2 * n, j, i), (2 * n + 1, n + i, n + j)]
    return verts, np.array(tris, dtype=int)
