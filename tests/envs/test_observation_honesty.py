"""Observations come from the sensors and the filter only, never from the truth.

For every registered ``pednav/`` env: one episode is played twice by the same
rule policy (:class:`baselines.InnovationAdaptivePolicy`, which reads the
observations), once as drawn and once with the episode's truth arrays replaced
in the core's lane buffers right after reset (the sensor data stay the same).
Observations and actions must agree bit for bit until the first step at which
either run ends: termination on divergence depends on the truth error, and the
reward and the truth entries of the info are meant to change (checked, so
that the replacement is known to have reached the episode).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from env_rollout import ENV_IDS, FAST_KWARGS

import pednav_env  # noqa: F401  (registers the environments)
from baselines import InnovationAdaptivePolicy

#: The rule that drives each env (the replay env shares FootZupt's spaces and rule).
RULE = {"pednav/FootZuptReplay-v0": "pednav/FootZupt-v0"}


def _replace_foot_truth(core: Any, rng: np.random.Generator) -> None:
    """Positions moved (offset plus noise, a few metres: below the divergence
    bound), stance labels inverted, distance walked tripled plus 10 m."""
    core.pos[0] += np.array([3.0, -2.0, 0.5]) + rng.normal(0.0, 0.3, core.pos[0].shape)
    core.true_stance[0] = ~core.true_stance[0]
    core.distance[0] = 3.0 * core.distance[0] + 10.0


def _replace_waist_truth(core: Any, rng: np.random.Generator) -> None:
    """Hip track moved, distance tripled plus 10 m, true-footfall window inverted,
    true leg length changed."""
    core.truth_grid[0] += np.array([3.0, -2.0]) + rng.normal(0.0, 0.3, core.truth_grid[0].shape)
    core.dist_grid[0] = 3.0 * core.dist_grid[0] + 10.0
    core.near_true[0] = ~core.near_true[0]
    core.leg_true[0] *= 1.3


def _replace_marker_truth(core: Any, rng: np.random.Generator) -> None:
    """Marker truth moved by a few centimetres (the lock-loss bound is 1 m) and
    the walk's start moved by 1 m."""
    core.tbuf[0] += 0.03 + rng.normal(0.0, 0.02, core.tbuf[0].shape)
    core.x_start[0] += 1.0


#: Every registered env says where its truth lives; a new env must be added here.
REPLACE_TRUTH: dict[str, Callable[[Any, np.random.Generator], None]] = {
    "pednav/FootZupt-v0": _replace_foot_truth,
    "pednav/FootZuptReplay-v0": _replace_foot_truth,
    "pednav/WaistStep-v0": _replace_waist_truth,
    "pednav/MarkerTrack-v0": _replace_marker_truth,
}


def play(env_id: str, seed: int, replace_truth: bool) -> dict[str, Any]:
    """One episode with the rule policy; per step: observation (reset's first),
    action, error, and whether the episode ended."""
    env = gym.make(env_id, **FAST_KWARGS.get(env_id, {}))
    policy = InnovationAdaptivePolicy(env.action_space, RULE.get(env_id, env_id))
    obs, _ = env.reset(seed=seed)
    if replace_truth:
        REPLACE_TRUTH[env_id](env.unwrapped.core, np.random.default_rng(99))
    observations, actions, errors, ends = [obs], [], [], []
    while True:
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        observations.append(obs)
        actions.append(action)
        errors.append(info["error"])
        ends.append(terminated or truncated)
        if terminated or truncated:
            break
    env.close()
    return {
        "obs": np.array(observations),
        "actions": np.array(actions),
        "errors": np.array(errors),
        "ends": ends,
    }


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_replacing_the_truth_changes_no_observation_or_action(env_id):
    assert env_id in REPLACE_TRUTH, f"{env_id}: say in REPLACE_TRUTH where its truth lives"
    plain = play(env_id, 3, replace_truth=False)
    moved = play(env_id, 3, replace_truth=True)
    # Steps played by both runs up to (and including) the first end of either.
    n = min(len(plain["ends"]), len(moved["ends"]))
    assert n >= 8, f"{env_id}: only {n} steps compared; the check needs a longer episode"
    assert not np.array_equal(plain["errors"][:n], moved["errors"][:n]), (
        "the replaced truth did not reach the error: the check would be empty"
    )
    np.testing.assert_array_equal(moved["actions"][:n], plain["actions"][:n])
    np.testing.assert_array_equal(moved["obs"][: n + 1], plain["obs"][: n + 1])
