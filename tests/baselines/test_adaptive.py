"""The innovation-adaptive baseline (baselines.adaptive): each env's rule follows the NIS
and the motion."""

import gymnasium as gym
import numpy as np
import pytest

from baselines import InnovationAdaptivePolicy
from pednav_env.envs.foot_core import OBS_FEATURES

ENV_ID = "pednav/FootZupt-v0"


def test_adaptive_rule_reacts_to_innovations_and_motion():
    space = gym.make(ENV_ID).action_space
    pol = InnovationAdaptivePolicy(space)
    idx = {f.name: i for i, f in enumerate(OBS_FEATURES)}
    obs = np.zeros((3, 20), np.float32)
    obs[:, idx["log_nis_interval"]] = np.log1p([40.0, 4.0, 0.4])  # NIS 10x, 1x, 0.1x expected
    obs[:, idx["gyro_norm_mean"]] = [0.05, 2.0, 6.0]  # still, walking, running
    obs[:, idx["accel_excess_std"]] = [0.01, 5.0, 20.0]
    a, _ = pol.predict(obs)
    assert a[0, 2] > 0 and a[1, 2] == pytest.approx(0.0, abs=1e-6) and a[2, 2] < 0
    assert a[0, 0] == 0.0 and a[0, 1] == 0.0  # still: paper thresholds
    assert a[2, 0] > a[1, 0] and a[2, 1] > a[1, 1]  # faster gait: wider thresholds
    with pytest.raises(ValueError, match="no innovation-adaptive rule"):
        InnovationAdaptivePolicy(space, "pednav/Other-v0")


@pytest.mark.parametrize(
    ("env_id", "feature", "knob"),
    [("pednav/WaistStep-v0", "log_nis_interval", 3), ("pednav/MarkerTrack-v0", "log_nis_mean", 0)],
)
def test_adaptive_rules_of_the_other_envs_follow_the_nis(env_id, feature, knob):
    """Too-large innovations raise the adapted noise scale, too-small ones lower it,
    and no update leaves it alone; all other knobs stay at the paper's values."""
    from pednav_env.envs import marker_core, waist_config

    core = waist_config if "Waist" in env_id else marker_core
    names = [f.name for f in core.OBS_FEATURES]
    space = gym.make(env_id).action_space
    obs = np.zeros((3, len(names) + space.shape[0]), np.float32)
    obs[:, names.index(feature)] = np.log1p([40.0, 0.04, 0.0])  # NIS ≫ m, ≪ m, none
    a, _ = InnovationAdaptivePolicy(space, env_id).predict(obs)
    assert a[0, knob] > 0 > a[1, knob] and a[2, knob] == 0
    others = np.delete(a, knob, axis=1)
    assert not others.any()
