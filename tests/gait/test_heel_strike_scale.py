"""The opt-in heel-strike share (StanceMotion.heel_strike_scale): the walking cycle's
shares, the strides it builds, its checks; at 1 nothing changes."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization


def test_the_cycle_shares():
    walker = StanceMotion(flat_fraction=0.3, heel_fraction=0.2, heel_strike_scale=0.5)
    flat, heel, swing = walker.cycle_fractions(1.0)
    assert (flat, heel) == (0.3, 0.2)
    assert swing == pytest.approx(1.0 - 0.3 - 0.2 - 0.1)
    same = StanceMotion(flat_fraction=0.3, heel_fraction=0.2)
    assert same.cycle_fractions(1.0) == (0.3, 0.2, 1.0 - 0.3 - 2.0 * 0.2)


def route(scale: float):
    stance = replace(StanceRandomization.calibrated(), heel_strike_scale=scale)
    rng = np.random.default_rng(5300)
    cfg = SpeedRouteConfig(
        speed_mps=(0.8, 1.3), duration_s=(12.0, 12.0), stance_motion=stance.draw(rng)
    )
    return speed_route(rng, cfg)


def test_every_walking_stride_strikes_for_the_scaled_share():
    short, equal = route(0.77), route(1.0)
    assert len(short.strides) == len(equal.strides)
    for a, b in zip(short.strides, equal.strides, strict=True):
        sa, sb = a.shape, b.shape
        assert sa.heel_strike_s == pytest.approx(0.77 * sa.heel_off_s)
        assert sb.heel_strike_s == sb.heel_off_s
        # the cycle keeps its length: the swing takes what heel strike gives up
        cycle_a = sa.stance_s + sa.heel_off_s + sa.swing_s + sa.heel_strike_s
        cycle_b = sb.stance_s + sb.heel_off_s + sb.swing_s + sb.heel_strike_s
        assert cycle_a == pytest.approx(cycle_b)
        assert sa.swing_s > sb.swing_s


def test_the_scale_is_checked_and_drawn():
    a = replace(StanceRandomization.calibrated(), heel_strike_scale=0.77)
    assert a.draw(np.random.default_rng(1)).heel_strike_scale == 0.77
    for bad in (0.1, 2.5, math.nan):
        with pytest.raises(ValueError, match=r"StanceMotion\.heel_strike_scale must be in"):
            StanceMotion(heel_strike_scale=bad)
        with pytest.raises(ValueError, match=r"StanceRandomization\.heel_strike_scale"):
            StanceRandomization(heel_strike_scale=bad)
