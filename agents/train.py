"""Train a filter tuner with Stable-Baselines3 on a native vector env.

``pednav train ENV_ID --algo ppo|sac [--timesteps N] [--seed S] [--n-envs K]
[--config FILE] [--run-dir DIR] [--resume]``

- The env is the native vector env (one batched filter for all K lanes)
  behind the thin :class:`agents.sb3_vec.NativeVecEnv` adapter, wrapped in
  ``VecMonitor`` and ``VecNormalize`` (observation statistics, and reward
  scaling for the optimiser; evaluation always reports raw errors).
- Hyperparameters come from ``agents/hyperparams/<algo>.yml`` keyed by env id
  (RL-Zoo style), or from ``--config FILE``.
- Training episodes use only training seeds (:mod:`baselines.seeds`).
- The run directory gets ``model.zip``, ``vecnormalize.pkl``, ``meta.json``,
  ``checkpoints/`` (model and statistics every ``checkpoint_steps``) and
  ``tb/`` (TensorBoard logs); ``--resume`` continues from the newest
  checkpoint.
"""

from __future__ import annotations

import json
import re
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import yaml

import pednav_env  # noqa: F401  (registers the environments)
from agents.sb3_vec import NativeVecEnv
from baselines.seeds import training_seed

HYPERPARAMS_DIR = Path(__file__).parent / "hyperparams"
ALGOS = ("ppo", "sac")
RUN_KEYS = ("n_envs", "n_timesteps", "normalize", "env_kwargs", "checkpoint_steps")


def load_hyperparams(algo: str, env_id: str, config_file: str | Path | None = None) -> dict:
    """The hyperparameter block of ``env_id`` for ``algo``."""
    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {ALGOS}, got {algo!r}")
    path = Path(config_file) if config_file else HYPERPARAMS_DIR / f"{algo}.yml"
    if not path.exists():
        raise ValueError(f"config file {str(path)!r} does not exist")
    table = yaml.safe_load(path.read_text()) or {}
    if env_id not in table:
        raise ValueError(f"{path} has no hyperparameters for {env_id!r}; it has {sorted(table)}")
    return dict(table[env_id])


def _latest_checkpoint(run_dir: Path) -> tuple[Path, Path] | None:
    ckpts = sorted(
        (run_dir / "checkpoints").glob("model_*_steps.zip"),
        key=lambda p: int(re.findall(r"_(\d+)_steps", p.name)[0]),
    )
    if not ckpts:
        return None
    steps = re.findall(r"_(\d+)_steps", ckpts[-1].name)[0]
    return ckpts[-1], run_dir / "checkpoints" / f"model_vecnormalize_{steps}_steps.pkl"


def train(
    env_id: str,
    algo: str = "ppo",
    timesteps: int | None = None,
    seed: int = 0,
    n_envs: int | None = None,
    config_file: str | Path | None = None,
    run_dir: str | Path | None = None,
    resume: bool = False,
    progress_bar: bool = True,
    hyperparams: dict[str, Any] | None = None,
) -> Path:
    """Train and save; returns the run directory."""
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import CheckpointCallback
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    hp = load_hyperparams(algo, env_id, config_file)
    hp.update(hyperparams or {})
    timesteps = int(timesteps or hp.get("n_timesteps", 100_000))
    n_envs = int(n_envs or hp.get("n_envs", 8))
    if timesteps < 1 or n_envs < 1:
        raise ValueError(f"timesteps and n_envs must be ≥ 1, got {timesteps}, {n_envs}")
    normalize = hp.get("normalize", {"norm_obs": True, "norm_reward": True})
    env_kwargs = hp.get("env_kwargs", {})
    checkpoint_steps = int(hp.get("checkpoint_steps", 50_000))
    algo_kwargs = {k: v for k, v in hp.items() if k not in RUN_KEYS}
    policy = algo_kwargs.pop("policy", "MlpPolicy")
    run_dir = Path(run_dir or f"runs/{env_id.split('/')[-1]}/{algo}_seed{seed}")
    run_dir.mkdir(parents=True, exist_ok=True)

    venv = gym.make_vec(
        env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **env_kwargs
    )
    vec = NativeVecEnv(venv)
    vec.seed(training_seed(seed))
    vec = VecMonitor(vec)
    cls = {"ppo": PPO, "sac": SAC}[algo]
    latest = _latest_checkpoint(run_dir) if resume else None
    if resume and latest is None:
        raise ValueError(f"--resume: no checkpoint in {run_dir / 'checkpoints'}")
    if latest is not None:
        vec = VecNormalize.load(str(latest[1]), vec)
        model = cls.load(latest[0], env=vec, device="cpu", tensorboard_log=str(run_dir / "tb"))
    else:
        vec = VecNormalize(vec, **normalize)
        model = cls(
            policy,
            vec,
            seed=seed,
            device="cpu",
            verbose=0,
            tensorboard_log=str(run_dir / "tb"),
            **algo_kwargs,
        )
    callback = CheckpointCallback(
        save_freq=max(1, checkpoint_steps // n_envs),
        save_path=str(run_dir / "checkpoints"),
        name_prefix="model",
        save_vecnormalize=True,
    )
    remaining = timesteps - (model.num_timesteps if latest is not None else 0)
    start = time.perf_counter()
    model.learn(
        max(remaining, 0),
        callback=callback,
        progress_bar=progress_bar,
        reset_num_timesteps=latest is None,
        tb_log_name=algo,
    )
    seconds = time.perf_counter() - start
    model.save(run_dir / "model.zip")
    vec.save(str(run_dir / "vecnormalize.pkl"))
    meta = {
        "env_id": env_id,
        "algo": algo,
        "seed": seed,
        "timesteps": int(model.num_timesteps),
        "n_envs": n_envs,
        "train_seconds": round(seconds, 1),
        "hyperparams": hp,
        "training_seeds_from": training_seed(seed),
        "command": " ".join(sys.argv),
    }
    (run_dir / "meta.json").write_text(json.dumps(meta, indent=2, default=str))
    vec.close()
    return run_dir
