"""``pednav/WaistStep-v0``: the filterpy oracle, batch-size independence, divergence, the
core's subset update, the step velocity, clipped actions, the paper scenario, episode
variety and configuration errors (the contract every env keeps is in
tests/envs/test_env_contract.py)."""

import doctest

import gymnasium as gym
import numpy as np
import pytest
from env_rollout import rollout

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.envs import waist_step
from pednav_env.envs.waist_config import WaistRandomization, WaistStepConfig
from pednav_env.envs.waist_episode import generate_episode
from pednav_env.nav.step_fusion_kf import StepFusionKF
from pednav_env.nav.step_velocity import (
    biomechanical_step_velocity,
    pendulum_step_velocity,
    prefix_integrals,
)
from pednav_env.testing.reference_waist import FilterpyWaistReference

ENV_ID = "pednav/WaistStep-v0"
SHORT = WaistStepConfig(randomization=WaistRandomization(duration_s=(12.0, 20.0)))
PAPER_SHORT = WaistStepConfig(scenario="paper", paper_steps=60)


def test_docstring_example_runs():
    failures, tried = doctest.testmod(waist_step, verbose=False)
    assert tried >= 5 and failures == 0


def test_wide_batch_lanes_equal_scalar_envs():
    """Batch-size independence of the batched numpy chain (24 lanes, 40 steps)."""
    n, seed = 24, 300
    venv = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", config=SHORT)
    obs, _ = venv.reset(seed=seed)
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1.2, 1.2, (40, n, 5))
    got = [obs]
    for a in actions:
        got.append(venv.step(a)[0])
    got = np.array(got)
    for i in (0, 13, 23):
        env = gym.make(ENV_ID, config=SHORT).unwrapped
        o, _ = env.reset(seed=seed + i)
        want = [o]
        for a in actions[:, i]:
            o, _, term, trunc, _ = env.step(a)
            if term or trunc:
                o, _ = env.reset()
            want.append(o)
        np.testing.assert_array_equal(np.array(want), got[:, i])


@pytest.mark.parametrize(("config", "seed"), [(PAPER_SHORT, 0), (SHORT, 1), (SHORT, 2)])
def test_return_is_minus_the_time_averaged_error_filterpy_oracle(config, seed):
    """Independent bookkeeping: a scalar re-implementation that streams the samples
    through the detector, uses the library's step-velocity function on each step's
    samples and two filterpy KalmanFilters, and averages its own error."""
    env = gym.make(ENV_ID, config=config).unwrapped
    env.reset(seed=seed)
    estimates, rewards = [], []
    while True:
        _, r, term, trunc, info = env.step(np.zeros(5))
        estimates.append(info["pos_est"])
        rewards.append(r)
        if term or trunc:
            break
    assert trunc and not term
    ref = FilterpyWaistReference(config, seed)
    while not ref.step():
        pass
    done = ref.finished
    np.testing.assert_allclose(np.array(estimates), done["estimates"], rtol=0, atol=1e-8)
    assert np.sum(rewards) == pytest.approx(-(done["weights"] * done["errors"]).sum(), rel=1e-9)
    assert done["weights"].sum() == pytest.approx(1.0)
    assert info["error"] == pytest.approx(done["errors"][-1], rel=1e-9)


def test_divergence_terminates_and_holds_the_final_error():
    cfg = WaistStepConfig(
        scenario="paper", paper_steps=60, divergence_error_m=0.05, divergence_error_fraction=0.0
    )
    env = gym.make(ENV_ID, config=cfg).unwrapped
    env.reset(seed=0)
    errors, rewards = [], []
    while True:
        _, r, term, trunc, info = env.step(np.zeros(5))
        errors.append(info["error"])
        rewards.append(r)
        if term or trunc:
            break
    assert term and not trunc and info["error"] > 0.05
    k, n = len(rewards), 60 * 50  # intervals played, samples of the walk
    weights = np.full(k, 50 / n)
    weights[-1] = 1.0 - 50 * (k - 1) / n  # the last error is held to the end of the walk
    assert np.sum(rewards) == pytest.approx(-(weights * np.array(errors)).sum(), rel=1e-12)
    assert k < 60


def test_filter_update_of_some_lanes_equals_masked_step_bit_for_bit():
    """The core updates a subset of lanes (:meth:`StepFusionKF.step_sequence`, its
    knobs as the filter's Q and R scales); the result equals the step with a mask
    on all lanes, bit for bit."""
    env = gym.make_vec(ENV_ID, num_envs=6, vectorization_mode="vector_entry_point", config=SHORT)
    env.reset(seed=7)
    rng = np.random.default_rng(5)
    for _ in range(4):
        env.step(rng.uniform(-1, 1, (6, 5)).astype(np.float32))
    core = env.unwrapped.core
    kf = core.kf
    ref = StepFusionKF(kf.config, 6, q_scale=core.knobs[:, 4], r_scale=core.knobs[:, 3] ** 2)
    ref.x, ref.P, ref.pos = kf.x.copy(), kf.P.copy(), kf.pos.copy()
    sel = np.array([1, 4, 5])
    mask = np.isin(np.arange(6), sel)
    v_ins, vb = rng.normal(1, 0.5, (6, 2)), rng.normal(1, 0.5, (6, 2))
    T = rng.uniform(0.02, 3.0, 6)
    ref.step(v_ins, vb, T, mask)
    kf.step_sequence(sel, v_ins[sel], vb[sel], T[sel])
    np.testing.assert_array_equal(kf.x[sel], ref.x[sel])
    np.testing.assert_array_equal(kf.P[sel], ref.P[sel])
    np.testing.assert_array_equal(kf.pos[sel], ref.pos[sel])
    np.testing.assert_array_equal(kf.y[sel], ref.y[sel])
    np.testing.assert_array_equal(kf.S[sel], ref.S[sel])


