"""Robot tour, sensor model and simulated runs: kinematics against the limits, interlaced timing
against hand-computed beam times, noise statistics, odometry, files and determinism."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lms200 import read_log, read_tum
from sim import OdometryConfig, SensorConfig, World, make_world, robot_tour, simulate_records
from sim.lidar import LMS200Sim
from sim.robot import RobotLimits

from sim_oracle import oracle_ranges

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ["office", "corridor", "angles", "pillars", "random"])
def test_tour_is_collision_free_and_within_limits(name: str) -> None:
    world = make_world(name, seed=4)
    lim = RobotLimits()
    tour = robot_tour(world, seed=4, duration=60.0, limits=lim)
    dt = 0.005
    t = np.arange(0.0, 60.0, dt)
    pose, twist = tour.pose_at(t), tour.twist_at(t)
    assert tour.end_time >= 60.0
    assert world.clearance(pose[:, :2]).min() >= lim.radius
    assert np.abs(twist[:, 0]).max() <= lim.v_max + 1e-9 and np.abs(twist[:, 1]).max() <= lim.w_max + 1e-9
    # continuous speed and turn rate: steps bounded by the acceleration limits
    assert np.abs(np.diff(twist[:, 0])).max() <= lim.a_max * dt + 1e-9
    assert np.abs(np.diff(twist[:, 1])).max() <= lim.alpha_max * dt + 1e-9
    # the pose is the integral of the twist (midpoint rule; its error at a triangular profile
    # apex is accel * dt^2 / 4)
    step = np.diff(pose, axis=0)
    mid = tour.twist_at(t[:-1] + dt / 2)
    assert np.allclose(np.hypot(step[:, 0], step[:, 1]), np.abs(mid[:, 0]) * dt, atol=lim.a_max * dt**2 / 4 + 1e-9)
    assert np.allclose(np.angle(np.exp(1j * step[:, 2])), mid[:, 1] * dt, atol=lim.alpha_max * dt**2 / 4 + 1e-9)
    # stops and turns on the spot are part of it
    assert np.any((twist[:, 0] == 0) & (twist[:, 1] != 0)) and np.any((twist == 0).all(axis=1))


def test_interlaced_beam_times_and_poses() -> None:
    s = SensorConfig()
    off = s.beam_time_offsets
    turn = 1 / 75
    assert off[0] == 0 and off[2] == pytest.approx(turn / 360)  # beam 2 = 1 deg later, same turn
    assert off[1] == pytest.approx(turn + 0.5 / 360 * turn)  # beam 1: second turn
    assert off.max() < s.scan_period
    quarter = SensorConfig.lms200_quarter_deg().beam_time_offsets  # four interlaced turns
    assert quarter[4] == pytest.approx(turn / 360) and quarter[3] == pytest.approx(3 * turn + 0.75 / 360 * turn)
    assert np.array_equal(SensorConfig.lms200_1deg().beam_time_offsets, np.arange(181) / 360 * turn)
    world = make_world("office")
    with LMS200Sim(world, SensorConfig.ideal(interlaced=True)) as sim:
        v, w = 0.5, 0.8
        bp = sim.beam_poses((1.0, 0.5, 0.3), twist=(v, w))
        t = SensorConfig().beam_time_offsets
        th = 0.3 + w * t
        assert np.allclose(bp[:, 2], th)
        assert np.allclose(bp[:, 0], 1.0 + v / w * (np.sin(th) - np.sin(0.3)))
        # each beam's range is the exact range from its own pose
        pose = (world.route_nodes[0][0], world.route_nodes[0][1], 0.2)
        bp = sim.beam_poses(pose, twist=(0.5, 1.0))
        scan = sim.scan_from_beam_poses(bp)
        for i in (0, 1, 180, 359, 360):
            ref, g = oracle_ranges(world.boxes, world.cylinders, world.scan_height, bp[i, :2],
                                   np.array([bp[i, 2] + sim.sensor.angles[i]]), 8.183)
            assert g[0] or scan.ranges[i] == pytest.approx(ref[0], abs=1e-3)


def test_noise_quantisation_dropouts_and_range_limit() -> None:
    world = make_world("corridor", seed=0)
    pose = (world.route_nodes[0][0], world.route_nodes[0][1], 0.0)
    exact = LMS200Sim(world, SensorConfig.ideal()).scan_at(pose).ranges
    sensor = SensorConfig(mixed_pixels=False, dropout_prob=0.05, interlaced=False)
    with LMS200Sim(world, sensor, seed=3) as sim:
        scans = np.array([sim.scan_at(pose).ranges for _ in range(200)])
    ok = np.isfinite(exact) & (exact < 8.0)
    vals = scans[:, ok]
    err = vals - exact[ok]
    good = np.isfinite(err)
    assert np.std(err[good]) == pytest.approx(np.hypot(0.005, 0.001 / np.sqrt(12)), rel=0.05)
    assert np.allclose(vals[good] * 1000, np.rint(vals[good] * 1000), atol=1e-6)  # 1 mm codes
    assert np.isnan(scans).mean() == pytest.approx(0.05, abs=0.01)
    # corridor looking down its 30 m length: beyond 8.183 m is +inf
    assert np.all(np.isinf(scans[:, ~np.isfinite(exact)] [~np.isnan(scans[:, ~np.isfinite(exact)])]))
    cm = LMS200Sim(world, SensorConfig(units="cm", noise_sigma=0.0, dropout_prob=0.0, mixed_pixels=False)).scan_at(pose)
    assert cm.range_max == 81.83 and np.nanmax(cm.ranges[np.isfinite(cm.ranges)]) > 20.0
    assert np.allclose(cm.ranges[np.isfinite(cm.ranges)] * 100, np.rint(cm.ranges[np.isfinite(cm.ranges)] * 100))


def test_mixed_pixels_lie_between_the_two_surfaces() -> None:
    # a thin pillar in front of a wall: beams at its silhouette straddle both
    from sim.layout import Layout
    lay = Layout("mixed", 0)
    lay.wall([(0, -3), (6, -3), (6, 3), (0, 3)], closed=True)
    lay.cylinder(2.0, 0.0, 0.3)
    world = lay.build()
    sensor = SensorConfig.ideal(mixed_pixels=True)
    ideal = LMS200Sim(world, SensorConfig.ideal()).scan_at((0.5, 0.0, 0.0)).ranges
    mixed = LMS200Sim(world, sensor).scan_at((0.5, 0.0, 0.0)).ranges
    changed = np.flatnonzero(np.abs(mixed - ideal) > 1e-9)
    assert 1 <= len(changed) <= 4  # only beams at the two silhouette edges
    for i in changed:
        near, far = 1.2, 5.45 / np.cos(sensor.angles[i])  # pillar front, far wall
        assert near < mixed[i] < far


def test_simulate_records_truth_odometry_rate() -> None:
    recs = simulate_records("angles", seed=1, duration=4.0, rate_hz=10.0, odometry=OdometryConfig())
    stamps = np.array([r.scan.stamp for r in recs])
    assert np.allclose(np.diff(stamps), 4 / 37.5)  # 37.5 scans/s decimated by 4 (~10/s)
    assert all(r.truth is not None and r.odom is not None for r in recs)
    assert simulate_records("angles", seed=1, duration=1.0)[0].odom is None
    world = make_world("angles", seed=1)
    tour = robot_tour(world, seed=1, duration=4.0)
    assert np.allclose([r.truth for r in recs], tour.pose_at(stamps))
    odom = np.array([r.odom for r in recs])
    drift = np.hypot(*(odom[:, :2] - tour.pose_at(stamps)[:, :2]).T)
    assert drift[0] == 0 and 0 < drift[-1] < 0.5


def test_odometry_noise_matches_the_motion_model() -> None:
    from sim.records import odometry_poses
    truth = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    rng = np.random.default_rng(0)
    cfg = OdometryConfig()
    ends = np.array([odometry_poses(truth, cfg, rng)[1] for _ in range(4000)])
    assert np.std(np.hypot(ends[:, 0], ends[:, 1])) == pytest.approx(cfg.alpha3 * 1.0, rel=0.05)
    assert np.std(ends[:, 2]) == pytest.approx(np.sqrt(2) * cfg.alpha2 * 1.0, rel=0.05)


def _simulate(out: Path, *extra: str) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "experiments.cli", "simulate", "--world", "office", "--seed", "2",
           "--duration", "3", "--out", str(out), *extra]
    return subprocess.run(cmd, capture_output=True, text=True, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})


@pytest.mark.slow
def test_simulate_command_files_and_determinism(tmp_path: Path) -> None:
    a, c = tmp_path / "a", tmp_path / "c"
    run = _simulate(a)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("simulated 112 scans") and "Traceback" not in run.stderr and "arning" not in run.stderr
    # a second run from the written config.yaml: the same files, byte for byte
    rerun = subprocess.run([sys.executable, "-m", "experiments.cli", "simulate", "--config", str(a / "config.yaml"),
                            "--out", str(c)], capture_output=True, text=True, env={"PYTHONPATH": str(ROOT)})
    assert rerun.returncode == 0, rerun.stderr
    for name in ["scans.clf", "groundtruth.tum", "world.json", "config.yaml", "map.png"]:
        assert (a / name).read_bytes() == (c / name).read_bytes(), name
    recs = list(read_log(a / "scans.clf"))
    stamps, poses = read_tum(a / "groundtruth.tum")
    assert len(recs) == len(stamps) == 112
    assert all(r.odom is None and r.truth is not None for r in recs)
    assert np.allclose([r.truth for r in recs], poses, atol=2e-6)
    # scans.clf stamps are exact (shortest round-trip decimals); groundtruth.tum's may be rounded to 6 decimals
    assert np.allclose([r.scan.stamp for r in recs], stamps, rtol=0, atol=5.1e-7)
    direct = simulate_records("office", seed=2, duration=3.0)
    assert np.allclose(recs[7].scan.ranges, direct[7].scan.ranges, equal_nan=True)
    assert np.allclose(World.from_json(a / "world.json").walls, make_world("office", 2).walls)


def test_simulate_command_errors(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from experiments.cli import main
    assert main(["simulate", "--world", "moon", "--out", str(tmp_path)]) == 2
    assert "unknown world 'moon'" in capsys.readouterr().err
    assert main(["simulate", "--world", "office", "--duration", "0", "--out", str(tmp_path)]) == 2
    assert "argument --duration: must be a finite number >= 0.1" in capsys.readouterr().err
    assert main(["simulate", "--world", str(tmp_path / "none.json"), "--out", str(tmp_path)]) == 2


@pytest.mark.parametrize("kwargs, name", [
    ({"duration": -1.0}, "duration"), ({"duration": float("nan")}, "duration"), ({"duration": float("inf")}, "duration"),
    ({"rate_hz": 0.0}, "rate_hz"), ({"rate_hz": -2.0}, "rate_hz"), ({"seed": -1}, "seed"), ({"seed": 1.5}, "seed")])
def test_simulate_records_refuses_bad_arguments_by_name(kwargs, name):
    """The Python API checks what the CLI checks (a negative duration gave an empty run, a rate of 0
    a ZeroDivisionError, a negative seed numpy's own message)."""
    from sim import simulate_records

    with pytest.raises(ValueError, match=f"^{name}: "):
        simulate_records("office", **{"seed": 0, "duration": 1.0, **kwargs})


def test_a_sensor_config_refuses_nan_and_inf():
    from sim import SensorConfig

    for name in ("noise_sigma", "dropout_prob", "beam_width", "resolution", "noise_sigma_per_m"):
        for bad in (float("nan"), float("inf")):
            with pytest.raises(ValueError, match=f"^{name}: must be finite"):
                SensorConfig(**{name: bad})
