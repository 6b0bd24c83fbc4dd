"""Clutter worlds (chair and table legs, people, plants, bins, glass, doors at any angle) and the
MIT-like preset: exact ranges and visible truth against the independent ray caster (which reads
glass as no return), clear routes, clutter 0 = no clutter, and world.json round trips."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from sim import SensorConfig, World, make_world, visible_truth
from sim.layout import Layout
from sim.lidar import LMS200Sim

from sim_oracle import free_poses, oracle_glass, oracle_ranges

CLUTTERED = [("cluttered", 0), ("cluttered", 5), ("mit", 1), ("corridor", 2)]


@functools.lru_cache(maxsize=None)
def _world(name: str, seed: int) -> World:
    """Worlds are built once per test run (the MIT preset takes seconds)."""
    return make_world(name, seed, clutter=2.0 if name == "corridor" else None)


def _reference(world: World, pose: np.ndarray, sensor: SensorConfig) -> tuple[np.ndarray, np.ndarray]:
    headings = pose[2] + sensor.angles
    ref, grazing = oracle_ranges(world.boxes, world.cylinders, world.scan_height, pose[:2], headings,
                                 sensor.range_max)
    ref = np.where(oracle_glass(world.glass, pose[:2], headings) < ref, np.inf, ref)
    return ref, grazing


def _route_clearance(world: World) -> float:
    """The smallest distance (m) from the route's edges, sampled 60 points an edge, to any solid."""
    return min(float(world.clearance(world.route_nodes[a] + np.linspace(0, 1, 60)[:, None]
                                     * (world.route_nodes[b] - world.route_nodes[a])).min())
               for a, b in world.route_edges)


def _assert_ideal_ranges_match_reference(world: World, rng: np.random.Generator, n_poses: int) -> None:
    """Noise-free ranges at ``n_poses`` free poses equal the independent ray caster's to 1 mm."""
    sensor = SensorConfig.ideal()
    with LMS200Sim(world, sensor) as lidar:
        for pose in free_poses(world, rng, n_poses):
            got = lidar.scan_at(tuple(pose)).ranges.copy()
            ref, grazing = _reference(world, pose, sensor)
            both = np.isfinite(ref) & np.isfinite(got) & ~grazing
            assert np.count_nonzero(both) > 200
            assert np.max(np.abs(got[both] - ref[both])) < 1e-3


def test_clutter_zero_is_the_world_without_clutter() -> None:
    for name in ("office", "random", "corridor"):
        a, b = make_world(name, 3), make_world(name, 3, clutter=0.0)
        assert np.array_equal(a.boxes, b.boxes) and np.array_equal(a.cylinders, b.cylinders)
        assert len(a.glass) == 0
    with pytest.raises(ValueError, match="clutter"):
        make_world("office", 0, clutter=-1.0)


def test_cluttered_worlds_hold_every_kind_of_clutter() -> None:
    worlds = [_world("cluttered", s) for s in range(6)] + [_world("mit", 1)]
    cyl = np.vstack([w.cylinders for w in worlds])
    boxes = np.vstack([w.boxes for w in worlds])
    assert np.any(cyl[:, 2] < 0.02)  # chair legs
    assert np.any((cyl[:, 2] >= 0.05) & (cyl[:, 2] <= 0.07) & (cyl[:, 4] == 0.9))  # people's legs
    assert np.any(np.isclose(boxes[:, 4], 0.015) & (boxes[:, 6] == 1.0))  # plants: rings of short faces
    assert np.any((boxes[:, 6] == 0.72) & (boxes[:, 3] < 0.031))  # table legs
    assert sum(len(w.glass) for w in worlds) >= 2
    leaves = boxes[np.isclose(boxes[:, 3], 0.45) & np.isclose(boxes[:, 4], 0.02)]
    off_axis = np.abs(np.sin(2 * leaves[:, 2])) > 0.05  # door leaves not at 0 / 90 deg
    assert off_axis.sum() >= 3
    mit = _world("mit", 1)
    assert mit.bounds[2] - mit.bounds[0] > SensorConfig().range_max  # a corridor beyond the mm-mode range


@pytest.mark.parametrize("name, seed", CLUTTERED)
def test_ideal_ranges_match_exact_ray_caster_with_glass(name: str, seed: int) -> None:
    world = _world(name, seed)
    sensor = SensorConfig.ideal()
    rng = np.random.default_rng(5)
    with LMS200Sim(world, sensor) as lidar:
        for pose in free_poses(world, rng, 8):
            got = lidar.scan_at(tuple(pose)).ranges.copy()
            ref, grazing = _reference(world, pose, sensor)
            ref[grazing] = got[grazing] = np.nan
            both = np.isfinite(ref) & np.isfinite(got)
            edge = np.abs(np.where(np.isfinite(ref), ref, sensor.range_max) - sensor.range_max) < 1e-3
            assert np.array_equal(np.isfinite(ref) | edge | grazing, np.isfinite(got) | edge | grazing)
            assert np.max(np.abs(got[both] - ref[both]), initial=0.0) < 1e-3


