"""Scan sources for the virtual LMS200: the route walk and the simulator scans along it."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from experiments.lms200_sources import STEP_M, TURN_RAD, log_scans, route_poses
from lms200 import LmsbenchError, Record, Scan, write_log


def test_route_walk_moves_in_small_steps_along_edges() -> None:
    nodes = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    edges = np.array([[0, 1], [1, 2]])
    poses = np.array(list(itertools.islice(route_poses(nodes, edges, seed=0), 400)))
    steps = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    turns = np.abs(np.remainder(np.diff(poses[:, 2]) + np.pi, 2 * np.pi) - np.pi)
    assert steps.max() <= STEP_M + 1e-9 and turns.max() <= TURN_RAD + 1e-9
    on_edge = (np.abs(poses[:, 1]) < 1e-9) | (np.abs(poses[:, 0] - 1.0) < 1e-9)  # x axis or x = 1
    assert on_edge.all() and poses[:, 1].max() == pytest.approx(1.0)  # reaches the far node


def test_no_route_graph_is_a_clear_error() -> None:
    with pytest.raises(LmsbenchError, match="route graph"):
        next(route_poses(np.zeros((0, 2)), np.zeros((0, 2), dtype=int)))


def test_simulator_scans_see_no_wall_closer_than_the_clearance() -> None:
    sim = pytest.importorskip("sim")
    from experiments.lms200_sources import simulator_scans

    world = sim.make_world("office", seed=0)
    poses = list(itertools.islice(route_poses(world.route_nodes, world.route_edges, 0), 0, 200, 40))
    scans = list(itertools.islice(simulator_scans("office", 0), 0, 200, 40))
    for pose, scan in zip(poses, scans):
        assert len(scan) == 361
        clearance = float(world.clearance(np.array([pose[:2]]))[0])
        assert clearance > 0.05  # the walk stays in free space
        assert np.nanmin(scan.ranges) >= clearance - 0.05  # 5 mm noise + 10 mm quantisation, generous


def test_log_replay_loops_in_order(tmp_path) -> None:  # noqa: ANN001
    scans = [Scan.lms200(np.full(361, 1.0 + i)) for i in range(3)]
    write_log(tmp_path / "a.clf", [Record(s) for s in scans])
    got = [s.ranges[0] for s in itertools.islice(log_scans(tmp_path / "a.clf"), 7)]
    assert got == [1.0, 2.0, 3.0, 1.0, 2.0, 3.0, 1.0]
    assert math.isclose(next(log_scans(tmp_path / "a.clf", loop=False)).ranges[5], 1.0)


def test_log_replay_keeps_no_scan(tmp_path) -> None:  # noqa: ANN001
    """Each pass reads the log again, as the first did (emulate --log kept every scan for its loop:
    250 MB for 60,000 scans), so a scan of one pass is not that of the pass before."""
    write_log(tmp_path / "a.clf", [Record(Scan.lms200(np.full(361, 1.0 + i))) for i in range(2)])
    first, _, again = itertools.islice(log_scans(tmp_path / "a.clf"), 3)
    assert first is not again and first.ranges[0] == again.ranges[0] == 1.0
    lines = (tmp_path / "a.clf").read_text().splitlines(keepends=True)
    (tmp_path / "a.clf").write_text("".join(lines[:-1]) + "ROBOTLASER1 x\n" + lines[-1])
    with pytest.raises(LmsbenchError, match="malformed"):  # the whole log is read before the first scan
        log_scans(tmp_path / "a.clf")
