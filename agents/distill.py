"""Teacher–student distillation (DAgger) of the privileged oracle into a sensor-only tuner.

The teacher is :class:`baselines.oracle.OraclePolicy`: the constant tuned for
the episode's true context. The student sees only the observation (without
the action in force), with the episode-history features of
:mod:`agents.features` (running mean and RMS of each entry), from which it must
recognise the context. It is the actor of an SB3 PPO ``MlpPolicy``, fitted
by regression of its mean action on the teacher's action (mean squared
error), along the student's own rollouts (DAgger, Ross, Gordon & Bagnell 2011):

1. iteration 0 plays the teacher on every lane; iteration i plays, at each
   decision step and lane, the teacher with probability ``beta ** i`` and the
   student otherwise, and labels every visited state with the teacher's action;
2. the states of all iterations are aggregated and the student refitted on all
   of them (``epochs`` passes of Adam, minibatch ``batch_size``).

Episodes are training episodes: run seed ``seed`` plays lane seeds
``training_seed(seed) + lane`` (:mod:`pednav_env.seeds`), each lane continuing
its generator. The run directory is a normal SB3 run (``model.zip``,
``vecnormalize.pkl`` with the feature statistics, ``meta.json`` saying
``"features": "history"``), so ``pednav evaluate --policy RUN_DIR`` and
``pretrained`` load it like a PPO run.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import pednav_env  # noqa: F401  (registers the environments)
from agents.backends import one_torch_thread
from agents.features import HISTORY, HistoryFeatures, feature_dim
from baselines.oracle import OraclePolicy
from pednav_env.files import writing
from pednav_env.sb3 import NativeVecEnv


class _Spaces(gym.Env):
    """An env that is only its spaces: what SB3 needs to build and save a model."""

    def __init__(self, observation_space: gym.spaces.Box, action_space: gym.spaces.Box) -> None:
        self.observation_space = observation_space
        self.action_space = action_space


def _student(obs_dim: int, action_space: gym.spaces.Box, seed: int, net_arch: list[int]) -> Any:
    """A PPO model over the feature vector and the frozen normaliser beside it."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    box = gym.spaces.Box(-np.inf, np.inf, (obs_dim,), np.float32)
    vec = VecNormalize(
        DummyVecEnv([lambda: _Spaces(box, action_space)]), norm_obs=True, norm_reward=False
    )
    vec.training = False
    model = PPO(
        "MlpPolicy",
        vec,
        seed=seed,
        device="cpu",
        policy_kwargs={"net_arch": {"pi": net_arch, "vf": net_arch}, "log_std_init": -2.0},
    )
    return model, vec


def _normalize(x: np.ndarray, norm: Any) -> np.ndarray:
    """``x`` as the frozen normaliser hands it to the network (the same formula as
    :class:`agents.policies.NormalizedModelPolicy`)."""
    z = (x - norm.obs_rms.mean) / np.sqrt(norm.obs_rms.var + norm.epsilon)
    return np.clip(z, -norm.clip_obs, norm.clip_obs).astype(np.float32)


def _actor_mean(policy: Any, x: Any) -> Any:
    """The PPO actor's mean action for (normalised) inputs ``x``."""
    latent = policy.mlp_extractor.forward_actor(policy.extract_features(x))
    return policy.action_net(latent)


def _fit(model: Any, x: np.ndarray, y: np.ndarray, epochs: int, batch_size: int, rng) -> float:
    """Regress the actor mean on ``y``; returns the last epoch's mean loss."""
    import torch

    policy = model.policy
    params = list(policy.mlp_extractor.policy_net.parameters()) + list(
        policy.action_net.parameters()
    )
    opt = torch.optim.Adam(params, lr=1e-3)
    xt = torch.as_tensor(x, dtype=torch.float32)
    yt = torch.as_tensor(y, dtype=torch.float32)
    loss_sum = 0.0
    for _ in range(epochs):
        order = torch.as_tensor(rng.permutation(len(x)))
        loss_sum, batches = 0.0, 0
        for start in range(0, len(x), batch_size):
            idx = order[start : start + batch_size]
            loss = torch.mean((_actor_mean(policy, xt[idx]) - yt[idx]) ** 2)
            opt.zero_grad()
            loss.backward()
            opt.step()
            loss_sum += float(loss.detach())
            batches += 1
        loss_sum /= max(batches, 1)
    return loss_sum


def distill(*args: Any, **kwargs: Any) -> Path:
    """:func:`run_distillation` with PyTorch on one thread (deterministic for a seed,
    whatever the core count; :func:`agents.backends.one_torch_thread`)."""
    with one_torch_thread():
        return run_distillation(*args, **kwargs)