@pytest.mark.parametrize("name, seed", CLUTTERED[:3])
def test_visible_truth_is_exact_in_clutter(name: str, seed: int) -> None:
    world = _world(name, seed)
    sensor = SensorConfig.ideal()
    rng = np.random.default_rng(9)
    for pose in free_poses(world, rng, 8):
        truth = visible_truth(world, tuple(pose), sensor)
        ref, grazing = _reference(world, pose, sensor)
        r = np.where(np.isfinite(ref), ref, np.nan)
        hits = np.column_stack((r * np.cos(sensor.angles), r * np.sin(sensor.angles)))
        covered = np.zeros(sensor.n_beams, dtype=bool)
        for (x1, y1, x2, y2), (first, last) in zip(truth.segments, truth.segment_beams):
            u = np.array([x2 - x1, y2 - y1]) / np.hypot(x2 - x1, y2 - y1)
            rel = hits[first:last + 1] - (x1, y1)
            ok = ~grazing[first:last + 1]
            # every beam of a span hits its segment (not glass in front of it, nothing else)
            assert np.all(np.abs(rel[ok] @ np.array([-u[1], u[0]])) < 1e-6)
            covered[first:last + 1] = True
        world_hits = pose[:2] + r[:, None] * np.column_stack((np.cos(pose[2] + sensor.angles),
                                                              np.sin(pose[2] + sensor.angles)))
        on_circle = np.zeros(sensor.n_beams, dtype=bool)
        for cx, cy, rad in world.circles:
            on_circle |= np.abs(np.hypot(world_hits[:, 0] - cx, world_hits[:, 1] - cy) - rad) < 1e-6
        assert np.all(covered[np.isfinite(ref) & ~on_circle & ~grazing])


@pytest.mark.parametrize("name, seed", [("cluttered", 0), ("cluttered", 1), ("cluttered", 5), ("mit", 1)])
def test_routes_keep_clear_of_clutter(name: str, seed: int) -> None:
    w = _world(name, seed)
    assert _route_clearance(w) >= 0.4


def test_glass_gives_no_return_and_hides_what_is_behind(tmp_path: Path) -> None:
    lay = Layout("glass", 0)
    lay.wall([(0, 0), (6, 0), (6, 4), (0, 4)], closed=True)
    lay.box(4.5, 2.0, 0.0, 0.2, 0.2)  # a box behind the glass
    world = lay.build(glass=[[3.0, 1.0, 3.0, 3.0]])
    sensor = SensorConfig.ideal()
    pose = (1.0, 2.0, 0.0)
    with LMS200Sim(world, sensor) as lidar:
        r = lidar.scan_at(pose).ranges
    edge = np.arctan2(1.0, 2.0)  # the glass spans bearings -edge..edge
    ahead = np.abs(sensor.angles) < edge - 0.01
    assert np.all(np.isposinf(r[ahead])) and np.all(np.isfinite(r[np.abs(sensor.angles) > edge + 0.01]))
    truth = visible_truth(world, pose, sensor)
    for first, last in truth.segment_beams:
        assert not ahead[first:last + 1].any()  # nothing behind the glass is visible truth
    world.to_json(tmp_path / "w.json")
    again = World.from_json(tmp_path / "w.json")
    assert np.array_equal(again.glass, world.glass) and np.array_equal(again.boxes, world.boxes)


