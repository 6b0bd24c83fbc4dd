"""PyBullet office worlds that emulate a SICK LMS200, with exact ground truth.

Public names: make_world, World, SensorConfig, LMS200Sim, visible_truth, VisibleTruth,
simulate_records, robot_tour, Tour, OdometryConfig. Heavier parts (PyBullet, the robot) load on
first use.
"""

from __future__ import annotations

import importlib
from typing import Any

from .sensor import SensorConfig
from .truth import VisibleTruth, visible_truth
from .world import World
from .worlds import WORLD_NAMES, make_world

_LAZY = {
    "LMS200Sim": ".lidar",
    "robot_tour": ".robot",
    "Tour": ".robot",
    "RobotLimits": ".robot",
    "OdometryConfig": ".records",
    "simulate_records": ".records",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'sim' has no attribute {name!r}")


__all__ = ["make_world", "World", "WORLD_NAMES", "SensorConfig", "visible_truth", "VisibleTruth", *_LAZY]


def _register_gym_env() -> None:
    """Register ``lmsbench/Office-v0`` with Gymnasium (the class loads on ``gymnasium.make``)."""
    try:
        import gymnasium
    except ImportError:  # pragma: no cover - gymnasium is a dependency
        return
    if "lmsbench/Office-v0" not in gymnasium.registry:
        gymnasium.register(id="lmsbench/Office-v0", entry_point="sim.gym_env:OfficeEnv")


_register_gym_env()
