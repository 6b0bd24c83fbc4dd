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
