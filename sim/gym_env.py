"""A Gymnasium environment: drive the robot through an office world on its LMS200 scans.

Registered as ``lmsbench/Office-v0`` (``import sim`` registers it, or pass
``gymnasium.make("sim.gym_env:lmsbench/Office-v0")``).

- Observation: the scan's ranges, float32 (n_beams,), in [0, range_max]; +inf (no return) and nan
  (dropout) read as range_max.
- Action: (forward speed m/s, turn rate rad/s) in [0, v_max] x [-w_max, w_max]; held for one
  control period (0.1 s); the pose moves along the exact unicycle arc and the scan is taken at
  the end of the period while moving (interlaced beams).
- Path: the first ``path_length_m`` metres of the route ``robot_tour(world, world_seed)`` drives.
- Reward: metres of progress along the world's planned tour path (arc length of the robot's
  projection, searched near the previous one) minus 0.01 a step; -10 on collision.
- Termination: collision (the robot's disc of radius 0.25 m touches a face or circle) or the end
  of the path reached (+10). Truncation: after ``max_steps`` steps (default 500).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from lms200 import Scan
from lms200.codes import unmasked
from lms200.errors import InputError

from .lidar import LMS200Sim
from .robot import RobotLimits, tour_path, wrap
from .sensor import SensorConfig
from .worlds import check_seed, make_world

ENV_ID = "lmsbench/Office-v0"
COLLISION_REWARD = -10.0
GOAL_REWARD = 10.0
STEP_COST = 0.01


class OfficeEnv(gym.Env):
    """Drive through ``world`` (a named world built with ``world_seed``) along its tour."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, world: str = "office", world_seed: int = 0, sensor: SensorConfig | None = None,
                 control_period: float = 0.1, max_steps: int = 500, path_length_m: float = 60.0,
                 render_mode: str | None = None) -> None:
        _check_env_args(control_period, max_steps, path_length_m, render_mode)
        self.world = make_world(world, world_seed)
        self.sensor = sensor if sensor is not None else SensorConfig()
        self.limits = RobotLimits()
        self.control_period = float(control_period)
        self.max_steps = int(max_steps)
        self.render_mode = render_mode
        self.sim = LMS200Sim(self.world, self.sensor, seed=0)
        # the path is path_length_m long (it was planned as a tour of path_length_m / v_max seconds, 5 m
        # more and to the end of its last leg: 66.7 m for the default 60, 12.9 m for 5)
        self.path = tour_path(self.world, world_seed, float(path_length_m))
        seg = np.diff(self.path, axis=0)
        self._seg_len = np.hypot(seg[:, 0], seg[:, 1])
        self._arc = np.concatenate(([0.0], np.cumsum(self._seg_len)))
        rmax = np.float32(self.sensor.range_max)
        self.observation_space = spaces.Box(0.0, rmax, shape=(self.sensor.n_beams,), dtype=np.float32)
        self.action_space = spaces.Box(np.array([0.0, -self.limits.w_max], dtype=np.float32),
                                       np.array([self.limits.v_max, self.limits.w_max], dtype=np.float32),
                                       dtype=np.float32)
        self.pose = np.zeros(3)
        self.progress = 0.0
        self.steps = 0
        self._scan: Scan | None = None

    # -- helpers ------------------------------------------------------------------------------
    def _project(self, xy: np.ndarray, near: float) -> float:
        """Arc length (m) of the path point nearest xy, searched within [near - 1, near + 2] m."""
        a, d = self.path[:-1], np.diff(self.path, axis=0)
        t = np.clip(((xy - a) * d).sum(1) / np.maximum(self._seg_len**2, 1e-18), 0, 1)
        s = self._arc[:-1] + t * self._seg_len
        dist = np.hypot(*(a + t[:, None] * d - xy).T)
        window = (s >= near - 1.0) & (s <= near + 2.0)
        dist = np.where(window, dist, np.inf)
        return float(s[int(np.argmin(dist))]) if np.isfinite(dist).any() else near

    def _observe(self, twist: tuple[float, float] | None) -> np.ndarray:
        x, y, th = (float(v) for v in self.pose)
        scan = self.sim.scan_at((x, y, th), stamp=self.steps * self.control_period, twist=twist)
        self._scan = scan
        r = np.where(np.isfinite(scan.ranges), scan.ranges, self.sensor.range_max)
        return np.minimum(r, self.sensor.range_max).astype(np.float32)

    def _info(self) -> dict[str, Any]:
        return {"pose": self.pose.copy(), "progress_m": self.progress, "path_length_m": float(self._arc[-1])}

    # -- Gymnasium API ------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        self._check_open("reset")
        if seed is not None:
            check_seed(seed)  # Gymnasium's own error otherwise (and a numpy one for 2**64)
            seed = int(seed)  # Gymnasium takes Python ints only (numpy's are refused)
        super().reset(seed=seed)
        self.sim.reseed(int(self.np_random.integers(2**62)))
        d = self.path[1] - self.path[0]
        heading = float(np.arctan2(d[1], d[0]) + self.np_random.uniform(-0.3, 0.3))
        self.pose = np.array([self.path[0, 0], self.path[0, 1], heading])
        self.progress = 0.0
        self.steps = 0
        return self._observe(None), self._info()

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        self._check_open("step")
        if self._scan is None:  # no episode: it stepped from pose (0, 0, 0), unseeded, with a reward and no word
            raise InputError("step: no episode yet: call reset() first (gymnasium.make's env says so too)")
        space = self.action_space
        assert isinstance(space, spaces.Box)
        v, w = np.clip(_action(action), space.low, space.high)
        dt = self.control_period
        x, y, th = self.pose
        if abs(w) < 1e-9:
            x, y = x + v * dt * np.cos(th), y + v * dt * np.sin(th)
        else:
            x += v / w * (np.sin(th + w * dt) - np.sin(th))
            y -= v / w * (np.cos(th + w * dt) - np.cos(th))
        self.pose = np.array([x, y, float(wrap(th + w * dt))])
        self.steps += 1
        collided = bool(self.world.clearance(self.pose[None, :2])[0] < self.limits.radius)
        new_progress = self._project(self.pose[:2], self.progress)
        reward = new_progress - self.progress - STEP_COST
        self.progress = max(self.progress, new_progress)
        reached = self.progress >= self._arc[-1] - 0.3
        if collided:
            reward += COLLISION_REWARD
        elif reached:
            reward += GOAL_REWARD
        obs = self._observe((float(v), float(w)))
        truncated = self.steps >= self.max_steps and not (collided or reached)
        return obs, float(reward), bool(collided or reached), bool(truncated), self._info()

    def render(self) -> np.ndarray | None:
        """rgb_array: a top view of the world, the path, the robot and its scan."""
        if self.render_mode != "rgb_array":
            return None
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import LineCollection

        fig, ax = plt.subplots(figsize=(4, 4), dpi=80)
        ax.add_collection(LineCollection(list(self.world.walls.reshape(-1, 2, 2)), colors="k", linewidths=0.6))
        ax.plot(self.path[:, 0], self.path[:, 1], "-", color="tab:blue", lw=0.6)
        if self._scan is not None:
            p = self._scan.points
            c, s = np.cos(self.pose[2]), np.sin(self.pose[2])
            ax.plot(self.pose[0] + c * p[:, 0] - s * p[:, 1], self.pose[1] + s * p[:, 0] + c * p[:, 1], ".",
                    ms=1, color="tab:red")
        ax.plot([self.pose[0]], [self.pose[1]], "o", color="tab:red")
        ax.set_aspect("equal")
        ax.autoscale_view()
        fig.canvas.draw()
        image = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()  # type: ignore[attr-defined]  # Agg canvas
        plt.close(fig)
        return image

    def close(self) -> None:
        """Release the simulator's PyBullet client (idempotent); the environment takes no step or reset after it."""
        self.sim.close()

    def _check_open(self, call: str) -> None:
        """InputError for ``step`` or ``reset`` after :meth:`close`: it was PyBullet's TypeError
        ("'NoneType' object cannot be interpreted as an integer"), naming nothing."""
        if self.sim.client is None:
            raise InputError(f"{call}: the environment is closed (close() was called); make a new one "
                             "(gymnasium.make or sim.gym_env.OfficeEnv)")


