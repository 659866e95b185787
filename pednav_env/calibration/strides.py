"""Stride segmentation of a walk without footprints: which stance runs start a
stride, and which strides the truth positions cannot measure
(docs/SIM_TO_REAL.md,
"Strides: split stances, the minimum stride and truth glitches").

A stride is two steps: one footfall of the instrumented foot to its next. Without
footprints the footfalls are the starts of the cleaned stance runs
(:func:`pednav_env.calibration.stats.walk_stats`, the cadence of
:mod:`pednav_env.calibration.cadence`), after two rules that join runs:

1. **Split stances** (:func:`merge_split_stances`): PyShoe's VICON labels split
   some stances by gaps of 0.05–0.1 s in which the foot does not move. With truth
   positions two runs are one stance when the foot moves less than
   :data:`MIN_SWING_M` between them; without them a gap shorter than
   :data:`MIN_SWING_S`.
2. **Minimum stride** (:func:`merge_short_strides`): no human stride (two steps)
   is shorter than :data:`MIN_STRIDE_S`: sprinters' step rate peaks near 4.5–5
   steps/s, a stride of 0.4–0.44 s (Weyand et al. 2000, J Appl Physiol
   89:1991–1999: top speed comes from ground force, not faster leg repositioning;
   Salo et al. 2011, Med Sci Sports Exerc 43:1055–1062: elite 100 m sprinters' step
   frequency and length; the figure is not checked against their tables, see
   docs/SIM_TO_REAL.md). A run that starts sooner after the run before it (e.g. a
   landing that slides 6 cm and settles) joins that run.

Where truth positions exist, the strides they cannot measure are found too
(:func:`truth_glitches`, :func:`overlaps_glitch`, :func:`glitched_strides`): a
horizontal step between two consecutive samples faster than
:data:`MAX_TRUTH_SPEED_MPS` is a tracking glitch (no foot moves that fast walking
or running), spanning that step and the run of identical positions (frozen truth,
e.g. a VICON dropout) just before it. Strides overlapping a glitch are left out of
the per-stride statistics and the cadence, and counted.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
Index = NDArray[np.int64]

#: Two stance runs are one stance when the foot moves less than this (m)
#: between them ...
MIN_SWING_M = 0.05
#: ... or, where no truth position tells, when the gap between them is shorter
#: than this (s) (:func:`merge_split_stances`).
MIN_SWING_S = 0.15
#: No stride (footfall to the same foot's next) is shorter than this (s)
#: (:func:`merge_short_strides`; module docstring).
MIN_STRIDE_S = 0.4
#: A horizontal truth step faster than this (m/s) between two samples is a truth
#: glitch (:func:`truth_glitches`).
MAX_TRUTH_SPEED_MPS = 20.0


def merge_split_stances(
    starts: Index,
    ends: Index,
    rate_hz: float,
    truth_pos: Array | None = None,
) -> tuple[Index, Index]:
    """Stance runs (``starts``, ``ends`` exclusive, as
    :func:`pednav_env.calibration.stats.runs` gives them) with split stances merged
    into one run from the first start to the last end.

    PyShoe's VICON labels split some stances by gaps of 0.05–0.1 s in which the
    foot does not move (5 mm or less), which the label cleaning does not close; a
    real swing moves the foot 0.15 m or more. With ``truth_pos``, the foot's
    movement alone decides: a run joins the one before it when the horizontal
    truth position moves less than :data:`MIN_SWING_M` from the last sample of
    the earlier run to the first of the later one, however short or long the gap
    (a foot that moved 5 cm or more took a step).

    Without ``truth_pos`` (walks with labels or a detector only), or where either
    of those two positions is missing (NaN), the gap's length decides instead: a
    gap shorter than :data:`MIN_SWING_S` is a split stance, a longer one a swing.
    """
    starts = np.asarray(starts, dtype=np.int64)
    ends = np.asarray(ends, dtype=np.int64)
    if starts.size < 2:
        return starts, ends
    # joins[k]: run k + 1 joins run k; the gap's length where no movement is known
    joins = (starts[1:] - ends[:-1]) / rate_hz < MIN_SWING_S
    if truth_pos is not None:
        pos = np.asarray(truth_pos, dtype=float)[:, :2]
        moved = np.linalg.norm(pos[starts[1:]] - pos[np.maximum(ends[:-1] - 1, 0)], axis=1)
        known = np.isfinite(moved)
        joins[known] = moved[known] < MIN_SWING_M
    return _join(starts, ends, joins)


def merge_short_strides(starts: Index, ends: Index, rate_hz: float) -> tuple[Index, Index]:
    """Stance runs with every run that starts less than :data:`MIN_STRIDE_S` after
    the start of the run before it joined to that run (module docstring, rule 2).

    Runs are taken in order, so "the run before it" is the merged run: a run
    that joined keeps the earlier start, and the next run is measured from it.
    """
    starts = np.asarray(starts, dtype=np.int64)
    ends = np.asarray(ends, dtype=np.int64)
    min_samples = MIN_STRIDE_S * rate_hz
    if starts.size < 2 or np.all(np.diff(starts) >= min_samples):
        return starts, ends
    joins = np.zeros(starts.size - 1, dtype=bool)
    current = starts[0]
    for k in range(1, starts.size):
        if starts[k] - current < min_samples:
            joins[k - 1] = True
        else:
            current = starts[k]
    return _join(starts, ends, joins)


def stride_stances(
    starts: Index, ends: Index, rate_hz: float, truth_pos: Array | None = None
) -> tuple[Index, Index]:
    """The stance runs whose starts bound the strides: split stances merged
    (:func:`merge_split_stances`), then runs closer than a minimum stride joined
    (:func:`merge_short_strides`)."""
    starts, ends = merge_split_stances(starts, ends, rate_hz, truth_pos)
    return merge_short_strides(starts, ends, rate_hz)


def _join(starts: Index, ends: Index, joins: NDArray[np.bool_]) -> tuple[Index, Index]:
    """Runs with run k + 1 joined to run k wherever ``joins[k]``."""
    first = np.concatenate(([True], ~joins))  # runs that start a merged run
    last = np.concatenate((~joins, [True]))  # runs that end one
    return starts[first], ends[last]


def truth_glitches(truth_pos: Array, rate_hz: float) -> Index:
    """Sample spans ``[first, last]`` (inclusive, shape (K, 2)) of the truth glitches
    (module docstring): each horizontal step k → k + 1 faster than
    :data:`MAX_TRUTH_SPEED_MPS`, from the first sample of the run of identical
    horizontal positions ending at k (k itself when the position was not frozen)
    to k + 1. Steps touching a missing (NaN) position are not glitches.
    """
    pos = np.asarray(truth_pos, dtype=float)[:, :2]
    if pos.shape[0] < 2:
        return np.zeros((0, 2), dtype=np.int64)
    diff = np.diff(pos, axis=0)
    speed = np.linalg.norm(diff, axis=1) * rate_hz
    jumps = np.flatnonzero(np.isfinite(speed) & (speed > MAX_TRUTH_SPEED_MPS))
    if not jumps.size:
        return np.zeros((0, 2), dtype=np.int64)
    frozen = np.all(diff == 0.0, axis=1)  # frozen[k]: position k + 1 equals position k
    spans = []
    for k in jumps:
        first = int(k)
        while first > 0 and frozen[first - 1]:
            first -= 1
        spans.append((first, int(k) + 1))
    return np.array(spans, dtype=np.int64)


def overlaps_glitch(starts: Index, stops: Index, glitches: Index) -> NDArray[np.bool_]:
    """For each stride spanning samples [``starts[k]``, ``stops[k]``] (its stance
    start to the next stride's start, both inclusive), whether it overlaps any
    glitch span of :func:`truth_glitches`."""
    a = np.asarray(starts, dtype=np.int64)[:, None]
    b = np.asarray(stops, dtype=np.int64)[:, None]
    g = np.asarray(glitches, dtype=np.int64).reshape(-1, 2)
    return np.any((a <= g[None, :, 1]) & (g[None, :, 0] <= b), axis=1)


def glitched_strides(bounds: Index, truth_pos: Array | None, rate_hz: float) -> NDArray[np.bool_]:
    """For each stride between consecutive ``bounds`` (sample indices of its start
    and of the next stride's start), whether it overlaps a truth glitch
    (:func:`truth_glitches`, :func:`overlaps_glitch`); all False without truth
    positions."""
    bounds = np.asarray(bounds, dtype=np.int64)
    if truth_pos is None or bounds.size < 2:
        return np.zeros(max(bounds.size - 1, 0), dtype=bool)
    return overlaps_glitch(bounds[:-1], bounds[1:], truth_glitches(truth_pos, rate_hz))
