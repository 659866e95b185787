"""One episode of a scalar env, for the env tests."""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym
import numpy as np


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
