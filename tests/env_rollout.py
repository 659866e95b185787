"""For the env tests: constructor arguments that keep episodes short, and one episode
of a scalar env."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from testdata import REPLAY_DATA

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.marker_config import MarkerTrackConfig
from pednav_env.envs.waist_config import WaistRandomization, WaistStepConfig
from pednav_env.gait.foot_route import RouteRandomization

#: Every registered pednav env (the envs register when pednav_env is imported).
ENV_IDS = sorted(env_id for env_id in gym.registry if env_id.startswith("pednav/"))
#: Constructor arguments per registered env that keep the episodes short (the
#: defaults walk for minutes); an env not listed here is made with its defaults.
FAST_KWARGS: dict[str, dict[str, Any]] = {
    "pednav/FootZupt-v0": {
        "config": FootZuptConfig(route=RouteRandomization(duration_s=(12.0, 20.0)))
    },
    "pednav/FootZuptReplay-v0": {"data_dir": str(REPLAY_DATA)},
    "pednav/MarkerTrack-v0": {
        "config": MarkerTrackConfig(
            duration_s=(4.0, 8.0),
            gait_change_rate_hz=0.5,
            reanchor_after_s=2.0,
            reanchor_keep_s=1.0,
        )
    },
    "pednav/WaistStep-v0": {
        "config": WaistStepConfig(randomization=WaistRandomization(duration_s=(12.0, 20.0)))
    },
}


def rollout(
    env: gym.Env,
    seed: int,
    policy: Callable[[int], np.ndarray] | None = None,
    max_steps: int = 10_000,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """One episode from ``reset(seed)`` with ``policy(t)`` (default: action 0):
    the observations (reset's first), the rewards and the last info."""
    obs, info = env.reset(seed=seed)
    observations, rewards = [obs], []
    for t in range(max_steps):
        a = np.zeros(env.action_space.shape, np.float32) if policy is None else policy(t)
        obs, r, term, trunc, info = env.step(a)
        observations.append(obs)
        rewards.append(r)
        if term or trunc:
            break
    return np.array(observations), np.array(rewards), info
