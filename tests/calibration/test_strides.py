"""Stride segmentation (calibration.strides): the minimum stride and the truth
glitches, alone and through walk_stats' strides and the cadence's."""

from __future__ import annotations

import numpy as np
import pytest
from labelled_walk import labelled_walk

from pednav_env.calibration.cadence import recorded_strides
from pednav_env.calibration.stats import WalkSamples, walk_stats
from pednav_env.calibration.strides import (
    MAX_TRUTH_SPEED_MPS,
    glitched_strides,
    merge_short_strides,
    overlaps_glitch,
    truth_glitches,
)

RATE = 200.0
#: Stances every 1 s (0.4 s long), the foot moving 1 m in each 0.6 s swing.
STANCES = [(0.0, 0.4), (1.0, 1.4), (2.0, 2.4), (3.0, 3.4), (4.0, 4.4)]
POSITIONS = [0.0, 1.0, 2.0, 3.0, 4.0]


def _walk(
    stances: list[tuple[float, float]],
    positions: list[float],
    freeze: tuple[float, float] | None = None,
    truth: bool = True,
) -> WalkSamples:
    return labelled_walk(stances, positions, RATE, freeze, truth)


@pytest.mark.parametrize(
    ("second", "merged"),
    [(26, True), (79, True), (80, False), (90, False)],  # 0.13 s, 0.395 s, 0.4 s, 0.45 s
)
def test_a_stride_shorter_than_the_minimum_joins_the_run_before(second: int, merged: bool) -> None:
    starts, ends = np.array([0, second, 400]), np.array([15, second + 60, 480])
    s, e = merge_short_strides(starts, ends, RATE)
    if merged:
        assert (s.tolist(), e.tolist()) == ([0, 400], [second + 60, 480])
    else:
        assert (s.tolist(), e.tolist()) == (starts.tolist(), ends.tolist())


def test_the_minimum_stride_counts_from_the_merged_run_start() -> None:
    # runs at 0, 0.2, 0.35 and 0.5 s: the second and third start less than 0.4 s after
    # the first (the merged run's start), the fourth 0.5 s after it
    starts, ends = np.array([0, 40, 70, 100]), np.array([20, 50, 80, 140])
    s, e = merge_short_strides(starts, ends, RATE)
    assert (s.tolist(), e.tolist()) == ([0, 100], [80, 140])


def test_a_landing_slide_is_not_a_stride() -> None:
    # the second stance touches down at 1.0 s, slides 5.8 cm by 1.13 s (a step for the
    # split-stance rule) and settles: a 0.13 s "stride" joins the stance before it
    stances = [(0.0, 0.4), (1.0, 1.075), (1.13, 1.5), (2.2, 2.6), (3.4, 3.8)]
    positions = [0.0, 1.0, 1.058, 2.0, 3.0]
    walk = _walk(stances, positions)
    st = walk_stats(walk).strides
    np.testing.assert_allclose(st.start_s, [0.0, 1.0, 2.2])
    np.testing.assert_allclose(st.duration_s, [1.0, 1.2, 1.2])
    np.testing.assert_allclose(st.stance_s, [0.4, 0.5, 0.4])
    np.testing.assert_allclose(recorded_strides(walk).cycle_s, [1.0, 1.2, 1.2])


@pytest.mark.parametrize(
    ("freeze", "left_out"),
    [
        ((1.6, 1.9), [[1.0, 2.0]]),  # inside the second stride's swing
        ((1.9, 2.1), [[1.0, 2.0], [2.0, 3.0]]),  # across the third stride's start
    ],
)
def test_frozen_then_jumping_truth_leaves_out_the_strides_it_overlaps(
    freeze: tuple[float, float], left_out: list[list[float]]
) -> None:
    walk = _walk(STANCES, POSITIONS, freeze)
    glitches = truth_glitches(walk.truth_pos, RATE)
    assert (glitches / RATE).tolist() == [[freeze[0], freeze[1]]]
    kept = [t for t in (0.0, 1.0, 2.0, 3.0) if [t, t + 1.0] not in left_out]
    s = walk_stats(walk)
    np.testing.assert_allclose(s.strides.start_s, kept)
    np.testing.assert_allclose(s.strides.speed_mps, 1.0)
    np.testing.assert_allclose(s.strides.glitch_left_out_s, left_out)
    summary = s.summary()
    assert summary["strides"] == len(kept)
    assert summary["strides_left_out_truth_glitch"] == len(left_out)
    assert summary["truth_glitch_strides_s"] == left_out
    cadence = recorded_strides(walk)
    np.testing.assert_allclose(cadence.start_s, kept)
    np.testing.assert_allclose(cadence.glitch_left_out_s, left_out)


def test_a_walk_without_truth_positions_is_not_checked() -> None:
    s = walk_stats(_walk(STANCES, POSITIONS, (1.6, 1.9), truth=False))
    np.testing.assert_allclose(s.strides.start_s, [0.0, 1.0, 2.0, 3.0])
    assert s.strides.glitch_left_out_s.shape == (0, 2)
    assert s.summary()["strides_left_out_truth_glitch"] == 0


@pytest.mark.parametrize(("speed", "glitch"), [(19.0, False), (21.0, True)])
def test_a_glitch_is_a_step_faster_than_20_m_s(speed: float, glitch: bool) -> None:
    # the foot walks at 1 m/s along y; one step of ``speed`` along x at sample 50
    pos = np.zeros((100, 3))
    pos[:, 1] = np.arange(100) / RATE
    pos[51:, 0] = speed / RATE
    assert MAX_TRUTH_SPEED_MPS == 20.0
    want = [[50, 51]] if glitch else []
    assert truth_glitches(pos, RATE).tolist() == want


def test_a_glitch_spans_the_frozen_run_before_its_jump_not_missing_samples() -> None:
    pos = np.zeros((100, 3))
    pos[:, 0] = np.arange(100) / RATE  # 1 m/s
    pos[30:60] = pos[30]  # frozen from sample 30 to 59, back on track at 60
    pos[80, 0] = np.nan  # a missing sample next to a fast step is no glitch
    pos[81, 0] = 5.0
    pos[82:, 0] = 5.0
    assert truth_glitches(pos, RATE).tolist() == [[30, 60]]


def test_overlap_includes_both_ends() -> None:
    glitches = np.array([[30, 60]])
    starts, stops = np.array([0, 10, 60, 61]), np.array([10, 30, 80, 90])
    assert overlaps_glitch(starts, stops, glitches).tolist() == [False, True, True, False]
    assert overlaps_glitch(starts, stops, np.zeros((0, 2))).tolist() == [False] * 4


def test_glitched_strides_marks_the_strides_through_a_glitch():
    pos = np.zeros((400, 3))
    pos[:, 0] = np.arange(400) * 0.005  # 1 m/s at 200 Hz
    pos[150:160] = pos[150]  # frozen for 50 ms ...
    pos[160:, 0] += 0.5  # ... then a 0.55 m jump in one sample: 110 m/s
    bounds = np.array([0, 100, 200, 300, 399])
    assert glitched_strides(bounds, pos, RATE).tolist() == [False, True, False, False]
    assert glitched_strides(bounds, None, RATE).tolist() == [False] * 4
    assert glitched_strides(np.array([5]), pos, RATE).size == 0
