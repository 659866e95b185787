"""The one thin bridge from our native Gymnasium vector envs to SB3's VecEnv.

SB3's ``VecEnv`` is not Gymnasium's vector API: it steps with auto-reset in
the same step and returns per-env info dicts carrying
``terminal_observation`` and ``TimeLimit.truncated``. Our native vector envs
autoreset in SAME_STEP mode, so the adapter only reshapes what they return;
all environments still step in one batched call.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv


class NativeVecEnv(VecEnv):
    """SB3 ``VecEnv`` over a native Gymnasium ``VectorEnv`` (SAME_STEP autoreset)."""

    def __init__(self, venv: gym.vector.VectorEnv) -> None:
        mode = venv.metadata.get("autoreset_mode")
        if mode != gym.vector.AutoresetMode.SAME_STEP:
            raise ValueError(f"NativeVecEnv needs SAME_STEP autoreset, got {mode!r}")
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self):
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        obs, info = self.venv.reset(seed=seeds)
        self.reset_infos = [self._lane_info(info, i) for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        dones = terminated | truncated
        infos = []
        for i in range(self.num_envs):
            lane = self._lane_info(info, i)
            if dones[i]:
                lane = dict(info["final_info"][i])
                lane["terminal_observation"] = info["final_obs"][i]
                lane["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            infos.append(lane)
        return obs, reward.astype(np.float32), dones, infos

    @staticmethod
    def _lane_info(info: dict[str, Any], i: int) -> dict[str, Any]:
        return {
            k: v[i]
            for k, v in info.items()
            if not k.startswith("_") and k not in ("final_obs", "final_info")
        }

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list:
        method = getattr(self.venv, method_name)
        return [method(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]
