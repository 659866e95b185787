"""``pednav/MarkerTrack-v0``: the return against an independent run of the EKF, the
filterpy oracle inside the env, the UWB record, re-anchoring, clipped actions,
divergence, the paper scenario and configuration errors (the contract every env keeps
is in tests/envs/test_env_contract.py)."""

import doctest
import itertools
import math

import gymnasium as gym
import numpy as np
import pytest
from env_rollout import rollout
from gymnasium.utils import seeding

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.envs import marker_track
from pednav_env.envs.marker_config import MarkerTrackConfig, uwb_spec
from pednav_env.envs.marker_core import MarkerTrackCore
from pednav_env.envs.marker_episode import generate_episode
from pednav_env.gait.heel_knee import simulate_heel_knee
from pednav_env.nav.marker_ekf import MarkerEkfEngine
from pednav_env.nav.marker_model import MarkerEkfConfig
from pednav_env.nav.marker_run import run_marker_ekf
from pednav_env.sensors.uwb import measure_uwb
from pednav_env.testing.reference_marker import FilterpyMarkerEngine

ENV_ID = "pednav/MarkerTrack-v0"
#: Short walks with gait changes and frequent re-anchoring, for fast tests.
SHORT = MarkerTrackConfig(
    duration_s=(4.0, 8.0), gait_change_rate_hz=0.5, reanchor_after_s=2.0, reanchor_keep_s=1.0
)


def test_docstring_example_runs():
    result = doctest.testmod(marker_track, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


@pytest.mark.parametrize("action", [np.zeros(4), np.array([0.4, -0.3, 0.5, 0.2])])
def test_return_is_minus_the_time_averaged_rms_error(action):
    """Independent bookkeeping: run the library's MarkerEKF over the episode's UWB
    record (paper scenario: no re-anchoring) with the action's constant Q and R
    scales, and average its RMS marker error over the decision intervals."""
    env = gym.make(ENV_ID, scenario="paper").unwrapped
    _, rewards, info = rollout(env, 0, lambda t: action)
    core = env.core
    K, k = int(core.length[0]), core.k
    assert K == 100 and len(rewards) == 20  # 10 s at 10 Hz, 0.5 s steps
    z = core.zbuf[0, :K].reshape(1, K, 2, 2)
    valid = core.vbuf[0, :K][:, (0, 2)][None]
    scale = [1000.0 ** action[0], 1000.0 ** action[1], 1000.0 ** action[2], 100.0 ** action[3]]
    q_scale = np.array([[scale[g] for g in (0, 0, 1, 1, 0, 2)]])
    run = run_marker_ekf(core.config.filter, z, valid, q_scale, scale[3])
    sq = ((run.markers.reshape(K, 4) - core.tbuf[0, :K]) ** 2).mean(axis=1)
    ends = list(range(0, K, k)) + [K]
    rms = np.array([math.sqrt(sq[a:b].mean()) for a, b in itertools.pairwise(ends)])
    weights = np.diff(ends) / K
    assert rewards.sum() == pytest.approx(-(weights * rms).sum(), rel=1e-9)
    assert info["error"] == pytest.approx(rms[-1], rel=1e-9)
    assert info["distance"] > 25.0  # 3 m/s heel trend for 9.9 s


def test_engine_matches_filterpy_inside_the_env():
    """The same episode, features and re-anchoring with filterpy's
    ExtendedKalmanFilter as the filter (the benchmark's reference)."""
    cfg = MarkerTrackConfig(
        duration_s=(12.0, 12.0),
        uwb_conditions=("realistic",),
        uwb_condition_weights=(1.0,),
        reanchor_after_s=3.0,
        reanchor_keep_s=1.0,
    )
    native = MarkerTrackCore(cfg, 1, ENV_ID)
    oracle = MarkerTrackCore(cfg, 1, ENV_ID, engine_factory=FilterpyMarkerEngine)
    native.reset_lanes(np.array([0]), [seeding.np_random(7)[0]])
    oracle.reset_lanes(np.array([0]), [seeding.np_random(7)[0]])
    assert not native.vbuf[0, : native.length[0]].all()  # dropped samples occur
    action = np.array([[0.2, 0.3, 0.3, -0.2]])
    for _ in range(24):
        o1, r1, t1, u1, i1 = native.step(action)
        o2, r2, _, u2, _ = oracle.step(action)
        x2, P2 = oracle.engine.x, oracle.engine.P
        assert np.max(np.abs(native.engine.x - x2)) <= 1e-8 * np.max(np.abs(x2))
        assert np.max(np.abs(native.engine.P - P2)) <= 1e-8 * np.max(np.abs(P2))
        assert r1[0] == pytest.approx(r2[0], rel=1e-9)
        np.testing.assert_allclose(o1, o2, rtol=1e-5, atol=1e-5)
        if t1[0] or u1[0]:
            break
    assert u1[0] and u2[0] and i1["reanchors"][0] >= 2


def test_episode_uwb_record_is_measure_uwb_of_its_walk():
    """The env's sensor is the library's ``measure_uwb`` (one implementation;
    tests/sensors/test_uwb.py checks it against a per-sample reference bit for bit)."""
    cfg = MarkerTrackConfig(uwb_conditions=("realistic",), uwb_condition_weights=(1.0,))
    ep = generate_episode(cfg, np.random.default_rng(3))
    k = ep.z.shape[0]
    rng = np.random.default_rng(3)  # replay the draws: duration, condition, σ factor, walk
    rng.uniform(*cfg.duration_s)
    rng.random()
    spec = uwb_spec("realistic", cfg.rate_hz, rng.uniform(*cfg.noise_factor_range))
    walk = simulate_heel_knee(cfg.truth_gait, k, [rng])
    ref = measure_uwb(spec, walk.markers, [rng])
    assert not ep.valid.all()
    np.testing.assert_array_equal(ep.truth, walk.markers[0].reshape(k, 4))
    np.testing.assert_array_equal(ep.valid, ref.valid[0])
    np.testing.assert_array_equal(ep.z, ref.z[0].reshape(k, 4))


def test_reanchoring_is_an_exact_reparametrisation():
    e = MarkerEkfEngine(MarkerEkfConfig(), 4)
    rng = np.random.default_rng(1)
    e.x[:] = (0.05 * np.abs(e.p0)[:, None] * rng.standard_normal((6, 4))).T
    t = np.array([9.0, 12.3, 20.0, 30.0])
    core = MarkerTrackCore(MarkerTrackConfig(), 4, ENV_ID)
    core.engine = e
    before = e.markers(t + 0.37)
    core._reanchor(np.round(t / 0.1).astype(np.int64), np.ones(4, dtype=bool))
    assert np.all(e.t_anchor > 0) and np.all(t - e.t_anchor >= core.config.reanchor_keep_s)
    omega = e.p0[5] + e.x[:, 5]
    cycles = omega * e.t_anchor / (2 * np.pi)
    np.testing.assert_allclose(cycles, np.round(cycles), atol=1e-9)  # a cycle boundary
    np.testing.assert_allclose(e.markers(t + 0.37), before, atol=1e-12)


def test_out_of_range_actions_are_clipped_and_counted():
    env = gym.make(ENV_ID, config=SHORT).unwrapped
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([3.0, -2.0, 0.0, 1.0]))
    assert info["clipped_actions"] == 1
    assert info["knobs"]["q_amplitude_scale"] == pytest.approx(1000.0)
    assert info["knobs"]["q_trend_scale"] == pytest.approx(1e-3)
    assert info["knobs"]["r_scale"] == pytest.approx(100.0)
    np.testing.assert_allclose(env.core.engine.r[0], 100.0 * 0.01)
    _, _, _, _, info = env.step(np.zeros(4))
    assert info["clipped_actions"] == 1


