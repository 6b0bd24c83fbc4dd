"""The solid side of a walls-only world.json (walls and circles, no boxes).

Rule: as in ``World.walls``, the solid is on the LEFT of p1 -> p2, so a room's walls run
clockwise and a free-standing block's counter-clockwise. Closed loops of walls are re-oriented
from the topology instead of trusting their drawn direction: the region a circle or route node
lies in is free space, loops alternate free / solid inwards, and without such hints the
outermost loops enclose free space (a room), unless the drawn directions consistently describe
solids with free space around them (an exported world with both faces of its walls).
Open walls are taken as drawn. ``unreproduced`` then checks that the thin boxes rebuilt behind
the walls give back every input wall as a face.
"""

from __future__ import annotations

import numpy as np

KEY_M = 1e-6  # m: end points closer than this are the same vertex


def _loops(walls: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Simple closed loops of walls (every vertex shared by exactly two walls of the loop):
    (wall indices in traversal order, vertices (k, 2) in that order, whether each wall is
    traversed from its p1)."""
    keys = [tuple(np.round(p / KEY_M).astype(np.int64)) for p in walls.reshape(-1, 2)]
    ends: dict[tuple, list[int]] = {}
    for end, key in enumerate(keys):
        ends.setdefault(key, []).append(end)  # end = 2 * wall + (0 start, 1 end)
    seen = np.zeros(len(walls), dtype=bool)
    loops = []
    for w0 in range(len(walls)):
        if seen[w0]:
            continue
        order, verts, forward, w, at = [], [], [], w0, 2 * w0
        closed = False
        while True:
            seen[w] = True
            order.append(w)
            forward.append(at % 2 == 0)
            verts.append(walls[w, 0:2] if at % 2 == 0 else walls[w, 2:4])
            other = at ^ 1  # the wall's far end
            shared = ends[keys[other]]
            if len(shared) != 2:
                break
            nxt = shared[0] if shared[1] == other else shared[1]
            if nxt // 2 == w0:
                closed = nxt == 2 * w0 or nxt == 2 * w0 + 1
                break
            if seen[nxt // 2]:
                break
            w, at = nxt // 2, nxt
        if closed and len(order) >= 3:
            loops.append((np.array(order), np.array(verts), np.array(forward)))
    return loops


def _inside(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd test: which of the (n, 2) points lie inside polygon (k, 2)."""
    x, y = points[:, 0:1], points[:, 1:2]
    x1, y1 = poly[:, 0], poly[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    crosses = (y1 > y) != (y2 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
    return (np.count_nonzero(crosses & (x < xi), axis=1) % 2) == 1


def _signed_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def orient_walls(walls: np.ndarray, free_points: np.ndarray) -> np.ndarray:
    """``walls`` (n, 4) with every closed loop re-oriented so that the solid is on the left of
    p1 -> p2 (see the module docstring); ``free_points`` (m, 2) are points known to lie in a free
    region (circle centres: the region around a cylinder; route nodes)."""
    walls = np.asarray(walls, dtype=float).reshape(-1, 4).copy()
    loops = _loops(walls)
    if not loops:
        return walls
    hints = np.asarray(free_points, dtype=float).reshape(-1, 2)
    polys = [v for _, v, _ in loops]
    probe = np.array([0.5 * (v[0] + v[1]) for v in polys])  # a point on each loop
    loop_depth = np.zeros(len(loops), dtype=int)
    hint_depth = np.zeros(len(hints), dtype=int)
    for k, poly in enumerate(polys):
        others = np.arange(len(loops)) != k
        loop_depth[others] += _inside(probe[others], poly)
        hint_depth += _inside(hints, poly) if len(hints) else 0
    ccw = np.array([_signed_area(v) > 0 for v in polys])
    # unbounded_free: the region outside every loop (depth 0) is free; depth d is free iff
    # (d even) == unbounded_free; the inside of a loop at depth k is at depth k + 1
    if len(hints):
        votes_free = np.count_nonzero(hint_depth % 2 == 0)
        unbounded_free = bool(votes_free > len(hints) - votes_free)
    else:
        # drawn by the rule with free space around solids: inside solid (CCW) at even loop depth
        consistent = np.array_equal(ccw, loop_depth % 2 == 0)
        unbounded_free = bool(consistent and loop_depth.max() >= 1)
    for k, (order, _, forward) in enumerate(loops):
        inside_free = ((loop_depth[k] + 1) % 2 == 0) == unbounded_free
        want_ccw = not inside_free  # solid inside -> counter-clockwise (solid on the left)
        swap = order[forward != (ccw[k] == want_ccw)]  # walls running against the wanted turn
        walls[swap] = walls[swap][:, [2, 3, 0, 1]]
    return walls


def unreproduced(walls: np.ndarray, faces: np.ndarray, tolerance_m: float) -> int | None:
    """Index of the first wall (n, 4) that the rebuilt world's ``faces`` (m, 4) do not reproduce:
    collinear faces of the same direction must cover it, except pieces of at most
    ``tolerance_m`` (where another wall's box abuts it); None when every wall is reproduced."""
    for i, (x1, y1, x2, y2) in enumerate(walls):
        d = np.array([x2 - x1, y2 - y1])
        length = float(np.hypot(*d))
        u = d / length
        n = np.array([-u[1], u[0]])
        a, b = faces[:, :2] - (x1, y1), faces[:, 2:] - (x1, y1)
        on_line = (np.abs(a @ n) < KEY_M) & (np.abs(b @ n) < KEY_M)
        ta, tb = a @ u, b @ u
        same_way = tb > ta
        lo = np.clip(ta[on_line & same_way], 0, length)
        hi = np.clip(tb[on_line & same_way], 0, length)
        covered_to, worst = 0.0, 0.0
        for s, e in sorted(zip(lo, hi)):
            worst = max(worst, s - covered_to)
            covered_to = max(covered_to, e)
        worst = max(worst, length - covered_to)
        if worst > tolerance_m + KEY_M:
            return i
    return None


def box_thickness(walls: np.ndarray, most_m: float) -> np.ndarray:
    """Thickness (m) of the box rebuilt behind each wall: ``most_m``, or half the distance to the
    nearest other wall behind it (rays along the left normal from 9 points of the wall) when that
    is less, so that the box of one face of a thin solid (a 4 cm door panel) does not cover the
    opposite face."""
    p1, p2 = walls[:, :2], walls[:, 2:]
    d = p2 - p1
    u = d / np.hypot(d[:, 0], d[:, 1])[:, None]
    normal = np.column_stack((-u[:, 1], u[:, 0]))
    t = np.linspace(0.1, 0.9, 9)
    out = np.full(len(walls), most_m)
    e = p2 - p1  # other walls: q = p1 + s e, s in [0, 1]
    for i in range(len(walls)):
        origin = p1[i] + t[:, None] * d[i]  # (9, 2) ray origins
        n = normal[i]
        denom = n[0] * e[:, 1] - n[1] * e[:, 0]  # cross(n, e)
        w = p1[None, :, :] - origin[:, None, :]  # (9, m, 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = (w[..., 0] * e[:, 1] - w[..., 1] * e[:, 0]) / denom  # along the ray
            s = (w[..., 0] * n[1] - w[..., 1] * n[0]) / denom  # along the other wall
        hit = (s >= 0) & (s <= 1) & (dist > 1e-9) & np.isfinite(dist)
        hit[:, i] = False
        if hit.any():
            out[i] = min(most_m, 0.5 * float(dist[hit].min()))
    return out