def test_wall_runs_stand_on_the_inside_of_walls_clear_of_the_route() -> None:
    """Runs of things along walls: every solid's back sinks into a wall face inside the room (none
    outside it, none floating), they keep the route clear, and the runs change nothing else."""
    from sim.clutter import ClutterConfig, add_clutter
    from sim.layout import EMBED_M

    def room() -> Layout:
        lay = Layout("runs", 0)
        lay.wall([(0, 0), (8, 0), (8, 5), (0, 5)], closed=True)
        a, b = lay.node(1.5, 2.5, target=True), lay.node(6.5, 2.5, target=True)
        lay.link(a, b)
        return lay

    lay = room()
    walls = len(lay.boxes)
    add_clutter(lay, np.random.default_rng(4), 1.0, ClutterConfig(0, 0, 0, 0, 0, 0, wall_runs=20.0))
    items = np.array(lay.boxes[walls:])
    assert len(items) >= 20
    corners = np.vstack([np.array(_corners(b)) for b in items])
    inside = 0.05 - EMBED_M - 1e-9  # the inner wall faces are at 0.05 and 8 - 0.05 / 5 - 0.05
    assert np.all((corners[:, 0] >= inside) & (corners[:, 0] <= 8 - inside))
    assert np.all((corners[:, 1] >= inside) & (corners[:, 1] <= 5 - inside))
    for b in items:  # each stands against a face: its nearest corner is sunk EMBED_M into the wall
        c = np.array(_corners(b))
        gap = np.min(np.minimum.reduce([c[:, 0] - 0.05, 7.95 - c[:, 0], c[:, 1] - 0.05, 4.95 - c[:, 1]]))
        assert abs(gap + EMBED_M) < 1e-9
    cyl = np.array(lay.cylinders)
    assert len(cyl) >= 5  # round things: sunk EMBED_M into a face too
    gap = np.minimum.reduce([cyl[:, 0] - 0.05, 7.95 - cyl[:, 0], cyl[:, 1] - 0.05, 4.95 - cyl[:, 1]]) - cyl[:, 2]
    assert np.allclose(gap, -EMBED_M, atol=1e-9)
    world = lay.build()
    pts = np.array([1.5, 2.5]) + np.linspace(0, 1, 60)[:, None] * np.array([5.0, 0.0])
    assert world.clearance(pts).min() >= 0.4
    bare = room()
    add_clutter(bare, np.random.default_rng(4), 1.0, ClutterConfig(0, 0, 0, 0, 0, 0))
    assert len(bare.boxes) == walls


def _corners(box) -> list:
    from sim.geometry import rectangle_corners
    return rectangle_corners(*box[:5]).tolist()


def test_glass_rate_sets_the_worlds_glass_panels() -> None:
    worlds = [make_world("cluttered", s, glass=0.0) for s in range(3)]
    assert all(len(w.glass) == 0 for w in worlds)
    many = [make_world("cluttered", s, glass=2.0) for s in range(3)]
    assert sum(len(w.glass) for w in many) > sum(len(_world("cluttered", s).glass) for s in range(3))
    with pytest.raises(ValueError, match="glass"):
        make_world("office", 0, glass=-0.1)


def test_sim2real_glass_follows_the_logs_no_returns() -> None:
    from lms200 import Record, Scan
    from experiments.sim2real import GLASS_NO_RETURN_SHARE, glass_rate, no_return_share
    from sim.worlds import MIT_PRESET

    assert glass_rate("mit", 0.0) == 0.0  # a log that never reads no return: no glass
    assert glass_rate("cluttered", 0.0) is None  # other worlds keep their own glass
    assert glass_rate("mit", 1.0) == MIT_PRESET["glass_per_10m"]  # never more than the preset
    assert glass_rate("mit", GLASS_NO_RETURN_SHARE / 2) == pytest.approx(MIT_PRESET["glass_per_10m"] / 2, abs=1e-4)
    r = np.array([1.0, np.inf, 50.0, np.nan, 2.0, 50.0, 3.0, 4.0])
    recs = [Record(Scan(r, -0.1, 0.01, 0.0, 81.83, 0.0))]
    assert no_return_share(recs) == pytest.approx(1 / 8)
    assert no_return_share(recs, max_reading=50.0) == pytest.approx(3 / 8)


