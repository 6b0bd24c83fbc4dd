"""The emulated LMS200 against an exact 2-D ray caster written here, independently of sim's
geometry code (it intersects rays with every raw box edge and circle of the world description)."""

from __future__ import annotations

import numpy as np
import pytest

from sim import SensorConfig, make_world
from sim.lidar import LMS200Sim

from sim_oracle import free_poses, oracle_ranges


@pytest.mark.parametrize("name", ["office", "corridor", "angles", "pillars", "random"])
def test_ideal_ranges_match_exact_ray_caster(name: str) -> None:
    world = make_world(name, seed=3)
    sensor = SensorConfig.ideal()
    rng = np.random.default_rng(7)
    with LMS200Sim(world, sensor) as sim:
        for pose in free_poses(world, rng, 12):
            scan = sim.scan_at(tuple(pose))
            ref, grazing = oracle_ranges(world.boxes, world.cylinders, world.scan_height, pose[:2],
                                         pose[2] + sensor.angles, sensor.range_max)
            got = scan.ranges.copy()
            ref[grazing] = got[grazing] = np.nan  # rays within 1 um of a vertex: ambiguous
            assert grazing.sum() <= 2
            both = np.isfinite(ref) & np.isfinite(got)
            # +inf exactly where the reference finds nothing within range (a hit within 1 mm of
            # range_max may fall either side)
            edge = np.abs(np.where(np.isfinite(ref), ref, sensor.range_max) - sensor.range_max) < 1e-3
            assert np.array_equal(np.isfinite(ref) | edge | grazing, np.isfinite(got) | edge | grazing)
            assert np.max(np.abs(got[both] - ref[both]), initial=0.0) < 1e-3
            assert both.sum() > 0.5 * len(ref)


def test_scan_geometry_is_lms200() -> None:
    world = make_world("office")
    for sensor, n, inc, rate in ((SensorConfig(), 361, 0.5, 37.5), (SensorConfig.lms200_1deg(), 181, 1.0, 75.0),
                                 (SensorConfig.lms200_quarter_deg(), 401, 0.25, 18.75)):
        with LMS200Sim(world, sensor) as sim:
            scan = sim.scan_at((1.0, 1.0, 0.0), stamp=2.5)
        assert len(scan) == n and scan.stamp == 2.5
        assert scan.angle_increment == pytest.approx(np.deg2rad(inc))
        assert scan.angle_max == pytest.approx(-scan.angle_min)
        assert scan.angle_max - scan.angle_min == pytest.approx(np.deg2rad((n - 1) * inc))
        assert 1 / sensor.scan_period == pytest.approx(rate)
    assert SensorConfig(units="cm").range_max == 81.83 and SensorConfig().range_max == 8.183


