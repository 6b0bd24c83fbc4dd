"""What the experiments share besides the comparison: simulated runs with their truth, the
experiments' sensor, flat parameter names, and timed feature sets for the figure panels.

The one comparison (interleaved timing, scores against truth, pooled summary) is
``experiments.compare.compare`` / ``summarise``, used by ``lmsbench compare``, the sweeps, the
figures and the demo; they hand it records simulated once through ``Source.from_records``.
"""

from __future__ import annotations

import time
from typing import Any, Iterable, Sequence

import numpy as np

from lms200 import Record, Scan

#: The extractors compared by default: the paper's method and the four baselines.
ALL_METHODS = ("sensor", "split_merge", "iepf", "hough", "ransac")


def split_params(params: dict[str, Any], prefix: str) -> dict[str, Any]:
    """The ``prefix.NAME`` entries of a flat parameter dict, as ``{NAME: value}``."""
    head = prefix + "."
    return {k[len(head):]: v for k, v in params.items() if k.startswith(head)}


def sensor_config(overrides: dict[str, Any] | None = None, sensor_file: str | None = None,
                  sensor_bytes: bytes | None = None):
    """The experiments' sensor: ``sim.SensorConfig(interlaced=False)`` (as ``experiments.compare``
    uses: the truth is that of one pose, so the robot's motion within a scan is not charged to
    the extractors) with the given fields changed (``interlaced=True`` for the moving-scan model).
    With ``sensor_file`` (a sensor YAML, e.g. from ``lmsbench calibrate``) the base is that file's
    config, exactly as written (its ``interlaced`` included), and ``overrides`` go on top (an old
    degree field, ``resolution_deg``, converted to radians with a warning: ``SensorConfig.replace``).
    ``sensor_bytes``: the sensor file's content, read already (``SensorConfig.from_yaml``'s ``data``)."""
    from sim import SensorConfig

    base = SensorConfig.from_yaml(sensor_file, sensor_bytes) if sensor_file else SensorConfig(interlaced=False)
    return base.replace(**(overrides or {}))


def simulate_run(world: str = "office", seed: int = 0, duration: float = 10.0, sensor=None,
                 rate_hz: float | None = None, world_bytes: bytes | None = None) -> tuple[Any, list[Record]]:
    """The world object and the records of a simulated run (truth pose on every record); ``world`` a
    built-in world's name or a world.json (a sweep's every cell failed on one: "unknown world"),
    ``world_bytes`` its content when read already (``World.from_json``'s ``data``)."""
    from sim import World, make_world, simulate_records

    world_obj = World.from_json(world, world_bytes) if world.endswith(".json") else make_world(world, seed=seed)
    return world_obj, simulate_records(world=world_obj, seed=seed, duration=duration, sensor=sensor, rate_hz=rate_hz)


def truths_for(world, records: Sequence[Record], sensor=None) -> list[Any]:
    """The visible ground truth (sensor frame) of every record, from its true pose."""
    from sim import SensorConfig, visible_truth

    sensor = sensor if sensor is not None else SensorConfig()
    return [visible_truth(world, r.truth, sensor) for r in records]


def extract_timed(scans: Iterable[Scan], method: str, params: dict[str, Any] | None = None
                  ) -> tuple[list[Any], np.ndarray]:
    """Feature sets of every scan and the time each extraction took (ms, perf_counter_ns).

    Raises:
        ScanGeometryError, ConfigError: what ``extract`` refuses and ``run`` does not check, naming the
            scan: more beams than the extractors take, a baseline's breakpoint_lambda not above its beam
            step (``features.registry.check_step``: Fig. 9's panels of a 12-deg log had no line, silently).
    """
    from features import registry

    config = registry.make_config(method, **(params or {}))
    run = registry.get_method(method).run  # time the algorithm alone, not the registry look-up
    results, times = [], []
    for k, scan in enumerate(scans):
        registry.check_beams(scan, f"scan {k}")  # extract's beam limit, which run does not check
        registry.check_step(config, scan.angle_increment, method, f"scan {k}")  # and its breakpoint_lambda check
        start = time.perf_counter_ns()
        results.append(run(scan, config))
        times.append((time.perf_counter_ns() - start) / 1e6)
    return results, np.asarray(times)
