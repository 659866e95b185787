"""What every native vector env shares: lane seeding and SAME_STEP autoreset.

A native vector env wraps a batched episode core (``core.reset_lanes(lanes,
rngs)``, ``core.step(actions)``, ``core.obs``, ``core.env_name``) and steps all
lanes in one call chain. Seeding: ``reset(seed=s)`` gives lane i the
generator ``seeding.np_random(s + i)`` — the one a scalar env reset with seed
s + i uses — and a lane's later episodes continue its generator, as a scalar
env's ``reset()`` without a seed does. Autoreset mode SAME_STEP: a finished
lane is reset within the same ``step``; its last observation and info are in
``info["final_obs"]`` / ``info["final_info"]`` (masks ``_final_obs`` /
``_final_info``), as Gymnasium's SyncVectorEnv does in that mode.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv


class NativeVectorEnv(VectorEnv):
    """Base class: subclasses set ``self.core``, ``self.num_envs`` and the spaces."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    core: Any
    _lane_rngs: list[np.random.Generator] | None = None

    def lane_info(self) -> dict[str, np.ndarray]:
        """Per-lane descriptors of the current episodes (e.g. the sensor grade)."""
        return {}

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        if isinstance(seed, int | np.integer):
            seeds: list[int | None] = [int(seed) + i for i in range(self.num_envs)]
        elif seed is None or all(s is None for s in seed):
            seed = None
            seeds = [None] * self.num_envs
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(
                    f"{self.core.env_name}: {len(seeds)} seeds for {self.num_envs} envs"
                )
        if seed is not None or self._lane_rngs is None:
            self._lane_rngs = [seeding.np_random(s)[0] for s in seeds]
        self.core.reset_lanes(np.arange(self.num_envs), self._lane_rngs)
        return self.core.obs.copy(), self.lane_info()

    def step(self, actions):
        if self._lane_rngs is None:
            raise RuntimeError(f"{self.core.env_name}: call reset() before step()")
        obs, reward, terminated, truncated, info = self.core.step(actions)
        info.update(self.lane_info())
        done = terminated | truncated
        if done.any():
            lanes = np.flatnonzero(done)
            info["final_obs"] = np.full(self.num_envs, None, dtype=object)
            info["final_info"] = np.full(self.num_envs, None, dtype=object)
            for lane in lanes:
                info["final_obs"][lane] = obs[lane].copy()
                info["final_info"][lane] = {
                    k: v[lane] for k, v in info.items() if k not in ("final_obs", "final_info")
                }
            info["_final_obs"] = done.copy()
            info["_final_info"] = done.copy()
            self.core.reset_lanes(lanes, [self._lane_rngs[i] for i in lanes])
            obs = self.core.obs.copy()
            info.update(self.lane_info())
        return obs, reward.astype(np.float64), terminated, truncated, info
