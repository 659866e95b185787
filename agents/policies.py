"""Learned policies as saved on disk: an SB3 model plus its normalisation statistics.

A run directory holds ``model.zip``, ``vecnormalize.pkl`` (observation
statistics from training) and ``meta.json`` (env, algorithm, budget,
command). :class:`NormalizedModelPolicy` applies the statistics itself, so
it has SB3's ``predict`` signature on raw observations and goes through the
same evaluation as the baselines.
"""

from __future__ import annotations

import json
import pickle
from pathlib import Path
from typing import Any

import numpy as np

#: Shipped tuners: agents/pretrained/<env name>/.
PRETRAINED_DIR = Path(__file__).parent / "pretrained"


class NormalizedModelPolicy:
    """An SB3 model with frozen observation normalisation."""

    def __init__(self, model: Any, obs_rms: Any | None, clip_obs: float, epsilon: float) -> None:
        self.model = model
        self.obs_rms = obs_rms
        self.clip_obs = clip_obs
        self.epsilon = epsilon

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        if self.obs_rms is None:
            return obs
        z = (obs - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        return np.clip(z, -self.clip_obs, self.clip_obs).astype(np.float32)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = self.normalize(np.asarray(observation, dtype=np.float32))
        return self.model.predict(
            obs, state=state, episode_start=episode_start, deterministic=deterministic
        )


def load_run(path: str | Path) -> NormalizedModelPolicy:
    """Load a run directory, or a ``model.zip`` with ``vecnormalize.pkl`` beside it."""
    from stable_baselines3 import PPO, SAC

    path = Path(path)
    model_file = path / "model.zip" if path.is_dir() else path
    if not model_file.exists():
        raise ValueError(f"policy {str(path)!r}: no such model file ({model_file})")
    meta_file = model_file.parent / "meta.json"
    algo = json.loads(meta_file.read_text()).get("algo") if meta_file.exists() else None
    classes = {"ppo": PPO, "sac": SAC}
    candidates = [classes[algo]] if algo in classes else [PPO, SAC]
    model = None
    for cls in candidates:
        try:
            model = cls.load(model_file, device="cpu")
            break
        except (ValueError, KeyError, RuntimeError, TypeError):
            continue
    if model is None:
        raise ValueError(f"policy {str(path)!r}: not a PPO or SAC model")
    stats_file = model_file.parent / "vecnormalize.pkl"
    if stats_file.exists():
        with stats_file.open("rb") as fh:
            vn = pickle.load(fh)
        return NormalizedModelPolicy(model, vn.obs_rms, vn.clip_obs, vn.epsilon)
    return NormalizedModelPolicy(model, None, 10.0, 1e-8)


def pretrained_dir(env_id: str) -> Path:
    """Directory of the shipped tuner for ``env_id`` (e.g. pednav/FootZupt-v0)."""
    return PRETRAINED_DIR / env_id.split("/")[-1]
