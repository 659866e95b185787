"""Teacher–student distillation (tiny budget) and the episode-history features."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np

from agents.distill import distill
from agents.evaluate import load_policy
from agents.features import FeaturePolicy, HistoryFeatures
from baselines.oracle import CONTEXTS, OraclePolicy
from pednav_env.envs.marker_config import MarkerTrackConfig

ENV_ID = "pednav/MarkerTrack-v0"
SHORT = {"config": MarkerTrackConfig(duration_s=(3.0, 4.0))}


def test_history_features_restart_at_each_episode_start():
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(7, 2, 5))  # steps × lanes × (3 entries + 2 action entries)
    starts = np.zeros((7, 2), dtype=bool)
    starts[0] = True
    starts[4, 1] = True  # lane 1 starts a new episode at step 4
    feats = HistoryFeatures(action_dim=2)
    out = [feats(obs[t], starts[t]) for t in range(7)]
    last = out[-1]
    for lane, first in ((0, 0), (1, 4)):
        seen = obs[first:, lane, :3]  # the action in force is left out
        assert last.shape == (2, 9)
        np.testing.assert_allclose(last[lane, :3], obs[-1, lane, :3], rtol=1e-6)
        np.testing.assert_allclose(last[lane, 3:6], seen.mean(axis=0), rtol=1e-5, atol=1e-6)
        rms = np.sqrt((seen**2).mean(axis=0))
        np.testing.assert_allclose(last[lane, 6:], rms, rtol=1e-5)  # float32 output


def test_distilled_student_learns_the_teacher_and_loads_as_a_run(tmp_path):
    """A teacher that plays one constant everywhere: after the fit the student's
    action is that constant (to 0.15 on every knob: a few hundred samples and
    gradient steps, far from the untrained network's ≈ 0), and the run directory
    loads through ``--policy PATH`` with its history features."""
    space = gym.make(ENV_ID, **SHORT).action_space
    target = np.array([0.5, -0.4, 0.3, -0.2], np.float32)
    n = len(CONTEXTS[ENV_ID].labels)
    teacher = OraclePolicy(np.tile(target, (n, 1)), CONTEXTS[ENV_ID].field_index, space)
    run = distill(
        ENV_ID,
        tmp_path / "run",
        lanes=8,
        iterations=2,
        steps_per_iteration=16,
        epochs=60,
        batch_size=64,
        teacher=teacher,
        env_kwargs=SHORT,
    )
    meta = json.loads((run / "meta.json").read_text())
    assert meta["features"] == "history" and meta["samples"] == 2 * 16 * 8
    policy = load_policy(str(run), space, ENV_ID)
    assert isinstance(policy, FeaturePolicy)
    venv = gym.make_vec(ENV_ID, num_envs=4, vectorization_mode="vector_entry_point", **SHORT)
    obs, _ = venv.reset(seed=20000)
    action, _ = policy.predict(obs, episode_start=np.ones(4, dtype=bool))
    assert action.shape == (4, 4)
    np.testing.assert_allclose(action, np.tile(target, (4, 1)), atol=0.15)