def test_rough_fill_lines_the_rooms_walls_only_with_exact_truth() -> None:
    """Rough fill (make_world(rough=...)): things 3-12 cm wide, each sunk into a wall face inside
    the room (none along the corridor), the route kept clear, the world's faces short, and ideal
    ranges equal to the independent ray caster's."""
    from sim.clutter import ROUGH_ITEM_M, ClutterConfig, add_clutter
    from sim.layout import EMBED_M

    def floor() -> Layout:  # a 8 x 4.9 m room (y 0.05-4.95) behind a 1 m door off a corridor (y 5.05-6.95)
        lay = Layout("rough", 0)
        lay.wall([(0, 0), (8, 0), (8, 7), (0, 7)], closed=True)
        lay.wall([(0, 5), (3.5, 5)])
        lay.wall([(4.5, 5), (8, 5)])
        lay.rooms.append((0.05, 7.95, 0.05, 4.95))
        a, b, c, d = lay.node(1.0, 6.0), lay.node(4.0, 6.0), lay.node(7.0, 6.0), lay.node(4.0, 2.5, target=True)
        lay.link(a, b, c)
        lay.link(b, d)
        return lay

    lay = floor()
    walls = len(lay.boxes)
    add_clutter(lay, np.random.default_rng(2), 1.0, ClutterConfig(0, 0, 0, 0, 0, 0, rough_cover=1.0))
    items = np.array(lay.boxes[walls:])
    assert len(items) >= 60 and np.all(2 * items[:, 4] <= ROUGH_ITEM_M[1] + 1e-9)
    corners = np.vstack([np.array(_corners(b)) for b in items])
    inside = 0.05 - EMBED_M - 1e-9
    assert np.all((corners[:, 0] >= inside) & (corners[:, 0] <= 8 - inside))
    assert np.all((corners[:, 1] >= inside) & (corners[:, 1] <= 4.95 + EMBED_M + 1e-9))  # none in the corridor
    for b in items:  # each stands against a room face: its nearest corner is sunk EMBED_M into the wall
        c = np.array(_corners(b))
        gap = np.min(np.minimum.reduce([c[:, 0] - 0.05, 7.95 - c[:, 0], c[:, 1] - 0.05, 4.95 - c[:, 1]]))
        assert abs(gap + EMBED_M) < 1e-9
    world = lay.build()
    assert _route_clearance(world) >= 0.4
    lengths = np.hypot(world.walls[:, 2] - world.walls[:, 0], world.walls[:, 3] - world.walls[:, 1])
    assert np.median(lengths) < 0.14  # shorter than a line extractor's shortest line at 2 m (8 beams)
    sensor = SensorConfig.ideal()
    with LMS200Sim(world, sensor) as lidar:
        for pose in ([4.0, 2.5, 0.3], [2.0, 2.0, 2.5], [6.5, 3.5, -1.2]):
            got = lidar.scan_at(tuple(pose)).ranges.copy()
            ref, grazing = _reference(world, np.array(pose), sensor)
            both = np.isfinite(ref) & np.isfinite(got) & ~grazing
            assert np.count_nonzero(both) > 300
            assert np.max(np.abs(got[both] - ref[both])) < 1e-3
    bare = floor()
    add_clutter(bare, np.random.default_rng(2), 1.0, ClutterConfig(0, 0, 0, 0, 0, 0, rough_cover=0.0))
    assert len(bare.boxes) == walls
    mit, bare_mit = _world("mit", 1), make_world("mit", 1, rough=0.0)  # the preset has 1 (MIT CSAIL's fit: 0.89)
    n = len(bare_mit.boxes)  # the fill comes last: the rest of the world is the same
    assert len(mit.boxes) > n + 50 and np.array_equal(mit.boxes[:n], bare_mit.boxes)
    with pytest.raises(ValueError, match="rough"):
        make_world("mit", 0, rough=1.5)


def test_near_unexplained_counts_beams_at_1_4_m_off_every_line() -> None:
    """The statistic the rough fill is fitted on: beams at 1-4 m on a straight wall are explained
    (share 0), beams scattered at random depths are not (share 1), beams outside 1-4 m don't count."""
    from lms200 import Record, Scan
    from experiments.sim2real import near_unexplained

    rng = np.random.default_rng(0)
    inc = np.deg2rad(0.5)
    b = -np.pi / 2 + inc * np.arange(361)
    wall = np.where(np.abs(b) <= np.deg2rad(60), 2.0 / np.cos(b) + rng.normal(0, 0.002, 361), 0.5)  # x = 2 m; 0.5 m aside
    scattered = np.where(np.abs(b) <= np.deg2rad(60), rng.uniform(1.2, 3.8, 361), 6.0)
    walls = [Record(Scan(wall.copy(), -np.pi / 2, inc, 0.0, 81.83, float(k))) for k in range(5)]
    noise = [Record(Scan(scattered.copy(), -np.pi / 2, inc, 0.0, 81.83, float(k))) for k in range(5)]
    assert near_unexplained(walls) < 0.02
    assert near_unexplained(noise) > 0.95
    assert np.isnan(near_unexplained([]))


def test_scaled_rooms_keep_exact_truth_and_scale_one_is_the_world() -> None:
    """make_world(scale=...): the rooms' width and depth times the scale (the corridor as it is), more
    furniture in bigger rooms, clear routes, ideal ranges equal to the independent ray caster's;
    scale 1 is the world bit for bit."""
    base, big = make_world("cluttered", 4), make_world("cluttered", 4, scale=1.5)
    assert np.array_equal(make_world("cluttered", 4, scale=1.0).boxes, base.boxes)
    (x0, y0, x1, y1), (bx0, by0, bx1, by1) = base.bounds, big.bounds
    t = 0.1  # the outer walls' thickness
    assert bx1 - bx0 - t == pytest.approx(1.5 * (x1 - x0 - t))  # three rooms of 4 m -> 6 m a side
    assert by1 - by0 - t - 2.0 == pytest.approx(1.5 * (y1 - y0 - t - 2.0))  # rooms 4 -> 6 m deep, corridor 2 m
    furniture = [np.count_nonzero(w.boxes[:, 6] == h) for w in (base, big) for h in (1.2, 2.0)]
    assert furniture[2] + furniture[3] > furniture[0] + furniture[1]  # cabinets and shelves: more in bigger rooms
    assert _route_clearance(big) >= 0.25
    _assert_ideal_ranges_match_reference(big, np.random.default_rng(3), 4)
    with pytest.raises(ValueError, match="scale"):
        make_world("mit", 0, scale=5.0)
    with pytest.raises(ValueError, match="no rooms to scale"):  # not silently ignored
        make_world("pillars", 0, scale=2.0)
    with pytest.raises(ValueError, match="needs a clutter level"):
        make_world("office", 0, rough=0.5)


