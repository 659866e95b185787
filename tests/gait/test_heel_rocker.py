"""The opt-in heel strike (StanceMotion.heel_rocker): the heel lands at rest on its
footfall and stays there while the foot rolls down; off, nothing changes."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.interpolate import CubicSpline, PPoly

from pednav_env.gait.foot import FootSimConfig, build_schedule, simulate_foot
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.splines import (
    clamped_cubic_coefficients,
    monotone_clamped_cubic_coefficients,
)
from pednav_env.gait.stance_motion import StanceMotion, StanceRandomization

#: Speed bands of the walks checked: slow walks, walking, fast walking and running.
BANDS = ((0.3, 0.5), (0.8, 1.3), (1.5, 3.0))
HEEL = FootSimConfig(rate_hz=400.0, lever_arm_m=(0.0, 0.0, 0.0))


def walks(heel_rocker: bool, band: tuple[float, float], n: int = 3, seed: int = 5100) -> list:
    """``n`` routes of the calibrated walkers (turns, stops), with the flag as given."""
    stance = replace(StanceRandomization.calibrated(), heel_rocker=heel_rocker)
    routes = []
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        cfg = SpeedRouteConfig(
            speed_mps=band, duration_s=(15.0, 20.0), stance_motion=stance.draw(rng)
        )
        routes.append(speed_route(rng, cfg))
    return routes


def footfalls(route) -> tuple[np.ndarray, np.ndarray]:
    """Footfall k (heel position of stance k) and the heading after stride k, from the
    route's strides: each stride turns, then puts the heel its length ahead."""
    heading = np.cumsum([s.heading_change for s in route.strides])
    forward = np.stack((np.cos(heading), np.sin(heading)), axis=1)
    lengths = np.array([s.shape.stride_length_m for s in route.strides])
    steps = lengths[:, None] * forward
    return np.vstack(([0.0, 0.0], np.cumsum(steps, axis=0))), forward


def heel_excursions(routes, config: FootSimConfig = HEEL) -> tuple[float, float]:
    """The largest distance (m) the heel gets ahead of the footfall it is heading to,
    along the heading after the stride, and the deepest it gets below the ground (m),
    over every cycle of the walks (IMU at the heel: its position is the heel's)."""
    traj = simulate_foot(routes, config, full_state=False)
    ahead, below = -np.inf, -np.inf
    for i, route in enumerate(routes):
        feet, forward = footfalls(route)
        pos = traj.pos_n[i, 1:]  # the state after sample m, labelled with sample m
        for k in range(len(route.strides)):
            cycle = traj.gait_step[i] == k
            assert cycle.any()
            rel = pos[cycle, :2] - feet[k + 1]
            ahead = max(ahead, float((rel @ forward[k]).max()))
            below = max(below, float(-pos[cycle, 2].min()))
    return ahead, below


@pytest.mark.parametrize("band", BANDS)
def test_with_the_flag_the_heel_never_passes_its_footfall_nor_the_ground(band) -> None:
    # the moving phases alone (route.realistic off leaves out the heel-strike
    # transient, which the kernels add on top: next test)
    routes = [replace(r, realistic=False) for r in walks(True, band)]
    ahead, below = heel_excursions(routes)
    assert ahead <= 1e-9 and below <= 1e-9
    # the same walks without the flag: the heel runs past the footfall and below ground
    old = [replace(r, realistic=False) for r in walks(False, band)]
    ahead_old, below_old = heel_excursions(old)
    assert ahead_old > 0.02 and below_old > 0.005


def test_with_the_heel_strike_transient_the_heel_stays_within_a_millimetre() -> None:
    # the realistic heel-strike transient (a decaying oscillation of the heel pad,
    # peak acceleration 10 v² m/s²) still moves the heel a fraction of a millimetre
    # about its footfall; without the flag the heel runs centimetres past it
    ahead, below = heel_excursions(walks(True, (1.5, 3.0)))
    assert 0 < ahead < 1e-3 and 0 < below < 1e-3
    ahead_old, _ = heel_excursions(walks(False, (1.5, 3.0)))
    assert ahead_old > 0.02


