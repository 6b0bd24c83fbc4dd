"""Ground truth (world faces, corners, visible_truth) against hand-built geometry and against the
independent exact ray caster in sim_oracle."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lms200 import LmsbenchError
from sim import SensorConfig, World, make_world, visible_truth
from sim.layout import Layout

from sim_oracle import free_poses, oracle_ranges


def test_square_room_faces_and_corners_by_hand() -> None:
    lay = Layout("room", 0)
    lay.wall([(0, 0), (4, 0), (4, 3), (0, 3)], closed=True)  # 10 cm walls centred on the lines
    w = lay.build()
    inner = [f for f in w.walls if max(abs(f[0] - 2), abs(f[2] - 2)) <= 1.95 + 1e-9 and max(abs(f[1] - 1.5), abs(f[3] - 1.5)) <= 1.45 + 1e-9]
    assert len(w.walls) == 8 and len(inner) == 4
    lengths = sorted(np.hypot(f[2] - f[0], f[3] - f[1]) for f in inner)
    assert lengths == pytest.approx([2.9, 2.9, 3.9, 3.9])
    assert len(w.corners) == 8
    concave = w.corners[w.corners[:, 3] == 0]
    assert sorted(map(tuple, np.round(concave[:, :2], 9))) == [(0.05, 0.05), (0.05, 2.95), (3.95, 0.05), (3.95, 2.95)]
    assert np.allclose(w.corners[:, 2], np.pi / 2)
    # solid on the left of every face: the room's centre is on the right of the inner faces
    for x1, y1, x2, y2 in inner:
        assert (x2 - x1) * (1.5 - y1) - (y2 - y1) * (2 - x1) < 0


def test_v_screen_corner_angles() -> None:
    w = make_world("angles", seed=0)
    degrees = np.rad2deg(w.corners[:, 2])
    assert np.any(np.abs(degrees - 135) < 0.5) and np.any(degrees < 60)
    convex_obtuse = w.corners[(w.corners[:, 3] == 1) & (np.abs(degrees - 135) < 0.5)]
    assert len(convex_obtuse) >= 1  # outside of the 135 deg V screen


def test_walls_only_world_json_is_simulated_on_boxes_behind_its_faces(tmp_path) -> None:
    (tmp_path / "w.json").write_text('{"walls": [[0, 0, 0, 4], [0, 4, 5, 4], [5, 4, 5, 0], [5, 0, 0, 0]], '
                                     '"circles": [[2.5, 2.0, 0.3]], "corners": []}')
    w = World.from_json(tmp_path / "w.json")
    from sim.lidar import LMS200Sim
    with LMS200Sim(w, SensorConfig.ideal()) as lidar:
        scan = lidar.scan_at((1.0, 2.0, 0.0))
    assert scan.ranges[180] == pytest.approx(1.5 - 0.3, abs=1e-9)  # the circle, straight ahead
    assert scan.ranges[0] == pytest.approx(2.0, abs=1e-9)  # the wall y = 0, to the right
    assert scan.ranges[360] == pytest.approx(2.0, abs=1e-9)  # the wall y = 4, to the left


def test_world_json_round_trip(tmp_path) -> None:
    w = make_world("office", seed=2)
    w.to_json(tmp_path / "world.json")
    d = json.loads((tmp_path / "world.json").read_text())
    assert set(d) >= {"walls", "circles", "corners"}
    assert all(len(r) == 4 for r in d["walls"]) and all(isinstance(c[3], bool) for c in d["corners"])
    w2 = World.from_json(tmp_path / "world.json")
    assert np.allclose(w2.walls, w.walls, atol=1e-8) and np.allclose(w2.corners, w.corners, atol=1e-8)
    w2.to_json(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_bytes() == (tmp_path / "world.json").read_bytes()


def test_make_world_is_seeded_and_names_checked() -> None:
    assert np.array_equal(make_world("random", 5).walls, make_world("random", 5).walls)
    assert not np.array_equal(make_world("random", 5).boxes.shape, make_world("random", 6).boxes.shape) or \
        not np.allclose(make_world("random", 5).boxes, make_world("random", 6).boxes)
    with pytest.raises(ValueError, match="unknown world 'moon'"):
        make_world("moon")


@pytest.mark.parametrize("name", ["office", "corridor", "angles", "pillars", "random"])
def test_routes_keep_clear_of_everything(name: str) -> None:
    for seed in range(3):
        w = make_world(name, seed)
        for a, b in w.route_edges:
            pts = w.route_nodes[a] + np.linspace(0, 1, 60)[:, None] * (w.route_nodes[b] - w.route_nodes[a])
            assert w.clearance(pts).min() >= 0.4


def _sensor_hits(pose: np.ndarray, ranges: np.ndarray, sensor: SensorConfig) -> np.ndarray:
    r = np.where(np.isfinite(ranges), ranges, np.nan)
    return np.column_stack((r * np.cos(sensor.angles), r * np.sin(sensor.angles)))


@pytest.mark.parametrize("name", ["office", "angles", "pillars"])
def test_visible_truth_agrees_with_exact_ray_caster(name: str) -> None:
    world = make_world(name, seed=1)
    sensor = SensorConfig.ideal()
    rng = np.random.default_rng(11)
    for pose in free_poses(world, rng, 10):
        truth = visible_truth(world, tuple(pose), sensor)
        ref, grazing = oracle_ranges(world.boxes, world.cylinders, world.scan_height, pose[:2],
                                     pose[2] + sensor.angles, sensor.range_max)
        hits = _sensor_hits(pose, ref, sensor)
        covered = np.zeros(sensor.n_beams, dtype=bool)
        for (x1, y1, x2, y2), (first, last) in zip(truth.segments, truth.segment_beams):
            assert 0 <= first <= last < sensor.n_beams
            u = np.array([x2 - x1, y2 - y1]) / np.hypot(x2 - x1, y2 - y1)
            rel = hits[first:last + 1] - (x1, y1)
            ok = ~grazing[first:last + 1]
            # every beam of the span hits this segment: on its line, between its ends
            assert np.all(np.abs(rel[ok] @ np.array([-u[1], u[0]])) < 1e-6)
            along = rel[ok] @ u
            assert np.all((along > -1e-6) & (along < np.hypot(x2 - x1, y2 - y1) + 1e-6))
            covered[first:last + 1] = True
        # every beam that hits a straight face is in some segment's span
        on_circle = np.zeros(sensor.n_beams, dtype=bool)
        world_hits = pose[:2] + np.where(np.isfinite(ref), ref, np.nan)[:, None] * np.column_stack((np.cos(pose[2] + sensor.angles), np.sin(pose[2] + sensor.angles)))
        for cx, cy, r in world.circles:
            on_circle |= np.abs(np.hypot(world_hits[:, 0] - cx, world_hits[:, 1] - cy) - r) < 1e-6
        should = np.isfinite(ref) & ~on_circle & ~grazing
        assert np.all(covered[should])
        # every visible corner: nothing between the scanner and it
        for (cx, cy, _, _), beam in zip(truth.corners, truth.corner_beams):
            bearing = np.arctan2(cy, cx)
            r, g = oracle_ranges(world.boxes, world.cylinders, world.scan_height, pose[:2],
                                 np.array([pose[2] + bearing]), sensor.range_max)
            assert g[0] or r[0] == pytest.approx(np.hypot(cx, cy), abs=1e-6)
            assert abs(sensor.angles[beam] - bearing) <= sensor.angle_increment / 2 + 1e-9


def test_visible_truth_sees_room_from_inside_by_hand() -> None:
    lay = Layout("room", 0)
    lay.wall([(0, 0), (4, 0), (4, 3), (0, 3)], closed=True)
    w = lay.build()
    t = visible_truth(w, (2.0, 1.5, 0.0), SensorConfig.ideal())
    # looking along +x from the centre: the far wall x = 3.95 whole, half of each side wall
    assert len(t.segments) == 3 and len(t.corners) == 2
    far = t.segments[1]
    assert far == pytest.approx([1.95, -1.45, 1.95, 1.45])
    assert t.segments[0] == pytest.approx([0.0, -1.45, 1.95, -1.45])  # beam 0 looks along -y
    assert t.segment_beams[0][0] == 0 and t.segment_beams[-1][1] == 360
    assert np.allclose(t.corners[:, :2], [[1.95, -1.45], [1.95, 1.45]])
    assert np.all(t.corners[:, 3] == 0)


def _square(tmp_path, name: str, loops: list, circles: list = (), extra: list = ()) -> World:
    walls = [[*p[i], *p[(i + 1) % len(p)]] for p in loops for i in range(len(p))] + list(extra)
    (tmp_path / name).write_text(json.dumps({"walls": walls, "circles": list(circles)}))
    return World.from_json(tmp_path / name)


def test_walls_only_room_is_the_same_drawn_either_way_round(tmp_path) -> None:
    """A 3 m room drawn counter-clockwise got thin boxes inside it (truth 1.45 m from the centre,
    8 faces); closed loops are now oriented from the topology, so both directions give the room
    with its walls 1.5 m from the centre, each wall a face running clockwise (solid on the left)."""
    from sim.lidar import LMS200Sim
    ccw = [(0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)]
    for name, loop in (("ccw.json", ccw), ("cw.json", ccw[::-1])):
        w = _square(tmp_path, name, [loop])
        inside = w.walls[(np.abs(w.walls - 1.5) <= 1.5 + 1e-9).all(axis=1)]
        assert len(inside) == 4, name
        assert all(x1 * y2 - x2 * y1 + (x2 - x1) * 1.5 - (y2 - y1) * 1.5 < 0 for x1, y1, x2, y2 in inside)  # CW
        with LMS200Sim(w, SensorConfig.ideal()) as lidar:
            scan = lidar.scan_at((1.5, 1.5, 0.0))
        assert scan.ranges[[0, 180, 360]] == pytest.approx([1.5, 1.5, 1.5], abs=1e-9), name
        truth = visible_truth(w, (1.5, 1.5, 0.0), SensorConfig.ideal())
        assert len(truth.segments) == 3  # right, front and left walls, none 5 cm inside
        rho = np.abs(truth.segments[:, 0] * truth.segments[:, 3] - truth.segments[:, 2] * truth.segments[:, 1]) / \
            np.hypot(truth.segments[:, 2] - truth.segments[:, 0], truth.segments[:, 3] - truth.segments[:, 1])
        assert rho == pytest.approx([1.5, 1.5, 1.5], abs=1e-9)


def test_walls_only_block_in_a_room_with_a_pillar(tmp_path) -> None:
    """Everything drawn counter-clockwise: the outer loop (the room, with a pillar in it) becomes
    clockwise, the loop inside it stays a solid block (counter-clockwise)."""
    room = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]
    block = [(4.0, 1.5), (5.0, 1.5), (5.0, 2.5), (4.0, 2.5)]
    w = _square(tmp_path, "w.json", [room, block], circles=[[1.0, 3.0, 0.2]])
    from sim.lidar import LMS200Sim
    with LMS200Sim(w, SensorConfig.ideal()) as lidar:
        scan = lidar.scan_at((2.0, 2.0, 0.0))
    assert scan.ranges[180] == pytest.approx(2.0, abs=1e-9)  # the block's near face at x = 4
    assert scan.ranges[0] == pytest.approx(2.0, abs=1e-9)  # the room's wall y = 0


def test_walls_only_exported_world_is_rebuilt_with_its_faces(tmp_path) -> None:
    """An office's faces (both sides of every wall, 4 cm door panels) exported without boxes come
    back unchanged: each original face is a face of the rebuilt world."""
    from sim.walls_only import unreproduced
    w = make_world("office", seed=0)
    (tmp_path / "w.json").write_text(json.dumps({"walls": w.walls.tolist(), "circles": w.circles.tolist()}))
    w2 = World.from_json(tmp_path / "w.json")
    assert unreproduced(w.walls, w2.walls, 1e-9) is None


def test_walls_only_walls_the_boxes_cannot_reproduce_are_an_error(tmp_path) -> None:
    """A screen drawn as two opposite walls on the same line (zero thickness: solid on both sides)
    cannot be rebuilt from boxes behind its faces: the file is refused with the direction rule."""
    room_cw = [(0.0, 0.0), (0.0, 3.0), (3.0, 3.0), (3.0, 0.0)]
    with pytest.raises(LmsbenchError, match=r"wall 4 \(1, 1\) -> \(2, 1\).*solid on the LEFT of p1 -> p2"):
        _square(tmp_path, "bad.json", [room_cw], extra=[[1.0, 1.0, 2.0, 1.0], [2.0, 1.0, 1.0, 1.0]])
    # a loose wall 2 cm in front of a room wall, solid towards it: its box is thinned to the gap
    w = _square(tmp_path, "thin.json", [room_cw], extra=[[2.0, 0.02, 1.0, 0.02]])
    assert any(np.allclose(f, [3.0, 0.0, 0.0, 0.0]) for f in w.walls)  # the room wall stays whole


def test_a_world_json_too_big_to_build_is_refused_before_the_geometry(tmp_path) -> None:
    """The wrong-input hunt: a walls-only world.json of 200,000 walls was read for hours (its faces
    are built pair by pair; 8,000 took 88 s) before `simulate` said anything, one of 20,000 route
    nodes took 4.8 GB (all pairs' shortest paths), and a file was read whole whatever its size."""
    import time

    from sim.world import MAX_ROUTE_NODES, MAX_SOLIDS, MAX_WORLD_JSON_BYTES

    walls = [[0.001 * i, 0.0, 0.001 * i + 0.0005, 1.0] for i in range(MAX_SOLIDS + 1)]
    (tmp_path / "walls.json").write_text(json.dumps({"walls": walls}))
    start = time.perf_counter()
    with pytest.raises(LmsbenchError, match=r"walls.json: walls and circles: 5,001 in all, more than the 5,000 "
                                            r"a world may hold \(the mit world has 909 solids"):
        World.from_json(tmp_path / "walls.json")
    assert time.perf_counter() - start < 5.0
    d = make_world("office", 0).to_dict()
    boxes = {**d, "boxes": d["boxes"] * (MAX_SOLIDS // len(d["boxes"]) + 1)}
    (tmp_path / "boxes.json").write_text(json.dumps(boxes))
    with pytest.raises(LmsbenchError, match=r"boxes.json: boxes and cylinders: [0-9,]+ in all, more than the 5,000"):
        World.from_json(tmp_path / "boxes.json")
    nodes = {**d, "route_nodes": [[1.0, 1.0]] * (MAX_ROUTE_NODES + 1)}
    (tmp_path / "nodes.json").write_text(json.dumps(nodes))
    with pytest.raises(LmsbenchError, match=r"nodes.json: route_nodes: 2,001, more than the 2,000 a world may hold"):
        World.from_json(tmp_path / "nodes.json")
    with open(tmp_path / "big.json", "wb") as fh:  # sparse: no disk used
        fh.truncate(MAX_WORLD_JSON_BYTES + 1)
    with pytest.raises(LmsbenchError, match=r"big.json: 33,554,433 bytes, more than the 33,554,432 a world.json may "
                                            r"hold \(refused unread"):
        World.from_json(tmp_path / "big.json")


def test_a_route_whose_targets_nearly_coincide_is_refused_not_toured_for_ever() -> None:
    """The wrong-input hunt: two route targets 1e-7 m apart made the tour planner add legs of
    1e-7 m until the path was long enough (7e7 of them for 2 s): `simulate` hung, its memory
    growing. Now a tour is refused past MAX_WAYPOINTS route nodes."""
    from sim.robot import robot_tour

    d = make_world("office", 0).to_dict()
    x, y = d["route_nodes"][0]
    w = World(name="close", seed=0, boxes=d["boxes"], cylinders=d["cylinders"],
              route_nodes=[[x, y], [x + 1e-7, y]], route_edges=[[0, 1]], route_targets=[0, 1])
    with pytest.raises(LmsbenchError, match=r"world 'close': a tour of [0-9.]+ m would pass more than 200,000 route "
                                            r"nodes \(its route targets are too close together"):
        robot_tour(w, seed=0, duration=2.0)


def test_a_world_json_key_given_twice_or_misspelt_is_refused_naming_it(tmp_path) -> None:
    """Found by fuzzing: json keeps the last of a key given twice and World.from_json passed over keys
    it does not read, so a world.json with a second "cylinders": [] or a misspelt "cylinder" was
    simulated without its pillars (`simulate --world` wrote a world.json of 0 cylinders), exit 0."""
    w = make_world("office", seed=0)
    text = json.dumps(w.to_dict())
    assert len(w.cylinders) == 4
    for bad, message in ((text[:-1] + ', "cylinders": []}', r"not a world\.json \(key 'cylinders' given twice"),
                         (text.replace('"cylinders"', '"cylinder"'),
                          r"not a world\.json \(unknown key\(s\) \['cylinder'\] \('cylinder' for 'cylinders'\?\): a world\.json "
                          r"has name, seed, scan_height, walls, circles"),
                         ('{"walls": [[0, 0, 0, 4]], "boxes": [], "route_nodes": {"a": 1, "a": 2}}', r"key 'a' given twice")):
        (tmp_path / "w.json").write_text(bad)
        with pytest.raises(LmsbenchError, match=message):
            World.from_json(tmp_path / "w.json")
    (tmp_path / "w.json").write_text(text)
    assert len(World.from_json(tmp_path / "w.json").cylinders) == 4


def test_a_world_json_seed_that_is_no_whole_number_is_refused() -> None:
    """Found by fuzzing: a world.json's seed went through int(), so 1.5 was the world of seed 1 and
    true seed 1, without a word; World itself refuses them (lms200.finite.check_seed)."""
    text = json.dumps(make_world("office", seed=0).to_dict())
    for seed in ("1.5", "true", "\"2\""):
        with pytest.raises(LmsbenchError, match=r"not a world\.json \(seed: must be a whole number >= 0, got "):
            World.from_json("w.json", data=text.replace('"seed": 0', f'"seed": {seed}').encode())
    assert World.from_json("w.json", data=text.replace('"seed": 0', '"seed": 7').encode()).seed == 7