def test_far_share_counts_readings_at_4_8_m_among_those_at_2_8_m() -> None:
    """The statistic the rooms' size is fitted on: of the valid readings at 2-8 m, the share at 4 m
    or more; nearer and farther readings and invalid ones do not count."""
    from lms200 import Record, Scan
    from experiments.sim2real import far_share

    inc = np.deg2rad(1.0)
    r = np.array([0.5] * 40 + [3.0] * 60 + [5.0] * 20 + [12.0] * 30 + [np.nan] * 10 + [np.inf] * 21)
    recs = [Record(Scan(r.copy(), -np.pi / 2, inc, 0.0, 81.83, float(k))) for k in range(3)]
    assert far_share(recs) == pytest.approx(20 / 80)
    assert np.isnan(far_share([]))


def test_wall_relief_panels_stand_proud_of_walls_with_exact_truth() -> None:
    """make_world(relief=...): flat panels parallel to a wall, their fronts 1-6 cm proud of its face
    and their backs sunk into it; each front is a face of World.walls; ideal ranges equal the
    independent ray caster's and the visible truth covers every beam off a circle; relief 0 (or
    none) is the world bit for bit, and the panels come last (the rest of the world is the same)."""
    from sim.clutter import RELIEF_PANEL_M, RELIEF_PROUD_M
    from sim.layout import EMBED_M

    base, world = make_world("cluttered", 2), make_world("cluttered", 2, relief=1.0)
    assert np.array_equal(make_world("cluttered", 2, relief=0.0).boxes, base.boxes)
    n = len(base.boxes)
    assert np.array_equal(world.boxes[:n], base.boxes) and np.array_equal(world.cylinders, base.cylinders)
    panels = world.boxes[n:]
    assert len(panels) >= 8
    walls = base.boxes[(base.boxes[:, 6] >= 2.0) & (base.boxes[:, 4] <= 0.08)]
    faces = {tuple(np.round(f, 9)) for f in world.walls}
    for cx, cy, yaw, hx, hy, *_ in panels:  # hx: half depth out from the wall, hy: half width along it
        assert RELIEF_PANEL_M[0] - 1e-9 <= 2 * hy <= RELIEF_PANEL_M[1] + 1e-9
        proud = 2 * hx - EMBED_M
        assert RELIEF_PROUD_M[0] - 1e-9 <= proud <= RELIEF_PROUD_M[1] + 1e-9
        normal = np.array([np.cos(yaw), np.sin(yaw)])
        back = np.array([cx, cy]) - normal * hx
        # the back lies EMBED_M inside a wall box parallel to the panel
        parallel = walls[np.abs(np.sin(walls[:, 2] - yaw + np.pi / 2)) < 1e-9]
        depth = np.abs((back[0] - parallel[:, 0]) * normal[0] + (back[1] - parallel[:, 1]) * normal[1])
        assert np.any(np.isclose(depth, parallel[:, 4] - EMBED_M, atol=1e-9))
        front = np.array([cx, cy]) + normal * hx
        along = np.array([-normal[1], normal[0]])
        a, b = front - along * hy, front + along * hy  # the front face, oriented with the solid on its left
        assert (*np.round(np.r_[b, a], 9),) in faces or (*np.round(np.r_[a, b], 9),) in faces
    sensor = SensorConfig.ideal()
    rng = np.random.default_rng(4)
    with LMS200Sim(world, sensor) as lidar:
        for pose in free_poses(world, rng, 6):
            got = lidar.scan_at(tuple(pose)).ranges.copy()
            ref, grazing = _reference(world, pose, sensor)
            both = np.isfinite(ref) & np.isfinite(got) & ~grazing
            assert np.max(np.abs(got[both] - ref[both])) < 1e-3
            truth = visible_truth(world, tuple(pose), sensor)
            r = np.where(np.isfinite(ref), ref, np.nan)
            hits = np.column_stack((r * np.cos(sensor.angles), r * np.sin(sensor.angles)))
            covered = np.zeros(sensor.n_beams, dtype=bool)
            for (x1, y1, x2, y2), (first, last) in zip(truth.segments, truth.segment_beams):
                u = np.array([x2 - x1, y2 - y1]) / np.hypot(x2 - x1, y2 - y1)
                rel = hits[first:last + 1] - (x1, y1)
                ok = ~grazing[first:last + 1]
                assert np.all(np.abs(rel[ok] @ np.array([-u[1], u[0]])) < 1e-6)
                covered[first:last + 1] = True
            wh = pose[:2] + r[:, None] * np.column_stack((np.cos(pose[2] + sensor.angles), np.sin(pose[2] + sensor.angles)))
            on_circle = np.zeros(sensor.n_beams, dtype=bool)
            for cx, cy, rad in world.circles:
                on_circle |= np.abs(np.hypot(wh[:, 0] - cx, wh[:, 1] - cy) - rad) < 1e-6
            assert np.all(covered[np.isfinite(ref) & ~on_circle & ~grazing])
    assert _route_clearance(world) >= 0.4
    with pytest.raises(ValueError, match="relief"):
        make_world("cluttered", 0, relief=1.5)
    with pytest.raises(ValueError, match="needs a clutter level"):
        make_world("office", 0, relief=0.5)


