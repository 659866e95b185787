"""Interval statistics of the foot environments' observation (entries 0–8).

What :class:`pednav_env.envs.foot_core.FootZuptCore` computes from a decision
interval's IMU samples and detector flags, on all lanes at once: the norms of
the rate and the specific force, their masked mean, standard deviation and
maximum (observation entries 0–5), the stance fraction (6), and the moving
average of the durations of the detected stances (8).

Every value is the arithmetic of the plain numpy forms, in their order, only
with fewer passes (docs/PERFORMANCE.md, "The foot env's own work per step"):

- :func:`vector_norms` is ``np.linalg.norm(x, axis=-1)`` for three components,
  ``sqrt((x₀² + x₁²) + x₂²)``: numpy sums three squares in that order, and its
  reduction over an axis of three entries cost five times the arithmetic;
- :func:`masked` skips the masking when every lane used the whole
  interval (``np.where`` with a mask that is all true returns the values);
- :func:`update_stance_average` goes through the stance ends of the interval
  rank by rank (first end of every lane, then second, …) as before, but on a
  list of the ends sorted by rank, where the earlier form made six passes over
  ``(N, K)`` per rank.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.nav.detectors import run_lengths

Array = NDArray[np.float64]


def vector_norms(x: Array) -> Array:
    """Euclidean norms ``(...)`` of the 3-vectors ``x`` ``(..., 3)``, bit for bit
    ``np.linalg.norm(x, axis=-1)``: ``sqrt((x₀² + x₁²) + x₂²)``."""
    s = x * x
    return np.sqrt((s[..., 0] + s[..., 1]) + s[..., 2])


def masked(x: NDArray, mask: NDArray[np.bool_], full: bool) -> NDArray:
    """``np.where(mask, x, 0)``; ``x`` itself when ``full`` (the mask is all true),
    which has the same values."""
    return x if full else np.where(mask, x, 0)


def masked_moments(
    x: Array, mask: NDArray[np.bool_], count: NDArray[np.integer], full: bool
) -> tuple[Array, Array]:
    """Mean and standard deviation of ``x`` ``(B, K)`` over the samples where
    ``mask`` ``(B, K)`` is true (``count`` of them per row, ≥ 1); ``full``: the
    mask is all true (:func:`masked`)."""
    mean = masked(x, mask, full).sum(1) / count
    var = masked((x - mean[:, None]) ** 2, mask, full).sum(1) / count
    return mean, np.sqrt(var)


def update_stance_average(
    average_s: Array,
    open_run: NDArray[np.integer],
    stance: NDArray[np.bool_],
    end: NDArray[np.bool_],
    dt: Array,
) -> tuple[Array, NDArray[np.int64]]:
    """The moving average (weight 0.2 on the newest) of the durations
    of the detected stances that ended in the interval, in their order, and the
    length of the stance left open at its end.

    ``average_s`` ``(B,)``: the average before the interval (0: none yet);
    ``open_run`` ``(B,)``: samples of the stance open before it; ``stance`` and
    ``end`` ``(B, K)``: the detector's flags and the stance ends (the sample after
    a stance's last); ``dt`` ``(B,)``: sample intervals (s). A stance of length 0
    leaves the average as it is. Returns new arrays.
    """
    run = run_lengths(stance, open_run)
    before = np.concatenate((open_run[:, None], run[:, :-1]), axis=1)
    average = average_s.copy()
    lane, col = np.nonzero(end)  # lane by lane, each lane's ends in sample order
    duration = before[lane, col] * dt[lane]
    rank = np.arange(lane.size) - np.searchsorted(lane, lane)  # 0: a lane's first end
    keep = duration > 0
    order = np.argsort(rank[keep], kind="stable")  # rank by rank, lanes ascending
    lane, duration = lane[keep][order], duration[keep][order]
    count = np.bincount(rank[keep])  # ends of each rank
    bounds = np.cumsum(count)
    for lo, hi in zip((bounds - count).tolist(), bounds.tolist(), strict=True):
        lanes, d = lane[lo:hi], duration[lo:hi]
        old = average[lanes]
        average[lanes] = np.where(old > 0, 0.8 * old + 0.2 * d, d)
    return average, run[:, -1].copy()
