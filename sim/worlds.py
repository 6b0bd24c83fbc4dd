"""Named worlds and the seeded procedural office generator.

- ``office``: a corridor with three rooms on each side behind doorways, a chamfered (135 deg)
  corridor end, open door leaves, cabinets, shelves, desks (only their panel legs cut the scan
  plane), screens leaning off walls at 45-60 deg (acute and obtuse corners) and the odd round
  pillar; the seed moves doors and furniture.
- ``corridor``: a 30 m corridor with door recesses (convex and concave right angles) and round
  columns half sunk into its walls.
- ``angles``: a hall whose corners are acute (50 deg) and obtuse (130-135 deg), with freestanding
  V-shaped screens (convex and concave 135 deg corners): the paper's Fig. 9c and 9e cases.
- ``pillars``: a hall with round pillars (r 0.1-0.5 m) and a curved wall (a cylinder of r 2 m
  sunk into a wall): curved surfaces a line extractor must not call lines.
- ``random``: the office generator with room count, sizes and corridor width drawn from the seed.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from lms200.errors import InputError
from lms200.finite import check_seed, float_of

from .clutter import ClutterConfig, add_clutter
from .geometry import rectangle_corners
from .layout import Layout, WALL_THICKNESS_M, distance_to_rects
from .world import World

ROBOT_RADIUS_M = 0.25
CLEARANCE_M = ROBOT_RADIUS_M + 0.15  # furniture keeps this far from the route
WORLD_NAMES = ("office", "corridor", "angles", "pillars", "random", "cluttered", "mit")
_STREAM_WORLD = 1  # numpy seed-sequence stream for world generation
_STREAM_CLUTTER = 3  # numpy seed-sequence stream for clutter (and the angles of clutter's door leaves)
DEFAULT_CLUTTER = {"cluttered": 1.0}  # clutter level of each world name (0 when not listed)
# The MIT-CSAIL-like preset (see docs/simulator.md: parameters fixed from the log's range
# histogram, segment lengths and share of beams on long walls, then frozen).
# Grid searched (two seeds, 40 s each, MIT CSAIL every 5th scan): room_w 3.6 / 5.0, room_d 4.2 / 6.0,
# corridor_w 1.8 / 2.4, clutter 1.5 / 3 / 4.5 at a glass rate of 0.1; the distance (range and
# segment-length histograms, long-wall share) ran 0.26-0.39; this is its minimum.
# Then runs of things standing along walls (sim.clutter._wall_run), since the log's segments are
# far more often short (51 % of split-and-merge segments under 0.5 m) than the preset's were (38 %).
# Rates of 0.75 / 1.0 runs per 10 m of route per clutter level (`lmsbench sim2real`, six seeds)
# gave MIT CSAIL short shares of 46 / 48 % and Intel (log: 27 %) 29 / 33 %;
# 0.75 comes nearest on both together. Every rate lowers the long-wall share (MIT 0.15 -> 0.10
# against the log's 0.22): runs stand along any wall, where real clutter gathers in places.
# Then the corridor's 14 m straight run past the rooms became two turns (``office(corridor_turns=True)``:
# a 7.8 m leg at each end, 15.6 m in all), since real corridors meet and end within the range: the
# preset's statistic distance to MIT CSAIL 0.307 -> 0.280 (three worlds, fill 0.89, relief 0.14;
# docs/simulator.md), corridors of 2.4 m 0.344.
MIT_PRESET = dict(n_per_side=6, room_w=5.0, room_d=6.0, corridor_w=1.8, door_w=1.0, chamfer=False,
                  corridor_turns=True, clutter=3.0, glass_per_10m=0.1, wall_runs_per_10m=0.75,
                  rough_cover=1.0)


MIN_SCALE, MAX_SCALE = 0.7, 3.0  # the rooms' size factor (make_world(scale=...)); below 0.7 routes pass closer
# to a solid than the robot's radius (0.17 m at 0.5, 0.25 at 0.6; >= 0.33 m at 0.7 over 8 seeds of every roomed world)
ROOMED_WORLDS = ("office", "cluttered", "random", "mit")  # the office generator's worlds, whose rooms scale
MAX_CLUTTER = 10.0  # densest clutter level (10x a furnished office); the object count grows with it
#: most glass panels per 10 m of route and clutter level (make_world(glass=...)): a panel is 1-2.5 m of a wall at least
#: 2.5 m long, so the walls are full long before it (office, clutter 10: 15 panels at 1, 16 at 2, 18 at 10, 19 at
#: 100), and each draw past that still tries 10 walls: at clutter 10, glass 10 ran 23 s on the office and 181 s on
#: the mit world (glass 2: 1.9 s and 13 s, as glass 1), 100 ran 103 s, 10**6 for hours
MAX_GLASS = 2.0


def make_world(name: str = "office", seed: int = 0, clutter: float | None = None, glass: float | None = None,
               rough: float | None = None, scale: float | None = None, relief: float | None = None) -> World:
    """Build a named world; every random choice comes from ``seed``.

    Args:
        name: one of WORLD_NAMES ("cluttered" = the office at clutter level 1; "mit" = the
            MIT-CSAIL-like preset, MIT_PRESET).
        seed: seed of every random choice (the clutter has its own stream of it).
        clutter: clutter level (0 none, 1 a furnished office, 2-3 busy; see ``sim.clutter``);
            None = the name's default. Level 0 gives the world without clutter, bit for bit; at
            most MAX_CLUTTER.
        glass: glass panels per 10 m of route and clutter level (None = the name's default:
            ``ClutterConfig.glass``, 0.1 in the mit preset); ``lmsbench sim2real`` sets it from a
            log's no-return readings, since a glass panel reads as no return.
        rough: share of the rooms' wall length behind rough fill (``sim.clutter``; None = the
            name's default: none, MIT_PRESET["rough_cover"] in the mit preset); needs a clutter
            level > 0. ``lmsbench sim2real`` fits it to a log (``experiments.sim2real.fit_rough``).
        scale: the rooms' size (width and depth) as a multiple of the world's own, in the office
            generator's worlds (office, cluttered, random, mit; None or 1 = as they are, bit for bit);
            furniture attempts per room grow with the room's perimeter. ``lmsbench sim2real`` fits it
            to a log's share of readings beyond 4 m (``experiments.sim2real.fit_scale``).
        relief: share of the free wall length (rooms and corridors) under flat panels standing
            1-6 cm proud of the wall (``sim.clutter``; None = none); needs a clutter level > 0.
            ``lmsbench sim2real`` fits it to a log (``experiments.sim2real.fit_relief``).

    Raises:
        InputError: (an ``LmsbenchError`` and a ``ValueError``) for an unknown name (listing the known ones), a seed that is not a whole number
            >= 0, a clutter level outside [0, MAX_CLUTTER], a glass rate outside [0, MAX_GLASS], a rough or relief
            share outside [0, 1] (or > 0 at clutter level 0), or a scale outside [MIN_SCALE, MAX_SCALE]
            (or other than 1 for a world without rooms).
    """
    check_seed(seed)
    rng = np.random.default_rng([int(seed), _STREAM_WORLD])
    crng = np.random.default_rng([int(seed), _STREAM_CLUTTER])
    if not isinstance(name, str):
        raise InputError(f"name: unknown world {name!r}; known worlds: {', '.join(WORLD_NAMES)}")
    for arg, value in (("clutter", clutter), ("glass", glass), ("rough", rough), ("scale", scale), ("relief", relief)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating))):
            raise InputError(f"{arg}: must be a number or None, got {value!r}")
        if value is not None and not math.isfinite(float_of(value, arg, InputError)):
            raise InputError(f"{arg}: must be finite, got {value!r}")
    clutter, glass, rough, scale, relief = (None if v is None else float(v) for v in (clutter, glass, rough, scale, relief))
    level = float(MIT_PRESET["clutter"] if name == "mit" else DEFAULT_CLUTTER.get(name, 0.0)) if clutter is None else float(clutter)
    if not 0 <= level <= MAX_CLUTTER:
        raise InputError(f"clutter: must be in [0, {MAX_CLUTTER:g}], got {clutter}")
    if glass is not None and not (np.isfinite(glass) and 0 <= glass <= MAX_GLASS):
        raise InputError(f"glass: must be a rate in [0, {MAX_GLASS:g}] (panels per 10 m of route and clutter level; "
                         f"the long walls are full of glass by {MAX_GLASS:g}), got {glass:g}")
    if rough is not None and not (np.isfinite(rough) and 0 <= rough <= 1):
        raise InputError(f"rough: must be a share in [0, 1] of the rooms' wall length, got {rough}")
    if relief is not None and not (np.isfinite(relief) and 0 <= relief <= 1):
        raise InputError(f"relief: must be a share in [0, 1] of the free wall length, got {relief}")
    if relief is not None and relief > 0 and level == 0:
        raise InputError(f"relief: wall relief is clutter, so it needs a clutter level > 0 (the {name!r} world at "
                         f"clutter {level:g}), got {relief}")
    if scale is not None and not (np.isfinite(scale) and MIN_SCALE <= scale <= MAX_SCALE):
        raise InputError(f"scale: must be in [{MIN_SCALE:g}, {MAX_SCALE:g}] (the rooms' size as a multiple), got {scale}")
    if scale is not None and float(scale) != 1.0 and name in WORLD_NAMES and name not in ROOMED_WORLDS:
        raise InputError(f"scale: the {name!r} world has no rooms to scale (scale applies to office, cluttered, "
                         f"random and mit), got {scale}")
    if rough is not None and rough > 0 and level == 0:
        raise InputError(f"rough: rough fill is clutter, so it needs a clutter level > 0 (the {name!r} world at "
                         f"clutter {level:g}), got {rough}")
    size = 1.0 if scale is None else float(scale)
    leaf_rng = crng if level > 0 else None
    if name in ("office", "cluttered"):
        lay = office(rng, name, seed, room_w=4.0 * size, room_d=4.0 * size, leaf_rng=leaf_rng, furniture_scale=size)
    elif name == "random":
        lay = office(rng, name, seed, n_per_side=int(rng.integers(2, 5)), room_w=float(rng.uniform(3.2, 5.0)) * size,
                     room_d=float(rng.uniform(3.5, 5.0)) * size, corridor_w=float(rng.uniform(1.6, 2.6)),
                     chamfer=bool(rng.random() < 0.5), leaf_rng=leaf_rng, furniture_scale=size)
    elif name == "mit":
        preset = {k: v for k, v in MIT_PRESET.items() if k not in ("clutter", "glass_per_10m", "wall_runs_per_10m", "rough_cover")}
        preset["room_w"] = float(preset["room_w"]) * size
        preset["room_d"] = float(preset["room_d"]) * size
        lay = office(rng, name, seed, leaf_rng=leaf_rng, furniture_scale=size, **preset)  # type: ignore[arg-type]
    elif name == "corridor":
        lay = corridor(rng, seed)
    elif name == "angles":
        lay = angles(rng, seed)
    elif name == "pillars":
        lay = pillars(rng, seed)
    else:
        raise InputError(f"name: unknown world {name!r}; known worlds: {', '.join(WORLD_NAMES)}")
    config = (ClutterConfig(glass=float(MIT_PRESET["glass_per_10m"]), wall_runs=float(MIT_PRESET["wall_runs_per_10m"]),
                            rough_cover=float(MIT_PRESET["rough_cover"]))
              if name == "mit" else None)
    if glass is not None:
        config = replace(config if config is not None else ClutterConfig(), glass=float(glass))
    if rough is not None:
        config = replace(config if config is not None else ClutterConfig(), rough_cover=float(rough))
    if relief is not None:
        config = replace(config if config is not None else ClutterConfig(), relief=float(relief))
    panels = add_clutter(lay, crng, level, config)
    return lay.build(glass=panels)


def _walls_with_doors(lay: Layout, y: float, length: float, doors: list[float], door_w: float) -> None:
    xs = [0.0]
    for xd in sorted(doors):
        xs += [xd - door_w / 2, xd + door_w / 2]
    xs.append(length)
    for k in range(0, len(xs), 2):
        first, last = k == 0, k == len(xs) - 2
        lay.wall([(xs[k], y), (xs[k + 1], y)], extend_ends=(first, last))


def office(rng: np.random.Generator, name: str, seed: int, n_per_side: int = 3, room_w: float = 4.0,
           room_d: float = 4.0, corridor_w: float = 2.0, door_w: float = 1.0, chamfer: bool = True,
           corridor_extension: float = 0.0, leaf_rng: np.random.Generator | None = None,
           furniture_scale: float = 1.0, corridor_turns: bool = False) -> Layout:
    """Rooms on both sides of a corridor along x (corridor centre line y = corridor_w / 2).

    ``corridor_extension`` (m) runs the corridor on past the last rooms (a long, bare corridor);
    ``corridor_turns`` turns the corridor at both ends instead (north past the east rooms, south
    past the west ones: an L at each end, the plan a Z) and runs it on, as wide, along the end
    room's side to an end wall (room depth + corridor width long); corridors that meet and end
    within the scanner's range, as real floors have, rather than one straight corridor;
    ``leaf_rng`` draws each door leaf's opening angle (75-170 deg; None: 90 deg); rooms scaled by
    ``furniture_scale`` get that many times more furniture attempts (their perimeter grows so)."""
    lay = Layout(name, seed)
    t, cw, rw, rd = WALL_THICKNESS_M, corridor_w, room_w, room_d
    length = n_per_side * rw
    if corridor_turns:  # the outline turns with the corridor at both ends; the end rooms' outer walls are the
        # legs' inner walls
        lay.wall([(0, -rd), (length, -rd), (length, 0.0), (length + cw, 0.0), (length + cw, cw + rd), (0, cw + rd),
                  (0, cw), (-cw, cw), (-cw, -rd)], closed=True)
        lay.wall([(length, cw), (length, cw + rd)])
        lay.wall([(0.0, -rd), (0.0, 0.0)])
    elif corridor_extension > 0:  # the outline runs out along the corridor, past the rooms
        ext = length + corridor_extension
        lay.wall([(0, -rd), (length, -rd), (length, 0.0), (ext, 0.0), (ext, cw), (length, cw), (length, cw + rd),
                  (0, cw + rd)], closed=True)
    else:
        lay.wall([(0, -rd), (length, -rd), (length, cw + rd), (0, cw + rd)], closed=True)
    slack = rw / 2 - door_w / 2 - 0.35
    doors = {side: [k * rw + rw / 2 + float(rng.uniform(-slack, slack)) for k in range(n_per_side)]
             for side in (1, -1)}
    _walls_with_doors(lay, cw, length, doors[1], door_w)
    _walls_with_doors(lay, 0.0, length, doors[-1], door_w)
    for k in range(1, n_per_side):
        lay.wall([(k * rw, cw), (k * rw, cw + rd)])
        lay.wall([(k * rw, -rd), (k * rw, 0.0)])
    if chamfer:  # a 45 deg wall across the corridor's east end: two concave 135 deg corners
        c = min(0.7, cw / 2 - 0.1)
        lay.segment_box(np.array([length, cw - c]), np.array([length - c, cw]), t, 0.01, 0.01)
    # route: along the corridor, through every door to the room's centre
    corridor_nodes = {x: lay.node(x, cw / 2) for x in sorted(doors[1] + doors[-1])}
    west, east = lay.node(0.8, cw / 2), lay.node(length - 0.8 - (0.4 if chamfer else 0.0), cw / 2)
    lay.link(west, *corridor_nodes.values(), east)
    if corridor_turns:  # round each turn to the end of its leg
        for x, y, end in ((-cw / 2, -rd + 0.8, west), (length + cw / 2, cw + rd - 0.8, east)):
            lay.link(end, lay.node(x, cw / 2), lay.node(x, y, target=True))
    elif corridor_extension > 0:
        far = lay.node(length + corridor_extension - 0.8, cw / 2, target=True)
        lay.link(east, far)
    for side in (1, -1):
        for k, xd in enumerate(doors[side]):
            face_y = cw + t / 2 if side == 1 else -t / 2  # the room side of the corridor wall
            inside = lay.node(xd, face_y + side * 0.8)
            centre = lay.node(k * rw + rw / 2, cw + rd / 2 if side == 1 else -rd / 2, target=True)
            lay.link(corridor_nodes[xd], inside, centre)
            room = (k * rw + t / 2, (k + 1) * rw - t / 2,
                    (cw + t / 2, cw + rd - t / 2) if side == 1 else (-rd + t / 2, -t / 2))
            lay.rooms.append((room[0], room[1], *room[2]))
            route = np.array([lay.nodes[inside], lay.nodes[centre]])
            _furnish_room(lay, rng, room, xd, door_w, side, route, leaf_rng, furniture_scale)
    return lay


def _furnish_room(lay: Layout, rng: np.random.Generator, room: tuple, xd: float, door_w: float,
                  side: int, route: np.ndarray, leaf_rng: np.random.Generator | None = None,
                  furniture_scale: float = 1.0) -> None:
    """Furniture against the walls of one room, an open door leaf, maybe a pillar; nothing comes
    within CLEARANCE_M of the room's route (door -> centre). ``furniture_scale`` multiplies the
    number of pieces tried (2-5)."""
    x0, x1, (y0, y1) = room
    pts = route[0] + np.linspace(0, 1, 40)[:, None] * (route[1] - route[0])
    door_face_y = y0 if side == 1 else y1
    far_face_y = y1 if side == 1 else y0
    # open door leaf: hinged at the jamb away from the room's centre, swung 90 deg into the room
    hinge_side = 1.0 if route[1][0] < xd else -1.0
    leaf_x = xd + hinge_side * (door_w / 2 - 0.04)
    door_span = (xd - door_w / 2 - 0.15, xd + door_w / 2 + 0.15)
    if leaf_rng is None:
        leaf_c = np.array([leaf_x, door_face_y + side * (0.45 - 0.01)])
        lay.box(leaf_c[0], leaf_c[1], 0.0, 0.02, 0.45, 0.0, 2.0)
    else:  # open at any angle that leaves the doorway clear: 75-170 deg from the closed position
        hinge = np.array([leaf_x, door_face_y])
        for _ in range(20):
            theta = np.deg2rad(float(leaf_rng.uniform(75.0, 170.0)))
            d = np.array([-hinge_side * np.cos(theta), side * np.sin(theta)])
            c = hinge + d * (0.45 - 0.01)
            rect = rectangle_corners(c[0], c[1], float(np.arctan2(d[1], d[0])), 0.45, 0.02)
            if distance_to_rects(pts, [rect]).min() >= CLEARANCE_M:
                break
        else:
            theta, d = np.pi / 2, np.array([0.0, float(side)])
            c = hinge + d * (0.45 - 0.01)
        lay.box(c[0], c[1], float(np.arctan2(d[1], d[0])), 0.45, 0.02, 0.0, 2.0)
        reach = 0.9 * max(-np.cos(theta), 0.0)  # swung back past the jamb along the wall
        door_span = (min(door_span[0], leaf_x - reach - 0.15), max(door_span[1], leaf_x + reach + 0.15))
    occupied = {"far": [], "west": [], "east": [], "door": [door_span]}
    walls = {  # name: (point at start of usable span, direction along, inward normal, span length)
        "far": (np.array([x0, far_face_y]), np.array([1.0, 0.0]), np.array([0.0, -side]), x1 - x0),
        "door": (np.array([x0, door_face_y]), np.array([1.0, 0.0]), np.array([0.0, side]), x1 - x0),
        "west": (np.array([x0, y0]), np.array([0.0, 1.0]), np.array([1.0, 0.0]), y1 - y0),
        "east": (np.array([x1, y0]), np.array([0.0, 1.0]), np.array([-1.0, 0.0]), y1 - y0),
    }
    kinds = {"cabinet": ((0.8, 1.2), 0.45), "desk": ((1.2, 1.6), 0.7), "shelf": ((0.8, 1.0), 0.4)}
    placed: list[np.ndarray] = []
    for _ in range(int(round(int(rng.integers(2, 6)) * furniture_scale))):
        kind = str(rng.choice(list(kinds)))
        wall = str(rng.choice(list(walls)))
        (wlo, whi), depth = kinds[kind]
        width = float(rng.uniform(wlo, whi))
        start, along, inward, span = walls[wall]
        lo, hi = 0.8 + width / 2, span - 0.8 - width / 2
        if hi <= lo:
            continue
        s = float(rng.uniform(lo, hi))
        offset = start[0] if wall in ("far", "door") else start[1]
        iv = (offset + s - width / 2 - 0.2, offset + s + width / 2 + 0.2)
        if any(iv[0] < b and a < iv[1] for a, b in occupied[wall]):
            continue
        at = start + along * s
        yaw = float(np.arctan2(inward[1], inward[0]))
        c = at + inward * depth / 2
        footprint = rectangle_corners(c[0], c[1], yaw, depth / 2, width / 2)
        if distance_to_rects(pts, [footprint]).min() < CLEARANCE_M:
            continue
        occupied[wall].append(iv)
        placed.append(footprint)
        lay.against_wall(kind, at, inward, width, depth)
    if rng.random() < 0.6:  # a screen leaning off a wall: acute (45-60 deg) and obtuse corners
        _angled_screen(lay, rng, walls, occupied, placed, pts)
    roomy = x1 - 0.9 >= x0 + 0.9 and y1 - 0.9 >= y0 + 0.9  # (small rooms, scale near MIN_SCALE, have no middle)
    if rng.random() < 0.4 and roomy:  # a round pillar somewhere free
        for _ in range(20):
            r = float(rng.uniform(0.12, 0.3))
            c = np.array([rng.uniform(x0 + 0.9, x1 - 0.9), rng.uniform(y0 + 0.9, y1 - 0.9)])
            free_route = np.hypot(*(pts - c).T).min() - r >= CLEARANCE_M
            free_furniture = not placed or distance_to_rects(c[None], placed)[0] - r >= 0.5
            if free_route and free_furniture:
                lay.cylinder(c[0], c[1], r)
                break


def _angled_screen(lay: Layout, rng: np.random.Generator, walls: dict, occupied: dict,
                   placed: list[np.ndarray], route_pts: np.ndarray) -> None:
    """A 5 cm screen, 0.8-1.2 m long, standing off a wall at 45-60 deg: with the wall it makes an
    acute and an obtuse concave corner; its foot is sunk 4 cm into the wall."""
    thickness = 0.05
    for _ in range(10):
        wall = str(rng.choice(["far", "west", "east"]))
        start, along, inward, span = walls[wall]
        phi = np.deg2rad(float(rng.uniform(45.0, 60.0)))
        length = float(rng.uniform(0.8, 1.2))
        lean = float(rng.choice([-1.0, 1.0]))
        direction = np.cos(phi) * lean * along + np.sin(phi) * inward
        reach = length * np.cos(phi)  # extent along the wall
        s_min, s_max = 0.9 + max(0.0, -lean * reach), span - 0.9 - max(0.0, lean * reach)
        if s_max < s_min:
            continue  # the wall is too short for this screen (small rooms: scale near MIN_SCALE)
        s = float(rng.uniform(s_min, s_max))
        at = start + along * s
        tip = at + direction * length
        foot = at - direction * (0.04 / np.sin(phi))
        mid = (foot + tip) / 2
        yaw = float(np.arctan2(direction[1], direction[0]))
        footprint = rectangle_corners(mid[0], mid[1], yaw, float(np.hypot(*(tip - foot))) / 2, thickness / 2)
        offset = start[0] if wall in ("far", "door") else start[1]
        lo, hi = sorted((offset + s, offset + s + lean * reach))
        iv = (lo - 0.2, hi + 0.2)
        if any(iv[0] < b and a < iv[1] for a, b in occupied[wall]):
            continue
        if distance_to_rects(route_pts, [footprint]).min() < CLEARANCE_M:
            continue
        lay.segment_box(foot, tip, thickness, z1=1.6)
        occupied[wall].append(iv)
        placed.append(footprint)
        return


def corridor(rng: np.random.Generator, seed: int, length: float = 30.0, width: float = 1.8) -> Layout:
    """A long corridor: door recesses (0.3 m deep) and half-sunk round columns along both walls."""
    lay = Layout("corridor", seed)
    for side, y in ((1, width), (-1, 0.0)):
        pts = [(0.0, y)]
        x = 1.5
        while x < length - 3.0:
            w = float(rng.uniform(0.9, 1.3))
            if rng.random() < 0.65:  # a door recess
                pts += [(x, y), (x, y + side * 0.3), (x + w, y + side * 0.3), (x + w, y)]
            elif rng.random() < 0.6:  # a round column half sunk into the wall
                lay.cylinder(x + w / 2, y - side * 0.05, float(rng.uniform(0.15, 0.25)))
            x += w + float(rng.uniform(1.5, 4.0))
        pts.append((length, y))
        lay.wall(pts)
    lay.wall([(0.0, 0.0), (0.0, width)])
    lay.wall([(length, 0.0), (length, width)])
    a = lay.node(0.8, width / 2, target=True)
    b = lay.node(length - 0.8, width / 2, target=True)
    lay.link(a, b)
    return lay


def _v_screen(lay: Layout, apex: np.ndarray, heading: float, opening_deg: float, arm: float) -> None:
    """A freestanding V-shaped screen (5 cm thick, 1.6 m tall) with its apex at ``apex``."""
    half = np.deg2rad(opening_deg) / 2
    a = apex + arm * np.array([np.cos(heading + half), np.sin(heading + half)])
    b = apex + arm * np.array([np.cos(heading - half), np.sin(heading - half)])
    lay.wall([tuple(a), tuple(apex), tuple(b)], thickness=0.05, extend_ends=(False, False), z1=1.6)


def angles(rng: np.random.Generator, seed: int) -> Layout:
    """A hall with an acute (about 50 deg) corner, obtuse (130-135 deg) corners and V screens."""
    lay = Layout("angles", seed)
    jitter = float(rng.uniform(-0.3, 0.3))
    hall = [(0.0, 0.0), (8.0, 0.0), (10.0, 2.0), (10.0, 6.0), (5.0 + jitter, 6.0)]
    lay.wall(hall, closed=True)
    _v_screen(lay, np.array([6.5, 3.9]), np.deg2rad(-90 + float(rng.uniform(-20, 20))), 135.0, 1.0)
    _v_screen(lay, np.array([5.2, 2.0]), np.deg2rad(180 + float(rng.uniform(-20, 20))), 100.0, 0.8)
    nodes = [lay.node(*p, target=True) for p in ((2.4, 1.0), (4.5, 0.8), (8.6, 1.4), (8.8, 4.8),
                                                 (6.0, 5.2), (4.2, 3.6))]
    lay.link(*nodes, nodes[0])
    return lay


def pillars(rng: np.random.Generator, seed: int) -> Layout:
    """A 12 x 8 m hall with round pillars of radius 0.1-0.5 m and a curved wall (r = 2 m)."""
    lay = Layout("pillars", seed)
    lay.wall([(0.0, 0.0), (12.0, 0.0), (12.0, 8.0), (0.0, 8.0)], closed=True)
    lay.cylinder(6.0, 8.0 + 1.2, 2.0)  # curved wall: bulges 0.75 m into the hall from the north wall
    for x in (3.0, 6.0, 9.0):
        for y in (2.5, 5.5):
            lay.cylinder(x + float(rng.uniform(-0.2, 0.2)), y + float(rng.uniform(-0.2, 0.2)),
                         float(rng.uniform(0.1, 0.5)))
    # lanes at y = 1.2, 4.0, 6.7 joined at x = 1.2 and 10.8
    loop = [(1.2, 1.2), (6.0, 1.2), (10.8, 1.2), (10.8, 4.0), (10.8, 6.7), (6.0, 6.7), (1.2, 6.7), (1.2, 4.0)]
    nodes = [lay.node(*p, target=True) for p in loop]
    lay.link(*nodes, nodes[0])
    middle = lay.node(6.0, 4.0, target=True)
    lay.link(nodes[7], middle, nodes[3])
    return lay
