"""How much a walk's path turns per stride, from its reference (docs/SIM_TO_REAL.md,
"The swing in three axes").

A footfall point is a footprint (walks with footprints) or the mean truth position over
a stance run (walks with a truth track: stance from the walk's labels or the simulator's
truth, else from the truth velocity, cleaned as :mod:`pednav_env.calibration.stats`
cleans labels). Consecutive points closer than :data:`MIN_STRIDE_M` are one footfall
(a stand, a split stance). A stride's turn is the change of heading from one footfall
step to the next, wrapped to [−π, π): a walk on a circle of radius r with strides of
length L turns by about L / r per stride.

The PyShoe VICON trials walk circles in the capture volume, about 1 rad per stride;
the hallway walks turn a few hundredths to a few tenths of a radian.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import pairwise
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from pednav_env.calibration.stats import (
    StanceSource,
    WalkSamples,
    log10_shoe,
    runs,
    walking_stance,
)
from pednav_env.calibration.strides import stride_stances, truth_glitches
from pednav_env.rotations import wrap_angle

Array = NDArray[np.float64]

#: Footfall points closer than this (m) are one footfall.
MIN_STRIDE_M = 0.2
#: Fewest stride turns a walk needs for :func:`turn_range`.
MIN_TURNS = 3
#: Longest footfall-to-footfall time (s) walked as one stride; the rest is a stand.
MAX_STRIDE_S = 1.5
#: Largest turn per stride a simulated route walks (rad;
#: :class:`pednav_env.gait.speed_route.SpeedRouteConfig`).
MAX_ROUTE_TURN_RAD = math.pi / 2


def _labelled_stance(samples: WalkSamples) -> tuple[StanceSource, NDArray[np.bool_]]:
    """The walk's stance source and cleaned stance flags
    (:func:`pednav_env.calibration.stats.walking_stance`)."""
    s = samples
    source, stance, _ = walking_stance(s, log10_shoe(s.omega_b, s.f_b, float(s.rate_hz), s.g))
    return source, stance


def footfall_points(samples: WalkSamples) -> Array:
    """``(K, 2)`` horizontal footfall points (m; module docstring); ``(0, 2)`` when the
    walk has neither footprints nor a truth track, or its stance comes from the detector
    rule only."""
    s = samples
    if s.footprints_m is not None:
        return np.asarray(s.footprints_m, dtype=float)[:, :2]
    if s.truth_pos is None:
        return np.zeros((0, 2))
    source, stance = _labelled_stance(s)
    if source == StanceSource.DETECTOR:
        return np.zeros((0, 2))
    points = []
    for a, b in zip(*runs(stance), strict=True):
        xy = np.asarray(s.truth_pos[a:b, :2], dtype=float)
        ok = np.all(np.isfinite(xy), axis=1)
        if ok.any():
            points.append(xy[ok].mean(axis=0))
    return np.array(points).reshape(-1, 2)


def stride_turns(points_m: Array, min_stride_m: float = MIN_STRIDE_M) -> Array:
    """Per stride, the heading change (rad, [−π, π)) between consecutive footfall steps
    of ``points_m`` ``(K, 2)``, points closer than ``min_stride_m`` merged."""
    pts = np.asarray(points_m, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points_m must be (K, 2), got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points_m must be finite")
    if not (np.isfinite(min_stride_m) and min_stride_m > 0):
        raise ValueError(f"min_stride_m must be > 0, got {min_stride_m!r}")
    kept: list[Array] = []
    for p in pts:
        if not kept or np.hypot(*(p - kept[-1])) >= min_stride_m:
            kept.append(p)
    if len(kept) < 3:
        return np.zeros(0)
    steps = np.diff(np.array(kept), axis=0)
    heading = np.arctan2(steps[:, 1], steps[:, 0])
    return wrap_angle(np.diff(heading))


def turn_range(samples: WalkSamples) -> tuple[float, float] | None:
    """The 25th and 75th percentile of the walk's |turn per stride| (rad), None with
    fewer than :data:`MIN_TURNS` strides."""
    turns = np.abs(stride_turns(footfall_points(samples)))
    if turns.size < MIN_TURNS:
        return None
    lo, hi = np.percentile(turns, [25.0, 75.0])
    return float(lo), float(hi)


def route_turn_range(samples: WalkSamples) -> tuple[float, float] | None:
    """:func:`turn_range` with both ends at most :data:`MAX_ROUTE_TURN_RAD`: the turn
    per stride of simulated walks that walk like this one (a stride that turns more, a
    turn on the spot, is walked at the limit)."""
    turn = turn_range(samples)
    if turn is None:
        return None
    return min(turn[0], MAX_ROUTE_TURN_RAD), min(turn[1], MAX_ROUTE_TURN_RAD)


def pooled_turn_range(walks: Sequence[WalkSamples]) -> tuple[float, float]:
    """The 25th and 75th percentile of |turn per stride| (rad) over the strides of all
    ``walks`` together (the PyShoe trials: 0.79–1.43 rad); ValueError with fewer than
    :data:`MIN_TURNS` strides in all."""
    turns = [stride_turns(footfall_points(w)) for w in walks]
    pooled = np.abs(np.concatenate(turns)) if turns else np.zeros(0)
    if pooled.size < MIN_TURNS:
        raise ValueError(f"pooled_turn_range: {pooled.size} stride turns, need {MIN_TURNS}")
    lo, hi = np.percentile(pooled, [25.0, 75.0])
    return float(lo), float(hi)


class StrideSequence(NamedTuple):
    """A walk's strides in order (:func:`stride_sequence`), each ``(S,)``: speed (m/s,
    footfall-to-footfall distance over the time between them), heading change (rad)
    and the stand before the stride (s)."""

    speed_mps: Array
    turn_rad: Array
    stop_s: Array


def _footfall_times(samples: WalkSamples) -> tuple[Array, Array, Array]:
    """Per footfall the time (s) the foot arrives, the time it leaves (NaN when not
    known) and ``(K, 2)`` points: footprints at their sample index (leaving unknown), or
    the start, end and mean truth position of each stance, the cleaned stance runs
    merged as the walk's strides merge them
    (:func:`pednav_env.calibration.strides.stride_stances`: split stances, runs closer
    than a minimum stride) and the truth positions of a truth glitch
    (:func:`pednav_env.calibration.strides.truth_glitches`) left out."""
    s = samples
    rate = float(s.rate_hz)
    if s.footprints_m is not None and s.footfall_index is not None:
        arrive = np.asarray(s.footfall_index, dtype=float) / rate
        return arrive, np.full(arrive.shape, np.nan), np.asarray(s.footprints_m, dtype=float)[:, :2]
    empty = np.zeros(0), np.zeros(0), np.zeros((0, 2))
    if s.truth_pos is None:
        return empty
    source, stance = _labelled_stance(s)
    if source == StanceSource.DETECTOR:
        return empty
    pos = np.array(s.truth_pos[:, :2], dtype=float)
    for a, b in truth_glitches(s.truth_pos, rate):  # frozen, then a jump: no position
        pos[a : b + 1] = np.nan
    arrive, leave, points = [], [], []
    for a, b in zip(*stride_stances(*runs(stance), rate, pos), strict=True):
        xy = pos[a:b]
        ok = np.all(np.isfinite(xy), axis=1)
        if ok.any():
            arrive.append(a / rate)
            leave.append(b / rate)
            points.append(xy[ok].mean(axis=0))
    return np.array(arrive), np.array(leave), np.array(points).reshape(-1, 2)


def stride_sequence(
    samples: WalkSamples, min_stride_m: float = MIN_STRIDE_M, max_stride_s: float = MAX_STRIDE_S
) -> StrideSequence:
    """The walk's strides in order, from its footfalls (module docstring). Footfalls
    closer than ``min_stride_m`` are one, at the first one's point, from the first
    arrival to the last departure. A stride runs from one footfall to the next and turns
    by the change of heading from the stride before (the first does not turn). With
    stance runs (a truth track), its time is the move from departure to the next arrival
    plus the footfall's stance up to the walk's median stance; the rest of that stance is
    a stand before the stride. With footprints only (no departures), its time is the
    time between the footprints up to ``max_stride_s``, the rest a stand. Its speed is
    its length over its time. Empty without two footfalls."""
    arrive, leave, pts = _footfall_times(samples)
    groups: list[list] = []  # point, first arrival, last arrival, last departure
    for t_in, t_out, p in zip(arrive, leave, pts, strict=True):
        if groups and np.hypot(*(p - groups[-1][0])) < min_stride_m:
            groups[-1][2], groups[-1][3] = float(t_in), float(t_out)
        else:
            groups.append([p, float(t_in), float(t_in), float(t_out)])
    if len(groups) < 2:
        return StrideSequence(np.zeros(0), np.zeros(0), np.zeros(0))
    step = np.diff(np.array([g[0] for g in groups]), axis=0)
    length = np.hypot(step[:, 0], step[:, 1])
    first_in = np.array([g[1] for g in groups])
    last_out = np.array([g[3] for g in groups])
    if np.all(np.isfinite(last_out)):
        stance = last_out[:-1] - first_in[:-1]
        typical = float(np.median(last_out - first_in))
        moving = np.maximum(first_in[1:] - last_out[:-1], 1e-3)
        kept = np.minimum(stance, typical)
        walked, stood = moving + kept, stance - kept
    else:
        gap = np.array([b[1] - a[2] for a, b in pairwise(groups)])
        before = np.array([g[2] - g[1] for g in groups[:-1]])
        walked = np.clip(gap, 1e-3, max_stride_s)
        stood = before + (gap - walked)
    heading = np.arctan2(step[:, 1], step[:, 0])
    turn = np.concatenate(([0.0], wrap_angle(np.diff(heading))))
    return StrideSequence(length / walked, turn, stood)