def _wall_scans(step_m: float, noise_m: float, n: int = 4, bend_rad: float = 0.0) -> list:
    """Scans of a wall 2 m ahead (x = 2) at 0.5 deg, beams within 54.8 deg of it, its half at y > 0
    ``step_m`` nearer (a panel proud of it) or turned by ``bend_rad`` about the point (2, 0); the
    other beams read 0.3 m (not used: under 0.5 m)."""
    from lms200 import Record, Scan

    rng = np.random.default_rng(1)
    inc = np.deg2rad(0.5)
    b = -np.pi / 2 + inc * np.arange(361)
    # the line x = 2 - step (y > 0) turned by bend about (2, 0): range along the beam at bearing b
    x = np.where(b > 0, (2.0 - step_m) * np.cos(bend_rad) / np.cos(b - bend_rad), 2.0 / np.cos(b))
    r = np.where(np.abs(b) <= np.deg2rad(54.8), x, 0.3)
    return [Record(Scan(r + rng.normal(0, noise_m, 361) * (noise_m > 0), -np.pi / 2, inc, 0.0, 81.83, float(k)))
            for k in range(n)]


def test_relief_share_counts_steps_between_straight_parallel_stretches() -> None:
    """The statistic the wall relief is fitted on (no extractor): a 3 cm step or a 5 deg bend in a
    straight wall is one break per scan among the joints of straight stretches; a plain wall has
    none, nor a 20 cm step (an object in front); at 2 cm noise a plain wall's joints rarely count."""
    from experiments.sim2real import RELIEF_WINDOW, relief_counts, relief_share

    steps, flat = relief_counts(_wall_scans(0.03, 0.0), 0.002)
    on_wall = 2 * 109 + 1  # beams within 54.8 deg (109 a side at 0.5 deg, and the one at 0)
    assert steps == 4  # the one joint between the stretch ending before the step and the one after it
    # every joint whose two stretches lie on one side of the step (2 window lengths: 2 * 5 beams)
    assert flat == 4 * (on_wall - 2 * RELIEF_WINDOW + 1 - (2 * RELIEF_WINDOW - 1))
    assert relief_counts(_wall_scans(0.0, 0.0), 0.002) == (0, 4 * (on_wall - 2 * RELIEF_WINDOW + 1))
    assert relief_counts(_wall_scans(0.20, 0.0), 0.002)[0] == 0
    bent = relief_counts(_wall_scans(0.0, 0.0, bend_rad=np.deg2rad(5.0)), 0.002)
    assert 4 <= bent[0] <= 4 * 2 * RELIEF_WINDOW  # joints near the bend see it too
    steps, flat = relief_counts(_wall_scans(0.0, 0.02), 0.02)  # 2 cm noise: a step must be 7 cm (3 standard errors)
    assert flat > 400 and steps < 0.1 * flat  # so noise alone makes few
    assert relief_share(_wall_scans(0.03, 0.002)) == pytest.approx(1 / (1 + flat / 4), rel=0.5)
    assert np.isnan(relief_share([]))


