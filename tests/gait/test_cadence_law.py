"""The opt-in walking cadence law (gait.stance_motion, gait.speed_route): the default is
today's route, the option's cycles follow its law, bad coefficients are rejected."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pednav_env.calibration.cadence import recorded_strides
from pednav_env.calibration.compare import model_from_json
from pednav_env.calibration.sources import samples_from_simulation
from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import Gait
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization
from pednav_env.sensors.imu import IMU_GRADES, simulate_imu


def test_the_default_law_is_the_routes_own() -> None:
    # 0.55 + 0.3 v, the cycle the route had before the option: T = 1/(0.55 + 0.3 v) ± 7 %
    route = speed_route(np.random.default_rng(3), SpeedRouteConfig(speed_mps=(0.3, 1.9)))
    walking = [s.shape for s in route.strides if s.shape.gait is not Gait.RUN]
    assert len(walking) > 10
    for shape in walking:
        ratio = shape.cycle_s * (0.55 + 0.3 * shape.speed)
        assert 0.93 - 1e-9 <= ratio <= 1.07 + 1e-9
    walker = StanceMotion(flat_fraction=0.3)
    assert walker.cadence_intercept_hz is None
    assert walker.stride_frequency_hz(0.4) == pytest.approx(0.67)


def test_the_law_at_the_default_coefficients_gives_the_same_walks_bit_for_bit() -> None:
    cfg = SpeedRouteConfig(speed_mps=(0.3, 1.6), duration_s=(25.0, 30.0))
    plain = StanceMotion(flat_fraction=0.3, swing_pitch_scale=1.2)
    same_law = replace(plain, cadence_intercept_hz=0.55, cadence_slope_hz_per_mps=0.3)
    a = speed_route(np.random.default_rng(9), replace(cfg, stance_motion=plain))
    b = speed_route(np.random.default_rng(9), replace(cfg, stance_motion=same_law))
    assert [s.shape.cycle_s for s in a.strides] == [s.shape.cycle_s for s in b.strides]
    assert [s.shape.stride_length_m for s in a.strides] == [
        s.shape.stride_length_m for s in b.strides
    ]
    # the knots follow the length, which under the default law is the speed's own
    for sa, sb in zip(a.strides, b.strides, strict=True):
        assert sb.shape.toe_off_pitch == pytest.approx(sa.shape.toe_off_pitch, abs=1e-12)
        assert sb.shape.swing_height_m == pytest.approx(sa.shape.swing_height_m, abs=1e-12)


def test_with_a_law_the_knots_are_the_default_strides_of_the_same_length() -> None:
    # f = 1.2 Hz at every speed: at 0.4 m/s a 0.333 m stride, which the default law
    # walks at v' = 0.55 L / (1 − 0.3 L) = 0.2037 m/s; the route's knots are then
    # 0.4 + 0.3 v' (toe-off), −(0.2 + 0.1 v') (heel strike), 0.06 + 0.04 v' (height)
    quick = StanceMotion(flat_fraction=0.3, cadence_intercept_hz=1.2, cadence_slope_hz_per_mps=0.0)
    v_eq = 0.55 * (0.4 / 1.2) / (1 - 0.3 * (0.4 / 1.2))
    assert quick.shape_speed(0.4) == pytest.approx(v_eq) == pytest.approx(0.20370, abs=1e-5)
    assert StanceMotion().shape_speed(0.4) == 0.4
    cfg = SpeedRouteConfig(speed_mps=(0.4, 0.4), speed_jitter=0.0, stop_probability=0.0)
    a = speed_route(np.random.default_rng(2), replace(cfg, stance_motion=quick))
    b = speed_route(
        np.random.default_rng(2),
        replace(cfg, stance_motion=StanceMotion(flat_fraction=0.3)),
    )
    for sa, sb in zip(a.strides, b.strides, strict=False):
        assert sa.shape.toe_off_pitch - sb.shape.toe_off_pitch == pytest.approx(0.3 * (v_eq - 0.4))
        assert sa.shape.heel_strike_pitch == pytest.approx(-(0.2 + 0.1 * v_eq))
        assert sb.shape.heel_strike_pitch == pytest.approx(-(0.2 + 0.1 * 0.4))
        assert sa.shape.swing_height_m - sb.shape.swing_height_m == pytest.approx(
            0.04 * (v_eq - 0.4)
        )
        assert sa.shape.cycle_s == pytest.approx(sa.shape.stride_length_m / 0.4)


def test_the_options_cycles_follow_its_law_on_generated_walks() -> None:
    # a slow walker with quick short strides: f = 0.9 + 0.1 v, i.e. 1.03 s at 0.4 m/s
    # (the default law: 1.49 s); each walking stride's cycle within the ±7 % jitter
    law = StanceMotion(
        flat_fraction=0.3, cadence_intercept_hz=0.9, cadence_slope_hz_per_mps=0.1, seed=4
    )
    cfg = SpeedRouteConfig(
        speed_mps=(0.35, 0.45), duration_s=(30.0, 30.0), stop_probability=0.0, stance_motion=law
    )
    rng = np.random.default_rng(21_800)
    route = speed_route(rng, cfg)
    for s in route.strides:
        ratio = s.shape.cycle_s * (0.9 + 0.1 * s.shape.speed)
        assert 0.93 - 1e-9 <= ratio <= 1.07 + 1e-9
        assert s.shape.stride_length_m == pytest.approx(s.shape.speed * s.shape.cycle_s)
    # and measured on the simulated walk, footfall to footfall from its truth stance
    truth = simulate_foot([route], FootSimConfig(rate_hz=200.0), full_state=False)
    imu = simulate_imu(truth.omega_b, truth.f_b, 200.0, IMU_GRADES["microstrain_gx5"](), [rng])
    strides = recorded_strides(samples_from_simulation(truth, imu, 0))
    assert strides.cycle_s.size >= 15
    measured = np.median(strides.cycle_s)
    assert 1 / (0.9 + 0.1 * 0.45) * 0.93 < measured < 1 / (0.9 + 0.1 * 0.35) * 1.07
    assert measured < 1 / (0.55 + 0.3 * 0.45) * 0.93  # not the default law's


def test_the_randomization_draws_a_walker_spread_only_when_the_law_is_set() -> None:
    shipped = StanceRandomization.calibrated()
    assert shipped.cadence_intercept_hz is None and shipped.cadence_log10_std == 0.0
    rng_a, rng_b = np.random.default_rng(12), np.random.default_rng(12)
    a = shipped.draw(rng_a)
    with_law = replace(
        shipped, cadence_intercept_hz=0.7, cadence_slope_hz_per_mps=0.13, cadence_log10_std=0.06
    )
    b = with_law.draw(rng_b)
    # the same walker otherwise; one more normal drawn, after all of today's draws
    assert replace(b, cadence_intercept_hz=None, cadence_slope_hz_per_mps=0.3) == a
    assert a.cadence_intercept_hz is None
    assert b.cadence_slope_hz_per_mps / b.cadence_intercept_hz == pytest.approx(0.13 / 0.7)
    # walkers' scales spread as 10^(0.06 ξ)
    scales = [
        with_law.draw(np.random.default_rng([5, i])).cadence_intercept_hz / 0.7 for i in range(400)
    ]
    assert np.std(np.log10(scales)) == pytest.approx(0.06, rel=0.15)
    fixed = replace(with_law, cadence_log10_std=0.0).draw(np.random.default_rng(1))
    assert fixed.cadence_intercept_hz == 0.7 and fixed.cadence_slope_hz_per_mps == 0.13


#: The message of a law outside the allowed stride frequencies names both coefficients.
LAW = "cadence_intercept_hz, cadence_slope_hz_per_mps = "


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"cadence_intercept_hz": -0.2}, LAW),
        ({"cadence_intercept_hz": float("nan")}, "cadence_intercept_hz must be finite"),
        ({"cadence_intercept_hz": 0.5, "cadence_slope_hz_per_mps": -0.4}, LAW),
        ({"cadence_intercept_hz": 2.4, "cadence_slope_hz_per_mps": 0.3}, LAW),
        ({"cadence_slope_hz_per_mps": float("inf")}, "cadence_slope_hz_per_mps"),
        ({"cadence_slope_hz_per_mps": 0.2}, "cadence_slope_hz_per_mps needs cadence_intercept"),
    ],
)
def test_bad_cadence_coefficients_are_rejected_by_name(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=f"StanceMotion.{name}"):
        StanceMotion(**kwargs)
    with pytest.raises(ValueError, match=f"StanceRandomization.{name}"):
        StanceRandomization(**kwargs)


def test_bad_cadence_spread_is_rejected_by_name(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="cadence_log10_std must be in"):
        StanceRandomization(cadence_intercept_hz=0.7, cadence_log10_std=0.5)
    with pytest.raises(ValueError, match="cadence_log10_std needs cadence_intercept_hz"):
        StanceRandomization(cadence_log10_std=0.05)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"cadence_intercept_hz": 0.7, "cadence_slope_hz_per_mps": -1.0}))
    with pytest.raises(ValueError, match=r"bad\.json.*cadence_intercept_hz, cadence_slope"):
        model_from_json(path)


def test_a_model_file_carries_the_law(tmp_path: Path) -> None:
    path = tmp_path / "law.json"
    values = {"flat_fraction": 0.3, "cadence_intercept_hz": 0.71, "cadence_log10_std": 0.06}
    path.write_text(json.dumps({"randomization": {**values, "cadence_slope_hz_per_mps": 0.13}}))
    stance = model_from_json(path).stance
    assert stance is not None
    assert (stance.cadence_intercept_hz, stance.cadence_slope_hz_per_mps) == (0.71, 0.13)
    assert stance.cadence_log10_std == 0.06
    path.write_text(json.dumps({"flat_fraction": 0.3, "cadence_intercept_hz": None}))
    stance = model_from_json(path).stance
    assert stance is not None and stance.cadence_intercept_hz is None
