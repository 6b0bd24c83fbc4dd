"""A world: 3-D solids (boxes, cylinders) for PyBullet plus their exact 2-D cross-section at the
scanner's height (the ground truth), and a route graph for the robot.

All coordinates in metres in the world frame, angles in radians.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lms200 import LmsbenchError
from lms200.codes import real_rows
from lms200.errors import InputError
from lms200.finite import check_seed, digit_limit_problem, is_number, seed_problem, shown, underflow_problem

from .geometry import distance_to_segments, face_corners, rectangle_corners, union_faces
from .walls_only import box_thickness, orient_walls, unreproduced

SCAN_HEIGHT_M = 0.35  # height of the scan plane above the floor (LMS200 on a Pioneer-class robot)
MAX_COORD_M = 1e6  # m: the largest coordinate a world may hold (a building is < 1 km; beyond, float geometry degrades)
FACE_BOX_THICKNESS_M = 0.05  # thickness of the boxes rebuilt behind faces for a walls-only world.json
#: solids a world may hold at most (boxes + cylinders; a walls-only world.json's walls + circles): its
#: faces are built pair by pair, in time quadratic in them. The mit world has 909 (2,345 faces, 1.6 s);
#: a world.json of 8,000 walls took 88 s to be read, one of 200,000 hours (found by the wrong-input hunt)
MAX_SOLIDS = 5_000
#: route nodes at most: a tour's shortest paths are all pairs' (12 bytes a pair): a world.json of
#: 20,000 route nodes took 4.8 GB and a minute (the mit world has 42)
MAX_ROUTE_NODES = 2_000
MAX_WORLD_JSON_BYTES = 32 << 20  # a world.json read at most (the mit world's is 0.54 MB): refused unread
#: the keys of a world.json (``World.to_dict``); any other, or one given twice, is refused (:func:`world_json_content`)
#: longest world name (a file name's 255 bytes): simulate draws it as map.png's title, and a world.json
#: named with 100,000 characters ran over a minute in matplotlib, its image (and memory) growing with it
MAX_NAME_CHARS = 255
WORLD_JSON_KEYS = ("name", "seed", "scan_height", "walls", "circles", "corners", "boxes", "cylinders", "route_nodes",
                   "route_edges", "route_targets", "glass")


def _unique_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    """A JSON object's mapping, ValueError for a key it gives twice (``json`` keeps the last, silently)."""
    out: dict[str, object] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"key {key!r} given twice (the last would be taken, silently)")
        out[key] = value
    return out


def read_world_json(path: str | Path) -> bytes:
    """The bytes of the world.json at ``path``, for :meth:`World.from_json` and slam's reader of a
    simulate folder: LmsbenchError, unread, for a path that is no regular file (a pipe was waited on
    for ever, /dev/zero read until the memory ran out) or one of more than ``MAX_WORLD_JSON_BYTES``
    (slam's reader of a simulate folder read a world.json of any size whole: 3 GB took as much
    memory and more, an internal MemoryError; found by fuzzing)."""
    from lms200.logs import regular_file

    p = regular_file(path, "world.json")
    size = p.stat().st_size
    if size > MAX_WORLD_JSON_BYTES:  # read whole: a 3 GB file took as much memory
        raise LmsbenchError(f"{path}: {size:,} bytes, more than the {MAX_WORLD_JSON_BYTES:,} a world.json may "
                            f"hold (refused unread; the mit world's is 0.5 MB)")
    return p.read_bytes()