def _action(action: object) -> np.ndarray:
    """``action`` as a float64 (v m/s, w rad/s) pair; InputError naming it when it is not two finite
    real numbers (a nan drove the pose to nan, and a scalar or a 1-element array was broadcast to
    both v and w; out-of-bounds values are clipped to the action space, as before)."""
    try:
        a = np.asarray(unmasked(action))  # a masked v or w: nan, refused (its hidden value was driven)
    except (TypeError, ValueError):
        a = np.asarray(None)
    if a.shape != (2,) or a.dtype.kind not in "iuf" or not np.all(np.isfinite(a)):
        raise InputError(f"action: must be two finite numbers (v m/s, w rad/s), shape (2,), got {action!r}")
    return a.astype(np.float64)


def _check_env_args(control_period: object, max_steps: object, path_length_m: object, render_mode: object) -> None:
    """InputError naming the first argument of OfficeEnv that cannot work (a nan control_period was a
    ScanError about a 'stamp', a negative one ran time backwards, path_length_m=1e9 planned a tour for
    minutes before running out of memory)."""
    from .records import MAX_DURATION_S

    def real(v: object) -> bool:
        return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))

    if not real(control_period) or not 0 < control_period <= 10.0:  # type: ignore[operator]
        raise InputError(f"control_period: must be a number of seconds in (0, 10], got {control_period!r}")
    if isinstance(max_steps, (bool, np.bool_)) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise InputError(f"max_steps: must be a whole number >= 1, got {max_steps!r}")
    longest = MAX_DURATION_S * RobotLimits().v_max
    if not real(path_length_m) or not 0 < path_length_m <= longest:  # type: ignore[operator]
        raise InputError(f"path_length_m: must be a number of metres in (0, {longest:g}], got {path_length_m!r}")
    if render_mode not in (None, "rgb_array"):
        raise InputError(f"render_mode: must be None or 'rgb_array', got {render_mode!r}")
