"""The opt-in pitch knots that follow the stride length (gait.stance_motion,
gait.speed_route, calibration.parameters): off is today's route bit for bit, on the
knots shrink with the stride's length below L_k, bad values are rejected."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pednav_env.calibration.compare import model_from_json
from pednav_env.calibration.parameters import (
    NAMES,
    PITCH_KNOTS,
    START,
    parameter_set,
    randomization,
)
from pednav_env.gait.foot_route import Gait
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization

WALKER = StanceMotion(
    flat_fraction=0.3,
    swing_pitch_scale=1.37,
    cadence_intercept_hz=0.71,
    cadence_slope_hz_per_mps=0.13,
    heel_rocker=True,
)


def knots(route) -> np.ndarray:
    """(n, 4): length, toe-off, mid-swing and heel-strike pitch of each stride."""
    return np.array(
        [
            (
                s.shape.stride_length_m,
                s.shape.toe_off_pitch,
                s.shape.mid_swing_pitch,
                s.shape.heel_strike_pitch,
            )
            for s in route.strides
        ]
    )


def test_off_is_the_same_route_bit_for_bit() -> None:
    cfg = SpeedRouteConfig(speed_mps=(0.3, 2.5), duration_s=(40.0, 50.0))
    a = speed_route(np.random.default_rng(21600), replace(cfg, stance_motion=WALKER))
    b = speed_route(
        np.random.default_rng(21600),
        replace(cfg, stance_motion=replace(WALKER, pitch_knot_stride_m=0.0)),
    )
    assert a == b
    assert StanceRandomization().draw(np.random.default_rng(1)).pitch_knot_stride_m == 0.0
    assert StanceRandomization.calibrated().pitch_knot_stride_m == 0.0


def test_the_knots_shrink_with_the_stride_length_on_generated_strides() -> None:
    cfg = SpeedRouteConfig(
        speed_mps=(0.3, 1.0), duration_s=(60.0, 60.0), stop_probability=0.0, leg_strides=(4, 6)
    )
    l_k = 0.7
    base = knots(speed_route(np.random.default_rng(21601), replace(cfg, stance_motion=WALKER)))
    on = knots(
        speed_route(
            np.random.default_rng(21601),
            replace(cfg, stance_motion=replace(WALKER, pitch_knot_stride_m=l_k)),
        )
    )
    # the same strides (lengths, draws); the knots differ only where L < L_k
    np.testing.assert_array_equal(on[:, 0], base[:, 0])
    short, long = base[:, 0] < l_k, base[:, 0] >= l_k
    assert short.sum() >= 5 and long.sum() >= 5
    np.testing.assert_array_equal(on[long], base[long])
    ratio = on[short, 1:] / base[short, 1:]
    # every knot of a short stride scaled by the same factor, its length over L_k
    np.testing.assert_allclose(ratio, np.repeat(base[short, :1] / l_k, 3, axis=1), rtol=1e-12)
    assert np.all(np.abs(on[short, 1:]) < np.abs(base[short, 1:]))
    # shorter strides keep smaller toe-off knots than the longest short ones
    toe = on[short, 1]
    order = np.argsort(base[short, 0])
    assert toe[order[0]] < toe[order[-1]]


def test_a_shuffle_hardly_pitches() -> None:
    cfg = SpeedRouteConfig(speed_mps=(0.2, 0.2), speed_jitter=0.0, stop_probability=0.0)
    shuffle = replace(WALKER, pitch_knot_stride_m=1.2)
    route = speed_route(np.random.default_rng(21602), replace(cfg, stance_motion=shuffle))
    table = knots(route)
    today = knots(speed_route(np.random.default_rng(21602), replace(cfg, stance_motion=WALKER)))
    walking = [s.shape.gait is Gait.SLOW_WALK for s in route.strides]
    assert all(walking) and table[:, 0].max() < 0.3
    # today's toe-off knot is at least 1.37 × (0.4 − 0.05) rad whatever the length;
    # strides under 0.3 m keep under a quarter of it
    assert np.all(today[:, 1] > 0.45)
    assert np.all(table[:, 1] < 0.25 * today[:, 1])
    assert shuffle.pitch_knot_factor(0.0) == 0.0
    assert shuffle.pitch_knot_factor(2.0) == 1.0
    assert WALKER.pitch_knot_factor(0.0) == 1.0


@pytest.mark.parametrize("bad", [-0.1, 3.5, float("nan"), float("inf"), True])
def test_bad_lengths_are_rejected_naming_the_field(bad: float) -> None:
    with pytest.raises(ValueError, match=r"StanceMotion\.pitch_knot_stride_m"):
        StanceMotion(pitch_knot_stride_m=bad)
    with pytest.raises(ValueError, match=r"StanceRandomization\.pitch_knot_stride_m"):
        StanceRandomization(pitch_knot_stride_m=bad)


def test_the_fit_takes_the_length_as_its_last_value() -> None:
    assert parameter_set(len(NAMES) + 1, knots=True)[-1] is PITCH_KNOTS
    assert parameter_set(len(NAMES) + 2, knots=True)[-2:][0].name == "swing_speed_exponent"
    assert randomization([*START, 0.0], knots=True) == randomization(START)
    fitted = randomization([*START, 0.7], {"heel_rocker": True}, knots=True)
    assert fitted.pitch_knot_stride_m == pytest.approx(0.7) and fitted.heel_rocker
    # clipped to the box like the other values
    assert randomization([*START, 5.0], knots=True).pitch_knot_stride_m == PITCH_KNOTS.upper
    with pytest.raises(ValueError, match="with the pitch knots has 16 or 17 values, got 15"):
        randomization(START, knots=True)


def test_the_model_file_carries_the_length(tmp_path: Path) -> None:
    good = tmp_path / "knots.json"
    good.write_text(json.dumps({"flat_fraction": 0.3, "pitch_knot_stride_m": 0.8}))
    assert model_from_json(good).stance.pitch_knot_stride_m == pytest.approx(0.8)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"flat_fraction": 0.3, "pitch_knot_stride_m": -1}))
    with pytest.raises(ValueError, match=r"bad\.json: .*pitch_knot_stride_m"):
        model_from_json(bad)
