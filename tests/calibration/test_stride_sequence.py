"""A walk's strides in order (calibration.path_turns.stride_sequence), routes that walk
them (gait.speed_route.footfall_route) and twins that do (SimModel.footfall_batch)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from testdata import PYSHOE_SAMPLE

from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.path_turns import stride_sequence
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import WalkSamples
from pednav_env.gait.foot_route import Gait
from pednav_env.gait.speed_route import footfall_route

RATE_HZ = 100.0


def printed(points, times_s) -> WalkSamples:
    n = int(max(times_s) * RATE_HZ) + 10
    return WalkSamples(
        np.zeros((n, 3)),
        np.tile([0.0, 0.0, 9.81], (n, 1)),
        RATE_HZ,
        footfall_index=(np.asarray(times_s) * RATE_HZ).astype(np.int64),
        footprints_m=np.asarray(points, dtype=float),
    )


def test_strides_from_footprints():
    # 1 m east in 1 s; a stand of 2 s (two footprints 5 cm apart: one footfall, at the
    # first); then 1.05 m north from it in 0.5 s
    walk = printed([[0, 0], [1, 0], [1, 0.05], [1, 1.05]], [0.0, 1.0, 3.0, 3.5])
    seq = stride_sequence(walk)
    np.testing.assert_allclose(seq.speed_mps, [1.0, 2.1])
    np.testing.assert_allclose(seq.turn_rad, [0.0, math.pi / 2])
    np.testing.assert_allclose(seq.stop_s, [0.0, 2.0])


def test_a_long_gap_is_a_stand_then_a_stride():
    walk = printed([[0, 0], [1.5, 0], [3.0, 0]], [0.0, 1.0, 6.0])
    seq = stride_sequence(walk)  # the second gap, 5 s: 1.5 s walked, 3.5 s stood
    np.testing.assert_allclose(seq.speed_mps, [1.5, 1.0])
    np.testing.assert_allclose(seq.stop_s, [0.0, 3.5])
    assert stride_sequence(printed([[0, 0], [0.1, 0]], [0.0, 1.0])).speed_mps.size == 0


def test_footfall_route_walks_the_strides_given():
    rng = np.random.default_rng(1)
    route = footfall_route(rng, [0.5, 1.4, 2.8], [0.0, 0.4, -0.3], [0.0, 1.5, 0.0])
    assert [s.shape.gait for s in route.strides] == [Gait.SLOW_WALK, Gait.FAST_WALK, Gait.RUN]
    np.testing.assert_allclose([s.shape.speed for s in route.strides], [0.5, 1.4, 2.8])
    assert [s.heading_change for s in route.strides] == [0.0, 0.4, -0.3]
    assert [s.stop_s for s in route.strides] == [0.0, 1.5, 0.0]
    assert route.initial_stand_s == 2.0
    later = footfall_route(rng, [1.0, 1.0], [0.0, 0.0], [3.5, 0.0])  # a longer first stand
    assert later.initial_stand_s == 3.5 and later.strides[0].stop_s == 0.0
    fast = footfall_route(rng, [5.0], [0.0], [0.0])  # clipped to the generator's 3.8 m/s
    assert fast.strides[0].shape.speed == pytest.approx(3.8)
    with pytest.raises(ValueError, match="one entry per stride"):
        footfall_route(rng, [1.0, 1.0], [0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="speed must be > 0"):
        footfall_route(rng, [0.0], [0.0], [0.0])
    with pytest.raises(ValueError, match="stop_s"):
        footfall_route(rng, [1.0], [0.0], [-1.0])


def test_twins_walk_the_strides_given_measured_on_their_truth():
    # 12 strides at 1.0 m/s turning 0.8 rad each, a 2 s stand before the seventh; the
    # first after the route's own 2 s stand
    speed, turn, stop = [1.0] * 12, [0.0] + [0.8] * 11, [0.0] * 6 + [2.0] + [0.0] * 5
    truth, imu = MODELS["calibrated"].footfall_batch(speed, turn, stop, 2, 4)
    for i in range(2):
        twin = stride_sequence(samples_from_simulation(truth, imu, i))
        assert twin.speed_mps.size == 12
        # footfall to footfall at the given speed, within the cycle's jitter
        np.testing.assert_allclose(twin.speed_mps, 1.0, rtol=0.1)
        np.testing.assert_allclose(np.abs(twin.turn_rad[1:]), 0.8, atol=0.1)
        assert twin.stop_s[6] == pytest.approx(2.0, abs=0.1)
        assert twin.stop_s[0] == pytest.approx(2.0, abs=0.1)
    assert stride_sequence(load_walk(PYSHOE_SAMPLE)).speed_mps.size >= 3


def labelled(split_gap_s: float = 0.0) -> WalkSamples:
    """Four stances 1 m apart (0.5 s each, swings of 0.6 s along x), stance labels and
    truth; the second stance split by ``split_gap_s`` of flickered labels (the foot still)."""
    rate = RATE_HZ
    labels, xs = [], []
    for k in range(4):
        n_st = int(0.5 * rate)
        stance = [True] * n_st
        if k == 1 and split_gap_s:
            gap = int(split_gap_s * rate)
            stance[20 : 20 + gap] = [False] * gap
        labels += stance
        xs += [float(k)] * n_st
        if k < 3:
            n_sw = int(0.6 * rate)
            labels += [False] * n_sw
            xs += list(k + (np.arange(n_sw) + 1) / (n_sw + 1))
    n = len(labels)
    pos = np.zeros((n, 3))
    pos[:, 0] = xs
    omega = np.where(np.array(labels)[:, None], 0.0, 3.0) * np.ones((n, 3))
    return WalkSamples(
        omega, np.tile([0.0, 0.0, 9.81], (n, 1)), rate, stance=np.array(labels), truth_pos=pos
    )


def test_split_stances_and_truth_glitches_make_no_false_strides():
    whole = stride_sequence(labelled())
    np.testing.assert_allclose(whole.speed_mps, 1.0 / 1.1, rtol=0.02)  # 1 m per 1.1 s cycle
    split = stride_sequence(labelled(split_gap_s=0.06))  # the foot did not move: one stance
    np.testing.assert_allclose(split.speed_mps, whole.speed_mps)
    glitched = labelled()
    pos = glitched.truth_pos.copy()
    pos[110:130, 0] = 3.0  # the second stance (x = 1 m): a frozen, wrong track, then a jump
    jumped = stride_sequence(replace(glitched, truth_pos=pos))
    np.testing.assert_allclose(jumped.speed_mps, whole.speed_mps)
