"""The opt-in mid-swing pitch at the midpoint (StanceMotion.mid_pitch_midpoint): each
walking stride's mid-swing knot moves to the midpoint of its toe-off and heel-strike
knots with the same jitter; off, nothing changes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pednav_env.gait.foot_route import Gait
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization


def route(on: bool):
    stance = replace(StanceRandomization.calibrated(), mid_pitch_midpoint=on)
    rng = np.random.default_rng(5400)
    walker = stance.draw(rng)
    cfg = SpeedRouteConfig(speed_mps=(0.5, 1.8), duration_s=(15.0, 15.0), stance_motion=walker)
    return walker, speed_route(rng, cfg)


def test_the_mid_swing_knot_moves_to_the_midpoint():
    walker, on = route(True)
    _, off = route(False)
    k = walker.swing_pitch_scale  # the calibrated walkers' scale does not vary with speed
    walking = 0
    for a, b in zip(on.strides, off.strides, strict=True):
        sa, sb = a.shape, b.shape
        assert (sa.toe_off_pitch, sa.heel_strike_pitch) == (sb.toe_off_pitch, sb.heel_strike_pitch)
        if sa.gait is Gait.RUN:
            assert sa.mid_swing_pitch == sb.mid_swing_pitch
            continue
        walking += 1
        midpoint = 0.5 * (sa.toe_off_pitch + sa.heel_strike_pitch)
        # on: k·(midpoint/k + draw − 0.05); off: k·draw
        assert sa.mid_swing_pitch - sb.mid_swing_pitch == pytest.approx(midpoint - 0.05 * k)
    assert walking > 5


def test_the_flag_draws_nothing_and_is_checked():
    on = replace(StanceRandomization.calibrated(), mid_pitch_midpoint=True)
    a = on.draw(np.random.default_rng(3))
    b = StanceRandomization.calibrated().draw(np.random.default_rng(3))
    assert a.mid_pitch_midpoint and replace(a, mid_pitch_midpoint=False) == b
    with pytest.raises(ValueError, match=r"StanceMotion\.mid_pitch_midpoint must be True"):
        StanceMotion(mid_pitch_midpoint=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"StanceRandomization\.mid_pitch_midpoint"):
        StanceRandomization(mid_pitch_midpoint="yes")  # type: ignore[arg-type]
