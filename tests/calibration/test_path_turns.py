"""Turn per stride from footfall points (calibration.path_turns), and circling routes."""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from testdata import PYSHOE_SAMPLE

from pednav_env.calibration.compare import MODELS, band_turns, compare
from pednav_env.calibration.path_turns import (
    footfall_points,
    pooled_turn_range,
    stride_turns,
    turn_range,
)
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import WalkSamples, walk_stats
from pednav_env.gait.speed_route import SpeedRouteConfig


def test_turns_of_a_square_and_a_zigzag():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]])
    np.testing.assert_allclose(stride_turns(square), [math.pi / 2] * 3)
    zigzag = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 1.0]])
    np.testing.assert_allclose(stride_turns(zigzag), [math.pi / 4, -math.pi / 4])


def test_points_closer_than_a_stride_are_one_footfall():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.05, 0.0], [2.0, 0.0], [2.0, 1.0]])
    np.testing.assert_allclose(stride_turns(pts), [0.0, math.pi / 2])
    assert stride_turns(pts[:2]).size == 0


@pytest.mark.parametrize(
    ("points", "kwargs", "message"),
    [
        (np.zeros((4, 3)), {}, "points_m must be"),
        (np.array([[0.0, 0.0], [np.nan, 1.0], [2.0, 2.0]]), {}, "finite"),
        (np.zeros((4, 2)), {"min_stride_m": 0.0}, "min_stride_m"),
    ],
)
def test_bad_points(points, kwargs, message):
    with pytest.raises(ValueError, match=message):
        stride_turns(points, **kwargs)


def test_footprints_are_the_footfall_points():
    prints = np.array([[0.0, 0.0], [0.0, 1.0], [-1.0, 1.0], [-1.0, 0.0]])
    walk = WalkSamples(
        np.zeros((100, 3)),
        np.tile([0.0, 0.0, 9.81], (100, 1)),
        100.0,
        footfall_index=np.array([10, 40, 70, 90]),
        footprints_m=prints,
    )
    np.testing.assert_array_equal(footfall_points(walk), prints)
    assert turn_range(walk) is None  # two turns only


@pytest.mark.parametrize("bad", [(0.5, 0.2), (-0.1, 0.2), (0.2, 2.0), (float("nan"), 0.3)])
def test_route_turn_range_is_checked(bad):
    with pytest.raises(ValueError, match="turn_per_stride_rad"):
        SpeedRouteConfig(turn_per_stride_rad=bad)


def test_circling_walks_turn_as_drawn_measured_from_their_truth():
    truth, imu = MODELS["calibrated"].batch((0.9, 1.1), 4, 5, (30.0, 30.0), (0.8, 1.0))
    for i in range(4):
        lo, hi = turn_range(samples_from_simulation(truth, imu, i))
        assert 0.7 < lo <= hi < 1.1
    truth, imu = MODELS["calibrated"].batch((0.9, 1.1), 4, 5, (30.0, 30.0))
    straight = [turn_range(samples_from_simulation(truth, imu, i)) for i in range(4)]
    assert all(r is not None and r[0] < 0.05 for r in straight)


def test_each_walk_its_own_turn():
    truth, imu = MODELS["calibrated"].batch(
        (0.9, 1.1), 2, 5, (30.0, 30.0), turns_per_walk=[(0.8, 1.0), None]
    )
    lo, hi = turn_range(samples_from_simulation(truth, imu, 0))
    assert 0.7 < lo <= hi < 1.1
    assert turn_range(samples_from_simulation(truth, imu, 1))[0] < 0.05
    with pytest.raises(ValueError, match="turns_per_walk"):
        MODELS["calibrated"].batch((0.9, 1.1), 2, 5, (30.0, 30.0), turns_per_walk=[None])
    with pytest.raises(ValueError, match="not both"):
        MODELS["calibrated"].batch(
            (0.9, 1.1), 2, 5, (30.0, 30.0), (0.5, 0.6), turns_per_walk=[None, None]
        )


def _stats(name: str, turn):
    return SimpleNamespace(name=name, turn_per_stride_rad=turn)


def test_band_turns_spread_the_recordings_over_the_walks():
    recs = [_stats("a", (0.1, 0.2)), _stats("b", None), _stats("c", (1.0, 1.2))]
    assert band_turns([_stats("a", None), _stats("b", None)], 4) is None
    assert band_turns(recs, 6) == [(0.1, 0.2), (0.1, 0.2), None, None, (1.0, 1.2), (1.0, 1.2)]
    assert band_turns(recs, 2) == [(0.1, 0.2), None]


def test_compare_walks_the_circles_of_recordings_that_carry_their_turn():
    stats = walk_stats(load_walk(PYSHOE_SAMPLE))
    assert stats.turn_per_stride_rad is None  # walk_stats leaves it unset
    circling = replace(stats, turn_per_stride_rad=(0.8, 1.0))
    plain = compare([stats], MODELS["calibrated"], 2, 3)
    turned = compare([circling], MODELS["calibrated"], 2, 3)
    band = next(i for i, b in enumerate(plain.bands) if b.real)
    assert not np.array_equal(plain.bands[band].sim[0].log_shoe, turned.bands[band].sim[0].log_shoe)
    other = next(i for i, b in enumerate(plain.bands) if not b.real)  # no recording: no circles
    np.testing.assert_array_equal(
        plain.bands[other].sim[0].log_shoe, turned.bands[other].sim[0].log_shoe
    )


def test_pooled_turn_range_over_walks():
    def walk_with(prints):
        prints = np.asarray(prints, dtype=float)
        n = len(prints)
        return WalkSamples(
            np.zeros((100, 3)),
            np.tile([0.0, 0.0, 9.81], (100, 1)),
            100.0,
            footfall_index=np.arange(n) * 10,
            footprints_m=prints,
        )

    square = walk_with([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]])  # three turns of π/2
    line = walk_with([[0, 0], [1, 0], [2, 0], [3, 0]])  # two of 0
    lo, hi = pooled_turn_range([square, line])
    # |turns| 0, 0, π/2, π/2, π/2: the 25th percentile 0, the 75th π/2
    assert lo == pytest.approx(0.0) and hi == pytest.approx(math.pi / 2)
    with pytest.raises(ValueError, match="need 3"):
        pooled_turn_range([line])
