"""Clutter that real offices have, added to any world built on a :class:`sim.layout.Layout`:
clusters of chair and table legs, standing and walking people (leg pairs), plants (irregular
polygons of many short faces), bins, glass panels in walls that give no return, and runs of
things standing along a wall (:func:`_wall_run`: boxes, computers, bags, round bins side by side,
turned, with gaps), which cover stretches of wall with short faces, depth steps and
recesses (the scan plane is at knee height, where offices keep such things); rough fill along
the rooms' walls (:func:`_rough_fill`) and wall relief (:func:`_relief`: flat panels standing
1-6 cm proud of a wall, as closed doors, boards and flush cabinets do).

Every item is made of the world's exact solids (boxes, cylinders, mitred rings of boxes), so the
ground truth (faces, circles, corners) stays exact; glass is a segment (``World.glass``) that the
ray caster reads as no return and the visible truth treats as an occluder. Items stand in free
space next to the route (reached by a clear line from it), keep CLEARANCE_M plus their size from
the route and 0.1 m from every solid and each other. Counts are Poisson draws with means per 10 m
of route times the clutter level, all from the clutter's own random stream, so a world with
clutter 0 is the world without clutter, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import rectangle_corners
from .layout import EMBED_M, Layout, distance_to_rects
from .nearest import nearest_solid
from .world import SCAN_HEIGHT_M

ROUTE_CLEARANCE_M = 0.40  # sim.worlds.CLEARANCE_M: robot radius 0.25 m + 0.15 m
ROUTE_SAMPLING_SLACK_M = 0.005  # the route is sampled every 0.1 m: between samples it comes ~3 mm nearer
ITEM_GAP_M = 0.10  # least gap between an item and any other solid
HORIZON_M = 1.0  # _Space.distance is exact up to this (every test it makes is at 0.5 m or less)
REACH_M = 3.0  # items stand at most this far from the route
GLASS_MIN_WALL_M = 2.5  # walls at least this long may get a glass panel
GLASS_END_MARGIN_M = 0.5  # a glass panel keeps this far from a wall box's ends


@dataclass(frozen=True)
class ClutterConfig:
    """Mean counts per 10 m of route at clutter level 1 (a furnished office)."""

    tables: float = 0.6  # a small table (4 legs) with 1-3 chairs pushed in
    chairs: float = 1.0  # a chair standing alone (4 legs, or an office chair's central column)
    people: float = 0.8  # a person standing (legs 0.1-0.25 m apart) or walking (0.3-0.6 m)
    plants: float = 0.5  # an irregular polygon of 10-16 short faces, 0.15-0.35 m across
    bins: float = 0.6  # a round or square bin
    glass: float = 0.4  # a glass panel of 1-2.5 m in a wall
    wall_runs: float = 0.0  # a 0.8-2.4 m run of things (boxes, computers, bags, bins) along a wall
    rough_cover: float = 0.0  # share of the rooms' free wall length behind rough fill (not scaled by level)
    relief: float = 0.0  # share of the free wall length under flat panels 1-6 cm proud of it (not scaled by level)


def _route_points(lay: Layout, step: float = 0.1) -> tuple[np.ndarray, float]:
    nodes = np.asarray(lay.nodes, dtype=float).reshape(-1, 2)
    pts, length = [], 0.0
    for a, b in lay.edges:
        p, q = nodes[a], nodes[b]
        d = float(np.hypot(*(q - p)))
        length += d
        n = max(2, int(np.ceil(d / step)) + 1)
        pts.append(p + np.linspace(0, 1, n)[:, None] * (q - p))
    return (np.vstack(pts) if pts else nodes), length


class _Space:
    """What is already solid at scan height: rectangles and circles (footprints of items too)."""

    def __init__(self, lay: Layout, route: np.ndarray, h: float) -> None:
        self.box_index = np.array([k for k, b in enumerate(lay.boxes) if b[5] <= h <= b[6]], dtype=int)
        rects = [rectangle_corners(*lay.boxes[k][:5]) for k in self.box_index]
        self.corners = np.array(rects, dtype=float).reshape(-1, 4, 2)  # CCW
        self.circles = [(c[0], c[1], c[2]) for c in lay.cylinders if c[3] <= h <= c[4]]
        self.route = route
        self._ids = self.box_index.astype(np.int64)  # the layout's box index; -2 for footprints taken
        self._lo, self._hi = self.corners.min(axis=1), self.corners.max(axis=1)
        self._circle_rows = np.array(self.circles, dtype=float).reshape(-1, 3)

    def distance(self, pts: np.ndarray, exclude: int = -1) -> np.ndarray:
        """Distance (m) from (n, 2) points to the nearest solid (0 inside a box), leaving out the
        layout's box ``exclude``; exact up to HORIZON_M, and at least HORIZON_M (maybe inf) beyond
        (``sim.nearest``)."""
        pts = np.ascontiguousarray(pts, dtype=float).reshape(-1, 2)
        return nearest_solid(pts, self.corners, self._lo, self._hi, self._ids, int(exclude), self._circle_rows,
                             HORIZON_M)

    def free(self, c: np.ndarray, radius: float, start: np.ndarray) -> bool:
        """A disc of ``radius`` at c is clear of the route and solids, and c is seen from start."""
        if np.hypot(*(self.route - c).T).min() < ROUTE_CLEARANCE_M + radius + ROUTE_SAMPLING_SLACK_M:
            return False
        if self.distance(c[None])[0] < radius + ITEM_GAP_M:
            return False
        line = start + np.linspace(0, 1, 30)[:, None] * (c - start)
        return bool(self.distance(line).min() > 0.0)

    def clear_of_route(self, rect: np.ndarray, gap: float) -> bool:
        """Whether every route point keeps at least ``gap`` (m) from the CCW rectangle ``rect``
        (4, 2); only the points within ``gap`` of its bounds are measured (the others keep more)."""
        lo, hi = rect.min(axis=0) - gap, rect.max(axis=0) + gap
        near = self.route[np.all((self.route >= lo) & (self.route <= hi), axis=1)]
        return not (len(near) and distance_to_rects(near, [rect]).min() < gap)

    def take(self, c: np.ndarray, radius: float) -> None:
        self.circles.append((float(c[0]), float(c[1]), float(radius)))
        self._circle_rows = np.array(self.circles, dtype=float).reshape(-1, 3)

    def take_rect(self, corners: np.ndarray) -> None:
        rect = np.asarray(corners, dtype=float).reshape(1, 4, 2)
        self.corners = np.concatenate((self.corners, rect))
        self._ids = np.append(self._ids, -2)
        self._lo, self._hi = np.vstack((self._lo, rect.min(axis=1))), np.vstack((self._hi, rect.max(axis=1)))


def _spot(rng: np.random.Generator, space: _Space, radius: float, tries: int = 60) -> np.ndarray | None:
    for _ in range(tries):
        start = space.route[int(rng.integers(len(space.route)))]
        ang = rng.uniform(-np.pi, np.pi)
        dist = rng.uniform(ROUTE_CLEARANCE_M + radius, REACH_M)
        c = start + dist * np.array([np.cos(ang), np.sin(ang)])
        if space.free(c, radius, start):
            space.take(c, radius)
            return c
    return None


def _room_faces(lay: Layout, h: float) -> list:
    """The wall faces (:func:`_wall_faces`) cut to the parts that face into a room (:func:`_in_room`,
    tested 0.2 m off the face every ROUGH_STEP_M), each part as a face of its own."""
    out = []
    rooms = np.array(lay.rooms, dtype=float).reshape(-1, 4)  # x0, x1, y0, y1
    for k, p0, u, n, length in _wall_faces(lay, h):
        s = np.arange(0.0, length, ROUGH_STEP_M) + ROUGH_STEP_M / 2
        pts = p0 + s[:, None] * u + n * 0.2
        x, y = pts[:, :1], pts[:, 1:]
        inside = (np.any((x >= rooms[:, 0]) & (x <= rooms[:, 1]) & (y >= rooms[:, 2]) & (y <= rooms[:, 3]), axis=1)
                  if len(rooms) else np.ones(len(s), dtype=bool))  # as _in_room at each point
        edges = np.flatnonzero(np.diff(np.concatenate(([0], inside.astype(int), [0]))))
        for a, b in zip(edges[::2], edges[1::2]):
            start, stop = a * ROUGH_STEP_M, min(b * ROUGH_STEP_M, length)
            if stop - start >= 0.5:
                out.append((k, p0 + u * start, u, n, stop - start))
    return out


def _chair_legs(rng: np.random.Generator, c: np.ndarray, yaw: float) -> list[tuple[float, float, float]]:
    """Cylinders (x, y, r) of a chair at scan height: four legs on a 0.40-0.45 m square, or an
    office chair's central column (its star base lies below the scan plane)."""
    if rng.random() < 0.5:
        half = float(rng.uniform(0.20, 0.225))
        r = float(rng.uniform(0.011, 0.018))
        ca, sa = np.cos(yaw), np.sin(yaw)
        return [(float(c[0] + ca * sx * half - sa * sy * half), float(c[1] + sa * sx * half + ca * sy * half), r)
                for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
    return [(float(c[0]), float(c[1]), float(rng.uniform(0.025, 0.035)))]


def _table_plan(rng: np.random.Generator) -> tuple:
    """A small table (4 square legs, top above the scan plane) with 1-3 chairs pushed in, around
    the origin: (leg boxes, chair cylinders, footprint radius)."""
    yaw = float(rng.uniform(-np.pi, np.pi))
    hx, hy = float(rng.uniform(0.25, 0.35)), float(rng.uniform(0.25, 0.32))
    leg = float(rng.uniform(0.02, 0.03))
    ca, sa = np.cos(yaw), np.sin(yaw)

    def at(ox: float, oy: float) -> np.ndarray:
        return np.array([ca * ox - sa * oy, sa * ox + ca * oy])

    legs = [(*at(sx * (hx - 0.04), sy * (hy - 0.04)), yaw, leg, leg) for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
    chairs: list[tuple[float, float, float]] = []
    for k in rng.permutation(4)[: int(rng.integers(1, 4))]:
        side = [(1, 0), (-1, 0), (0, 1), (0, -1)][int(k)]
        chairs += _chair_legs(rng, at(side[0] * (hx + 0.1), side[1] * (hy + 0.1)), yaw + float(rng.normal(0, 0.3)))
    radius = max([np.hypot(x, y) + leg * np.sqrt(2) for x, y, *_ in legs] + [np.hypot(x, y) + r for x, y, r in chairs])
    return legs, chairs, float(radius), (yaw, hx, hy)


def _place_table(lay: Layout, c: np.ndarray, plan: tuple) -> None:
    legs, chairs, _, (yaw, hx, hy) = plan
    for x, y, lyaw, lx, ly in legs:
        lay.box(c[0] + x, c[1] + y, lyaw, lx, ly, 0.0, 0.72)
    lay.box(c[0], c[1], yaw, hx, hy, 0.72, 0.75)  # the top: above the scan plane
    for x, y, r in chairs:
        lay.cylinder(c[0] + x, c[1] + y, r, 0.0, 0.45)


def _chair(lay: Layout, rng: np.random.Generator, c: np.ndarray, yaw: float) -> None:
    for x, y, r in _chair_legs(rng, c, yaw):
        lay.cylinder(x, y, r, 0.0, 0.45)


def _person(lay: Layout, rng: np.random.Generator, c: np.ndarray) -> None:
    heading = float(rng.uniform(-np.pi, np.pi))
    walking = rng.random() < 0.5
    r = float(rng.uniform(0.05, 0.07))  # a leg (or trouser) at knee height
    if walking:  # legs apart along the heading
        apart = float(rng.uniform(0.30, 0.60))
        u = np.array([np.cos(heading), np.sin(heading)])
    else:  # side by side
        apart = float(rng.uniform(0.10, 0.25)) + 2 * r
        u = np.array([-np.sin(heading), np.cos(heading)])
    for s in (-0.5, 0.5):
        p = c + s * apart * u
        lay.cylinder(p[0], p[1], r, 0.0, 0.9)


def _plant(lay: Layout, rng: np.random.Generator, c: np.ndarray, radius: float) -> None:
    """A closed ring of short mitred faces (10-16 vertices, radius jittered by up to 20 %)."""
    n = int(rng.integers(10, 17))
    step = 2 * np.pi / n
    ang = np.arange(n) * step + rng.uniform(-0.3, 0.3, n) * step  # stays in order: gaps >= 0.4 step
    rad = radius * (1 + rng.uniform(-0.2, 0.2, n))
    pts = [(float(c[0] + r * np.cos(a)), float(c[1] + r * np.sin(a))) for a, r in zip(ang, rad)]
    lay.wall(pts, closed=True, thickness=0.03, z1=1.0)


def _bin(lay: Layout, rng: np.random.Generator, c: np.ndarray) -> None:
    if rng.random() < 0.6:
        lay.cylinder(c[0], c[1], float(rng.uniform(0.12, 0.2)), 0.0, 0.5)
    else:
        lay.box(c[0], c[1], float(rng.uniform(-np.pi, np.pi)), float(rng.uniform(0.12, 0.18)),
                float(rng.uniform(0.1, 0.15)), 0.0, 0.5)


def _glass_panel(lay: Layout, rng: np.random.Generator, h: float) -> list[float] | None:
    """Cut a 1-2.5 m gap into a long wall box and put glass in it; returns the glass segment."""
    walls = [k for k, b in enumerate(lay.boxes) if b[6] >= 2.0 and b[5] <= h and 2 * b[3] >= GLASS_MIN_WALL_M
             and b[4] <= 0.08]
    for _ in range(10):
        if not walls:
            return None
        k = walls[int(rng.integers(len(walls)))]
        cx, cy, yaw, hx, hy, z0, z1 = lay.boxes[k]
        width = float(rng.uniform(1.0, min(2.5, 2 * hx - 2 * GLASS_END_MARGIN_M)))
        if width < 1.0:
            continue
        s0 = float(rng.uniform(-hx + GLASS_END_MARGIN_M, hx - GLASS_END_MARGIN_M - width))
        s1 = s0 + width
        u = np.array([np.cos(yaw), np.sin(yaw)])
        c = np.array([cx, cy])
        mid = c + u * (s0 + s1) / 2
        gap = rectangle_corners(float(mid[0]), float(mid[1]), yaw, width / 2, hy)
        others = [rectangle_corners(b[0], b[1], b[2], b[3], b[4]) for j, b in enumerate(lay.boxes) if j != k and b[5] <= h <= b[6]]
        samples = gap[0] + np.linspace(0, 1, 25)[:, None, None] * (gap[1:] - gap[0])[None]
        samples = np.vstack([samples.reshape(-1, 2), gap])
        if others and distance_to_rects(samples, others).min() < 0.05:
            continue  # something stands against or meets the wall there
        cyls = [cl for cl in lay.cylinders if cl[3] <= h <= cl[4]]
        if any(np.hypot(*(samples - cl[:2]).T).min() < cl[2] + 0.05 for cl in cyls):
            continue
        del lay.boxes[k]
        for a, b in ((-hx, s0), (s1, hx)):
            m = c + u * (a + b) / 2
            lay.box(m[0], m[1], yaw, (b - a) / 2, hy, z0, z1)
        p, q = c + u * s0, c + u * s1
        walls = [j for j, b in enumerate(lay.boxes) if b[6] >= 2.0 and b[5] <= h and 2 * b[3] >= GLASS_MIN_WALL_M
                 and b[4] <= 0.08]
        return [float(p[0]), float(p[1]), float(q[0]), float(q[1])]
    return None


WALL_RUN_M = (0.8, 2.4)  # length of a run of wall-side stuff
FLOOR_ITEM_M = (0.15, 0.5)  # width and depth of a box, bag or computer on the floor
ROUND_SHARE = 0.4  # share of the things along walls that are round (bags, rolls, round bins)
TURN_MAX_RAD = 0.4  # the others (boxes) stand turned by up to this from the wall's line
FLOOR_GAP_M = 0.3  # most space between two things along a wall
ROUGH_RUN_M = (0.3, 2.0)  # length of a stretch of rough fill
ROUGH_ITEM_M = (0.03, 0.12)  # width of one thing in it
ROUGH_DEPTH_M = (0.05, 0.40)  # its depth
ROUGH_GAP_M = 0.06  # most space between two things
ROUGH_ROUND_SHARE = 0.3
ROUGH_TURN_MAX_RAD = 0.6
ROUGH_SIGHTS = 4  # route points a stretch of rough fill may be seen from (a room's walls, from its route)
ROUGH_STEP_M = 0.1  # where a stretch of rough fill does not fit, the walk along the wall moves on this far


def _wall_faces(lay: Layout, h: float) -> list[tuple[int, np.ndarray, np.ndarray, np.ndarray, float]]:
    """Both long faces of every wall box (full height, thin) at scan height: (box index, start
    point, unit direction, unit outward normal, length)."""
    out = []
    for k, (cx, cy, yaw, hx, hy, z0, z1) in enumerate(lay.boxes):
        if z1 < 2.0 or z0 > h or hy > 0.08 or 2 * hx < WALL_RUN_M[0] + 0.4:
            continue
        u = np.array([np.cos(yaw), np.sin(yaw)])
        for side in (1.0, -1.0):
            n = side * np.array([-u[1], u[0]])
            out.append((k, np.array([cx, cy]) + n * hy - u * hx, u, n, 2 * hx))
    return out


def _run_items(rng: np.random.Generator, length: float) -> list[tuple[float, float, float, float, bool]]:
    """The solids of one run along a wall, in the run's frame (s along the wall from the run's
    start, d out from the wall face): (s centre, half width, depth, yaw offset, round): things of
    FLOOR_ITEM_M width and depth, 0-FLOOR_GAP_M apart; a share ROUND_SHARE of them round (bags, rolls,
    round bins: depth = width), the others boxes turned by up to TURN_MAX_RAD."""
    return _items_along(rng, length, FLOOR_ITEM_M, FLOOR_ITEM_M, FLOOR_GAP_M, ROUND_SHARE, TURN_MAX_RAD)


def _rough_items(rng: np.random.Generator, length: float) -> list[tuple[float, float, float, float, bool]]:
    """The solids of one stretch of rough fill (as :func:`_run_items`): things ROUGH_ITEM_M wide
    and ROUGH_DEPTH_M deep (binders, files, cables, shoes, the folds of bags), 0-ROUGH_GAP_M
    apart; a share ROUGH_ROUND_SHARE round, the others turned by up to ROUGH_TURN_MAX_RAD. Each
    front is shorter than a line extractor's shortest line (8 beams: 0.14 m at 2 m) and most
    neighbouring fronts step in depth by more than the 3 cm a line may explain; a turned item's
    side face can be as long as its depth."""
    return _items_along(rng, length, ROUGH_ITEM_M, ROUGH_DEPTH_M, ROUGH_GAP_M, ROUGH_ROUND_SHARE, ROUGH_TURN_MAX_RAD)


def _items_along(rng: np.random.Generator, length: float, widths: tuple[float, float], depths: tuple[float, float],
                 gap: float, round_share: float, turn_max: float) -> list[tuple[float, float, float, float, bool]]:
    """Things side by side along ``length`` m of a wall face, from s = 0 until the next would pass
    ``length``, as :func:`_run_items` gives them: each ``widths`` wide and ``depths`` deep (m, drawn
    uniformly), 0-``gap`` m apart; a share ``round_share`` round (depth = width), the others turned by
    up to ``turn_max`` rad (the run's and the rough fill's, which wrote this loop out twice)."""
    items = []
    s = 0.0
    while True:
        w, d = float(rng.uniform(*widths)), float(rng.uniform(*depths))
        if s + w > length:
            break
        if rng.random() < round_share:
            items.append((s + w / 2, w / 2, w, 0.0, True))
        else:
            items.append((s + w / 2, w / 2, d, float(rng.uniform(-turn_max, turn_max)), False))
        s += w + float(rng.uniform(0.0, gap))
    return items


RELIEF_PANEL_M = (0.4, 1.5)  # width of one flat panel on a wall (a closed door, a board, a radiator, a cabinet's front)
RELIEF_PROUD_M = (0.01, 0.06)  # how far its front stands proud of the wall face


def _relief_items(rng: np.random.Generator, length: float) -> list[tuple[float, float, float, float, bool]]:
    """One flat panel filling ``length`` m of wall (as :func:`_run_items`): parallel to the wall,
    its front RELIEF_PROUD_M proud of the face (its depth includes the EMBED_M sunk into the wall)."""
    return [(length / 2, length / 2, float(rng.uniform(*RELIEF_PROUD_M)) + EMBED_M, 0.0, False)]


def _relief(lay: Layout, rng: np.random.Generator, space: _Space, h: float, cover: float) -> float:
    """Wall relief along every wall face (rooms and corridors): each face is walked from one end in
    slots of a panel's width (RELIEF_PANEL_M) and a bare stretch after it (as wide again, drawn the
    same way); a slot gets its flat panel with probability ``cover`` where it keeps clear of the
    route and of every other solid by 5 cm and is seen from the nearest route point
    (:func:`_place_run`). Every slot's draws come from its own stream (one seed drawn from ``rng``,
    then the face and slot numbers), so the slots and panels do not depend on ``cover``: a world's
    panels at one cover are those at any higher cover with some left out. Real walls at knee height
    are not one plane: closed doors in their frames, boards, radiators, cabinets flush with the
    wall stand a few cm proud of it, and a line extractor sees the steps. Returns the length
    covered (m)."""
    faces = _wall_faces(lay, h)
    base = int(rng.integers(2 ** 32))
    done = 0.0
    for f, face in enumerate(faces):
        s, end = 0.2, face[4] - 0.2
        for slot in range(int(face[4] / RELIEF_PANEL_M[0]) + 1):
            srng = np.random.default_rng([base, f, slot])
            length, bare = (float(v) for v in srng.uniform(*RELIEF_PANEL_M, 2))
            length = min(length, end - s)
            if length < RELIEF_PANEL_M[0]:
                break
            if srng.random() < cover and _place_run(lay, srng, space, face, s, length, _relief_items):
                done += length
            s += length + bare
    return done


def _in_room(lay: Layout, p: np.ndarray) -> bool:
    """Whether a point lies in one of the layout's rooms (``Layout.rooms``; anywhere when it has none)."""
    return not lay.rooms or any(x0 <= p[0] <= x1 and y0 <= p[1] <= y1 for x0, x1, y0, y1 in lay.rooms)


def _seen(space: _Space, front: np.ndarray, sights: int) -> bool:
    """Whether a clear straight line joins ``front`` to one of ``sights`` route points within
    REACH_M + 3 m of it: the nearest, then points at even steps down the list by distance."""
    dist = np.hypot(*(space.route - front).T)
    order = np.argsort(dist, kind="stable")
    order = order[dist[order] <= REACH_M + 3.0]
    for rank in np.unique((np.arange(sights) * len(order)) // max(sights, 1)):
        if rank >= len(order):
            break
        near = space.route[int(order[rank])]
        steps = int(np.ceil(np.hypot(*(front - near)) / 0.02)) + 1  # finer than the thinnest wall
        line = near + np.linspace(0, 1, steps)[:, None] * (front - near)
        if space.distance(line).min() > 0.0:
            return True
    return False


def _wall_run(lay: Layout, rng: np.random.Generator, space: _Space, faces: list, h: float) -> bool:
    """Put one run of wall-side stuff (:func:`_run_items`) along a free stretch of some wall face,
    drawn by length, in a room (:func:`_in_room`: corridors are kept clear; tried 30 times)."""
    if not faces:
        return False
    weights = np.array([f[4] for f in faces])
    for _ in range(30):
        face = faces[int(rng.choice(len(faces), p=weights / weights.sum()))]
        length = float(rng.uniform(*WALL_RUN_M))
        if face[4] - 0.4 < length:
            continue
        s0 = float(rng.uniform(0.2, face[4] - 0.2 - length))
        if not _in_room(lay, face[1] + face[2] * (s0 + length / 2) + face[3] * 0.2):
            continue  # corridors are kept clear: their long walls stay plain
        if _place_run(lay, rng, space, face, s0, length, _run_items):
            return True
    return False


def _place_run(lay: Layout, rng: np.random.Generator, space: _Space, face: tuple, s0: float, length: float,
               make_items=_run_items, sights: int = 1) -> bool:
    """Put the things ``make_items`` draws along ``length`` m of a wall face from ``s0`` (m along
    it), if their hull keeps clear of the route and of every other solid and its front is seen
    from the route (:func:`_seen`, from up to ``sights`` route points). Every solid's back sinks
    EMBED_M into the wall, so the run and the wall are one solid."""
    k, p0, u, n, _ = face
    items = make_items(rng, length)
    if not items:
        return False
    depth = max(d * abs(np.cos(j)) + 2 * w * abs(np.sin(j)) for _, w, d, j, _ in items)  # out from the face
    overhang = max(d / 2 * abs(np.sin(j)) for _, w, d, j, _ in items)  # turned things reach past the ends
    start = p0 + u * s0
    mid = start + u * length / 2 + n * (depth / 2 + 0.005)
    hull = rectangle_corners(float(mid[0]), float(mid[1]), float(np.arctan2(u[1], u[0])), length / 2 + overhang,
                             depth / 2 - 0.005)
    steps = int(np.ceil(length / 0.05)) + 1
    samples = hull[0] + np.linspace(0, 1, steps)[:, None, None] * (hull[1:] - hull[0])[None]
    samples = np.vstack([samples.reshape(-1, 2), hull])
    if not space.clear_of_route(hull, ROUTE_CLEARANCE_M + ROUTE_SAMPLING_SLACK_M):
        return False
    if space.distance(samples, exclude=k).min() < ITEM_GAP_M / 2:
        return False
    front = start + u * length / 2 + n * (depth + 0.05)
    if not _seen(space, front, sights):
        return False  # the far side of a wall, or behind something
    for sc, hw, d, j, round_ in items:
        top = float(rng.uniform(0.5, 2.0))
        if round_:
            c = start + u * sc + n * (hw - EMBED_M)
            lay.cylinder(float(c[0]), float(c[1]), hw, 0.0, top)
            continue
        hd = d / 2
        reach = hd * abs(np.cos(j)) + hw * abs(np.sin(j))  # half extent out from the wall
        c = start + u * sc + n * (reach - EMBED_M)
        yaw = float(np.arctan2(n[1], n[0])) + j
        lay.box(float(c[0]), float(c[1]), yaw, hd, hw, 0.0, top)
    space.take_rect(hull)
    return True


def _rough_fill(lay: Layout, rng: np.random.Generator, space: _Space, h: float, cover: float) -> float:
    """Rough fill along the rooms' walls: each wall of each room (:func:`_room_faces`) is filled
    with probability ``cover`` (drawn from its own stream: one seed from ``rng``, then the face's
    number, so the walls chosen at one cover are those chosen at any higher cover with some left out), and
    then along its length: walked from one end in stretches of ROUGH_RUN_M (:func:`_place_run`; where
    a stretch does not fit, the walk moves on ROUGH_STEP_M). Real rooms keep their stuff along some
    walls and leave others plain, which the scanner then sees as long walls. Returns the length
    filled (m)."""
    faces = _room_faces(lay, h)
    base = int(rng.integers(2 ** 32))
    done = 0.0
    for f, face in enumerate(faces):
        frng = np.random.default_rng([base, f])
        if frng.random() >= cover:
            continue
        s, end = 0.2, face[4] - 0.2
        while end - s >= ROUGH_RUN_M[0]:
            length = min(float(frng.uniform(*ROUGH_RUN_M)), end - s)
            while end - s >= length and not _place_run(lay, frng, space, face, s, length, _rough_items, ROUGH_SIGHTS):
                s += ROUGH_STEP_M
            if end - s >= length:
                done += length
            s += length + ITEM_GAP_M
    return done


def add_clutter(lay: Layout, rng: np.random.Generator, level: float, config: ClutterConfig | None = None,
                scan_height: float = SCAN_HEIGHT_M) -> list[list[float]]:
    """Add clutter to a layout (its route must be in place); returns the glass segments."""
    if level <= 0:
        return []
    cfg = config if config is not None else ClutterConfig()
    route, length = _route_points(lay)
    if len(route) == 0:
        return []
    scale = level * length / 10.0
    glass = []
    for _ in range(int(rng.poisson(cfg.glass * scale))):
        seg = _glass_panel(lay, rng, scan_height)
        if seg is not None:
            glass.append(seg)
    space = _Space(lay, route, scan_height)
    if cfg.wall_runs > 0:  # (no draw at all otherwise: worlds without runs stay bit for bit)
        faces = _wall_faces(lay, scan_height)
        for _ in range(int(rng.poisson(cfg.wall_runs * scale))):
            _wall_run(lay, rng, space, faces, scan_height)
    plan = ([("table", 0.0)] * int(rng.poisson(cfg.tables * scale)) + [("chair", 0.3)] * int(rng.poisson(cfg.chairs * scale))
            + [("person", 0.4)] * int(rng.poisson(cfg.people * scale)) + [("plant", 0.42)] * int(rng.poisson(cfg.plants * scale))
            + [("bin", 0.22)] * int(rng.poisson(cfg.bins * scale)))
    order = rng.permutation(len(plan))
    for k in order:
        kind, radius = plan[int(k)]
        table = _table_plan(rng) if kind == "table" else None
        c = _spot(rng, space, table[2] if table is not None else radius)
        if c is None:
            continue
        if table is not None:
            _place_table(lay, c, table)
        elif kind == "chair":
            _chair(lay, rng, c, float(rng.uniform(-np.pi, np.pi)))
        elif kind == "person":
            _person(lay, rng, c)
        elif kind == "plant":
            _plant(lay, rng, c, float(rng.uniform(0.15, 0.3)))
        else:
            _bin(lay, rng, c)
    if cfg.rough_cover > 0:  # last, and no draw without it: the rest of the clutter is the same at any cover
        _rough_fill(lay, rng, space, scan_height, min(cfg.rough_cover, 1.0))
    if cfg.relief > 0:  # after the rough fill, and no draw without it: the rest is the same at any relief
        _relief(lay, rng, space, scan_height, min(cfg.relief, 1.0))
    return glass
