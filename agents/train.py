"""Train a filter tuner with Stable-Baselines3 on a native vector env.

``pednav train ENV_ID --algo ppo|sac [--timesteps N] [--seed S] [--n-envs K]
[--config FILE] [--run-dir DIR] [--resume] [--overwrite]``

- The env is the native vector env (one batched filter for all K lanes)
  behind the :class:`pednav_env.sb3.NativeVecEnv` adapter, wrapped in
  ``VecMonitor`` and ``VecNormalize`` (observation statistics, and reward
  scaling for the optimiser; evaluation always reports raw errors).
- Hyperparameters come from ``agents/hyperparams/<algo>.yml`` keyed by env id
  (RL-Zoo style), or from ``--config FILE``.
- Training episodes use only training seeds (:mod:`pednav_env.seeds`): run
  seed S plays lane seeds ``training_seed(S) + i``; a resumed run moves on to
  the next ``n_envs`` seeds of its block, so it does not replay its first
  episodes.
- The run directory gets ``model.zip``, ``vecnormalize.pkl``, ``meta.json``,
  ``checkpoints/`` (model and statistics every ``checkpoint_steps``) and
  ``tb/`` (TensorBoard logs); ``--resume`` continues from the newest
  checkpoint.
- A run directory that already holds a run, and with ``--seeds`` a parent holding
  ``<algo>_seed<S>`` directories of seeds not in the list, would mix the earlier run's
  files into the new one (:mod:`agents.run_dirs`): ``pednav train`` refuses them unless
  ``--overwrite`` (which removes them first); ``--resume`` keeps the runs it continues,
  after :func:`check_resumable` found a checkpoint in each.
- :func:`train_seeds` trains one run per seed (``pednav train --seeds``), in
  this process or as parallel tasks of a backend (:mod:`agents.backends`).
"""

from __future__ import annotations

import json
import re
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import yaml

import pednav_env  # noqa: F401  (registers the environments)
from agents.backends import one_torch_thread
from agents.policies import FAMILY_ENVS
from agents.run_dirs import check_seeds
from pednav_env.envs.foot_filters import LEARNED_FAMILY
from pednav_env.files import writing
from pednav_env.sb3 import NativeVecEnv
from pednav_env.seeds import training_seed

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
    try:
        table = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None)
        line = f" at line {where.line + 1}" if where is not None else ""
        raise ValueError(f"config file {str(path)!r}: not valid YAML{line}") from None
    if not isinstance(table, dict):
        raise ValueError(f"config file {str(path)!r}: expected a mapping ENV_ID: {{...}}")
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


def check_resumable(run_dirs: Sequence[str | Path]) -> None:
    """ValueError unless each of ``run_dirs`` holds a checkpoint for ``--resume``."""
    for run_dir in run_dirs:
        if _latest_checkpoint(Path(run_dir)) is None:
            raise ValueError(f"--resume: no checkpoint in {Path(run_dir) / 'checkpoints'}")


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
    filter_family: str | None = None,
) -> Path:
    """Train and save; returns the run directory. ``filter_family``: the foot envs'
    filter family (default :data:`~pednav_env.envs.foot_filters.LEARNED_FAMILY`),
    kept in meta.json as ``"filter"``."""
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
    env_kwargs = dict(hp.get("env_kwargs", {}))
    family = None
    if env_id in FAMILY_ENVS:
        family = filter_family or env_kwargs.get("filter") or LEARNED_FAMILY
        env_kwargs["filter"] = family
    checkpoint_steps = int(hp.get("checkpoint_steps", 50_000))
    algo_kwargs = {k: v for k, v in hp.items() if k not in RUN_KEYS}
    policy = algo_kwargs.pop("policy", "MlpPolicy")
    run_dir = Path(run_dir or default_run_dir(env_id, algo, seed))
    run_dir.mkdir(parents=True, exist_ok=True)
    if resume:
        check_resumable([run_dir])
    latest = _latest_checkpoint(run_dir) if resume else None
    meta_file = run_dir / "meta.json"
    earlier = json.loads(meta_file.read_text()) if latest and meta_file.exists() else {}
    resumes = int(earlier.get("resumes", 0)) + 1 if latest is not None else 0

    venv = gym.make_vec(
        env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **env_kwargs
    )
    # The adapter reads SB3's seed (also the one PPO(seed=...) passes) as a run seed.
    vec = NativeVecEnv(venv, split="training", lane_offset=resumes * n_envs)
    lane_seeds = vec.seed(seed)
    vec = VecMonitor(vec)
    cls = {"ppo": PPO, "sac": SAC}[algo]
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
    # checkpoints/ and tb/ are written during learn: a failed write there names the run dir
    with one_torch_thread(), writing(run_dir):  # the same weights in any process
        model.learn(
            max(remaining, 0),
            callback=callback,
            progress_bar=progress_bar,
            reset_num_timesteps=latest is None,
            tb_log_name=algo,
        )
    seconds = time.perf_counter() - start
    with writing(run_dir / "model.zip"):
        model.save(run_dir / "model.zip")
    with writing(run_dir / "vecnormalize.pkl"):
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
        "lane_seeds": [*earlier.get("lane_seeds", []), [lane_seeds[0], lane_seeds[-1]]],
        "resumes": resumes,
        "command": " ".join(sys.argv),
    }
    if family is not None:
        meta["filter"] = family
    with writing(meta_file):
        meta_file.write_text(json.dumps(meta, indent=2, default=str))
    vec.close()
    return run_dir


def default_run_dir(env_id: str, algo: str, seed: int, parent: str | Path | None = None) -> Path:
    """``runs/<env name>/<algo>_seed<seed>`` (or under ``parent``)."""
    base = Path(parent) if parent is not None else Path("runs") / env_id.split("/")[-1]
    return base / f"{algo}_seed{seed}"


@dataclass(frozen=True)
class TrainJob:
    """One training run of :func:`train_seeds` (the arguments of :func:`train`)."""

    env_id: str
    algo: str
    seed: int
    run_dir: Path
    timesteps: int | None = None
    n_envs: int | None = None
    config_file: str | None = None
    resume: bool = False
    progress_bar: bool = False
    hyperparams: dict[str, Any] = field(default_factory=dict)
    filter_family: str | None = None


def run_job(job: TrainJob) -> Path:
    """Train ``job``; returns its run directory."""
    return train(
        job.env_id,
        job.algo,
        job.timesteps,
        job.seed,
        job.n_envs,
        job.config_file,
        job.run_dir,
        job.resume,
        progress_bar=job.progress_bar,
        hyperparams=job.hyperparams,
        filter_family=job.filter_family,
    )


def train_seeds(
    env_id: str,
    algo: str,
    seeds: Sequence[int],
    parent_dir: str | Path | None = None,
    backend: Any = None,
    on_run: Callable[[int], None] | None = None,
    **train_kwargs: Any,
) -> list[Path]:
    """One run per seed, in ``parent_dir/<algo>_seed<S>`` (default
    ``runs/<env name>/``); ``backend`` None runs them in turn, else as its parallel
    tasks. Each run is the same as ``train(env_id, algo, seed=S, ...)`` alone.
    ``on_run(1)`` is called as each run finishes."""
    check_seeds(seeds)
    jobs = [
        TrainJob(env_id, algo, s, default_run_dir(env_id, algo, s, parent_dir), **train_kwargs)
        for s in seeds
    ]
    if backend is None:
        out = []
        for job in jobs:
            out.append(run_job(job))
            if on_run is not None:
                on_run(1)
        return out
    return list(backend.map(run_job, jobs, on_done=lambda i: on_run and on_run(1)))
