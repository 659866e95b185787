"""Foot gait simulator (paper 003's model and its realistic extension)."""

import math

import numpy as np
import pytest

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.gait.foot import FootSimConfig, build_schedule, simulate_foot
from pednav_env.gait.foot_route import (
    Gait,
    RouteRandomization,
    Stride,
    StrideShape,
    paper_stride_shape,
    random_route,
    square_route,
)


def test_paper_stance_is_exactly_static(paper_walk):
    st = paper_walk.stance
    assert st.mean() > 0.3  # stances are there at all
    np.testing.assert_array_equal(paper_walk.omega_b[st], 0.0)
    f_st = paper_walk.f_b[st]
    np.testing.assert_allclose(
        f_st, np.broadcast_to([0.0, 0.0, STANDARD_GRAVITY], f_st.shape), atol=1e-12
    )
    # velocity on the grid points bounding stance samples
    idx = np.flatnonzero(st[0])
    np.testing.assert_allclose(paper_walk.vel_n[0, idx], 0.0, atol=1e-12)
    np.testing.assert_allclose(paper_walk.vel_n[0, idx + 1], 0.0, atol=1e-12)


def test_paper_square_closes_and_has_the_right_length(paper_walk):
    # 3 m square, 1 m strides: the heel ends where it started, heading south, so
    # the IMU (lever arm 0.1 m forward) ends at (0, −0.1) − (0.1, 0) from its start.
    np.testing.assert_allclose(paper_walk.pos_n[0, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(paper_walk.pos_n[0, -1], [-0.1, -0.1, 0.0], atol=1e-9)
    # the heel walks 12 m; the IMU, 11 cm off the heel, also sways as the foot
    # pitches (±0.5 rad) and turns: a few cm per stride more, never less.
    assert 12.0 < paper_walk.distance_m[0, -1] < 12.0 * 1.05
    # every stance IMU height equals the initial one (flat ground, h = x₃ = 0)
    np.testing.assert_allclose(paper_walk.pos_n[0, :-1][paper_walk.stance[0], 2], 0.0, atol=1e-12)


def test_spline_is_c2_inside_moving_phases_and_c1_at_stances():
    route = square_route(2.0, paper_stride_shape(1.0))
    pp = build_schedule(route).pp
    eps = 1e-7
    stance_breaks = []
    for i, b in enumerate(pp.x[1:-1], start=1):
        left = [pp(b - eps, nu) for nu in range(3)]
        right = [pp(b + eps, nu) for nu in range(3)]
        np.testing.assert_allclose(left[0], right[0], atol=1e-6)
        np.testing.assert_allclose(left[1], right[1], atol=1e-5)
        # second derivative: continuous unless one side is a constant stance piece
        constant_side = np.all(pp.c[:3, i - 1] == 0) or np.all(pp.c[:3, i] == 0)
        if constant_side:
            stance_breaks.append(b)
        else:
            np.testing.assert_allclose(left[2], right[2], atol=1e-4)
    assert len(stance_breaks) >= 2 * len(route.strides) - 1


def test_lever_arm_kinematics_against_finite_differences(realistic_walk):
    """Truth velocity is the derivative of position, and the specific force the
    accelerometers see integrates (in nav axes) to the truth velocity."""
    tr = realistic_walk
    dt = 1.0 / tr.rate_hz
    vel_fd = np.gradient(tr.pos_n[0], dt, axis=0)
    err = np.abs(vel_fd[2:-2] - tr.vel_n[0, 2:-2])
    # central differences err by dt²/6·|jerk|: tens of m/s³ at heel strike → < 0.03 m/s
    assert np.percentile(err, 99) < 0.03
    # Δv over one sample from the averaged specific force with mid-sample attitude
    from pednav_env.rotations import euler_to_dcm

    e_mid = 0.5 * (tr.euler[0, :-1] + tr.euler[0, 1:])
    acc = np.einsum("tij,tj->ti", euler_to_dcm(e_mid), tr.f_b[0]) - [0, 0, STANDARD_GRAVITY]
    dv = np.diff(tr.vel_n[0], axis=0) / dt
    assert np.median(np.abs(acc - dv)) < 0.05
    assert np.percentile(np.abs(acc - dv), 95) < 1.0


def test_realistic_stances_are_not_still_and_grow_with_speed():
    rng = np.random.default_rng(7)
    slow = StrideShape(
        stride_length_m=0.6, gait=Gait.SLOW_WALK, toe_off_pitch=0.5, heel_strike_pitch=-0.2
    )
    fast = StrideShape(
        stride_length_m=1.4,
        stance_s=0.3,
        heel_off_s=0.15,
        swing_s=0.3,
        heel_strike_s=0.15,
        gait=Gait.FAST_WALK,
        toe_off_pitch=0.8,
        heel_strike_pitch=-0.3,
    )
    from pednav_env.gait.foot_route import Route

    stance_rate = []
    for shape in (slow, fast):
        route = Route(
            tuple(Stride(shape) for _ in range(6)),
            1.0,
            1.0,
            realistic=True,
            seed_phases=tuple(rng.uniform(0, 6, 3)),
        )
        tr = simulate_foot(route)
        walking = tr.stance[0] & (tr.t[:-1] > 1.5) & (tr.t[:-1] < tr.duration_s[0] - 1.5)
        stance_rate.append(np.percentile(np.linalg.norm(tr.omega_b[0][walking], axis=-1), 90))
    assert stance_rate[0] > 0.01  # not perfectly still
    assert stance_rate[1] > 2 * stance_rate[0]


def test_random_routes_are_seeded_and_varied():
    a = random_route(np.random.default_rng(3))
    b = random_route(np.random.default_rng(3))
    c = random_route(np.random.default_rng(4))
    assert a == b
    assert a != c
    lo, hi = RouteRandomization().duration_s
    routes = [random_route(np.random.default_rng(s)) for s in range(30)]
    durations = [r.duration_s for r in routes]
    assert min(durations) >= lo - 3 and max(durations) <= hi
    gaits = {s.shape.gait for r in routes for s in r.strides}
    assert gaits == {Gait.SLOW_WALK, Gait.WALK, Gait.FAST_WALK, Gait.RUN}
    assert any(s.stop_s > 0 for r in routes for s in r.strides)
    lengths = [
        s.shape.stride_length_m for r in routes for s in r.strides if s.shape.gait != Gait.RUN
    ]
    assert 0.4 <= min(lengths) and max(lengths) <= 1.4


def test_batch_equals_single_walks():
    routes = [random_route(np.random.default_rng(s)) for s in (1, 2)]
    both = simulate_foot(routes)
    one = simulate_foot(routes[1])
    n = one.num_samples
    np.testing.assert_array_equal(both.omega_b[1, :n], one.omega_b[0])
    np.testing.assert_array_equal(both.pos_n[1, : n + 1], one.pos_n[0])
    # padding after the shorter walk is standing still
    if both.num_samples > n:
        assert np.all(both.stance[1, n:])


@pytest.mark.parametrize(
    ("factory", "name"),
    [
        (lambda: StrideShape(stride_length_m=-0.5), "stride_length_m"),
        (lambda: StrideShape(stride_length_m=3.5), "stride_length_m"),
        (lambda: StrideShape(stance_s=0.0), "stance_s"),
        (lambda: StrideShape(swing_height_m=1.0), "swing_height_m"),
        (lambda: StrideShape(mid_swing_pitch=math.nan), "mid_swing_pitch"),
        (lambda: StrideShape(leg_length_m=-1.0), "leg_length_m"),
        (lambda: Stride(StrideShape(), stop_s=-1.0), "stop_s"),
        (lambda: FootSimConfig(rate_hz=0.0), "rate_hz"),
        (lambda: FootSimConfig(rate_hz=math.inf), "rate_hz"),
        (lambda: square_route(5.0, paper_stride_shape(0.7)), "side_m"),
        (lambda: RouteRandomization(duration_s=(10.0, 5.0)), "duration_s"),
    ],
)
def test_impossible_configurations_raise(factory, name):
    with pytest.raises(ValueError, match=name):
        factory()
