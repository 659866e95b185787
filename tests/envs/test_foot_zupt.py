"""``pednav/FootZupt-v0``: the return against an independent run of the engine, the
held-error tail after termination, clipped actions, the minimum-stance knob, the paper
scenario and configuration errors (the contract every env keeps is in
tests/envs/test_env_contract.py)."""

import warnings
from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest
from env_rollout import rollout

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.envs.foot_core import FootZuptConfig, generate_episode
from pednav_env.gait.foot_route import RouteRandomization
from pednav_env.nav.zupt_ukf import ZuptUkf

ENV_ID = "pednav/FootZupt-v0"
SHORT = FootZuptConfig(route=RouteRandomization(duration_s=(12.0, 20.0)))


def test_return_is_minus_the_time_averaged_error():
    """Independent bookkeeping: run the engine over the episode's IMU record and
    average its horizontal error at the ends of the decision intervals."""
    env = gym.make(ENV_ID, scenario="paper").unwrapped
    _, rewards, info = rollout(env, 0)
    core = env.core
    t = int(core.length[0])
    engine = ZuptUkf(core.config.filter, core.config.rate_hz, 1)
    # the same blocks as the env's decision intervals (identical rounding)
    run = engine.run(core.omega[:, :t], core.f[:, :t], block_samples=core.k)
    k0, k = run.start_sample, core.k
    ends = list(range(k0 + k, t, k)) + [t]
    weights = np.diff([k0, *ends]) / (t - k0)
    err = np.linalg.norm(run.x[0, ends, :2] - core.pos[0, ends, :2], axis=1)
    assert rewards.sum() == pytest.approx(-(weights * err).sum(), rel=1e-9)
    assert info["error"] == pytest.approx(err[-1], rel=1e-9)
    assert info["distance"] > 19.0  # the 5 m square


def test_out_of_range_actions_are_clipped_and_counted():
    env = gym.make(ENV_ID, config=SHORT).unwrapped
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([3.0, -2.0, 0.0, 1.0]))
    assert info["clipped_actions"] == 1
    assert info["knobs"]["omega_max"] == pytest.approx(0.22 * 10.0)
    assert info["knobs"]["delta_f_max"] == pytest.approx(0.33 / 10.0)
    _, _, _, _, info = env.step(np.zeros(4))
    assert info["clipped_actions"] == 1


def test_fuzz_with_the_minimum_stance_knob_over_whole_episodes():
    """The fifth knob (minimum stance, ``tune_min_stance=True``) at random and extreme
    values; tests/envs/test_env_contract.py fuzzes the four default knobs."""
    env = gym.make(ENV_ID, config=SHORT, tune_min_stance=True).unwrapped
    rng = np.random.default_rng(99)
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * 5)).reshape(5, -1).T
    policies = [
        lambda t: rng.uniform(-1, 1, 5),
        lambda t: rng.choice([-1e6, -1.0, 1.0, 1e6], 5),
        lambda t: corners[t % len(corners)],
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        for seed, policy in enumerate(policies):
            obs, rewards, _info = rollout(env, seed, policy)
            assert np.all(np.isfinite(obs)) and np.all(np.isfinite(rewards))
            assert env.observation_space.contains(obs[-1])
            assert np.all(rewards <= 0)


def test_paper_scenario_and_action_zero_is_the_paper_filter():
    env = gym.make(ENV_ID, scenario="paper").unwrapped
    obs, info = env.reset(seed=1)
    assert info["imu_grade"] == "paper003"
    assert info["knobs"] == {
        "omega_max": 0.22,
        "delta_f_max": 0.33,
        "process_noise_scale": 1.0,
        "zupt_noise_scale": 1.0,
    }
    assert env.core.engine.config.calibrate_gyro_bias is False
    assert obs.shape == (20,)


def test_bad_configuration_raises():
    with pytest.raises(ValueError, match="imu_grades"):
        FootZuptConfig(imu_grades=("nope",), imu_grade_weights=(1.0,))


def test_termination_holds_the_final_error_for_the_rest_of_the_walk():
    """A tight divergence bound (0.3 m, no distance term) ends the episode early:
    ``terminated`` (not truncated), the errors up to then are those of the
    uncapped run, and the return is minus the time-averaged error with the last
    error held for the walk's remaining samples. The walk length comes from the
    episode generator, the error series from the per-step info."""
    capped = replace(SHORT, divergence_error_m=0.3, divergence_error_fraction=0.0)
    seed = 4
    steps = {}
    for name, config in (("full", SHORT), ("capped", capped)):
        env = gym.make(ENV_ID, config=config)
        env.reset(seed=seed)
        errors, rewards = [], []
        while True:
            _, r, term, trunc, info = env.step(np.zeros(4, np.float32))
            errors.append(info["error"])
            rewards.append(r)
            if term or trunc:
                break
        steps[name] = (np.array(errors), np.array(rewards), term, trunc)
    walk = generate_episode(SHORT, gym.utils.seeding.np_random(seed)[0])
    nav = walk.omega_b.shape[0] - round(SHORT.filter.alignment_s * SHORT.rate_hz)
    k = round(SHORT.decision_interval_s * SHORT.rate_hz)
    full_err, _, full_term, full_trunc = steps["full"]
    assert full_trunc and not full_term and len(full_err) == -(-nav // k)
    err, rew, term, trunc = steps["capped"]
    m = len(err)
    assert term and not trunc and 2 <= m < len(full_err)
    assert err[-1] > 0.3 and np.all(err[:-1] <= 0.3)
    np.testing.assert_array_equal(err, full_err[:m])  # the bound only ends the episode
    held = np.concatenate((np.repeat(err[:-1], k), np.full(nav - (m - 1) * k, err[-1])))
    assert rew.sum() == pytest.approx(-held.mean(), rel=1e-12)  # float sums: ~1e-15
