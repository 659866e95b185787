"""First-episode scores of per-lane constant or rule-based policies, batched."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

import pednav_env  # noqa: F401  (registers the environments)


def first_episode_errors(
    env_id: str,
    act: Callable[[np.ndarray], np.ndarray],
    seeds: list[int],
    env_kwargs: dict[str, Any] | None = None,
) -> np.ndarray:
    """Time-averaged error (= −return) of each lane's first episode.

    One native vector env with a lane per seed; ``act(obs (N, d)) -> (N, k)``.
    """
    venv = gym.make_vec(
        env_id, num_envs=len(seeds), vectorization_mode="vector_entry_point", **(env_kwargs or {})
    )
    obs, _ = venv.reset(seed=list(seeds))
    n = len(seeds)
    total = np.zeros(n)
    done = np.zeros(n, dtype=bool)
    while not done.all():
        obs, reward, term, trunc, _ = venv.step(act(obs))
        total += np.where(done, 0.0, reward)
        done |= term | trunc
    venv.close()
    return -total
