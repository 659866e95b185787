"""The opt-in swing roll (StanceMotion.swing_roll_rad): every stride's mid-swing roll
knot gains the walker's roll, walking and running; off, nothing changes."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from pednav_env.gait.foot_route import Gait
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization


def route(roll: float):
    stance = replace(StanceRandomization.calibrated(), swing_roll_rad=roll)
    rng = np.random.default_rng(5500)
    cfg = SpeedRouteConfig(
        speed_mps=(0.8, 3.0), duration_s=(20.0, 20.0), stance_motion=stance.draw(rng)
    )
    return speed_route(rng, cfg)


def test_every_stride_rolls_by_the_walkers_roll():
    on, off = route(0.25), route(0.0)
    gaits = set()
    for a, b in zip(on.strides, off.strides, strict=True):
        gaits.add(a.shape.gait)
        assert a.shape.mid_swing_roll - b.shape.mid_swing_roll == pytest.approx(0.25)
        assert a.shape.mid_swing_pitch == b.shape.mid_swing_pitch
    assert Gait.RUN in gaits and len(gaits) > 1


def test_the_roll_is_checked_and_drawn():
    a = replace(StanceRandomization.calibrated(), swing_roll_rad=0.25)
    assert a.draw(np.random.default_rng(1)).swing_roll_rad == 0.25
    for bad in (0.6, -0.7, math.inf, True):
        with pytest.raises(ValueError, match=r"StanceMotion\.swing_roll_rad must be in"):
            StanceMotion(swing_roll_rad=bad)
        with pytest.raises(ValueError, match=r"StanceRandomization\.swing_roll_rad"):
            StanceRandomization(swing_roll_rad=bad)
