"""Stable-Baselines3 on the native vector envs: train and evaluate with your own code.

SB3 does not take a Gymnasium ``VectorEnv`` (``PPO("MlpPolicy",
gym.make_vec(...))`` fails with "not a Gymnasium environment"): it has its own
``VecEnv`` API, which steps with auto-reset in the same step and returns
per-env info dicts carrying ``terminal_observation`` and
``TimeLimit.truncated``. :class:`NativeVecEnv` is the thin bridge: our native
vector envs autoreset in SAME_STEP mode, so it only reshapes what they return,
and all lanes still step in one batched call. :func:`make_vec_env` builds it
(plus ``VecMonitor`` and, on request, ``VecNormalize``)::

    from stable_baselines3 import PPO
    from pednav_env.sb3 import make_vec_env

    vec = make_vec_env("pednav/FootZupt-v0", n_envs=8, seed=0, normalize=True)
    model = PPO("MlpPolicy", vec, seed=0).learn(100_000)
    model.save("run/model.zip")
    vec.save("run/vecnormalize.pkl")  # `pednav evaluate run/` needs it beside model.zip

Seeds (:mod:`pednav_env.seeds`): with ``split="training"`` (the default)
``seed(r)`` — what SB3 calls for ``PPO(seed=r)`` — takes a training *run seed*
r ∈ [0, 10 000) and seeds lane i with ``training_seed(r) + i`` (≥ 1 000 000),
so a training script never plays evaluation episodes, whatever seed it passes.
With ``split="evaluation"`` ``seed(s)`` seeds lane i with s + i, and s … s + n − 1
must be evaluation seeds (< 1 000 000).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecMonitor, VecNormalize

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.seeds import LANES_PER_RUN, MAX_RUN_SEED, check_evaluation_seeds, training_seed

Split = Literal["training", "evaluation"]


class NativeVecEnv(VecEnv):
    """SB3 ``VecEnv`` over a native Gymnasium ``VectorEnv`` (SAME_STEP autoreset).

    ``split`` says how :meth:`seed` reads its argument (see the module docstring).
    ``lane_offset`` (training only) shifts the lanes within the run's seed block,
    e.g. for a resumed run that should not replay its first episodes. An unseeded
    training env draws a random run seed at its first reset; an unseeded
    evaluation env refuses to reset.
    """

    def __init__(
        self, venv: gym.vector.VectorEnv, split: Split = "training", lane_offset: int = 0
    ) -> None:
        mode = venv.metadata.get("autoreset_mode")
        if mode != gym.vector.AutoresetMode.SAME_STEP:
            raise ValueError(f"NativeVecEnv needs SAME_STEP autoreset, got {mode!r}")
        if split not in ("training", "evaluation"):
            raise ValueError(f"split must be 'training' or 'evaluation', got {split!r}")
        if lane_offset < 0 or (split == "training" and lane_offset + venv.num_envs > LANES_PER_RUN):
            raise ValueError(
                f"lane_offset + num_envs must lie in [0, {LANES_PER_RUN}] (a run's seed block), "
                f"got {lane_offset} + {venv.num_envs}"
            )
        if split == "evaluation" and lane_offset:
            raise ValueError("lane_offset applies to the training split only")
        self.venv = venv
        self.split = split
        self.lane_offset = lane_offset
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray | None = None
        #: The env's privileged ``info["context"]`` of each lane's current episode
        #: (None when the env has none), updated at every reset and step; only the
        #: evaluation hands it to policies that declare ``needs_context``.
        self.context: np.ndarray | None = None
        #: Lane seeds of the last :meth:`seed` call (None before any).
        self.lane_seeds: list[int] | None = None

    def seed(self, seed: int | None = None) -> list[int | None]:
        """Lane seeds for the next reset: training run seed ``seed`` (random when
        None) or, for the evaluation split, the first evaluation seed."""
        if self.split == "training":
            run = int(np.random.default_rng().integers(MAX_RUN_SEED)) if seed is None else int(seed)
            first = training_seed(run) + self.lane_offset
        else:
            if seed is None:
                raise ValueError("an evaluation NativeVecEnv needs an explicit seed")
            check_evaluation_seeds(int(seed), self.num_envs)
            first = int(seed)
        self.lane_seeds = [first + i for i in range(self.num_envs)]
        self._seeds = list(self.lane_seeds)
        return self.lane_seeds

    def reset(self):
        if self.lane_seeds is None:
            self.seed(None)
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        obs, info = self.venv.reset(seed=seeds)
        self.context = self._context(info)
        self.reset_infos = [self._lane_info(info, i) for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        self.context = self._context(info)
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
    def _context(info: dict[str, Any]) -> np.ndarray | None:
        """The current episodes' context (after an autoreset: the new episode's)."""
        value = info.get("context")
        return None if value is None else np.array(value, dtype=np.float64)

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


def make_vec_env(
    env_id: str,
    n_envs: int = 8,
    seed: int | None = 0,
    *,
    normalize: bool | dict[str, Any] = False,
    normalize_stats: str | Path | None = None,
    evaluation_seed: int | None = None,
    monitor: bool = True,
    **env_kwargs: Any,
) -> VecEnv:
    """An SB3 ``VecEnv`` of ``n_envs`` lanes of ``env_id`` (one native vector env).

    - ``seed``: training run seed (lanes ``training_seed(seed) + i``); ``None``
      draws one at the first reset. ``PPO(seed=r)`` re-seeds with run seed r.
    - ``evaluation_seed``: instead, lanes ``evaluation_seed + i`` (evaluation
      seeds, < 1 000 000); ``seed`` is then ignored.
    - ``normalize``: wrap in ``VecNormalize`` (``True`` or its keyword arguments)
      for training; save its statistics (``vec.save("vecnormalize.pkl")``).
    - ``normalize_stats``: load saved ``VecNormalize`` statistics, frozen
      (``training=False``, raw rewards), to evaluate a model trained with them.
    - ``monitor``: wrap in ``VecMonitor`` (episode returns and lengths for SB3's
      logger) before any normalisation.
    - ``env_kwargs``: passed to ``gymnasium.make_vec`` (e.g. ``scenario="paper"``).
    """
    if n_envs < 1:
        raise ValueError(f"n_envs must be ≥ 1, got {n_envs}")
    if normalize and normalize_stats is not None:
        raise ValueError("give normalize (new statistics) or normalize_stats (saved), not both")
    venv = gym.make_vec(
        env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **env_kwargs
    )
    split: Split = "training" if evaluation_seed is None else "evaluation"
    vec: VecEnv = NativeVecEnv(venv, split=split)
    if evaluation_seed is not None:
        vec.seed(evaluation_seed)
    elif seed is not None:
        vec.seed(seed)
    if monitor:
        vec = VecMonitor(vec)
    if normalize_stats is not None:
        path = Path(normalize_stats)
        if not path.is_file():
            raise ValueError(f"normalize_stats: no such file {str(path)!r}")
        vec = VecNormalize.load(str(path), vec)
        vec.training = False
        vec.norm_reward = False
    elif normalize:
        vec = VecNormalize(vec, **({} if normalize is True else dict(normalize)))
    return vec
