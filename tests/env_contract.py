"""Checks every native environment must pass (used by tests/test_env_*.py)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np


def rollout(env, seed, actions=None, max_steps=10_000):
    """One episode from ``reset(seed)``: observations, rewards and the last info."""
    obs, _ = env.reset(seed=seed)
    out = [obs]
    rewards = []
    for t in range(max_steps):
        a = np.zeros(env.action_space.shape, np.float32) if actions is None else actions(t)
        obs, r, term, trunc, info = env.step(a)
        out.append(obs)
        rewards.append(r)
        if term or trunc:
            break
    return np.array(out), np.array(rewards), info


def assert_same_seed_same_episode(env) -> None:
    """Same seed ⇒ the same episode; another seed ⇒ another one."""
    a = rollout(env, 3)
    b = rollout(env, 3)
    c = rollout(env, 4)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert a[0].shape != c[0].shape or not np.array_equal(a[0], c[0])


def assert_lanes_equal_scalar_envs(
    env_id: str,
    env_kwargs: dict,
    n: int = 3,
    seed: int = 20,
    action_bound: float = 1.0,
    info_keys: tuple[str, ...] = (),
) -> None:
    """Lane i of a vector env reset with ``seed`` plays, bit for bit, the episodes
    of a scalar env reset with ``seed + i`` (two episodes per lane: autoreset)."""
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **env_kwargs)
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    k = venv.single_action_space.shape[0]
    obs, _ = venv.reset(seed=seed)
    lane_obs = [[obs[i]] for i in range(n)]
    lane_rew = [[] for _ in range(n)]
    lane_info = [{key: [] for key in info_keys} for _ in range(n)]
    episodes_done = np.zeros(n, dtype=int)
    rng = np.random.default_rng(0)
    actions = []
    while episodes_done.min() < 2:
        a = rng.uniform(-action_bound, action_bound, (n, k)).astype(np.float32)
        actions.append(a)
        obs, r, term, trunc, info = venv.step(a)
        for i in range(n):
            lane_rew[i].append(r[i])
            for key in info_keys:
                lane_info[i][key].append(info[key][i])
            if term[i] or trunc[i]:
                lane_obs[i].append(info["final_obs"][i])
                episodes_done[i] += 1
            lane_obs[i].append(obs[i])
    for i in range(n):
        env = gym.make(env_id, **env_kwargs).unwrapped
        obs_s, _ = env.reset(seed=seed + i)
        got_obs, got_rew = [obs_s], []
        got_info = {key: [] for key in info_keys}
        for a in actions:
            o, r, term, trunc, info = env.step(a[i])
            got_obs.append(o)
            got_rew.append(r)
            for key in info_keys:
                got_info[key].append(info[key])
            if term or trunc:
                o, _ = env.reset()  # next episode from the same generator
                got_obs.append(o)
        np.testing.assert_array_equal(np.array(got_obs), np.array(lane_obs[i]))
        np.testing.assert_array_equal(np.array(got_rew), np.array(lane_rew[i]))
        for key in info_keys:
            np.testing.assert_array_equal(np.array(got_info[key]), np.array(lane_info[i][key]))


def assert_ppo_trains_for_2000_steps(env, action_dim: int) -> None:
    """SB3 PPO learns for 2 000 steps on ``env`` and predicts actions of ``action_dim``."""
    from stable_baselines3 import PPO

    model = PPO(
        "MlpPolicy",
        env,
        n_steps=256,
        batch_size=64,
        n_epochs=2,
        seed=0,
        policy_kwargs={"net_arch": [32, 32]},
        device="cpu",
    )
    model.learn(2000)
    assert model.num_timesteps >= 2000
    action, _ = model.predict(env.reset(seed=1)[0], deterministic=True)
    assert action.shape == (action_dim,)
