"""Routes in a speed band (gait.speed_route): every stride's speed in the band, the gait
following the speed."""

from dataclasses import fields

import numpy as np

from pednav_env.gait.foot_route import Gait, StrideShape
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route


def test_speed_route_strides_stay_in_the_band_and_gait_follows_speed() -> None:
    for band in ((0.3, 0.8), (1.3, 1.8), (2.6, 3.8)):
        route = speed_route(np.random.default_rng(3), SpeedRouteConfig(speed_mps=band))
        speeds = np.array([s.shape.speed for s in route.strides])
        assert speeds.min() >= band[0] - 1e-12 and speeds.max() <= band[1] + 1e-12
        gaits = {s.shape.gait for s in route.strides}
        if band[0] >= 2.0:
            assert gaits == {Gait.RUN}
        if band[1] <= 0.8:
            assert Gait.RUN not in gaits and Gait.FAST_WALK not in gaits


def test_the_fastest_runs_stay_within_the_leg_model() -> None:
    # at 3.9–4 m/s a drawn running cycle (0.65–0.8 s) would make strides up to 3.2 m;
    # every stride must pass StrideShape's own checks (the leg model's 3.118 m at most)
    route = speed_route(np.random.default_rng(0), SpeedRouteConfig(speed_mps=(3.9, 4.0)))
    for stride in route.strides:
        StrideShape(**{f.name: getattr(stride.shape, f.name) for f in fields(StrideShape)})
        assert 3.9 - 1e-9 <= stride.shape.speed <= 4.0 + 1e-9
