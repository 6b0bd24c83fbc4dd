"""The emulated LMS200: PyBullet ray casting against a world's solids plus the sensor model.

One PyBullet DIRECT client per simulator object; every PyBullet call names it. Bullet's ray test
says which solid a ray meets first; the range is then the exact distance to that solid (the ray's
entry into the box, or onto the cylinder's circle; ``sim.hits``), not ``hitFraction * length``, so
it does not depend on how far the ray was cast. Rays are cast to 3 m first and only those that
meet nothing there on to the maximum range: most beams indoors end within 3 m, and Bullet's cost
grows with a ray's length.
"""

from __future__ import annotations

import ctypes
import functools
import os
import sys
from operator import itemgetter
from contextlib import contextmanager
from typing import Iterator

import numpy as np

from lms200 import Scan
from lms200.codes import real_rows, real_vector
from lms200.errors import InputError

from .checks import check_beam_poses, check_instance, check_pose, check_twist
from .geometry import rectangle_corners
from .hits import depth_steps, finish_ranges, mix_samples, resolve_hits
from .sensor import OUTLIER_RANGE_SHARE, SensorConfig
from .world import World
from .worlds import check_seed

_STREAM_SENSOR = 2
_STREAM_SURFACE = 3  # the rough cells' grid offset and hash key (apart from the noise stream)
_BODY, _LINK, _FRACTION = itemgetter(0), itemgetter(1), itemgetter(2)  # rayTestBatch result: body id, link, hit fraction


def _flush_c_stdout() -> None:
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # pragma: no cover - no C library handle
        pass


@contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence fds 1 and 2 (PyBullet prints a build banner from C on import and connect). A closed
    one is left alone, and the copies kept are numbered above 2: with fd 2 closed at start (a daemon,
    ``2>&-``), ``os.dup(1)`` took number 2, the silencing wrote /dev/null over it, and stdout was
    /dev/null for the rest of the process, silently."""
    import fcntl

    saved: dict[int, int] = {}
    for fd in (1, 2):
        try:
            saved[fd] = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 3)
        except OSError:  # closed: nothing to silence there
            pass
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        devnull = -1
    if devnull < 0 or not saved:
        for copy in saved.values():
            os.close(copy)
        if devnull >= 0:
            os.close(devnull)
        yield
        return
    try:
        for stream in (sys.stdout, sys.stderr):  # None where the descriptor was closed at start (`2>&-`, a
            try:  # Dask worker of such a process): "import sim.lidar" failed on its AttributeError
                if stream is not None:
                    stream.flush()
            except (OSError, ValueError):  # said where the stream is written next, not as an import error
                pass
        for fd in saved:
            os.dup2(devnull, fd)
        yield
    finally:
        _flush_c_stdout()  # the banner may sit in C's stdio buffer: flush it into /dev/null
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


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
        check_instance(world, World, "world", optional=False)
        check_instance(sensor, SensorConfig, "sensor")
        check_seed(seed)
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
        self._half_width = np.float64(s.beam_width) / 2  # rad
        surface = np.random.default_rng([int(seed), _STREAM_SURFACE])
        self._cell_offset = surface.uniform(0.0, 1.0, 2) * s.noise_tail_patch_m
        self._cell_key = np.uint64(surface.integers(0, 2**63))
        self._dark_offset = surface.uniform(0.0, 1.0, 2) * s.dropout_patch_m  # drawn after: the rest is unchanged
        self._dark_key = np.uint64(surface.integers(0, 2**63))

    def _load(self, world: World) -> None:
        """Load each solid as a static triangle mesh (Bullet's ray test against meshes is exact in
        double precision, while its convex cast against primitive boxes and cylinders is off by
        up to 2 cm near edges). Cylinders are prisms circumscribing the circle; a hit on one is
        moved onto the exact circle, and a hit Bullet accepts just outside a box's edge (its
        ray-triangle test tolerates 1e-4 x the triangle's width) is rejected (see :meth:`cast`
        and :func:`sim.hits.resolve_hits`). The meshes go into bodies of up to _SOLIDS_PER_BODY
        (a base and fixed links, all at the origin, so the vertices stay as given): one Bullet
        body per solid took 0.27 ms each to create (0.25 s for the 916 solids of ``mit``)."""
        cid = self.client
        verts, tris = _box_meshes(world.boxes)
        indices = tris.ravel().tolist()
        shapes = [pb.createCollisionShape(pb.GEOM_MESH, vertices=v, indices=indices, physicsClientId=cid)
                  for v in verts.tolist()]
        for cx, cy, r, z0, z1 in world.cylinders:
            prism, prism_tris = _prism_mesh(cx, cy, r, z0, z1)
            shapes.append(pb.createCollisionShape(pb.GEOM_MESH, vertices=prism.tolist(), indices=prism_tris,
                                                  physicsClientId=cid))
        first_solid: list[int] = []  # by body id: the solid of its base (its link j is solid first + 1 + j)
        for start in range(0, len(shapes), _SOLIDS_PER_BODY):
            part = shapes[start:start + _SOLIDS_PER_BODY]
            n = len(part) - 1
            body = pb.createMultiBody(0.0, part[0], -1, [0, 0, 0], [0, 0, 0, 1], linkMasses=[0.0] * n,
                                      linkCollisionShapeIndices=part[1:], linkVisualShapeIndices=[-1] * n,
                                      linkPositions=[[0, 0, 0]] * n, linkOrientations=[[0, 0, 0, 1]] * n,
                                      linkInertialFramePositions=[[0, 0, 0]] * n,
                                      linkInertialFrameOrientations=[[0, 0, 0, 1]] * n, linkParentIndices=[0] * n,
                                      linkJointTypes=[pb.JOINT_FIXED] * n, linkJointAxis=[[0, 0, 1]] * n,
                                      physicsClientId=cid)
            first_solid += [-1] * (body + 1 - len(first_solid))
            first_solid[body] = start
        self._first_solid = np.array(first_solid + [0], dtype=np.int64)  # last slot: body -1 (no hit)
        # by solid (boxes, then cylinders; the last slot = no hit): kind (0 box, 1 cylinder, -1 none), row
        n_boxes, n_cyl = len(world.boxes), len(world.cylinders)
        self._kind_of_solid = np.concatenate((np.zeros(n_boxes), np.ones(n_cyl), [-1])).astype(np.int64)
        self._index_of_solid = np.concatenate((np.arange(n_boxes), np.arange(n_cyl), [0])).astype(np.int64)
        self._boxes = np.asarray(world.boxes, dtype=float)
        self._box_cos, self._box_sin = np.cos(self._boxes[:, 2]), np.sin(self._boxes[:, 2])
        self._circles = np.ascontiguousarray(world.cylinders[:, :3], dtype=float)
        self._glass = np.ascontiguousarray(np.asarray(world.glass, dtype=float).reshape(-1, 4))

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
        if not isinstance(seed, np.random.Generator):
            check_seed(seed)  # -1 was numpy's own ValueError
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng([int(seed), _STREAM_SENSOR])

    # -- ray casting --------------------------------------------------------------------------
    def cast(self, origins: np.ndarray, headings: np.ndarray, _depth: int = 0) -> np.ndarray:
        """Exact ranges (m) of horizontal rays at scan height from (n, 2) origins along (n,)
        world headings (rad); +inf where nothing is hit within range_max.

        Raises:
            InputError: origins that are no finite (n, 2) array or headings no n finite numbers
                (found by fuzzing: nan origins hit nothing, every range +inf, (n, 3) origins were
                read by their first two columns, silently; mismatched counts numpy's errors).
        """
        if _depth == 0:
            origins = real_rows(origins, "origins", 2, "x m, y m")
            headings = real_vector(headings, "headings", "rad")
            if headings.size != origins.shape[0]:
                raise InputError(f"headings: {headings.size} headings for {origins.shape[0]} origins")
            if origins.shape[0] > _RAY_BATCH:  # Bullet's batch limit: more rays were an error, 16,384 no hits at all
                return np.concatenate([self.cast(origins[i:i + _RAY_BATCH], headings[i:i + _RAY_BATCH])
                                       for i in range(0, origins.shape[0], _RAY_BATCH)])
        origins = np.ascontiguousarray(origins, dtype=float)
        ux, uy = np.cos(headings), np.sin(headings)
        first = min(_FIRST_STAGE_M, self._ray_length)
        solid, dist = self._ray_test(origins, ux, uy, 0.0, first)
        if first < self._ray_length:  # beams that meet nothing near: the rest of the ray
            far = np.flatnonzero(solid < 0)
            if far.size:
                solid[far], dist[far] = self._ray_test(origins[far], ux[far], uy[far], first - _STAGE_OVERLAP_M,
                                                      self._ray_length)
        ranges, again = resolve_hits(solid, dist, origins, ux, uy, self._kind_of_solid, self._index_of_solid,
                                     self._boxes, self._box_cos, self._box_sin, self._circles, _BOX_TOL_M)
        redo = np.flatnonzero(again)
        if redo.size:
            if _depth >= _MAX_RECASTS:
                ranges[redo] = np.inf
            else:  # go on from just past the false hit
                skip = ranges[redo] + _RECAST_STEP_M
                ahead = origins[redo] + skip[:, None] * np.column_stack((ux[redo], uy[redo]))
                ranges[redo] = skip + self.cast(ahead, headings[redo], _depth + 1)
        finish_ranges(ranges, origins, ux, uy, self._glass if _depth == 0 else _NO_GLASS, self.sensor.range_max)
        return ranges

    def _ray_test(self, origins: np.ndarray, ux: np.ndarray, uy: np.ndarray, near: float,
                  far: float) -> tuple[np.ndarray, np.ndarray]:
        """Bullet's first hit on each ray from ``origins`` (n, 2) along (ux, uy) between ``near``
        and ``far`` m: (n,) solids hit (boxes numbered first, then cylinders; -1 for none) and
        distances from the origin (m)."""
        if self.client is None:  # pybullet's "'NoneType' object cannot be interpreted as an integer"
            raise InputError("LMS200Sim: closed (close() was called), so it casts no ray; make a new one")
        n = len(ux)
        a, b = np.empty((n, 3)), np.empty((n, 3))
        a[:, 2] = b[:, 2] = self.world.scan_height
        a[:, 0], a[:, 1] = origins[:, 0] + near * ux, origins[:, 1] + near * uy
        b[:, 0], b[:, 1] = origins[:, 0] + far * ux, origins[:, 1] + far * uy
        hits = pb.rayTestBatch(a, b, physicsClientId=self.client)
        body = np.fromiter(map(_BODY, hits), dtype=np.int64, count=n)
        solid = self._first_solid[body]  # body -1 (no hit) reads the last slot
        solid += np.fromiter(map(_LINK, hits), dtype=np.int64, count=n)
        solid += 1
        solid[body < 0] = -1
        fraction = np.fromiter(map(_FRACTION, hits), dtype=float, count=n)
        return solid, near + fraction * (far - near)

    def beam_poses(self, pose: tuple[float, float, float], twist: tuple[float, float] | None = None) -> np.ndarray:
        """(n_beams, 3) scanner pose at each beam's time for a scan starting at ``pose`` and moving
        with a constant twist (v m/s, w rad/s) when interlaced; else ``pose`` for every beam.
        InputError naming ``pose`` / ``twist`` unless they are 3 / 2 finite numbers."""
        x, y, th = check_pose(pose)
        twist = check_twist(twist)
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
        bp = check_beam_poses(beam_poses, self.sensor.n_beams)
        return self.cast(bp[:, :2], bp[:, 2] + self._angles)

    def scan_at(self, pose: tuple[float, float, float], stamp: float = 0.0,
                twist: tuple[float, float] | None = None) -> Scan:
        """One emulated scan from scanner pose (x m, y m, theta rad) in the world frame at the
        time of its first beam ``stamp`` (s); ``twist`` = (v, w) moves the scanner during the
        scan when the sensor is interlaced."""
        return self.scan_from_beam_poses(self.beam_poses(pose, twist), stamp)

    def scan_from_beam_poses(self, beam_poses: np.ndarray, stamp: float = 0.0) -> Scan:
        """One emulated scan whose beam i is taken from ``beam_poses[i]`` (x, y, theta); InputError
        unless they are (n_beams, 3) finite numbers."""
        s = self.sensor
        bp = check_beam_poses(beam_poses, s.n_beams)
        ranges = self.exact_ranges(bp)
        if s.mixed_pixels:
            ranges = self._mix_edges(bp, ranges)
        noise = self.rng.standard_normal(s.n_beams)
        dropped = self.rng.random(s.n_beams) < s.dropout_prob
        finite = np.isfinite(ranges)
        surface = np.where(finite, ranges, 0.0)  # where each beam meets its surface (m)
        r = surface
        from_surface = finite  # beams whose echo is the surface's (dark and rough cells apply to them)
        if s.outlier_prob > 0:  # extra draws only when asked for: the datasheet model's stream is unchanged
            spurious = finite & (self.rng.random(s.n_beams) < s.outlier_prob)
            lo, hi = OUTLIER_RANGE_SHARE
            r = np.where(spurious, r * self.rng.uniform(lo, hi, s.n_beams), r)
            from_surface = finite & ~spurious  # a spurious echo comes back before the surface: read whatever it is
        if s.dropout_patch_m > 0:  # dark cells of the surfaces; the draw above still made (same stream)
            dark = self._cells(bp, surface, s.dropout_patch_m, self._dark_offset, self._dark_key, s.dropout_prob)
            dropped = np.where(finite, dark & from_surface, dropped)
        sigma = s.sigma_at(r) if s.noise_sigma_per_m else s.noise_sigma
        if s.noise_tail_prob > 0:
            rough = (self._rough_cells(bp, surface) & from_surface if s.noise_tail_patch_m > 0
                     else self.rng.random(s.n_beams) < s.noise_tail_prob)
            sigma = np.where(rough, s.noise_tail_sigma, sigma)
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

    def _rough_cells(self, bp: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """Which beams end in a rough cell of the surface grid (see SensorConfig.noise_tail_patch_m)."""
        s = self.sensor
        return self._cells(bp, ranges, s.noise_tail_patch_m, self._cell_offset, self._cell_key, s.noise_tail_prob)

    def _cells(self, bp: np.ndarray, ranges: np.ndarray, size: float, offset: np.ndarray, key: np.uint64,
               share: float) -> np.ndarray:
        """Which beams end in a marked cell of a surface grid of ``size`` (m) at ``offset``: a
        share ``share`` of the cells, by a hash of the cell and ``key``."""
        heading = bp[:, 2] + self._angles
        cell = np.floor((bp[:, :2] + ranges[:, None] * np.column_stack((np.cos(heading), np.sin(heading)))
                         - offset) / size).astype(np.int64).view(np.uint64)
        return _unit_hash(cell[:, 0], cell[:, 1], key) < share

    def _mix_edges(self, bp: np.ndarray, ranges: np.ndarray) -> np.ndarray:
        """Mixed pixels. Each beam's spot is sampled at 5 bearings (-w/2, -w/4, 0, +w/4, +w/2 of
        beam width w): the centre is the beam's own ray; the half facing a neighbour across a
        depth step (> mixed_gap, or return / no return) gets two sub-rays from the beam's own pose,
        the other half is taken as the centre's surface. Where the samples split into a near and a
        far group, the beam returns their mean (with a far group at no return, the near mean when
        the near group holds the larger share, else no return)."""
        gap = self.sensor.mixed_gap
        g = depth_steps(ranges, gap)
        if g.size == 0:
            return ranges
        hw = self._half_width
        right = np.array([hw / 2, hw])  # beam g looks towards g + 1
        left = np.array([-hw, -hw / 2])  # beam g + 1 looks towards g
        origins = np.vstack((np.repeat(bp[g, :2], 2, axis=0), np.repeat(bp[g + 1, :2], 2, axis=0)))
        heads = np.concatenate((((bp[g, 2] + self._angles[g])[:, None] + right).ravel(),
                                ((bp[g + 1, 2] + self._angles[g + 1])[:, None] + left).ravel()))
        return mix_samples(ranges, g, self.cast(origins, heads), gap)


def _unit_hash(a: np.ndarray, b: np.ndarray, key: np.uint64) -> np.ndarray:
    """A uniform number in [0, 1) for each pair of 64-bit integers (splitmix64 of a mix of both)."""
    z: np.ndarray
    with np.errstate(over="ignore"):
        z = a * np.uint64(0x9E3779B97F4A7C15) + b * np.uint64(0xC2B2AE3D27D4EB4F) + key
        z = np.bitwise_xor(z, np.right_shift(z, np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = np.bitwise_xor(z, np.right_shift(z, np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = np.bitwise_xor(z, np.right_shift(z, np.uint64(31)))
    return np.right_shift(z, np.uint64(11)).astype(np.float64) * 2.0 ** -53


_PRISM_TOLERANCE_M = 2e-4  # largest gap between a cylinder and its circumscribed prism


def _prism_sides(r: np.ndarray | float) -> np.ndarray:
    """Sides of a circumscribed prism whose faces stay within _PRISM_TOLERANCE_M of the circle."""
    r = np.asarray(r, dtype=float)
    return np.maximum(12, np.ceil(np.pi / np.arccos(r / (r + _PRISM_TOLERANCE_M)))).astype(int)


_NO_GLASS = np.zeros((0, 4))
_SOLIDS_PER_BODY = 64  # a base and 63 links; from 128 links on, Bullet's rayTestBatch named other links (checked on mit)
_FIRST_STAGE_M = 3.0  # rays are cast to this range first, and only those meeting nothing on to range_max
_STAGE_OVERLAP_M = 1e-3  # the second stage starts this far before the first one's end
_BOX_TOL_M = 1e-7  # a box hit farther than this outside the box is Bullet's edge tolerance
_RECAST_STEP_M = 1e-4  # a rejected hit's ray goes on from this far past it
_MAX_RECASTS = 4
#: most rays of one ``pb.rayTestBatch`` (pybullet 3.2.7: 16,384 returned no hits, more raised
#: 'Number of rays exceed the maximum batch size'); :meth:`LMS200Sim.cast` splits larger calls
_RAY_BATCH = 16383


# the 12 triangles of a box's 24 vertices (_box_meshes): two per side face (vertices 4k .. 4k + 3
# are side k's bottom start, bottom end, top start, top end), then the bottom and the top
_BOX_TRIANGLES = np.array([t for k in range(0, 16, 4) for t in ((k, k + 1, k + 3), (k, k + 3, k + 2))]
                          + [(19, 18, 17), (19, 17, 16), (20, 21, 22), (20, 22, 23)], dtype=int)


def _box_meshes(boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 24, 3) of boxes (n, 7: cx, cy, yaw, hx, hy, z0, z1) and the triangles (12, 3)
    every box shares: each side face as two triangles, its corners for each side (the end as
    start + 1.0 * (end - start)), then the corners at the bottom and at the top."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 7)
    n = len(boxes)
    xy = np.array([rectangle_corners(cx, cy, yaw, hx, hy) for cx, cy, yaw, hx, hy in boxes[:, :5]]).reshape(n, 4, 2)
    step = np.roll(xy, -1, axis=1) - xy
    start, end = xy + 0.0 * step, xy + 1.0 * step  # (n, 4, 2): the two ends of each side
    verts = np.empty((n, 24, 3))
    z0, z1 = boxes[:, 5, None], boxes[:, 6, None]
    for corner, (ends, z) in enumerate(((start, z0), (end, z0), (start, z1), (end, z1))):
        verts[:, corner:16:4, :2], verts[:, corner:16:4, 2] = ends, z
    verts[:, 16:20, :2], verts[:, 16:20, 2] = xy, z0
    verts[:, 20:24, :2], verts[:, 20:24, 2] = xy, z1
    return verts, _BOX_TRIANGLES


def _prism_mesh(cx: float, cy: float, r: float, z0: float, z1: float) -> tuple[np.ndarray, tuple[int, ...]]:
    """A regular prism circumscribing the cylinder (its faces touch the circle): vertices (2n + 2, 3)
    and the flat list of its triangles' vertex indices (shared by every prism of n sides)."""
    n = int(_prism_sides(r))
    rc = r / np.cos(np.pi / n)
    a = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack((cx + rc * np.cos(a), cy + rc * np.sin(a)))
    verts = np.vstack([np.column_stack((ring, np.full(n, z0))), np.column_stack((ring, np.full(n, z1))),
                       [[cx, cy, z0], [cx, cy, z1]]])
    return verts, _prism_triangles(n)


@functools.lru_cache(maxsize=None)
def _prism_triangles(n: int) -> tuple[int, ...]:
    """The flat vertex indices of an n-sided prism's triangles (_prism_mesh's vertex order)."""
    tris: list[int] = []
    for i in range(n):
        j = (i + 1) % n
        tris += [i, j, n + j, i, n + j, n + i, 2 * n, j, i, 2 * n + 1, n + i, n + j]
    return tuple(tris)