def test_the_foot_rolls_about_the_resting_heel() -> None:
    route = walks(True, (0.8, 1.3), n=1)[0]
    sched = build_schedule(route)
    old = build_schedule(
        replace(route, stance_motion=replace(route.stance_motion, heel_rocker=False))
    )
    np.testing.assert_array_equal(sched.breaks, old.breaks)
    # the angles are those of the walk without the flag
    np.testing.assert_allclose(sched.coefs[:, 3:], old.coefs[:, 3:], rtol=0, atol=1e-12)
    pp = sched.pp
    feet, _ = footfalls(route)
    for k, t_hs in enumerate(sched.strike_t):
        t_next = sched.stance_start[k + 1]
        # at rest on the footfall from the strike knot to the next stance ...
        for t in np.linspace(t_hs, t_next, 7):
            np.testing.assert_allclose(pp(t)[:2], feet[k + 1], atol=1e-12)
            assert abs(pp(t)[2]) < 1e-12
            np.testing.assert_allclose(pp(t, 1)[:3], 0.0, atol=1e-12)
        # ... while the foot pitches from toes-up down to flat
        assert pp(t_hs)[4] < -0.1 and abs(pp(t_next)[4]) < 1e-12
    # the heel's position is C¹ everywhere (values and rates match across every break)
    eps = 1e-7
    for b in pp.x[1:-1]:
        np.testing.assert_allclose(pp(b - eps)[:3], pp(b + eps)[:3], atol=1e-6)
        np.testing.assert_allclose(pp(b - eps, 1)[:3], pp(b + eps, 1)[:3], atol=1e-5)


def test_without_the_flag_the_walk_is_the_clamped_spline_through_all_knots() -> None:
    route = walks(False, (0.8, 1.3), n=1)[0]
    sched = build_schedule(route)
    # one moving phase: scipy's clamped spline through its five knots
    pieces = np.flatnonzero(np.any(sched.coefs[:3] != 0, axis=(0, 1)))
    first = pieces[0]
    t = sched.breaks[first : first + 5]
    y = np.array([sched.pp(v) for v in t])
    y[-1] = sched.pp(t[-1] + 1e-9)  # the next stance's constant (continuity)
    spline = CubicSpline(t, y, bc_type="clamped")
    for v in np.linspace(t[0], t[-1], 31):
        np.testing.assert_allclose(sched.pp(v), spline(v), atol=1e-9)


def test_the_flag_draws_nothing_and_is_checked() -> None:
    on = replace(StanceRandomization.calibrated(), heel_rocker=True)
    a = on.draw(np.random.default_rng(3))
    b = StanceRandomization.calibrated().draw(np.random.default_rng(3))
    assert a.heel_rocker and not b.heel_rocker
    assert replace(a, heel_rocker=False) == b
    with pytest.raises(ValueError, match=r"StanceMotion\.heel_rocker must be True or False"):
        StanceMotion(heel_rocker=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"StanceRandomization\.heel_rocker"):
        StanceRandomization(heel_rocker="yes")  # type: ignore[arg-type]


def test_monotone_spline_equals_the_clamped_one_where_no_slope_is_limited() -> None:
    t = np.array([[0.0, 0.3, 0.7, 1.0]])
    y = np.array([[[0.0], [0.3], [0.7], [1.0]]])  # a straight line: slopes within 3δ
    np.testing.assert_allclose(
        monotone_clamped_cubic_coefficients(t, y), clamped_cubic_coefficients(t, y), atol=1e-12
    )


def test_monotone_spline_keeps_each_piece_between_its_knots() -> None:
    # a fast middle and flat ends: the clamped C² spline overshoots the last knot
    # and dips below the first; the limited one does not, and stays C¹
    t = np.array([[0.0, 0.2, 0.25, 0.5]])
    y = np.array([[[0.0, 1.0], [0.1, 1.0], [0.9, 0.2], [1.0, 0.0]]])
    for func, monotone in (
        (clamped_cubic_coefficients, False),
        (monotone_clamped_cubic_coefficients, True),
    ):
        pp = PPoly(func(t, y), t[0])
        inside = []
        for k in range(3):
            s = np.linspace(t[0, k], t[0, k + 1], 201)
            v = pp(s)
            lo, hi = np.minimum(y[0, k], y[0, k + 1]), np.maximum(y[0, k], y[0, k + 1])
            inside.append(np.all((v >= lo - 1e-12) & (v <= hi + 1e-12)))
        assert all(inside) == monotone
    pp = PPoly(monotone_clamped_cubic_coefficients(t, y), t[0])
    np.testing.assert_allclose(pp(t[0, [0, -1]], 1), 0.0, atol=1e-12)  # at rest at both ends
    for b in t[0, 1:-1]:
        np.testing.assert_allclose(pp(b - 1e-9, 1), pp(b + 1e-9, 1), atol=1e-5)
    assert math.isclose(float(pp(0.5)[0]), 1.0)
