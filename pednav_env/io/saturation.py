"""Saturated IMU samples: detection and polynomial bridging (paper 003).

Paper 003's real walk exceeded its gyro range (6 rad/s against pitch rates
up to 10 rad/s); the saturated spans were bridged by a 5th-order polynomial.
Here each saturated run of one axis is replaced by the quintic whose value,
first and second derivative match, at both joins, those of the quadratic
through the three good samples on that side — the bridge is C² at the joins
with respect to the local interpolant, and it may (as it should) exceed the
range in between.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Minimum length of a run at the column's extreme value that counts as
#: clipping when no range is declared (2 equal maxima can be chance).
MIN_PLATEAU = 3


def saturation_mask(x: Array, limit: float | None = None, min_run: int = MIN_PLATEAU) -> NDArray:
    """Saturated samples of each column of ``x`` ``(T, 3)``.

    With ``limit`` (the declared range, same unit as ``x``), a sample is
    saturated when ``|x| ≥ limit``. Without it, a run of at least
    ``min_run`` consecutive samples sitting exactly on the column's largest
    ``|x|`` is taken for clipping (the signature of a saturated converter),
    unless that largest value is below 1.5 × the median ``|x|`` (a constant
    signal such as gravity on a still axis).
    """
    x = np.asarray(x, dtype=float)
    if limit is not None:
        if not limit > 0:
            raise ValueError(f"saturation limit must be > 0, got {limit!r}")
        return np.abs(x) >= limit * (1.0 - 1e-9)
    mask = np.zeros(x.shape, dtype=bool)
    for c in range(x.shape[1]):
        a = np.abs(x[:, c])
        peak = a.max()
        if peak == 0 or peak < 1.5 * np.median(a):  # a (nearly) constant column: no clipping
            continue
        at_peak = a == peak
        for s, e in runs(at_peak):
            if e - s >= min_run:
                mask[s:e, c] = True
    return mask


def runs(flags: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Half-open index spans ``[start, end)`` of consecutive True values."""
    f = np.concatenate(([False], np.asarray(flags, dtype=bool), [False]))
    d = np.diff(f.astype(np.int8))
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(), strict=True))


def _local_derivatives(t: Array, y: Array) -> tuple[float, float, float]:
    """Value, slope and curvature at ``t[-1]`` of the quadratic through 3 points."""
    c = np.polyfit(t - t[-1], y, 2)
    return float(c[2]), float(c[1]), float(2.0 * c[0])


def quintic_bridge(t0: float, d0: tuple, t1: float, d1: tuple, t: Array) -> Array:
    """The quintic p with (p, p', p'') = ``d0`` at ``t0`` and ``d1`` at ``t1``, at ``t``."""
    h = t1 - t0
    # p(s) = Σ c_k s^k, s = t − t0; the first three coefficients come from d0.
    c0, c1, c2 = d0[0], d0[1], 0.5 * d0[2]
    A = np.array(
        [[h**3, h**4, h**5], [3 * h**2, 4 * h**3, 5 * h**4], [6 * h, 12 * h**2, 20 * h**3]]
    )
    rhs = np.array(
        [
            d1[0] - (c0 + c1 * h + c2 * h**2),
            d1[1] - (c1 + 2 * c2 * h),
            d1[2] - 2 * c2,
        ]
    )
    c3, c4, c5 = np.linalg.solve(A, rhs)
    s = np.asarray(t, dtype=float) - t0
    return c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))


def bridge_saturated(t: Array, x: Array, mask: NDArray[np.bool_]) -> Array:
    """Replace the masked samples of ``x`` ``(T, 3)`` by quintic bridges.

    Raises
    ------
    ValueError
        When a run has fewer than 3 good samples on either side (at the start
        or end of the record, or between two runs): it cannot be bridged.
    """
    t = np.asarray(t, dtype=float)
    out = np.array(x, dtype=float, copy=True)
    for c in range(out.shape[1]):
        for s, e in runs(mask[:, c]):
            left, right = np.arange(s - 3, s), np.arange(e, e + 3)
            if left[0] < 0 or right[-1] >= len(t) or mask[left, c].any() or mask[right, c].any():
                raise ValueError(
                    f"saturated samples {s}…{e - 1} (axis {c}) lack 3 good samples on both "
                    "sides and cannot be bridged"
                )
            d0 = _local_derivatives(t[left], out[left, c])
            # Right side: fit at the first good sample (reverse so that it is last).
            r = right[::-1]
            d1 = _local_derivatives(t[r], out[r, c])
            out[s:e, c] = quintic_bridge(t[s - 1], d0, t[e], d1, t[s:e])
    return out