def _repeated_scans(sensor: SensorConfig, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(exact, measured (n, beams)) ranges of n scans from one pose in the office world: the
    surface cells are the simulator's (one seed), only the per-scan draws change."""
    world = make_world("office", seed=0)
    pose = tuple(free_poses(world, np.random.default_rng(4), 1)[0])
    with LMS200Sim(world, SensorConfig.ideal()) as ideal:
        exact = ideal.scan_at(pose).ranges
    with LMS200Sim(world, sensor, seed=5) as lidar:
        measured = np.array([lidar.scan_at(pose).ranges for _ in range(n)])
    return exact, measured


def _spurious(exact: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Readings that are a noise-free spurious echo: 10-90 % of the exact range (OUTLIER_RANGE_SHARE)."""
    with np.errstate(invalid="ignore"):
        share = measured / exact
    return (share >= 0.1 - 1e-12) & (share <= 0.9 + 1e-12)


def test_a_spurious_echo_in_front_of_a_dark_cell_is_read_and_elsewhere_never_drops() -> None:
    """Dark cells are a property of the surface a beam meets: a beam reads nan in every scan in
    which its reading would be the surface's echo, or in none, whatever its spurious echoes do (a
    spurious echo's point in mid-air is no surface); a spurious echo (dust, stray light) comes
    back before the surface, so it is read even in front of a dark cell."""
    sensor = SensorConfig.ideal(dropout_prob=0.3, dropout_patch_m=0.3, outlier_prob=0.3)
    exact, measured = _repeated_scans(sensor, 40)
    hit = np.isfinite(exact)
    exact, measured = exact[hit], measured[:, hit]
    nan, spurious = np.isnan(measured), _spurious(exact, measured)
    surface = measured == exact
    assert np.all(nan | spurious | surface)  # nothing else in this noise-free model
    dark = nan.mean(axis=0) > 0.25  # a dark beam reads nan unless its echo is spurious (30 %)
    assert 0.1 < dark.mean() < 0.6
    assert not np.any(surface[:, dark])  # a dark beam never reads its surface ...
    assert not np.any(nan[:, ~dark])  # ... and a beam on a lit cell never reads nan
    assert spurious[:, dark].mean() == pytest.approx(0.3, abs=0.06)  # spurious echoes are read in front of dark cells


def test_a_spurious_echo_carries_the_core_noise_not_its_surfaces_roughness() -> None:
    """Rough cells, like dark ones, belong to the surface: a beam ending on a smooth cell reads
    its exact range or a noise-free spurious echo (core sigma 0), never the 1 m tail."""
    sensor = SensorConfig.ideal(noise_tail_prob=0.5, noise_tail_sigma=1.0, noise_tail_patch_m=0.3, outlier_prob=0.3)
    exact, measured = _repeated_scans(sensor, 40)
    hit = np.isfinite(exact)
    exact, measured = exact[hit], measured[:, hit]
    spurious, surface = _spurious(exact, measured), measured == exact
    smooth = surface.any(axis=0)  # a rough beam reads its exact range with probability 0
    assert 0.2 < smooth.mean() < 0.8
    assert np.all((surface | spurious)[:, smooth])
    assert spurious[:, smooth].mean() == pytest.approx(0.3, abs=0.06)


def _numpy_box_entry(o: np.ndarray, u: np.ndarray, box: np.ndarray, c: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The slab method over arrays with numpy's nan rules (np.fmin / np.fmax drop a nan,
    np.maximum / np.minimum keep it): each ray's entry distance into its box, nan where none."""
    px, py = o[:, 0] - box[:, 0], o[:, 1] - box[:, 1]
    lo_x, lo_y = c * px + s * py, -s * px + c * py
    dx, dy = c * u[:, 0] + s * u[:, 1], -s * u[:, 0] + c * u[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        tx1, tx2 = (-box[:, 3] - lo_x) / dx, (box[:, 3] - lo_x) / dx
        ty1, ty2 = (-box[:, 4] - lo_y) / dy, (box[:, 4] - lo_y) / dy
        t_in = np.maximum(np.fmin(tx1, tx2), np.fmin(ty1, ty2))
        t_out = np.minimum(np.fmax(tx1, tx2), np.fmax(ty1, ty2))
        return np.where((t_in <= t_out) & (t_in > 0), t_in, np.nan)


def test_box_entry_is_numpys_slab_method_bit_for_bit() -> None:
    """sim.hits' exact box entry (through resolve_hits, a box hit whose entry is found replaces
    Bullet's distance, here nan) equals the slab method over numpy arrays bit for bit, on rays
    that enter, miss, start inside, run parallel to a face, lie in a face's plane (0 / 0 in the
    slab test, either sign of zero) or aim at a corner; an entry lies on the box's outline."""
    from sim.hits import resolve_hits

    rng = np.random.default_rng(11)
    n = 6000
    box = np.column_stack((rng.normal(0, 2, n), rng.normal(0, 2, n), rng.uniform(-np.pi, np.pi, n),
                           rng.uniform(0.05, 1.5, n), rng.uniform(0.05, 1.5, n), np.zeros(n), np.ones(n)))
    o = rng.normal(0, 3, (n, 2))
    heading = rng.uniform(-np.pi, np.pi, n)
    u = np.column_stack((np.cos(heading), np.sin(heading)))
    plane = np.arange(n) % 4 == 0  # axis-aligned boxes, rays in the plane x = cx -+ hx along y
    box[plane, 2] = 0.0
    box[plane, 0], box[plane, 3] = np.round(box[plane, 0] * 8) / 8, np.ceil(box[plane, 3] * 8) / 8  # exact sums
    side = np.where(rng.random(plane.sum()) < 0.5, -1.0, 1.0)
    o[plane, 0] = box[plane, 0] + side * box[plane, 3]
    u[plane] = np.column_stack((np.where(rng.random(plane.sum()) < 0.5, 0.0, -0.0), np.sign(rng.normal(size=plane.sum()))))
    corner = np.arange(n) % 4 == 1  # aimed at a corner of an axis-aligned box
    box[corner, 2] = 0.0
    tip = box[corner, :2] + box[corner, 3:5] * np.sign(rng.normal(size=(corner.sum(), 2)))
    d = tip - o[corner]
    u[corner] = d / np.hypot(d[:, 0], d[:, 1])[:, None]
    c, s = np.cos(box[:, 2]), np.sin(box[:, 2])
    ids = np.arange(n)
    got, again = resolve_hits(ids, np.full(n, np.nan), o, u[:, 0].copy(), u[:, 1].copy(),
                              np.append(np.zeros(n, dtype=np.int64), -1), np.append(ids, 0), box, c, s,
                              np.zeros((0, 3)), 1e-7)
    ref = _numpy_box_entry(o, u, box, c, s)
    assert np.array_equal(got.view(np.uint64), ref.view(np.uint64)) and not again.any()
    hit = np.isfinite(got)
    assert 0.1 < hit.mean() < 0.9 and not hit[plane].any() and hit[corner].mean() > 0.2
    at = o[hit] + got[hit, None] * u[hit] - box[hit, :2]
    lx, ly = c[hit] * at[:, 0] + s[hit] * at[:, 1], -s[hit] * at[:, 0] + c[hit] * at[:, 1]
    np.testing.assert_allclose(np.maximum(np.abs(lx) / box[hit, 3], np.abs(ly) / box[hit, 4]), 1.0, atol=1e-9)