@pytest.mark.slow
def test_fit_relief_tells_walls_with_relief_from_plain_walls_on_worlds_other_than_its_probes(monkeypatch) -> None:
    """fit_relief (two probe worlds, seeds 100-101, 60 s each) on simulated logs of two other mit
    worlds (60 s each) at wall relief 0 and 0.75: plain walls fit at 0 (0.000-0.002 on seed pairs
    (8, 9), (10, 11), (12, 13)), relief 0.75 at 0.63-1.0 on the same pairs. The fit tells relief
    from none; it does not recover the amount closely (docs/simulator.md), so that is not asserted.
    The probe runs (a third of the test's time each) are computed once for both fits: a second
    call with arguments equal in every respect (the probes depend on no log) takes the first's
    shares, a call that differs in any is run."""
    import experiments.sim2real as s2r
    from experiments.sim2real import fit_relief
    from sim import simulate_records

    probe_shares, probed = s2r._probe_shares, {}

    def once(*args, **kwargs):
        key = repr((args, sorted(kwargs.items())))
        if key not in probed:
            probed[key] = probe_shares(*args, **kwargs)
        return list(probed[key])

    monkeypatch.setattr(s2r, "_probe_shares", once)
    sensor, rough, seeds = SensorConfig(), 0.14, (10, 11)
    fits = {}
    for relief in (0.0, 0.75):
        log = [rec for seed in seeds
               for rec in simulate_records(make_world("mit", seed, glass=0.0, rough=rough, relief=relief), seed, 60.0,
                                           sensor, rate_hz=3.0)]
        fits[relief] = fit_relief(log, sensor, None, 0.0, duration=60.0, n_probe_seeds=2, rough=rough)
    shares = fits[0.0].probe_shares
    assert shares == fits[0.75].probe_shares and shares[0] < shares[1] < shares[2]  # more relief, more breaks
    assert len(probed) == 1  # the two fits asked for the same probes
    assert fits[0.0].cover <= 0.05
    assert fits[0.75].cover >= 0.5


def _nearest_solid_oracle(pts: np.ndarray, corners: np.ndarray, keep: np.ndarray, circles: np.ndarray) -> np.ndarray:
    """Every point against every edge of every kept box and every circle, in numpy (no pruning)."""
    from sim.geometry import distance_to_segments

    d = np.full(len(pts), np.inf)
    for rect in corners[keep]:
        a, b = rect, np.roll(rect, -1, axis=0)
        ab, rel = b - a, pts[:, None, :] - a
        inside = np.all(ab[:, 0] * rel[..., 1] - ab[:, 1] * rel[..., 0] > 0, axis=1)
        d = np.minimum(d, np.where(inside, 0.0, distance_to_segments(pts, a, b).min(axis=1)))
    for cx, cy, r in circles:
        d = np.minimum(d, np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) - r)
    return d


def test_space_distance_is_the_numpy_distance_bit_for_bit_within_its_horizon() -> None:
    """The compiled nearest-solid distance that placing clutter asks (sim.nearest) against every
    edge in numpy: equal bit for bit below HORIZON_M, at least HORIZON_M beyond; the excluded box
    left out, footprints taken later counted."""
    from sim.clutter import HORIZON_M, _Space
    from sim.geometry import rectangle_corners

    rng = np.random.default_rng(7)
    lay = Layout("t", 0)
    for _ in range(60):
        lay.box(*rng.uniform(0, 12, 2), rng.uniform(-np.pi, np.pi), *rng.uniform(0.01, 0.8, 2), 0.0,
                float(rng.choice([0.2, 2.5])))
    for _ in range(15):
        lay.cylinder(*rng.uniform(0, 12, 2), rng.uniform(0.02, 0.4), 0.0, 1.0)
    space = _Space(lay, np.zeros((1, 2)), 0.35)
    for _ in range(5):
        space.take_rect(rectangle_corners(*rng.uniform(0, 12, 2), rng.uniform(-np.pi, np.pi), *rng.uniform(0.05, 0.5, 2)))
        space.take(rng.uniform(0, 12, 2), float(rng.uniform(0.05, 0.3)))
    pts = np.vstack([rng.uniform(-2, 14, (4000, 2)), space.corners[:, 0] + rng.normal(0, 1e-9, (len(space.corners), 2))])
    ids = np.append(space.box_index, np.full(len(space.corners) - len(space.box_index), -2))
    circles = np.array(space.circles)
    for exclude in (-1, int(space.box_index[3])):
        got = space.distance(pts, exclude=exclude)
        ref = _nearest_solid_oracle(pts, space.corners, ids != exclude, circles)
        near = ref < HORIZON_M
        assert 1000 < near.sum() < len(pts) and (ref == 0).sum() > 100 and (ref < 0).sum() > 10
        assert np.array_equal(got[near], ref[near])
        assert np.all(got[~near] >= HORIZON_M)


def test_the_smallest_scale_builds_every_roomed_world_with_exact_ranges() -> None:
    """scale = MIN_SCALE (the office's rooms 2 m a side) failed in every roomed world ("high - low <
    0": a leaning screen's or a pillar's place drawn in a room too small for it); such a room now
    goes without. Ideal ranges equal the independent ray caster's. Routes keep the robot's radius
    from every solid at MIN_SCALE (at 0.5 they came within 0.17 m, docs/simulator.md)."""
    from sim.worlds import MIN_SCALE, ROBOT_RADIUS_M, ROOMED_WORLDS

    for name in ROOMED_WORLDS:
        for seed in (0, 4):
            world = make_world(name, seed, scale=MIN_SCALE)
            assert len(world.walls) > 20
            assert _route_clearance(world) >= ROBOT_RADIUS_M, (name, seed)
    _assert_ideal_ranges_match_reference(make_world("office", 0, scale=MIN_SCALE), np.random.default_rng(5), 4)


