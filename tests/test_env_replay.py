"""``pednav/FootZuptReplay-v0`` on the shipped PyShoe excerpt: the env checkers,
the FootZupt spaces, determinism, scalar-vector equivalence, pickling, and the
policy-driven `pednav run` path replaying the same filter."""

from __future__ import annotations

import pickle
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.envs.foot_replay_core import FootReplayConfig, FootReplayCore
from pednav_env.io import load_recording

ENV_ID = "pednav/FootZuptReplay-v0"
DATA = Path(__file__).parent / "data" / "replay"


def rollout(env, seed, action=None):
    obs, info = env.reset(seed=seed)
    out, rewards = [obs], []
    while True:
        a = np.zeros(env.action_space.shape, np.float32) if action is None else action
        obs, r, term, trunc, info = env.step(a)
        out.append(obs)
        rewards.append(r)
        if term or trunc:
            return np.array(out), np.array(rewards), info


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID, data_dir=str(DATA))
    yield e
    e.close()


def test_checkers_pass_without_warnings(env):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(env.unwrapped)
        sb3_check_env(env, warn=True)


def test_same_spaces_as_the_simulated_env(env):
    sim = gym.make("pednav/FootZupt-v0")
    assert env.action_space == sim.action_space
    assert env.observation_space == sim.observation_space


def test_episode_is_the_trial_and_the_return_is_minus_the_mean_error(env):
    _, rewards, info = rollout(env, 0)
    assert info["trial"] == "pyshoe_2017-11-22-11-48-35_first7s"
    assert info["imu_grade"] == "recorded"
    assert len(rewards) == 12  # (1400 − alignment) samples / 100 per step
    assert np.all(rewards <= 0) and -rewards.sum() < 1.0
    assert info["distance"] > 3.0
    a = rollout(env, 5)
    b = rollout(env, 5)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def test_vector_lanes_equal_scalar_envs(env):
    venv = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", data_dir=DATA)
    venv.reset(seed=3)
    single = [rollout(env, 3 + i) for i in range(2)]
    lane_rewards = [[], []]
    for _ in range(len(single[0][1])):
        _, r, term, trunc, info = venv.step(np.zeros((2, 4), np.float32))
        for i in range(2):
            lane_rewards[i].append(r[i])
    assert np.all(term | trunc)
    for i in range(2):
        np.testing.assert_array_equal(np.array(lane_rewards[i]), single[i][1])
        np.testing.assert_array_equal(info["final_obs"][i], single[i][0][-1])
    venv.close()


def test_pickle_and_bad_arguments(env):
    clone = pickle.loads(pickle.dumps(env.unwrapped))
    a, _ = env.reset(seed=1)
    b, _ = clone.reset(seed=1)
    np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="data_dir is required"):
        gym.make(ENV_ID)
    with pytest.raises(ValueError, match="not a directory"):
        gym.make(ENV_ID, data_dir=str(DATA / "nope"))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3, np.float32))


def test_policy_schedule_replays_the_core_exactly():
    """`pednav run` with a policy: the knob schedule recorded in the replay core,
    replayed by the runner, gives the core's own estimate at every interval end."""
    rec = load_recording(DATA / "pyshoe_2017-11-22-11-48-35_first7s.mat")
    core = FootReplayCore(FootReplayConfig(), 1, "test", recordings=[rec])
    core.reset_lanes(np.array([0]), [np.random.default_rng(0)])
    rng = np.random.default_rng(1)
    from pednav_env.replay.runner import run_prepared

    ends, knobs = [], {}
    while core.cursor[0] < core.length[0]:
        _, _, _, _, info = core.step(rng.uniform(-1, 1, (1, 4)))
        ends.append((int(core.cursor[0]), info["pos_est"][0].copy()))
        for k, v in core.knob_values().items():
            knobs.setdefault(k, []).append(v.copy())
    run = run_prepared(core._trial(0).prepared, schedule={k: np.array(v) for k, v in knobs.items()})
    for cursor, pos in ends:
        np.testing.assert_allclose(run.pos[0, cursor - 1], pos, atol=1e-12)