def test_divergence_terminates_and_holds_the_final_error():
    cfg = MarkerTrackConfig(scenario="paper", divergence_error_m=0.01)
    env = gym.make(ENV_ID, config=cfg).unwrapped
    env.reset(seed=0)
    _, reward, terminated, truncated, info = env.step(np.zeros(4))
    assert terminated and not truncated and info["lock_lost"] and not info["diverged"]
    # 5 of 100 samples scored, the error held for the other 95: −error in total
    assert reward == pytest.approx(-info["error"], rel=1e-12)
    assert info["reward_error"] == pytest.approx(-info["error"] * 0.05, rel=1e-12)


def test_paper_scenario_and_action_zero_is_the_paper_filter():
    env = gym.make(ENV_ID, scenario="paper").unwrapped
    obs, info = env.reset(seed=1)
    assert info["uwb_condition"] == "paper"
    assert info["knobs"] == {
        "q_amplitude_scale": 1.0,
        "q_trend_scale": 1.0,
        "q_cadence_scale": 1.0,
        "r_scale": 1.0,
    }
    paper = MarkerEkfConfig()
    np.testing.assert_array_equal(env.core.engine.q[0], paper.process.process_noise)
    np.testing.assert_array_equal(env.core.engine.r[0], paper.meas_std**2)
    assert env.config.reanchor_after_s == math.inf
    assert obs.shape == (29,)
    _, _, info = rollout(env, 1)
    assert info["reanchors"] == 0


def test_bad_configuration_raises():
    with pytest.raises(ValueError, match="uwb_conditions"):
        MarkerTrackConfig(uwb_conditions=("fog",), uwb_condition_weights=(1.0,))
    with pytest.raises(ValueError, match="uwb_condition_weights"):
        MarkerTrackConfig(uwb_condition_weights=(1.0, -1.0, 1.0, 1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="duration_s"):
        MarkerTrackConfig(duration_s=(10.0, 5.0))
    with pytest.raises(ValueError, match="reanchor_after_s"):
        MarkerTrackConfig(reanchor_after_s=1.0, reanchor_keep_s=2.0)
    with pytest.raises(ValueError, match=r"filter\.sample_period"):
        MarkerTrackConfig(rate_hz=20.0, filter=MarkerEkfConfig())
    with pytest.raises(ValueError, match="divergence_error_m"):
        MarkerTrackConfig(divergence_error_m=0.0)