def world_json_text(data: bytes) -> str:
    """A world.json's bytes as text: UTF-8 (JSON's encoding, RFC 8259), after a byte-order mark some
    editors put first, which a JSON reader may skip (the TUM, relations and CARMEN readers skip it
    too); ValueError naming the first byte that is not UTF-8. It was read as ASCII: a world.json saved
    with a mark, or holding a "name" of letters beyond ASCII, was "'ascii' codec can't decode byte 0xef
    in position 0" for simulate and compare, while slam read it (fuzz4)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"not UTF-8 text (byte {exc.start} is not UTF-8)") from None


def _nonzero_float(text: str) -> float:
    """A JSON number with a fraction or exponent as ``json`` reads it, ValueError where it is written
    nonzero and reads as 0 (``lms200.finite.underflow_problem``: it was taken as 0 without a word)."""
    value = float(text)
    problem = underflow_problem(text, value)
    if problem:
        raise ValueError(problem)
    return value


def world_json_content(text: str) -> dict:
    """The mapping a world.json's text holds, for :meth:`World.from_json` and slam's reader of a
    simulate folder: ValueError / TypeError for text that is no JSON mapping, for a key given twice
    in any object, and for a key that is none of ``WORLD_JSON_KEYS``: a misspelt key
    (``"cylinder"``) or a second ``"cylinders": []`` left the pillars out of the simulation (or the
    walls out of slam's map score) without a word, exit 0. Text nested too deeply for ``json``
    (``[[[[...]]]]`` 100,000 deep) is a ValueError too: its RecursionError was slam's internal error."""
    try:  # a number written nonzero that reads as 0 (1e-400: a radius or a wall end at 0) is refused
        d = json.loads(text, object_pairs_hook=_unique_keys, parse_float=_nonzero_float)
    except RecursionError:
        raise ValueError("nested too deeply to parse") from None
    except ValueError as exc:  # Python's own limit: "... use sys.set_int_max_str_digits() to increase the limit"
        problem = digit_limit_problem(exc)
        if problem is None:
            raise
        raise ValueError(f"{problem}, which no field takes") from None
    if not isinstance(d, dict):
        raise TypeError(f"the top level is a {type(d).__name__}, not a mapping of walls, boxes, ...")
    unknown = sorted(set(d) - set(WORLD_JSON_KEYS))
    if unknown:
        import difflib

        near = {k: difflib.get_close_matches(k, WORLD_JSON_KEYS, n=1) for k in unknown}
        hint = "; ".join(f"{k!r} for {m[0]!r}?" for k, m in near.items() if m)
        raise ValueError(f"unknown key(s) {unknown}{' (' + hint + ')' if hint else ''}: a world.json has "
                         f"{', '.join(WORLD_JSON_KEYS)}")
    _check_plain_fields(d)
    return d


def _check_plain_fields(d: dict) -> None:
    """ValueError naming the field (and the row) for a world.json's ``name``, ``seed`` or ``corners``
    of the wrong kind: they were taken unread or as anything. A ``seed`` of 400 digits was kept and
    written again into simulate's world.json and drawn in map.png's title; 1.5 said only "must be a
    whole number"; ``"name": ["x"]`` became the title "['x']"; ``corners`` (the public truth, written
    for the user and rebuilt from the solids on reading) holding ``"x"`` or a row of two numbers
    was read, exit 0, though no world wrote it."""
    if "name" in d and not isinstance(d["name"], str):
        raise ValueError(f"name: must be text (the world's name), got {shown(d['name'])}")
    if "seed" in d:
        problem = seed_problem(d["seed"])  # the simulator's own rule: a world it made and wrote reads back
        if problem is not None:
            raise ValueError(f"seed: {problem}")
    corners = d.get("corners", [])
    must = ("a corner must be a list of x, y (m), angle_rad (finite numbers) and convex (true or false), "
            "as World.to_json writes it")
    if not isinstance(corners, list):
        raise ValueError(f"corners: must be a list of corners ({must}), got {shown(corners)}")
    for i, row in enumerate(corners):
        ok = isinstance(row, list) and len(row) == 4 and all(is_number(v) for v in row[:3]) and isinstance(row[3], bool)
        if ok:
            try:
                ok = all(math.isfinite(float(v)) for v in row[:3])
            except OverflowError:  # a whole number of 400 digits
                ok = False
        if not ok:
            raise ValueError(f"corners: corner {i} is {shown(row)}: {must}")


def spans_plane(z0: np.ndarray, z1: np.ndarray, scan_height: float) -> np.ndarray:
    """Which solids (bottoms ``z0``, tops ``z1``) the scan plane at ``scan_height`` cuts, ends included:
    only their cross-sections are walls and circles (World), and only they are scanned."""
    return (np.asarray(z0) <= scan_height) & (np.asarray(z1) >= scan_height)


def json_rows(value: object, field: str, item: str, columns: int, what: str) -> np.ndarray:
    """A world.json list of rows (``walls``, ``circles``, ``route_nodes``) as a float64 (k,
    ``columns``) array: a list of lists of ``columns`` numbers, or a flat list of numbers (read
    ``columns`` at a time, as before). ValueError, one line naming the field and the row's index
    and saying what a row must be, for anything else: a wall of 3 numbers was numpy's
    "inhomogeneous shape after 1 dimensions. The detected shape was (140,) + inhomogeneous part"."""
    must = f"a {item} must be a list of {columns} numbers {what}"
    if not isinstance(value, list):
        raise ValueError(f"{field}: must be a list of {item}s ({must}), got {shown(value)}")
    if all(is_number(v) for v in value):  # flat: one row, or rows run together
        if len(value) % columns:
            raise ValueError(f"{field}: a flat list of {len(value)} numbers is no whole number of {item}s ({must})")
        rows = [value[i:i + columns] for i in range(0, len(value), columns)]
    else:
        rows = value
    for i, row in enumerate(rows):
        if not (isinstance(row, list) and len(row) == columns and all(is_number(v) for v in row)):
            count = f" ({len(row)} numbers)" if isinstance(row, list) and all(is_number(v) for v in row) else ""
            raise ValueError(f"{field}: {item} {i} is {shown(row)}{count}: {must}")
    try:
        return np.asarray(rows, dtype=float).reshape(-1, columns)
    except OverflowError:  # a whole number too large for a float (400 digits) was an internal OverflowError
        for i, row in enumerate(rows):  # the row that holds it, looked for only when there is one
            try:
                [float(v) for v in row]
            except OverflowError:
                raise ValueError(f"{field}: {item} {i} is {shown(row)}, holding a number too large for a "
                                 f"float: {must}") from None
        raise


@dataclass(eq=False)
class World:
    """A simulated office world.

    Attributes:
        boxes: (n, 7) cx, cy, yaw, hx, hy, z0, z1: boxes (centre, heading, half sizes, bottom and
            top height), as PyBullet builds them.
        cylinders: (m, 5) cx, cy, r, z0, z1: vertical cylinders.
        scan_height: height of the scan plane (m).
        walls: (k, 4) x1, y1, x2, y2: every straight face of the cross-section at scan_height (the
            boundary of the union of the solids cut by the plane), solid on the left of p1 -> p2.
        circles: (c, 3) cx, cy, r: cylinders cut by the scan plane.
        corners: (q, 4) x, y, angle_rad, convex: where one face meets the next; angle_rad is the
            angle of the wedge the two faces make, in (0, pi); convex = 1 when that wedge is solid
            (the corner points into free space), 0 when it is free space (a room's corner).
        corner_faces: (q, 2) int: indices into walls of the face ending and the face starting at
            each corner.
        route_nodes: (p, 2) free-space points the robot may drive between; route_edges: (e, 2)
            int pairs of nodes joined by a collision-free straight drive; route_targets: node
            indices worth visiting (room centres).
        glass: (g, 4) x1, y1, x2, y2: glass panels at scan height. Not solids: a beam that meets
            one first reads no return (+inf); the visible truth counts them as occluders, never as
            faces.
    """

    name: str
    seed: int
    boxes: np.ndarray
    cylinders: np.ndarray
    scan_height: float = SCAN_HEIGHT_M
    route_nodes: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    route_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=int))
    route_targets: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    glass: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    walls: np.ndarray = field(init=False)
    circles: np.ndarray = field(init=False)
    corners: np.ndarray = field(init=False)
    corner_faces: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise InputError(f"name: must be text, got {type(self.name).__name__} {self.name!r}")
        if len(self.name) > MAX_NAME_CHARS:  # map.png's title: 100,000 characters drew for minutes, growing
            raise InputError(f"name: at most {MAX_NAME_CHARS} characters (a title, as a file name), got {shown(self.name)}")
        check_seed(self.seed)
        self.boxes = _rows_of(self.boxes, "boxes", 7, "cx, cy, yaw, hx, hy, z0, z1")
        self.cylinders = _rows_of(self.cylinders, "cylinders", 5, "cx, cy, r, z0, z1")
        self.route_nodes = _rows_of(self.route_nodes, "route_nodes", 2, "x, y")
        self.route_edges = _indices_of(self.route_edges, "route_edges", 2)
        self.route_targets = _indices_of(self.route_targets, "route_targets", 1).reshape(-1)
        self.glass = _rows_of(self.glass, "glass", 4, "x1, y1, x2, y2")
        if not is_number(self.scan_height):  # text was math.isfinite's TypeError
            raise InputError(f"scan_height: must be a finite height >= 0 m, got {shown(self.scan_height)}")
        self.scan_height = float(self.scan_height)
        self._check()
        h = self.scan_height
        cut_boxes = self.boxes[spans_plane(self.boxes[:, 5], self.boxes[:, 6], h)]
        cut_cyl = self.cylinders[spans_plane(self.cylinders[:, 3], self.cylinders[:, 4], h)]
        self.circles = cut_cyl[:, :3].copy()
        rects = [rectangle_corners(*b[:5]) for b in cut_boxes]
        self.walls = union_faces(rects, self.circles)
        self.corners, self.corner_faces = face_corners(self.walls)

    def _check(self) -> None:
        """Raise InputError (a ValueError) naming the field for values no world can have: non-finite or larger than
        MAX_COORD_M coordinates, solids of no size or upside down, a route that names nodes it does
        not have (the robot's tour indexes them)."""
        for name in ("boxes", "cylinders", "route_nodes", "glass"):
            a = getattr(self, name)
            if not np.isfinite(a).all() or (a.size and np.abs(a).max() > MAX_COORD_M):
                raise InputError(f"{name}: must be finite numbers within +-{MAX_COORD_M:g} m")
        if not (math.isfinite(self.scan_height) and 0 <= self.scan_height <= MAX_COORD_M):
            raise InputError(f"scan_height: must be a finite height >= 0 m, got {self.scan_height}")
        b, c = self.boxes, self.cylinders
        if ((b[:, 3] <= 0) | (b[:, 4] <= 0) | (b[:, 6] <= b[:, 5])).any():
            raise InputError("boxes: half sizes hx, hy must be > 0 and the top z1 above the bottom z0")
        if ((c[:, 2] <= 0) | (c[:, 4] <= c[:, 3])).any():
            raise InputError("cylinders: the radius must be > 0 and the top z1 above the bottom z0")
        _check_sizes(len(b) + len(c), "boxes and cylinders", len(self.route_nodes))
        n = len(self.route_nodes)
        for name in ("route_edges", "route_targets"):
            idx = getattr(self, name)
            if idx.size and (idx.min() < 0 or idx.max() >= n):
                raise InputError(f"{name}: node indices must be in [0, {n}) (route_nodes has {n}), "
                                 f"got {int(idx.min())}..{int(idx.max())}")

    # -- JSON ---------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The world.json content: the public ground truth (walls, circles, corners) plus what
        rebuilds the world exactly (solids, scan height, route)."""
        return {
            "name": self.name,
            "seed": int(self.seed),
            "scan_height": float(self.scan_height),
            "walls": _rows(self.walls),
            "circles": _rows(self.circles),
            "corners": [[*map(_num, c[:3]), bool(c[3])] for c in self.corners],
            "boxes": _rows(self.boxes),
            "cylinders": _rows(self.cylinders),
            "route_nodes": _rows(self.route_nodes),
            "route_edges": self.route_edges.tolist(),
            "route_targets": self.route_targets.tolist(),
            **({"glass": _rows(self.glass)} if len(self.glass) else {}),
        }

    def to_json(self, path: str | Path) -> None:
        """Write world.json (see :meth:`to_dict`)."""
        Path(path).write_text(json.dumps(self.to_dict(), indent=1) + "\n", encoding="ascii")

    @classmethod
    def from_json(cls, path: str | Path, data: bytes | None = None) -> "World":
        """Read a world.json. A file with only walls/circles gets thin boxes rebuilt behind each
        face (on its solid side, see ``sim.walls_only``: closed loops are oriented from the
        topology, open walls taken as drawn, solid on the left of p1 -> p2) and cylinders of 2 m
        height, so it can be simulated.

        ``data``: the file's bytes, read already (a sweep cell parses the bytes it keyed itself by);
        ``path`` then only names it.

        Raises:
            LmsbenchError: for a file that is not a world description, or a walls-only file whose
                rebuilt boxes do not give back its walls as faces.
        """
        if data is None:
            data = read_world_json(path)
        elif len(data) > MAX_WORLD_JSON_BYTES:  # read whole: a 3 GB file took as much memory
            raise LmsbenchError(f"{path}: {len(data):,} bytes, more than the {MAX_WORLD_JSON_BYTES:,} a world.json "
                                f"may hold (refused unread; the mit world's is 0.5 MB)")
        try:
            d = world_json_content(world_json_text(data))
            walls = json_rows(d.get("walls", []), "walls", "wall", 4, "x1, y1, x2, y2 (m)")
            circles = json_rows(d.get("circles", []), "circles", "circle", 3, "cx, cy, r (m)")
            for name, a in (("walls", walls), ("circles", circles)):  # before the walls-only rebuild, which
                if not np.isfinite(a).all() or (a.size and np.abs(a).max() > MAX_COORD_M):  # overflowed (warnings)
                    raise InputError(f"{name}: must be finite numbers within +-{MAX_COORD_M:g} m")
            route = json_rows(d.get("route_nodes", []), "route_nodes", "route node", 2, "x, y (m)")
            if "boxes" not in d:  # before the walls-only rebuild, quadratic in the walls
                _check_sizes(len(walls) + len(circles), "walls and circles", len(route))
        except WorldSizeError as exc:
            raise LmsbenchError(f"{path}: {exc}") from None
        except (ValueError, TypeError, UnicodeDecodeError) as exc:
            raise LmsbenchError(f"{path}: not a world.json ({exc})") from None
        try:
            h = d.get("scan_height", SCAN_HEIGHT_M)
            try:
                h = float(h)
            except OverflowError:  # 400 digits: "not a world.json (OverflowError: int too large to convert to float)"
                raise ValueError(f"scan_height: must be a finite height >= 0 m, got {shown(h)}") from None
            walls_only = "boxes" not in d
            if walls_only:
                walls = orient_walls(walls, np.vstack([circles[:, :2], route]))
                boxes = boxes_behind_faces(walls, h)
                cylinders = np.array([[cx, cy, r, 0.0, 2.0] for cx, cy, r in circles], dtype=float).reshape(-1, 5)
            else:
                boxes, cylinders = d["boxes"], d.get("cylinders", [])
            for field_, item, columns, what, value in (  # a 400-digit number: the row that holds it, not "got list"
                    ("boxes", "box", 7, "cx, cy, yaw, hx, hy, z0, z1", boxes),
                    ("cylinders", "cylinder", 5, "cx, cy, r, z0, z1", cylinders),
                    ("glass", "glass panel", 4, "x1, y1, x2, y2 (m)", d.get("glass", []))):
                _overflow_row(value, field_, item, columns, what)
            if len(boxes) == 0 and len(cylinders) == 0:  # `{}` or `{"walls": []}`: compare scored every extractor
                raise LmsbenchError(f"{path}: not a world.json: it holds no walls, circles or boxes, nothing to "
                                    "scan or score against")  # against no face (F1 0), slam ran, exit 0
            world = cls(
                name=str(d.get("name", Path(path).stem)),
                seed=d.get("seed", 0),  # int() read 1.5 as the world of seed 1, silently
                boxes=boxes,
                cylinders=cylinders,
                scan_height=h,
                route_nodes=route,
                route_edges=d.get("route_edges", []),
                route_targets=d.get("route_targets", []),
                glass=d.get("glass", []),
            )
        except WorldSizeError as exc:
            raise LmsbenchError(f"{path}: {exc}") from None
        except (ValueError, TypeError, KeyError, IndexError, OverflowError) as exc:  # a ValueError's text names its
            kind = "" if isinstance(exc, ValueError) else f"{type(exc).__name__}: "  # field (was "ValueError: ")
            raise LmsbenchError(f"{path}: not a world.json ({kind}{exc})") from None
        bad = unreproduced(walls, world.walls, FACE_BOX_THICKNESS_M) if walls_only else None
        if bad is not None:
            x1, y1, x2, y2 = walls[bad]
            raise LmsbenchError(
                f"{path}: wall {bad} ({x1:g}, {y1:g}) -> ({x2:g}, {y2:g}) is not a face of the world rebuilt "
                f"from the walls: a walls-only world.json needs the solid on the LEFT of p1 -> p2 (a room's "
                f"walls clockwise, a free-standing block's counter-clockwise; closed loops are re-oriented "
                f"automatically, open walls are taken as drawn), and thin boxes of {FACE_BOX_THICKNESS_M} m "
                f"behind each wall must not cover another wall; reverse that wall, or give 'boxes'"
            )
        return world

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the cross-section (m)."""
        pts = [self.walls[:, :2], self.walls[:, 2:]]
        if len(self.circles):
            c = self.circles
            pts += [c[:, :2] - c[:, 2:3], c[:, :2] + c[:, 2:3]]
        allp = np.vstack(pts)
        return (*allp.min(axis=0), *allp.max(axis=0))  # type: ignore[return-value]

    def clearance(self, points: np.ndarray) -> np.ndarray:
        """Distance (m) from each of (n, 2) points to the nearest face or circle."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        d = distance_to_segments(p, self.walls[:, :2], self.walls[:, 2:]).min(axis=1)
        if len(self.circles):
            c = self.circles
            dc = np.hypot(p[:, None, 0] - c[:, 0], p[:, None, 1] - c[:, 1]) - c[:, 2]
            d = np.minimum(d, dc.min(axis=1))
        return d


def _overflow_row(value: object, field: str, item: str, columns: int, what: str) -> None:
    """ValueError naming the row (``json_rows``'s) when the world.json list ``value`` holds a whole
    number too large for a float (World's own check said "boxes: must be a (k, 7) array of real
    numbers ..., got list", naming no row); anything else is left to World's checks."""
    try:
        np.asarray(value, dtype=float)
    except OverflowError:
        json_rows(value, field, item, columns, what)
    except (ValueError, TypeError):
        pass


def _rows_of(value: object, name: str, columns: int, what: str) -> np.ndarray:
    """A World field as a float64 (k, ``columns``) array (one row may be given flat); InputError
    naming the field for what is no array of real numbers of that shape. (Read by ``reshape(-1,
    columns)``: text and None were numpy's bare ValueError, complex numbers lost their imaginary
    part with a ComplexWarning, bools read as 0 / 1 m, and 12 numbers given as (2, 6) boxes were an
    internal error while 14 were read as two boxes of garbled fields.)"""
    if isinstance(value, np.ndarray) and value.shape == (columns,) or (
            isinstance(value, (list, tuple)) and len(value) == columns and all(is_number(v) for v in value)):
        value = np.reshape(value, (1, columns))
    return real_rows(value, name, columns, what, finite=False)  # finite and within MAX_COORD_M: _check


def _indices_of(value: object, name: str, columns: int) -> np.ndarray:
    """Route node indices as an int64 (k, ``columns``) array; InputError naming the field for
    what are no whole numbers (``route_edges=[[0.5, 1.7]]`` was truncated to the edge 0 - 1)."""
    column = value
    if columns == 1 and isinstance(value, (list, tuple, np.ndarray)):
        try:
            column = np.reshape(value, (-1, 1))
        except ValueError:  # a ragged list: refused by real_rows, naming it
            pass
    a = real_rows(column, name, columns, "route node indices")
    if not (np.abs(a) < 2**62).all() or not (a == np.rint(a)).all():  # (a cast of 1e300 to int64 warned)
        raise InputError(f"{name}: must be whole numbers (route node indices), got {shown(value)}")
    return a.astype(np.int64)  # exact: whole numbers below 2**62


class WorldSizeError(InputError):
    """A world of more solids or route nodes than it may hold (:func:`_check_sizes`)."""


def _check_sizes(solids: int, what: str, route_nodes: int) -> None:
    """WorldSizeError (an InputError) for a world of more than MAX_SOLIDS solids (``what``: their kinds) or
    MAX_ROUTE_NODES route nodes, before anything is built from them."""
    if solids > MAX_SOLIDS:
        raise WorldSizeError(f"{what}: {solids:,} in all, more than the {MAX_SOLIDS:,} a world may hold (the mit world "
                         "has 909 solids; the faces are built pair by pair, in time that grows as their square)")
    if route_nodes > MAX_ROUTE_NODES:
        raise WorldSizeError(f"route_nodes: {route_nodes:,}, more than the {MAX_ROUTE_NODES:,} a world may hold (the mit "
                         "world has 42; the tour plans over the shortest paths between every pair)")


def boxes_behind_faces(walls: np.ndarray, height: float) -> np.ndarray:
    """Thin boxes (n, 7) whose right face lies exactly on each wall face (solid on the left),
    ``FACE_BOX_THICKNESS_M`` thick or half the gap to the next wall behind (``box_thickness``)."""
    out = []
    walls = np.asarray(walls, dtype=float).reshape(-1, 4)
    thickness = box_thickness(walls, FACE_BOX_THICKNESS_M) if len(walls) else np.zeros(0)
    for (x1, y1, x2, y2), thick in zip(walls, thickness):
        d = np.array([x2 - x1, y2 - y1])
        length = float(np.hypot(*d))
        u = d / length
        left = np.array([-u[1], u[0]])
        c = np.array([(x1 + x2) / 2, (y1 + y2) / 2]) + left * thick / 2
        yaw = float(np.arctan2(u[1], u[0]))
        out.append([c[0], c[1], yaw, length / 2, thick / 2, 0.0, max(2.0, 2 * height)])
    return np.array(out, dtype=float).reshape(-1, 7)


def _num(v: float) -> float:
    return float(v) + 0.0  # full precision (exact round trip); + 0.0 turns -0.0 into 0.0


def _rows(a: np.ndarray) -> list[list[float]]:
    return [[_num(v) for v in row] for row in np.asarray(a)]
