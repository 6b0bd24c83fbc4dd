"""Benchmark of the LMS200 emulator: emulated scans per second for each named world, along the
robot's tour (each beam from its own pose), with the default sensor model and with the ideal one.
Only the scan calls are timed (perf_counter_ns); the median of repeated blocks is reported, since
pre-emption on a shared machine swamps means. Target: >= 1,000 scans/s for office (27x the
sensor's 37.5 scans/s)."""

from __future__ import annotations

import os
import time

import numpy as np

from sim import WORLD_NAMES, SensorConfig, make_world
from sim.lidar import LMS200Sim
from sim.robot import robot_tour

NAME = "sim"


def _rate(world, sensor: SensorConfig, blocks: int, per_block: int) -> tuple[float, float, float]:
    """(median wall-clock scans/s, best wall-clock scans/s, median CPU-time scans/s) of blocks of
    ``per_block`` scans along the tour."""
    tour = robot_tour(world, seed=0, duration=per_block * sensor.scan_period + 1.0)
    stamps = np.arange(per_block) * sensor.scan_period
    offsets = sensor.beam_time_offsets
    beam_poses = [tour.pose_at(t + offsets) for t in stamps]
    rates, cpu_rates = [], []
    with LMS200Sim(world, sensor, seed=0) as sim:
        sim.scan_from_beam_poses(beam_poses[0])  # warm up
        for _ in range(blocks):
            t0, c0 = time.perf_counter_ns(), time.process_time_ns()
            for bp, t in zip(beam_poses, stamps):
                sim.scan_from_beam_poses(bp, float(t))
            rates.append(per_block / ((time.perf_counter_ns() - t0) * 1e-9))
            cpu_rates.append(per_block / (max(time.process_time_ns() - c0, 1) * 1e-9))
    return float(np.median(rates)), float(np.max(rates)), float(np.median(cpu_rates))


def run(quick: bool = False) -> list[dict]:
    """One row per world and sensor model: median and best wall-clock scans/s, and scans per
    second of this process's CPU time (what an unshared core would give)."""
    blocks, per_block = (3, 100) if quick else (7, 300)
    rows = []
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    for name in WORLD_NAMES:
        world = make_world(name, seed=0)
        for label, sensor in (("default", SensorConfig()), ("ideal", SensorConfig.ideal())):
            median, best, cpu = _rate(world, sensor, blocks, per_block)
            rows.append({"world": name, "sensor": label, "scans_per_s": median, "best_scans_per_s": best,
                         "cpu_scans_per_s": cpu, "boxes": int(len(world.boxes)),
                         "cylinders": int(len(world.cylinders)), "load_avg_1min": load})
    return rows