def test_rough_fill_takes_whole_walls_nested_in_its_share() -> None:
    """The rough fill chooses whole walls of rooms (sim.clutter._room_faces), each with probability
    cover from its own stream: at cover 0.5 about half the room walls carry fill and the others none
    (filling each 0.3-2 m stretch of every wall at 0.5, as before, left almost no 4-6 m wall bare), at
    cover 1 most do (not short pieces by doors and furniture), and the walls chosen at 0.5 are among
    those chosen at 1."""
    from sim.clutter import ClutterConfig, _room_faces, add_clutter
    from sim.worlds import office

    def filled_faces(seed: int, cover: float) -> tuple[set[int], int]:
        lay = office(np.random.default_rng(seed), "office", seed, n_per_side=3, room_w=5.0, room_d=6.0)
        faces = _room_faces(lay, 0.35)
        n = len(lay.boxes)
        add_clutter(lay, np.random.default_rng([seed, 9]), 1.0, ClutterConfig(0, 0, 0, 0, 0, 0, rough_cover=cover))
        got = set()
        for cx, cy, *_ in lay.boxes[n:]:
            c = np.array([cx, cy])
            best, arg = np.inf, -1
            for f, (_, p0, u, nrm, length) in enumerate(faces):
                s = float(np.clip((c - p0) @ u, 0.0, length))
                d = float(np.hypot(*(c - p0 - u * s)))
                if (c - p0) @ nrm > 0 and d < best:
                    best, arg = d, f
            assert best < 0.45  # every piece of fill stands against a room wall
            got.add(arg)
        return got, len(faces)

    half = full = total = 0
    for seed in range(3):
        at_half, n_faces = filled_faces(seed, 0.5)
        at_full, _ = filled_faces(seed, 1.0)
        assert at_half <= at_full
        half, full, total = half + len(at_half), full + len(at_full), total + n_faces
    assert total >= 30
    assert full / total >= 0.75  # (short pieces of wall by doors and furniture take no fill)
    assert 0.3 <= half / full <= 0.7


def test_mit_corridor_turns_at_both_ends_to_end_walls_at_their_exact_distances() -> None:
    """The mit preset's corridor turns at both ends (an L each, the plan a Z) and each leg ends in a
    wall: from the corner of a turn the scanner sees the wall across the corridor's end and the
    leg's end wall head-on, at the distances the preset's sizes give (ideal cm-mode sensor, no
    clutter, so nothing stands between)."""
    from dataclasses import replace

    from sim.layout import WALL_THICKNESS_M
    from sim.worlds import MIT_PRESET

    world = make_world("mit", 3, clutter=0.0)
    cw, rd, t = float(MIT_PRESET["corridor_w"]), float(MIT_PRESET["room_d"]), WALL_THICKNESS_M
    length = int(MIT_PRESET["n_per_side"]) * float(MIT_PRESET["room_w"])
    sensor = replace(SensorConfig.ideal(), units="cm")
    middle = sensor.n_beams // 2  # the beam straight ahead
    # (pose, exact distance ahead): east turn, looking on east / up the leg; west turn, looking west / down its leg
    cases = [((length + cw / 2, cw / 2, 0.0), cw / 2 - t / 2),
             ((length + cw / 2, cw / 2, np.pi / 2), cw / 2 + rd - t / 2),
             ((-cw / 2, cw / 2, np.pi), cw / 2 - t / 2),
             ((-cw / 2, cw / 2, -np.pi / 2), cw / 2 + rd - t / 2),
             ((length + cw / 2, cw / 2, np.pi), length + 3 * cw / 2 - t / 2)]  # down the whole corridor to the west leg
    with LMS200Sim(world, sensor) as lidar:
        for pose, want in cases:
            got = lidar.scan_at(pose).ranges[middle]
            assert got == pytest.approx(want, abs=1e-6)
            ref, _ = _reference(world, np.array(pose), sensor)
            assert ref[middle] == pytest.approx(want, abs=1e-6)
    ends = world.route_nodes[world.route_targets]
    assert np.any(np.all(np.isclose(ends, [length + cw / 2, cw + rd - 0.8]), axis=1))  # the robot drives both legs
    assert np.any(np.all(np.isclose(ends, [-cw / 2, -rd + 0.8]), axis=1))
