"""random_route and build_schedule against the plain numpy calls they stand for.

random_route draws its gait classes with pednav_env.draws, its stride values as
``low + (high − low) · rng.random``, and builds strides without their checks;
build_schedule computes the strides' speeds in one array. The references here
are the plain forms (``rng.choice``, ``rng.uniform``, checked constructors, the
``speed`` property), written out in the test."""

import math

import numpy as np
import pytest

from pednav_env.gait.foot import build_schedule
from pednav_env.gait.foot_route import (
    RUN_DRAWS,
    WALK_DRAWS,
    Gait,
    Route,
    RouteRandomization,
    Stride,
    StrideShape,
    random_route,
)

WALK_COLUMN = {Gait.SLOW_WALK: 0, Gait.WALK: 2, Gait.FAST_WALK: 4}


def reference_shape(rng: np.random.Generator, gait: Gait) -> StrideShape:
    """One stride shape from one ``rng.uniform`` call over the draws' ranges, checked."""
    ranges = np.array(RUN_DRAWS if gait is Gait.RUN else WALK_DRAWS)
    row = rng.uniform(ranges[:, 0], ranges[:, 1]).tolist()
    if gait is Gait.RUN:
        length, cycle, stance_frac, height, toe_off, heel_strike, pitch, roll = row
        t0, t1 = stance_frac * cycle, 0.10 * cycle
        t2, heel_strike = cycle - t0 - 2 * t1, -heel_strike
    else:
        length, cycle = row[WALK_COLUMN[gait]], row[WALK_COLUMN[gait] + 1]
        a, d_height, d_toe_off, pitch, roll = row[6:]
        t0, t1, t2 = a * cycle, (0.5 - a) * cycle, a * cycle
        speed = length / cycle
        height = 0.06 + 0.04 * speed + d_height
        toe_off, heel_strike = 0.4 + 0.3 * speed + d_toe_off, -(0.2 + 0.1 * speed)
    return StrideShape(
        stride_length_m=length,
        stance_s=t0,
        heel_off_s=t1,
        swing_s=t2,
        heel_strike_s=t1,
        swing_height_m=height,
        mid_swing_pitch=pitch,
        mid_swing_roll=roll,
        toe_off_pitch=toe_off,
        heel_strike_pitch=heel_strike,
        gait=gait,
    )


def reference_route(rng: np.random.Generator, cfg: RouteRandomization) -> Route:
    """random_route's walk drawn with rng.choice and one rng.uniform per stride."""
    target = rng.uniform(*cfg.duration_s)
    w = np.asarray(cfg.gait_weights, dtype=float)
    strides: list[Stride] = []
    elapsed = 3.0
    while True:
        gait = [Gait.SLOW_WALK, Gait.WALK, Gait.FAST_WALK, Gait.RUN][
            int(rng.choice(4, p=w / w.sum()))
        ]
        n_leg = int(rng.integers(cfg.leg_strides[0], cfg.leg_strides[1] + 1))
        turn_total = rng.uniform(-math.pi, math.pi)
        n_turn = max(1, math.ceil(abs(turn_total) / cfg.max_turn_per_stride))
        stop = rng.uniform(*cfg.stop_s) if rng.uniform() < cfg.stop_probability else 0.0
        shapes = [reference_shape(rng, gait) for _ in range(n_leg)]
        for i, shape in enumerate(shapes):
            s = Stride(
                shape,
                heading_change=turn_total / n_turn if i < n_turn else 0.0,
                stop_s=stop if i == 0 else 0.0,
            )
            if elapsed + s.shape.cycle_s + s.stop_s > target and strides:
                phases = tuple(rng.uniform(0, 2 * math.pi, 3))
                return Route(tuple(strides), 2.0, 1.0, realistic=True, seed_phases=phases)
            strides.append(s)
            elapsed += s.shape.cycle_s + s.stop_s


@pytest.mark.parametrize(
    "cfg",
    [
        RouteRandomization(),
        RouteRandomization(gait_weights=(0.0, 0.0, 0.0, 1.0), stop_probability=1.0),
        RouteRandomization(duration_s=(2.0, 6.0), leg_strides=(1, 2)),
    ],
)
def test_random_route_is_the_plain_draws(cfg):
    for seed in range(40):
        ours, plain = np.random.default_rng(seed), np.random.default_rng(seed)
        route = random_route(ours, cfg)
        expected = reference_route(plain, cfg)
        assert route == expected
        # the unchecked strides' values are the exact floats (== would take −0 for +0)
        assert repr(route) == repr(expected)
        assert ours.bit_generator.state == plain.bit_generator.state


def test_schedule_speeds_and_gaits_are_the_strides():
    for seed in range(20):
        route = random_route(np.random.default_rng(seed))
        sched = build_schedule(route)
        speeds = [s.shape.speed for s in route.strides]
        np.testing.assert_array_equal(sched.stance_speed[: len(speeds)], speeds)
        assert sched.span_gait.tolist() == [int(s.shape.gait) for s in route.strides]
        assert sched.span_gait.dtype == np.int64
