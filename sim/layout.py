"""Building blocks for world descriptions: walls along polylines (boxes with mitred joints),
furniture (cabinets, desks with panel legs, open door leaves), pillars, and a route graph."""

from __future__ import annotations

import numpy as np

from .geometry import distance_to_segments, rectangle_corners
from .world import SCAN_HEIGHT_M, World

WALL_THICKNESS_M = 0.10
WALL_HEIGHT_M = 2.5
EMBED_M = 0.01  # furniture backs sink this far into the wall, so faces never coincide


class Layout:
    """Accumulates solids and a route graph, then builds a :class:`World`."""

    def __init__(self, name: str, seed: int) -> None:
        self.name, self.seed = name, seed
        self.boxes: list[list[float]] = []
        self.cylinders: list[list[float]] = []
        self.nodes: list[tuple[float, float]] = []
        self.edges: list[tuple[int, int]] = []
        self.targets: list[int] = []
        self.rooms: list[tuple[float, float, float, float]] = []  # x0, x1, y0, y1 of each room (clutter's rough fill)

    # -- solids -------------------------------------------------------------------------------
    def box(self, cx: float, cy: float, yaw: float, hx: float, hy: float,
            z0: float = 0.0, z1: float = WALL_HEIGHT_M) -> None:
        self.boxes.append([cx, cy, yaw, hx, hy, z0, z1])

    def segment_box(self, p: np.ndarray, q: np.ndarray, thickness: float, ext0: float = 0.0,
                    ext1: float = 0.0, z0: float = 0.0, z1: float = WALL_HEIGHT_M) -> None:
        """A box centred on segment p-q, lengthened by ext0 before p and ext1 after q."""
        p, q = np.asarray(p, float), np.asarray(q, float)
        d = q - p
        length = float(np.hypot(*d))
        u = d / length
        a, b = p - u * ext0, q + u * ext1
        c = (a + b) / 2
        self.box(c[0], c[1], float(np.arctan2(u[1], u[0])), (length + ext0 + ext1) / 2, thickness / 2, z0, z1)

    def wall(self, points: list[tuple[float, float]], closed: bool = False, thickness: float = WALL_THICKNESS_M,
             extend_ends: tuple[bool, bool] = (True, True), z1: float = WALL_HEIGHT_M) -> None:
        """A wall along a polyline: one box per leg, mitred at each joint so that the faces on both
        sides meet exactly (legs lengthened by (t/2) tan(turn/2)). Free ends are lengthened by t/2
        where ``extend_ends`` says so (to sink into a crossing wall), or end flush (a door jamb)."""
        pts = [np.asarray(p, float) for p in points]
        if closed:
            pts = pts + [pts[0]]
        n = len(pts) - 1

        def miter(d0: np.ndarray, d1: np.ndarray) -> float:  # extension at a joint turning from d0 to d1
            turn = abs(np.arctan2(d0[0] * d1[1] - d0[1] * d1[0], d0 @ d1))
            return thickness / 2 * np.tan(turn / 2)

        def joint(k: int) -> float:  # extension at the joint between leg k-1 and leg k
            return miter(pts[k] - pts[k - 1], pts[k + 1] - pts[k])

        closing = miter(pts[n] - pts[n - 1], pts[1] - pts[0]) if closed else 0.0  # last leg -> first
        for k in range(n):
            if k > 0:
                e0 = joint(k)
            elif closed:
                e0 = closing
            else:
                e0 = thickness / 2 if extend_ends[0] else 0.0
            if k < n - 1:
                e1 = joint(k + 1)
            elif closed:
                e1 = closing
            else:
                e1 = thickness / 2 if extend_ends[1] else 0.0
            self.segment_box(pts[k], pts[k + 1], thickness, e0, e1, 0.0, z1)

    def cylinder(self, cx: float, cy: float, r: float, z0: float = 0.0, z1: float = WALL_HEIGHT_M) -> None:
        self.cylinders.append([cx, cy, r, z0, z1])

    def against_wall(self, kind: str, at: np.ndarray, inward: np.ndarray, width: float,
                     depth: float) -> list[np.ndarray]:
        """Furniture standing with its back on a wall face: ``at`` is the middle of its back on the
        face, ``inward`` the unit normal into the room. Returns the footprint rectangles (CCW
        corners) it adds at scan height, for clearance checks.

        kinds: cabinet (one box, 1.2 m tall), desk (top at 0.72-0.75 m on two panel legs 3 cm
        thick), shelf (0.4 m deep, 2 m tall).
        """
        at, inward = np.asarray(at, float), np.asarray(inward, float)
        yaw = float(np.arctan2(inward[1], inward[0]))
        along = np.array([-inward[1], inward[0]])
        centre = at + inward * (depth / 2 - EMBED_M)
        if kind in ("cabinet", "shelf"):
            height = 1.2 if kind == "cabinet" else 2.0
            self.box(centre[0], centre[1], yaw, depth / 2, width / 2, 0.0, height)
            return [rectangle_corners(centre[0], centre[1], yaw, depth / 2, width / 2)]
        if kind == "desk":
            self.box(centre[0], centre[1], yaw, depth / 2, width / 2, 0.72, 0.75)
            rects = []
            for side in (-1, 1):
                leg = centre + along * side * (width / 2 - 0.015)
                self.box(leg[0], leg[1], yaw, depth / 2, 0.015, 0.0, 0.72)
                rects.append(rectangle_corners(leg[0], leg[1], yaw, depth / 2, 0.015))
            return rects
        raise ValueError(f"kind: unknown furniture {kind!r}")

    # -- route --------------------------------------------------------------------------------
    def node(self, x: float, y: float, target: bool = False) -> int:
        self.nodes.append((float(x), float(y)))
        if target:
            self.targets.append(len(self.nodes) - 1)
        return len(self.nodes) - 1

    def link(self, *chain: int) -> None:
        for a, b in zip(chain, chain[1:]):
            self.edges.append((a, b))

    def build(self, scan_height: float = SCAN_HEIGHT_M, glass: list[list[float]] | None = None) -> World:
        return World(self.name, self.seed, np.array(self.boxes), np.array(self.cylinders).reshape(-1, 5),
                     scan_height, np.array(self.nodes), np.array(self.edges), np.array(self.targets),
                     np.array(glass or [], dtype=float).reshape(-1, 4))


def distance_to_rects(points: np.ndarray, rects: list[np.ndarray]) -> np.ndarray:
    """Distance (m) from (n, 2) points to the nearest of some CCW rectangles (0 inside)."""
    p = np.asarray(points, float).reshape(-1, 2)
    best = np.full(len(p), np.inf)
    for r in rects:
        a, b = r, np.roll(r, -1, axis=0)
        ab = b - a
        d = distance_to_segments(p, a, b).min(axis=1)
        rel = p[:, None, :] - a
        inside = np.all(ab[:, 0] * rel[..., 1] - ab[:, 1] * rel[..., 0] > 0, axis=1)
        best = np.minimum(best, np.where(inside, 0.0, d))
    return best
