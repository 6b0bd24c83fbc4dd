"""The Gymnasium environment: API conformance, seeding, termination and reward."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim  # noqa: F401  (registers lmsbench/Office-v0)
from sim.gym_env import COLLISION_REWARD, OfficeEnv


def _rollout(seed: int, steps: int = 25) -> tuple[np.ndarray, np.ndarray]:
    env = gym.make("lmsbench/Office-v0")
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    observations, rewards = [obs], []
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        observations.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            break
    env.close()
    return np.array(observations), np.array(rewards)


def test_check_env_passes() -> None:
    env = gym.make("lmsbench/Office-v0")
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_same_seed_same_rollout() -> None:
    a_obs, a_rew = _rollout(5)
    b_obs, b_rew = _rollout(5)
    assert np.array_equal(a_obs, b_obs) and np.array_equal(a_rew, b_rew)
    c_obs, _ = _rollout(6)
    assert not np.array_equal(a_obs[: len(c_obs)], c_obs[: len(a_obs)])


def test_observation_is_clipped_scan() -> None:
    env = OfficeEnv(world="corridor")
    obs, info = env.reset(seed=0)
    assert obs.dtype == np.float32 and obs.shape == (361,)
    assert np.all((obs >= 0) & (obs <= np.float32(8.183)))
    assert np.any(obs == np.float32(8.183))  # looking down the 30 m corridor: beyond range
    env.close()


def test_following_the_path_earns_progress_and_a_wall_ends_it() -> None:
    env = OfficeEnv(world="corridor", max_steps=30)
    env.reset(seed=1)
    env.pose[2] = np.arctan2(*(env.path[1] - env.path[0])[::-1])  # face along the path
    total = 0.0
    for _ in range(20):
        _, reward, terminated, truncated, info = env.step(np.array([0.5, 0.0], dtype=np.float32))
        total += reward
        assert not terminated
    assert info["progress_m"] == pytest.approx(20 * 0.1 * 0.5, abs=1e-6)
    assert total == pytest.approx(1.0 - 20 * 0.01, abs=1e-6)
    for _ in range(10):
        *_, terminated, truncated, _ = env.step(np.array([0.0, 0.0], dtype=np.float32))
    assert truncated and not terminated
    # turn to face the corridor wall and drive into it
    env.reset(seed=1)
    env.pose[2] = np.pi / 2
    for _ in range(40):
        _, reward, terminated, _, info = env.step(np.array([0.5, 0.0], dtype=np.float32))
        if terminated:
            break
    assert terminated and reward < COLLISION_REWARD + 1
    assert env.world.clearance(info["pose"][None, :2])[0] < env.limits.radius
    env.close()


@pytest.mark.parametrize("world, length", [("office", 5.0), ("corridor", 60.0)])
def test_path_length_m_is_the_planned_paths_length_in_metres(world: str, length: float) -> None:
    """It was taken as a tour of path_length_m / v_max seconds, planned 5 m longer and to the end of its
    last leg: office 5 m gave a 12.9 m path, the default 60 m one of 66.7 m. The path is the start of
    the route robot_tour drives (the independent reference), cut on its last edge."""
    from sim import make_world, robot_tour

    env = OfficeEnv(world=world, world_seed=2, path_length_m=length)
    arc = np.hypot(*np.diff(env.path, axis=0).T)
    assert arc.sum() == pytest.approx(length, abs=1e-9)
    _, info = env.reset(seed=0)
    assert info["path_length_m"] == pytest.approx(length, abs=1e-9)
    env.close()
    route = robot_tour(make_world(world, 2), 2, duration=length / 0.5).waypoints
    route = route[np.concatenate(([True], np.hypot(*np.diff(route, axis=0).T) > 1e-9))]
    k = len(env.path) - 1
    assert np.array_equal(env.path[:k], route[:k])
    end = env.path[k] - route[k - 1]  # on the route's next edge, short of its end
    edge = route[k] - route[k - 1]
    assert abs(end[0] * edge[1] - end[1] * edge[0]) < 1e-9 and 0 < end @ edge <= edge @ edge
