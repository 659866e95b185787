"""The foot envs' filter families and the calibrated scenario: action 0 of the shoe
family is ``real-fixed`` (read from real_fixed.json) in simulation and on a recording,
the knob mapping, the per-lane SHOE statistic, the family defaults, the privileged
``info["context"]``, and policies carrying their family."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
from testdata import REPLAY_DATA

import pednav_env  # noqa: F401  (registers the environments)
from agents.policies import load_policy
from pednav_env.envs.foot_context import CONTEXT_FIELDS, CONTEXT_GRADES, SPEED_BANDS
from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_replay_core import FootReplayConfig, FootReplayCore
from pednav_env.gait.speed_route import SpeedRouteConfig
from pednav_env.io import load_recording
from pednav_env.nav.detectors import ShoeDetectorConfig, shoe_statistic, shoe_statistic_at
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import REAL_FIXED_FILE

ENV_ID = "pednav/FootZupt-v0"
TRIAL = REPLAY_DATA / "pyshoe_2017-11-22-11-48-35_first7s.mat"
#: Short calibrated walks (the default is 60–120 s).
SHORT_SPEED = SpeedRouteConfig(speed_mps=(0.3, 3.0), duration_s=(12.0, 16.0))


def real_fixed_json() -> dict:
    return json.loads(REAL_FIXED_FILE.read_text())["setup"]


def test_shoe_action_zero_is_real_fixed_and_the_knobs_scale_it():
    rf = real_fixed_json()
    env = gym.make(ENV_ID, filter="shoe").unwrapped
    assert env.config.scenario == "calibrated" and env.config.rate_hz == 200.0
    _, info = env.reset(seed=20_000)
    assert info["imu_grade"] == "microstrain_gx5"
    assert info["knobs"] == {
        "shoe_threshold": rf["detector"]["threshold"],
        "shoe_window_s": rf["detector"]["window_s"],
        "process_noise_scale": rf["filter"]["process_noise_scale"],
        "zupt_noise_scale": rf["filter"]["zupt_noise_scale"],
    }
    engine = env.core.engine
    assert engine.uses_shoe and not engine.settings.boundaries_only
    det = engine.config.detector
    assert isinstance(det, ShoeDetectorConfig)
    assert det.accel_noise_std == rf["detector"]["accel_noise_std"]
    _, _, _, _, info = env.step(np.array([1.0, -1.0, 0.5, -0.5], np.float32))
    # log knobs: base · span ** a with spans 100 (γ), 4 (window), 100 (Q and R)
    assert info["knobs"]["shoe_threshold"] == pytest.approx(rf["detector"]["threshold"] * 100)
    assert info["knobs"]["shoe_window_s"] == pytest.approx(rf["detector"]["window_s"] / 4)
    assert info["knobs"]["process_noise_scale"] == pytest.approx(
        rf["filter"]["process_noise_scale"] * 10
    )
    assert info["knobs"]["zupt_noise_scale"] == pytest.approx(rf["filter"]["zupt_noise_scale"] / 10)


def test_paper_family_is_the_default_and_families_are_checked():
    env = gym.make(ENV_ID).unwrapped
    assert env.config.filter_family == "paper" and env.config.scenario == "random"
    assert not env.core.engine.uses_shoe
    with pytest.raises(ValueError, match="filter"):
        gym.make(ENV_ID, filter="pyshoe")
    with pytest.raises(ValueError, match="SHOE detector"):
        FootZuptConfig(filter_family="shoe", filter=FootZuptConfig().filter)
    # an explicit scenario and rate are kept for the shoe family
    cfg = gym.make(ENV_ID, filter="shoe", scenario="random").unwrapped.config
    assert cfg.scenario == "random" and cfg.rate_hz == 100.0


def test_lane_windows_of_the_shoe_statistic_match_the_record_statistic():
    """Per-lane windows and interval starts (the env's knob) against the whole-record
    statistic of each window (an independent cumulative-sum path), start of record included."""
    rng = np.random.default_rng(0)
    omega = rng.normal(0.0, 0.3, (3, 120, 3))
    f = rng.normal(0.0, 0.5, (3, 120, 3)) + [0.0, 0.0, 9.81]
    windows = np.array([1, 4, 9])
    first = np.array([0, 50, 3])
    out = shoe_statistic_at(omega, f, first, 30, windows, ShoeDetectorConfig())
    for i, w in enumerate(windows):
        cfg = ShoeDetectorConfig(window_s=w / 100.0)
        ref = shoe_statistic(omega[i : i + 1], f[i : i + 1], cfg, 100.0)[0]
        # the accelerometer term cancels |f|² ≈ 96 against 2g·|f̄| − g²: a few
        # 1e-14 absolute of the record's sums, well below 1e-9 of the statistic
        np.testing.assert_allclose(out[i], ref[first[i] : first[i] + 30], rtol=1e-9)


def test_shoe_replay_action_zero_runs_the_real_fixed_filter():
    """On a recording, action 0 of the shoe family is the `real-fixed` run of the
    replay runner (its whole-record SHOE statistic): the same estimate at every
    interval end, up to rounding."""
    rec = load_recording(TRIAL)
    core = FootReplayCore(FootReplayConfig(filter_family="shoe"), 1, "test", recordings=[rec])
    core.reset_lanes(np.array([0]), [np.random.default_rng(0)])
    ends = []
    while core.cursor[0] < core.length[0]:
        _, _, _, _, info = core.step(np.zeros((1, 4)))
        ends.append((int(core.cursor[0]), info["pos_est"][0].copy()))
    run = run_prepared(prepare(rec, core.replay_config.setup), interval_s=0.5)
    for cursor, pos in ends:
        # the per-interval statistic differs from the record's by ~1e-11 relative
        # (summation order) and decides no stance differently on this trial
        np.testing.assert_allclose(run.pos[0, cursor - 1], pos, atol=1e-9)
    assert len(ends) > 5


def test_context_is_the_coming_interval_speed_band_and_grade():
    env = gym.make(
        ENV_ID,
        config=FootZuptConfig(filter_family="shoe", speed_route=SHORT_SPEED),
    ).unwrapped
    assert CONTEXT_FIELDS == ("speed_band", "imu_grade", "speed_mps")
    _, info = env.reset(seed=20_001)
    assert info["context"].shape == (3,) and info["context"].dtype == np.float64
    assert info["context"][0] == 0  # the walk starts standing
    core = env.core
    k, dt = core.k, core.dt
    bands = set()
    while True:
        c0 = int(core.cursor[0])
        ctx = info["context"]
        lo, hi = max(c0 - k // 2, 0), min(c0 + k + k // 2, int(core.length[0]))
        speed = (core.distance[0, hi] - core.distance[0, lo]) / ((hi - lo) * dt)
        assert ctx[2] == pytest.approx(speed)
        lo_b, hi_b = SPEED_BANDS[int(ctx[0])]
        assert lo_b <= ctx[2] < hi_b
        assert CONTEXT_GRADES[int(ctx[1])] == "microstrain_gx5"
        bands.add(int(ctx[0]))
        _, _, term, trunc, info = env.step(np.zeros(4, np.float32))
        if term or trunc:
            break
    assert len(bands) >= 2


def test_vector_context_after_autoreset_is_the_new_episode():
    cfg = FootZuptConfig(filter_family="shoe", speed_route=SHORT_SPEED)
    venv = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", config=cfg)
    _, info = venv.reset(seed=20_002)
    assert info["context"].shape == (2, 3)
    for _ in range(200):
        _, _, term, trunc, info = venv.step(np.zeros((2, 4), np.float32))
        done = term | trunc
        if done.any():
            lane = int(np.flatnonzero(done)[0])
            assert info["context"][lane, 0] == 0  # a new walk starts standing
            assert info["final_info"][lane]["context"].shape == (3,)
            return
    pytest.fail("no episode ended")


def test_policies_carry_their_filter_family(tmp_path):
    space = gym.make(ENV_ID).action_space
    assert load_policy("paper", space, ENV_ID).filter_family == "paper"
    assert load_policy("real-fixed", space, ENV_ID).filter_family == "shoe"
    assert load_policy("adaptive", space, ENV_ID).filter_family == "shoe"  # the default
    assert load_policy("adaptive:paper", space, ENV_ID).filter_family == "paper"
    assert load_policy("adaptive", space, ENV_ID, filter_family="paper").filter_family == "paper"
    tuned = load_policy("tuned:paper", space, ENV_ID)
    assert tuned.filter_family == "paper"
    # a tuned-actions file keyed by env and family
    path = tmp_path / "tuned_actions.json"
    path.write_text(json.dumps({f"{ENV_ID}:shoe": {"action": [0.1, 0.0, 0.0, 0.0]}}))
    pol = load_policy(str(path), space, ENV_ID)
    assert pol.filter_family == "shoe" and pol.action[0] == pytest.approx(0.1)
    with pytest.raises(ValueError, match="no tuned-fixed action"):
        load_policy(str(path), space, ENV_ID, filter_family="paper")


def test_shoe_adaptive_moves_only_the_process_noise():
    env = gym.make(ENV_ID, config=FootZuptConfig(filter_family="shoe", speed_route=SHORT_SPEED))
    policy = load_policy("adaptive:shoe", env.action_space, ENV_ID)
    obs, _ = env.reset(seed=20_003)
    actions = []
    while True:
        actions.append(policy.predict(obs)[0])
        obs, _, term, trunc, _ = env.step(actions[-1])
        if term or trunc:
            break
    a = np.array(actions)
    assert np.all(a[:, [0, 1, 3]] == 0)  # γ, window and R at real-fixed's values
    assert np.any(a[:, 2] != 0)
