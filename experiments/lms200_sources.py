"""Scan sources for the virtual LMS200: the simulator driving along a world's route graph, or a
replayed log. The command line wires them into :class:`lms200.virtual.VirtualLMS200` (``lms200``
itself imports nothing from ``sim``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from lms200 import LmsbenchError, Scan, read_log
from lms200.angles import wrap

STEP_M = 0.02  # scanner travel between two scans sent (0.75 m/s at 37.5 scans/s)
TURN_RAD = math.radians(3.0)  # largest heading change between two scans, turning in place


def route_poses(nodes: np.ndarray, edges: np.ndarray, seed: int = 0) -> Iterator[tuple[float, float, float]]:
    """Endless scanner poses (x m, y m, theta rad): a seeded random walk on a route graph, driving
    straight along edges in STEP_M steps and turning in place at nodes in TURN_RAD steps."""
    rng = np.random.default_rng(seed)
    neighbours: dict[int, list[int]] = {}
    for a, b in np.asarray(edges, dtype=int):
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    if not neighbours:
        raise LmsbenchError("the world has no route graph to drive along")
    node = min(neighbours)
    heading = 0.0
    previous = -1
    while True:
        options = [n for n in neighbours[node] if n != previous] or neighbours[node]
        nxt = options[int(rng.integers(len(options)))]
        (x0, y0), (x1, y1) = nodes[node], nodes[nxt]
        target = math.atan2(y1 - y0, x1 - x0)
        turn = wrap(target - heading)
        for k in range(1, int(abs(turn) // TURN_RAD) + 1):
            yield float(x0), float(y0), wrap(heading + math.copysign(k * TURN_RAD, turn))
        heading = target
        steps = max(1, math.ceil(math.hypot(x1 - x0, y1 - y0) / STEP_M - 1e-9))
        for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
            yield float(x0 + t * (x1 - x0)), float(y0 + t * (y1 - y0)), heading
        previous, node = node, nxt


def simulator_scans(world: str = "office", seed: int = 0) -> Iterator[Scan]:
    """Endless emulated LMS200 scans (``sim.LMS200Sim``) along the world's route graph.

    Raises:
        LmsbenchError: when the simulator is not installed or the world has no route graph.
    """
    try:
        from sim import LMS200Sim, make_world
    except ImportError as exc:
        raise LmsbenchError(f"the simulator is not available ({exc}); replay a log with --log FILE") from None
    w = make_world(world, seed=seed)
    lidar = LMS200Sim(w, seed=seed)
    poses = route_poses(w.route_nodes, w.route_edges, seed)
    return (lidar.scan_at(pose) for pose in poses)


def log_scans(path: str | Path, loop: bool = True, read_options: dict[str, Any] | None = None) -> Iterator[Scan]:
    """The scans of a log (CARMEN or bag), in order, replayed endlessly when ``loop``;
    ``read_options``: keywords of ``lms200.read_log`` (topic, skip_bad_lines, geometry). The whole
    log is read once first, keeping nothing (a malformed line is said before the device serves),
    and each pass of the replay reads it again: the scans were all kept for the loop, 3.3 KB each
    (emulate --log of 60,000 scans held 250 MB; a day's log at 37.5 scans/s would take 10 GB)."""
    from experiments.logargs import report_skipped

    options = read_options or {}
    reader = read_log(path, **options)
    scans = sum(1 for _ in reader)
    report_skipped(reader)  # emulate --skip-bad-lines skipped them silently
    if not scans:
        raise LmsbenchError(f"{path} holds no scans to replay")

    def replay() -> Iterator[Scan]:
        while True:
            yield from (rec.scan for rec in read_log(path, **options))
            if not loop:
                return

    return replay()