def run_distillation(
    env_id: str,
    run_dir: str | Path,
    seed: int = 0,
    lanes: int = 64,
    iterations: int = 6,
    steps_per_iteration: int = 400,
    beta: float = 0.5,
    epochs: int = 3,
    batch_size: int = 1024,
    net_arch: tuple[int, ...] = (64, 64),
    teacher: OraclePolicy | None = None,
    env_kwargs: dict[str, Any] | None = None,
    on_iteration: Callable[[int, float], None] | None = None,
    filter_family: str | None = None,
) -> Path:
    """Train a student by DAgger from ``teacher`` (the shipped oracle by default);
    write the run directory and return it. ``on_iteration(i, loss)`` after each fit.
    ``filter_family`` (foot envs): the family the episodes run (the env's ``filter``
    argument), whose oracle table teaches and which ``meta.json`` records."""
    import torch

    for name, value in (
        ("lanes", lanes),
        ("iterations", iterations),
        ("steps_per_iteration", steps_per_iteration),
        ("epochs", epochs),
        ("batch_size", batch_size),
    ):
        if not (isinstance(value, int) and value >= 1):
            raise ValueError(f"{name} must be an integer ≥ 1, got {value!r}")
    if not 0.0 <= beta <= 1.0:
        raise ValueError(f"beta must lie in [0, 1], got {beta!r}")
    start_time = time.perf_counter()
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    env_kwargs = dict(env_kwargs or {})
    if filter_family is not None:
        env_kwargs["filter"] = filter_family
    venv = gym.make_vec(
        env_id, num_envs=lanes, vectorization_mode="vector_entry_point", **env_kwargs
    )
    vec = NativeVecEnv(venv, split="training")
    vec.seed(seed)
    space = vec.action_space
    if teacher is None:
        teacher = OraclePolicy.for_env(env_id, space, filter_family)
    obs_dim = int(vec.observation_space.shape[0])
    action_dim = int(space.shape[0])
    model, norm = _student(feature_dim(obs_dim, HISTORY, action_dim), space, seed, list(net_arch))
    history = HistoryFeatures(action_dim)
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    obs = vec.reset()
    starts = np.ones(lanes, dtype=bool)
    episodes = 0
    losses = []
    for it in range(iterations):
        p_teacher = beta**it
        for _ in range(steps_per_iteration):
            x = history(obs, starts)
            target, _ = teacher.predict(obs, context=vec.context)
            act = target
            if p_teacher < 1.0:
                z = _normalize(x, norm)
                with torch.no_grad():
                    own = _actor_mean(model.policy, torch.as_tensor(z, dtype=torch.float32))
                own = np.clip(own.numpy(), space.low, space.high)
                use_teacher = rng.random(lanes) < p_teacher
                act = np.where(use_teacher[:, None], target, own)
            xs.append(x)
            ys.append(target)
            obs, _, dones, _ = vec.step(act)
            starts = dones
            episodes += int(dones.sum())
        x_all = np.concatenate(xs)
        y_all = np.concatenate(ys)
        norm.obs_rms.mean = x_all.mean(axis=0).astype(np.float64)
        norm.obs_rms.var = x_all.var(axis=0).astype(np.float64)
        norm.obs_rms.count = float(len(x_all))
        z_all = _normalize(x_all, norm)
        losses.append(_fit(model, z_all, y_all, epochs, batch_size, rng))
        if on_iteration is not None:
            on_iteration(it, losses[-1])
    vec.close()
    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    with writing(run_dir / "model.zip"):
        model.save(run_dir / "model.zip")
    with writing(run_dir / "vecnormalize.pkl"):
        norm.save(str(run_dir / "vecnormalize.pkl"))
    meta = {
        "env_id": env_id,
        "algo": "ppo",
        "method": "dagger distillation of the privileged oracle (agents/distill.py)",
        "features": HISTORY,
        "seed": seed,
        "lanes": lanes,
        "iterations": iterations,
        "steps_per_iteration": steps_per_iteration,
        "beta": beta,
        "epochs": epochs,
        "batch_size": batch_size,
        "net_arch": list(net_arch),
        "samples": int(sum(len(x) for x in xs)),
        "episodes_finished": episodes,
        "loss_per_iteration": losses,
        "training_seconds": round(time.perf_counter() - start_time, 1),
        "env_kwargs": {k: repr(v) for k, v in env_kwargs.items()},
    }
    if filter_family is not None:
        meta["filter"] = filter_family
    with writing(run_dir / "meta.json"):
        (run_dir / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    return run_dir
