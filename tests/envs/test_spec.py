"""The shared env specs: knob mappings, the action check, the env-config base."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from pednav_env.envs import foot_core, marker_config, marker_core, waist_config
from pednav_env.envs.spec import (
    EnvConfig,
    Knob,
    ObsFeature,
    obs_bounds,
    require_range,
    validate_action,
)


def test_knob_mappings_give_the_paper_value_at_zero_and_their_range_at_the_ends():
    # the foot env's ω_max (0.22 rad/s, span 10) and the waist env's linear knobs
    omega = Knob("omega_max", "log", 0.22, 10.0, "rad/s")
    np.testing.assert_allclose(omega.value(np.array([-1.0, 0.0, 1.0])), [0.022, 0.22, 2.2])
    threshold = Knob("step_threshold", "linear", 0.0, 3.0, "m/s²")
    np.testing.assert_allclose(threshold.value(np.array([-1.0, 0.5])), [-3.0, 1.5])
    hysteresis = Knob("step_hysteresis", "linear_positive", 0.0, 2.0, "m/s²")
    np.testing.assert_allclose(hysteresis.value(np.array([-1.0, 0.25])), [0.0, 0.5])


@pytest.mark.parametrize(
    "args", [("k", "exp", 1.0, 2.0, "1"), ("k", "log", 0.0, 2.0, "1"), ("k", "log", 1.0, -2.0, "1")]
)
def test_a_knob_with_an_unknown_mapping_or_a_bad_base_or_span_is_refused(args):
    with pytest.raises(ValueError, match="Knob 'k'"):
        Knob(*args)


def test_obs_bounds_append_the_action_in_force():
    low, high = obs_bounds((ObsFeature("a", 0.0, 1.0), ObsFeature("b", -2.0, 3.0, "m")), 2)
    assert low.dtype == np.float32
    np.testing.assert_array_equal(low, [0.0, -2.0, -1.0, -1.0])
    np.testing.assert_array_equal(high, [1.0, 3.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="ObsFeature 'c'"):
        ObsFeature("c", 1.0, 0.0)


@pytest.mark.parametrize(
    "action, message",
    [
        ([["x", "y"]], "not numeric"),
        ([[0.0, 0.0, 0.0]], "shape"),
        ([[0.0, np.nan]], "NaN or inf"),
        ([[np.inf, 0.0]], "NaN or inf"),
    ],
)
def test_validate_action_names_the_env_and_the_fault(action, message):
    with pytest.raises(ValueError, match=f"pednav/Test-v0: .*{message}"):
        validate_action(action, (1, 2), "pednav/Test-v0")


def test_validate_action_returns_float64_of_the_given_values():
    a = validate_action(np.array([[0.5, -1.0]], np.float32), (1, 2), "e")
    assert a.dtype == np.float64
    np.testing.assert_array_equal(a, [[0.5, -1.0]])


@dataclass(frozen=True)
class _Config(EnvConfig):
    scenario: str = "random"
    decision_interval_s: float = 0.5
    rate_hz: float = 100.0
    divergence_error_m: float = 25.0
    divergence_error_fraction: float = 0.25

    def __post_init__(self) -> None:
        self.check_env_settings()


@pytest.mark.parametrize(
    "field, value",
    [
        ("scenario", "office"),
        ("rate_hz", 0.0),
        ("rate_hz", float("nan")),
        ("decision_interval_s", -0.5),
        ("decision_interval_s", 0.001),  # shorter than one sample at 100 Hz
        ("divergence_error_m", 0.0),
        ("divergence_error_fraction", -0.1),
    ],
)
def test_env_config_base_refuses_bad_common_settings_naming_them(field, value):
    assert _Config().interval_samples == 50
    with pytest.raises(ValueError, match=field):
        _Config(**{field: value})


def test_knob_action_inverts_a_log_knob_and_is_refused_for_linear_ones():
    omega = Knob("omega_max", "log", 0.22, 10.0, "rad/s")
    np.testing.assert_allclose(omega.action(np.array([0.022, 0.22, 2.2])), [-1.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="log knobs only"):
        Knob("step_threshold", "linear", 0.0, 3.0, "m/s²").action(1.0)


@pytest.mark.parametrize(
    "knobs, features",
    [
        (foot_core.ACTION_KNOBS, foot_core.OBS_FEATURES),
        (marker_config.ACTION_KNOBS, marker_core.OBS_FEATURES),
        (waist_config.ACTION_KNOBS, waist_config.OBS_FEATURES),
    ],
)
def test_every_env_declares_its_knobs_and_features_with_the_shared_specs(knobs, features):
    assert all(type(k) is Knob for k in knobs) and all(type(f) is ObsFeature for f in features)
    assert len({f.name for f in features}) == len(features)  # names index the observation


def test_require_range_within_bounds_names_the_setting():
    require_range("slope_deg", (0.0, 30.0), within=(0.0, 30.0))  # the bounds are allowed
    for bad in ((2.0, 31.0), (-1.0, 8.0)):
        with pytest.raises(ValueError, match=r"slope_deg must lie within \(0.0, 30.0\)"):
            require_range("slope_deg", bad, within=(0.0, 30.0))
