"""`pretrained` for the foot envs' shoe family is the shipped gait-adaptive rule
fitted on recordings (`gait-rule-real`)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import pednav_env  # noqa: F401  (registers the envs)
from agents.gait_rule import PARAMS_FILE, REAL_PARAMS_FILE, GaitRulePolicy, read_params
from agents.policies import load_policy

FOOT = "pednav/FootZupt-v0"


def test_shoe_pretrained_is_the_recordings_rule_and_acts_like_it():
    space = gym.make(FOOT, filter="shoe").action_space
    pretrained = load_policy("pretrained", space, FOOT)
    rule = load_policy("gait-rule-real", space, FOOT)
    assert isinstance(pretrained, GaitRulePolicy)
    assert pretrained.params == read_params(REAL_PARAMS_FILE)
    assert pretrained.params != read_params(PARAMS_FILE)  # not the simulated walks' rule
    assert pretrained.filter_family == "shoe"
    env = gym.make(FOOT, filter="shoe")
    obs, _ = env.reset(seed=20_000)
    for _ in range(5):
        a, _ = pretrained.predict(obs)
        b, _ = rule.predict(obs)
        np.testing.assert_array_equal(a, b)
        obs, *_ = env.step(a)


def test_paper_pretrained_is_still_the_paper_network():
    space = gym.make(FOOT, filter="paper").action_space
    policy = load_policy("pretrained:paper", space, FOOT)
    assert not isinstance(policy, GaitRulePolicy)
    assert policy.filter_family == "paper"


def test_pretrained_off_the_foot_envs_needs_a_network():
    with pytest.raises(ValueError, match="no pretrained tuner"):
        load_policy("pretrained", gym.make(FOOT).action_space, "pednav/Other-v0")