def test_prefix_step_velocity_equals_library_function():
    ep = generate_episode(SHORT, np.random.default_rng(3))
    dt = 1.0 / SHORT.rate_hz
    c1, c2 = prefix_integrals(ep.a_up, dt, "delta_v")
    rng = np.random.default_rng(0)
    j0 = rng.integers(0, ep.a_up.size - 400, 50)
    n = rng.integers(1, 300, 50)
    leg = np.full(50, ep.leg_length_assumed)
    v, h, clipped = pendulum_step_velocity(c1[None], c2[None], np.zeros(50, int), j0, n, leg, dt)
    for i in range(50):
        want = biomechanical_step_velocity(
            ep.a_up[j0[i] : j0[i] + n[i] + 1][None], dt, [[0, n[i]]], leg[i], rule="delta_v"
        )
        assert v[i] == pytest.approx(want.velocity[0, 0], rel=1e-9, abs=1e-9)
        assert h[i] == pytest.approx(want.hip_rise[0, 0], rel=1e-9, abs=1e-12)
        assert clipped[i] == want.clipped[0, 0]


def test_out_of_range_actions_are_clipped_and_counted():
    env = gym.make(ENV_ID, config=SHORT).unwrapped
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([3.0, -2.0, 1.0, 0.0, -1.0]))
    assert info["clipped_actions"] == 1
    knobs = info["knobs"]
    assert knobs["step_threshold"] == pytest.approx(3.0)
    assert knobs["step_hysteresis"] == 0.0
    assert knobs["min_step_duration"] == pytest.approx(0.5)
    assert knobs["bm_noise_scale"] == 1.0
    assert knobs["process_noise_scale"] == pytest.approx(0.01)
    _, _, _, _, info = env.step(np.zeros(5))
    assert info["clipped_actions"] == 1
    obs, _, _, _, info = env.step(np.full(5, 1.5))
    assert info["clipped_actions"] == 2
    np.testing.assert_array_equal(obs[-5:], np.ones(5, np.float32))


def test_paper_scenario_and_action_zero_is_the_paper_configuration():
    env = gym.make(ENV_ID, config=PAPER_SHORT).unwrapped
    obs, info = env.reset(seed=1)
    assert info["sensor_grade"] == "paper004"
    assert info["knobs"] == {
        "step_threshold": 0.0,
        "step_hysteresis": 0.0,
        "min_step_duration": 0.0,
        "bm_noise_scale": 1.0,
        "process_noise_scale": 1.0,
    }
    assert obs.shape == (25,)
    core = env.core
    assert core.leg[0] == core.leg_true[0] == 0.7
    assert core.length[0] == 60 * 50 + 1  # 60 steps of 0.5 s at 100 Hz
    _, rewards, info = rollout(env, 1)
    # Ideal accelerometer, pure zero crossing: one detection per footfall (the last
    # is the final stop), none false; steps of exactly 0.5 s, 0.7 m along 30°.
    assert core.kf.steps[0] == 60 and info["false_step_detections"] == 0
    assert info["distance"] == pytest.approx(42.0)
    assert core.step_last_s[0] == pytest.approx(0.5)
    assert rewards.size == 60


def test_random_episodes_vary():
    grades, legs, durations = set(), [], []
    for seed in range(12):
        ep = generate_episode(WaistStepConfig(), np.random.default_rng(seed))
        grades.add(ep.sensor_grade)
        legs.append(ep.leg_length)
        durations.append(ep.f_norm.size / 100.0)
        assert ep.leg_length_assumed != ep.leg_length
        assert np.all(np.isfinite(ep.f_norm)) and np.all(np.isfinite(ep.ins_pos))
    assert len(grades) >= 3
    assert np.ptp(legs) > 0.05
    assert min(durations) >= 60.0 and max(durations) <= 180.0 + 0.02


def test_bad_configuration_raises():
    with pytest.raises(ValueError, match="paper_steps"):
        gym.make(ENV_ID, scenario="paper", paper_steps=0)
    with pytest.raises(ValueError, match="sensor_grades"):
        WaistStepConfig(sensor_grades=("nope",), sensor_grade_weights=(1.0,))
    with pytest.raises(ValueError, match="sensor_grade_weights"):
        WaistStepConfig(sensor_grade_weights=(1.0,))
    with pytest.raises(ValueError, match="duration_s"):
        WaistRandomization(duration_s=(60.0, 10.0))
    with pytest.raises(ValueError, match="leg_length_m"):
        WaistRandomization(leg_length_m=(-1.0, 0.9))
    with pytest.raises(ValueError, match="stop_probability"):
        WaistRandomization(stop_probability=1.5)
    with pytest.raises(ValueError, match="slope_deg"):
        WaistRandomization(slope_deg=(2.0, 40.0))
    with pytest.raises(ValueError, match="step_jitter"):
        WaistRandomization(step_jitter=0.5)
    with pytest.raises(ValueError, match="gait_weights"):
        WaistRandomization(gait_weights=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="divergence_error_m"):
        WaistStepConfig(divergence_error_m=0.0)
