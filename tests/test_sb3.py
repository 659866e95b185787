"""pednav_env.sb3: the public SB3 adapter, its seed split and make_vec_env."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3 import PPO

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.gait.foot_route import RouteRandomization
from pednav_env.sb3 import NativeVecEnv, make_vec_env
from pednav_env.seeds import LANES_PER_RUN, TRAIN_SEED_BASE, training_seed

ENV_ID = "pednav/FootZupt-v0"
SHORT = FootZuptConfig(route=RouteRandomization(duration_s=(10.0, 14.0)))


def first_obs(seed: int) -> np.ndarray:
    """Independent path: the scalar env's first observation for ``seed``."""
    return gym.make(ENV_ID, config=SHORT).reset(seed=seed)[0]


def test_ppo_seed_zero_plays_training_seeds_not_evaluation_seeds():
    """SB3's PPO(seed=0) calls env.seed(0); the adapter maps it to run seed 0's lanes."""
    vec = make_vec_env(ENV_ID, n_envs=2, seed=7, config=SHORT)
    PPO("MlpPolicy", vec, seed=0, n_steps=8, batch_size=8, device="cpu")
    obs = vec.reset()
    for lane in range(2):
        np.testing.assert_array_equal(obs[lane], first_obs(training_seed(0) + lane))
        assert not np.array_equal(obs[lane], first_obs(lane))  # evaluation seed `lane`
    vec.close()


def test_make_vec_env_seeds_normalizes_and_loads_frozen_statistics(tmp_path):
    vec = make_vec_env(ENV_ID, n_envs=3, seed=4, normalize=True, config=SHORT)
    raw = vec.venv.reset()  # VecNormalize -> VecMonitor -> NativeVecEnv
    for lane in range(3):
        np.testing.assert_array_equal(raw[lane], first_obs(training_seed(4) + lane))
    vec.reset()
    for _ in range(5):
        vec.step(np.zeros((3, 4), np.float32))
    vec.save(str(tmp_path / "vecnormalize.pkl"))
    ev = make_vec_env(
        ENV_ID,
        n_envs=2,
        evaluation_seed=5000,
        normalize_stats=tmp_path / "vecnormalize.pkl",
        config=SHORT,
    )
    assert ev.training is False and ev.norm_reward is False
    np.testing.assert_allclose(ev.obs_rms.mean, vec.obs_rms.mean)
    obs = ev.reset()
    np.testing.assert_allclose(obs[1], ev.normalize_obs(first_obs(5001)[None])[0], rtol=1e-6)
    with pytest.raises(ValueError, match="no such file"):
        make_vec_env(ENV_ID, 1, normalize_stats=tmp_path / "nope.pkl")
    with pytest.raises(ValueError, match="not both"):
        make_vec_env(ENV_ID, 1, normalize=True, normalize_stats=tmp_path / "vecnormalize.pkl")


def test_seed_split_is_enforced_by_the_adapter():
    venv = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", config=SHORT)
    with pytest.raises(ValueError, match="reserved for training"):
        NativeVecEnv(venv, split="evaluation").seed(TRAIN_SEED_BASE - 1)
    with pytest.raises(ValueError, match="explicit seed"):
        NativeVecEnv(venv, split="evaluation").reset()
    with pytest.raises(ValueError, match=r"\[0, 10000\)"):
        NativeVecEnv(venv).seed(10_000)
    assert NativeVecEnv(venv, lane_offset=6).seed(2) == [training_seed(2) + 6, training_seed(2) + 7]
    with pytest.raises(ValueError, match="seed block"):
        NativeVecEnv(venv, lane_offset=LANES_PER_RUN - 1)
    unseeded = NativeVecEnv(venv)  # draws a random training run seed at its first reset
    assert unseeded.reset().shape == (2, 20)
    first = unseeded.lane_seeds[0]
    assert unseeded.lane_seeds == [first, first + 1] and first >= TRAIN_SEED_BASE
    with pytest.raises(ValueError, match="split"):
        NativeVecEnv(venv, split="test")
