"""The `lmsbench simulate` driver: simulate a run and write its files.

Files in the output folder:
- ``scans.clf``: CARMEN log, one ROBOTLASER1 line per scan, each preceded by a TRUEPOS line with
  the true scanner pose at the scan's timestamp (the time of its first beam); odometry only when
  asked for (else the pose fields are zeros and ``PARAM lmsbench_odometry absent`` says so).
- ``groundtruth.tum``: the true pose at every scan's timestamp (TUM, z = 0).
- ``world.json``: the world's ground truth (walls, circles, corners) and solids.
- ``config.yaml``: everything needed to rerun it (no run timestamps: same seed, same bytes).
- ``map.png``: the world, the path and one scan.

Each file is written whole or not at all (a hidden temporary file renamed into place), and the
hidden ``.simulate-unfinished`` (options.SIMULATE_UNFINISHED), written before them and removed once
they are all whole and on disk, tells a run stopped or killed while writing from a finished one:
every reader of the folder refuses it, and the next run into the folder takes it. It holds the
run's settings (config.yaml's content under a comment), so ``simulate --config DIR/.simulate-unfinished
--out DIR`` reruns the run that did not finish.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from lms200 import Record
from lms200.carmen import write_carmen
from lms200.finite import printable
from lms200.logs import SIMULATE_LOG
from lms200.tum import write_tum
from lms200.yamlio import dump as dump_yaml
from sim import SensorConfig, World, make_world, simulate_records
from sim.records import OdometryConfig
from sim.sensor import upgrade_fields
from sim.robot import RobotLimits

from experiments.options import SIMULATE_OUTPUTS, SIMULATE_UNFINISHED
from experiments.provenance import marked_unfinished, write_record


SIMULATION_KEYS = frozenset({"world", "seed", "duration", "rate_hz", "sensor", "odometry", "robot", "clutter"})


@dataclass(frozen=True)
class SimulationConfig:
    """One simulated run (the content of config.yaml)."""

    world: str = "office"
    seed: int = 0
    duration: float = 120.0
    rate_hz: float | None = None
    sensor: SensorConfig = SensorConfig()
    odometry: OdometryConfig | None = None
    robot: RobotLimits = RobotLimits()
    clutter: float | None = None  # clutter level of a named world (None: the name's default)

    def to_dict(self) -> dict:
        return {
            "world": self.world,
            "seed": int(self.seed),
            "duration": float(self.duration),
            "rate_hz": None if self.rate_hz is None else float(self.rate_hz),
            "sensor": self.sensor.to_dict(),
            "odometry": None if self.odometry is None else self.odometry.to_dict(),
            "robot": {k: list(v) if isinstance(v, tuple) else v for k, v in self.robot.to_dict().items()},
            **({} if self.clutter is None else {"clutter": float(self.clutter)}),
        }

    @classmethod
    def from_dict(cls, d: dict, where: str | None = None) -> "SimulationConfig":
        """The inverse of :meth:`to_dict`. Raises ValueError for a key this config does not have
        (a file of another kind would otherwise run the defaults) and for values of the wrong type.
        A sensor section in degrees (``resolution_deg``, ``beam_width_deg``: a config.yaml written
        before the sensor config held radians) is read, converted, with a warning naming ``where``
        (the file)."""
        unknown = sorted(set(d) - SIMULATION_KEYS, key=str)
        if unknown:  # a section's field at the top (`pause_s: 5`) is named with the section it belongs to
            homes = [f"{key} belongs under {section}: ({section}: {{{key}: ...}})" for key in unknown
                     for section, cls in SECTIONS.items() if key in {f.name for f in fields(cls)}]
            raise ValueError(f"unknown key(s) {unknown}; a simulate config has {sorted(SIMULATION_KEYS)}"
                             + (f"; {', '.join(homes)}" if homes else ""))
        seed = d.get("seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise ValueError(f"seed: must be a whole number, got {seed!r}")
        world = d.get("world", "office")
        if not isinstance(world, str):
            raise ValueError(f"world: must be a world's name or a world.json path, got {world!r}")
        robot = dict(_mapping(d, "robot"))
        if isinstance(robot.get("pause_s"), list):  # YAML has no tuples; anything else RobotLimits refuses, naming it
            robot["pause_s"] = tuple(robot["pause_s"])
        duration, rate_hz, clutter = (_number(d, key) for key in ("duration", "rate_hz", "clutter"))
        return cls(world=world, seed=seed, duration=120.0 if duration is None else duration, rate_hz=rate_hz,
                   sensor=_section({"sensor": upgrade_fields(_mapping(d, "sensor"),
                                                             f"{where}: sensor" if where else "sensor")}, "sensor"),
                   odometry=_section(d, "odometry") if _mapping(d, "odometry") else None,
                   robot=_section({"robot": robot}, "robot"), clutter=clutter)


SECTIONS = {"sensor": SensorConfig, "odometry": OdometryConfig, "robot": RobotLimits}  # key -> its config class


def _section(d: dict, key: str) -> Any:
    """The config of section ``key`` from its mapping; ValueError naming ``key.FIELD`` for a field the
    section does not have (with the fields it has) or a bad value: `robot: {bogus: 1}` said
    "RobotLimits.__init__() got an unexpected keyword argument 'bogus'", `robot: {pause_s: 5}`
    "'int' object is not iterable"."""
    cls, values = SECTIONS[key], _mapping(d, key)
    known = [f.name for f in fields(cls)]
    unknown = sorted((k for k in values if k not in known), key=str)
    if unknown:
        raise ValueError(f"{key}: unknown field(s) {unknown}; {key}: has {', '.join(known)}")
    try:
        return cls(**values)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{key}.{' '.join(str(exc).split())}") from None


def _number(d: dict, key: str) -> float | None:
    """``d[key]`` as a float, None when absent or null; ValueError naming ``key`` for anything but a
    number (``duration: true`` ran 1 s, ``duration: [2]`` said "float() argument must be ...")."""
    value = d.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{key}: must be a number, got {value!r}")
    return float(value)


def _mapping(d: dict, key: str) -> dict:
    """``d[key]``, a mapping of fields ({} when absent or null); ValueError naming ``key`` otherwise."""
    value = d.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ValueError(f"{key}: must be a mapping of fields, got {value!r}")
    return value


def run_simulation(cfg: SimulationConfig, out: Path, progress: bool = False) -> list[Record]:
    """Simulate ``cfg`` and write scans.clf, groundtruth.tum, world.json, config.yaml, map.png
    (with a progress bar on stderr when ``progress``)."""
    world = World.from_json(cfg.world) if cfg.world.endswith(".json") else make_world(cfg.world, cfg.seed, cfg.clutter)
    bar = None

    def step(done: int, total: int) -> None:
        nonlocal bar
        if not progress:
            return
        if bar is None:
            from tqdm import tqdm

            bar = tqdm(total=total, unit="scan", desc="simulate", mininterval=1.0, disable=None)  # terminal only
        bar.update(done - bar.n)

    try:
        records = simulate_records(world, cfg.seed, cfg.duration, cfg.sensor, cfg.odometry, cfg.rate_hz, cfg.robot,
                                   progress=step)
    finally:
        if bar is not None:
            bar.close()
    # the folder marked unfinished from before any output until all are whole and on disk: a run killed
    # from here on (SIGKILL, a crash, a power loss) left a cut scans.clf, or the earlier run's files beside
    # its new config.yaml, read as a finished run. The marker holds the run's settings, which the readers'
    # refusal reruns with --config MARKER (config.yaml, written next, is still the earlier run's, or absent,
    # when the run stops before it)
    marker = ("# lmsbench simulate is writing this folder; removed once its files are whole (a folder\n"
              "# holding this file is one whose run did not finish). Below, the settings of that run (a\n"
              "# simulate config): lmsbench simulate --config DIR/.simulate-unfinished --out DIR reruns it.\n"
              + dump_yaml(cfg.to_dict(), sort_keys=False))
    with marked_unfinished(out, SIMULATE_UNFINISHED, marker, SIMULATE_OUTPUTS):
        # config.yaml first, whole: it tells the folder as simulate's (options.SIMULATE_OWNER); a run
        # stopped while writing scans.clf left a folder the next run into it refused
        write_record(out / "config.yaml", dump_yaml(cfg.to_dict(), sort_keys=False))
        write_record(out / SIMULATE_LOG, lambda tmp: write_carmen(tmp, records))  # streamed into the temporary file
        stamps = np.array([r.scan.stamp for r in records], dtype=float)
        write_record(out / "groundtruth.tum",
                     lambda tmp: write_tum(tmp, stamps, np.array([r.truth for r in records]).reshape(-1, 3)))
        write_record(out / "world.json", world.to_json)  # a record too: whole, or a cut one refused the next run
        write_record(out / "map.png", lambda tmp: draw_map(world, records, tmp))
    return records


def draw_map(world: World, records: list[Record], path: Path) -> None:
    """The world's cross-section, the driven path and the middle scan (world frame)."""
    try:
        from experiments.style import apply_style, equal_axes
        apply_style()
    except ImportError:  # pragma: no cover - style module of another area
        equal_axes = None
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Circle

    fig, ax = plt.subplots(figsize=(7, 6))
    ax.add_collection(LineCollection(world.walls.reshape(-1, 2, 2), colors="k", linewidths=0.8))
    for cx, cy, r in world.circles:
        ax.add_patch(Circle((cx, cy), r, fill=False, color="k", lw=0.8))
    if len(world.glass):
        ax.add_collection(LineCollection(world.glass.reshape(-1, 2, 2), colors="tab:cyan", linewidths=2.0,
                                         label="glass (no return)"))
    if records:
        truth = np.array([r.truth for r in records])
        ax.plot(truth[:, 0], truth[:, 1], "-", color="tab:blue", lw=1.0, label="path")
        mid = records[len(records) // 2]
        x, y, th = mid.truth
        pts = mid.scan.points
        c, s = np.cos(th), np.sin(th)
        ax.plot(x + c * pts[:, 0] - s * pts[:, 1], y + s * pts[:, 0] + c * pts[:, 1], ".", ms=1.5,
                color="tab:red", label=f"scan at t = {mid.scan.stamp:.2f} s")
        ax.plot([x], [y], "o", color="tab:red", ms=4)
    ax.autoscale_view()
    if equal_axes is not None:
        equal_axes(ax)
    else:
        ax.set_aspect("equal")
    ax.set_title(f"world {printable(world.name)} (seed {world.seed})")  # a world file's stem may not be UTF-8
    ax.legend(loc="upper right")
    from experiments.style import savefig  # a full disk its OSError, not matplotlib's cleanup error

    savefig(fig, path, format="png", dpi=120, metadata={"Software": None})  # path: a temporary name
    plt.close(fig)
