"""The opt-in monotone swing pitch (StanceMotion.monotone_pitch): the pitch stays
between its knots' values on every piece, only the pitch row changes, and off nothing
changes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pednav_env.gait.foot import build_schedule
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization

PITCH = 4  # rows x, y, z, ψ, θ, γ


def route(monotone: bool, heel_rocker: bool = False, band=(0.8, 1.3), seed: int = 5200):
    stance = replace(
        StanceRandomization.calibrated(), heel_rocker=heel_rocker, monotone_pitch=monotone
    )
    rng = np.random.default_rng(seed)
    cfg = SpeedRouteConfig(speed_mps=band, duration_s=(15.0, 20.0), stance_motion=stance.draw(rng))
    return speed_route(rng, cfg)


def pitch_overshoot(sched) -> float:
    """The largest distance (rad) the pitch gets outside the range of its two knots over
    any piece of the walk."""
    pp = sched.pp
    worst = 0.0
    for a, b in zip(sched.breaks[:-1], sched.breaks[1:], strict=True):
        ends = pp(np.array([a, b - 1e-12]))[:, PITCH]
        inside = pp(np.linspace(a, b, 41)[1:-1])[:, PITCH]
        worst = max(worst, float(np.max(inside) - ends.max()), float(ends.min() - np.min(inside)))
    return worst


@pytest.mark.parametrize("heel_rocker", [False, True])
@pytest.mark.parametrize("band", [(0.3, 0.5), (0.8, 1.3), (1.5, 3.0)])
def test_the_monotone_pitch_stays_between_its_knots(heel_rocker, band) -> None:
    on = build_schedule(route(True, heel_rocker, band))
    off = build_schedule(route(False, heel_rocker, band))
    assert pitch_overshoot(on) < 1e-9
    assert pitch_overshoot(off) > 1e-3  # the clamped C² spline overshoots somewhere
    np.testing.assert_array_equal(on.breaks, off.breaks)
    # every other row is the walk without the flag
    rows = [r for r in range(6) if r != PITCH]
    np.testing.assert_array_equal(on.coefs[:, rows], off.coefs[:, rows])


def test_the_flag_draws_nothing_and_is_checked() -> None:
    on = replace(StanceRandomization.calibrated(), monotone_pitch=True)
    a = on.draw(np.random.default_rng(3))
    b = StanceRandomization.calibrated().draw(np.random.default_rng(3))
    assert a.monotone_pitch and not b.monotone_pitch
    assert replace(a, monotone_pitch=False) == b
    with pytest.raises(ValueError, match=r"StanceMotion\.monotone_pitch must be True or False"):
        StanceMotion(monotone_pitch=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"StanceRandomization\.monotone_pitch"):
        StanceRandomization(monotone_pitch="yes")  # type: ignore[arg-type]
