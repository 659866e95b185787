"""Numpy stance detectors: the oracle of the compiled detector of the ZUPT kernel.

The production detector of paper 003 eq (5) and the stance logic run inside
:func:`pednav_env.nav.zupt_kernel.advance_block`. These numpy versions compute
the same from the same inputs, written the plain way, for the tests and for
the filterpy reference of ``pednav bench foot``:

- :func:`threshold_condition` and :func:`apply_min_duration` on whole records
  (offline);
- :class:`OnlineStanceDetector`, one sample of N walkers at a time (causal
  window means of eq 5, minimum stance duration, start and end events);
- :func:`shoe_statistic_at_numpy`, the SHOE statistic of lanes with their own
  windows in batched numpy (the oracle of the compiled
  :func:`pednav_env.nav.detectors.shoe_statistic_at`, which replaced it).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from pednav_env.nav.detectors import (
    DetectorConfig,
    ShoeDetectorConfig,
    ThresholdDetectorConfig,
    causal_moving_mean,
    detector_window,
    min_stance_samples,
)

Array = NDArray[np.float64]


def threshold_condition(
    omega_b: Array, f_n3: Array, config: ThresholdDetectorConfig, rate_hz: float
) -> NDArray[np.bool_]:
    """Eq (5) on whole records: ``omega_b`` (N, T, 3) (rad/s), ``f_n3`` (N, T) (m/s²)."""
    n = detector_window(config, rate_hz)
    w = causal_moving_mean(np.linalg.norm(omega_b, axis=-1), n)
    f = causal_moving_mean(np.asarray(f_n3, dtype=float), n)
    return (w <= config.omega_max) & (np.abs(f - config.g) <= config.delta_f_max)


def apply_min_duration(condition: NDArray[np.bool_], min_samples: int) -> NDArray[np.bool_]:
    """Stance declared once ``condition`` (N, T) held for ``min_samples`` samples (causal)."""
    condition = np.asarray(condition, dtype=bool)
    if min_samples <= 1:
        return condition.copy()
    run = np.zeros(condition.shape[0], dtype=np.int64)
    out = np.zeros_like(condition)
    for m in range(condition.shape[1]):
        run = np.where(condition[:, m], run + 1, 0)
        out[:, m] = run >= min_samples
    return out


class OnlineStanceDetector:
    """Causal detector state of N walkers, fed one sample at a time.

    :meth:`condition_threshold` evaluates eq (5) on the causal window means of
    |ω'| and f'_x3 and advances the window; :meth:`advance` applies the
    minimum stance duration to a condition (eq 5's or SHOE's T_k < γ) and
    reports stance starts and ends. Thresholds may change between calls.
    """

    def __init__(self, config: DetectorConfig, rate_hz: float, num_walkers: int) -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz must be > 0, got {rate_hz!r}")
        self.config = config
        self.rate_hz = rate_hz
        self.n = num_walkers
        self.window = detector_window(config, rate_hz)
        # Inputs (|ω'|, f'_x3) of the last W−1 samples, oldest first; zeros before
        # the first sample, which the count leaves out of the mean.
        self.history = np.zeros((num_walkers, self.window - 1, 2))
        self.count = np.zeros(num_walkers, dtype=np.int64)
        self.run = np.zeros(num_walkers, dtype=np.int64)
        self.in_stance = np.zeros(num_walkers, dtype=bool)

    def reset(self, mask: NDArray[np.bool_] | None = None) -> None:
        sel = slice(None) if mask is None else mask
        self.history[sel] = 0.0
        self.count[sel] = 0
        self.run[sel] = 0
        self.in_stance[sel] = False

    def condition_threshold(
        self, omega_norm: Array, f_n3: Array, omega_max: Array, delta_f_max: Array
    ) -> NDArray[np.bool_]:
        """Eq (5) for one sample of every walker (|ω'| (rad/s), f'_x3 (m/s²), ``(N,)``)
        with causal window means; advances the window."""
        x = np.stack(
            (
                np.broadcast_to(np.asarray(omega_norm, dtype=float), (self.n,)),
                np.broadcast_to(np.asarray(f_n3, dtype=float), (self.n,)),
            ),
            axis=-1,
        )
        window = np.concatenate((self.history, x[:, None, :]), axis=1)  # (N, W, 2)
        self.count = np.minimum(self.count + 1, self.window)
        mean = window.sum(axis=1) / self.count[:, None]
        self.history = window[:, 1:]
        return (mean[:, 0] <= omega_max) & (np.abs(mean[:, 1] - self.config.g) <= delta_f_max)

    def advance(
        self, condition: NDArray[np.bool_], min_stance_s: Array | float
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Feed one sample's condition ``(N,)``; return (stance_start, stance_end) events."""
        condition = np.asarray(condition, dtype=bool).reshape(self.n)
        self.run = np.where(condition, self.run + 1, 0)
        now = self.run >= min_stance_samples(min_stance_s, self.rate_hz)
        start, end = now & ~self.in_stance, self.in_stance & ~now
        self.in_stance = now
        return start, end


def shoe_statistic_at_numpy(
    omega_b: Array,
    f_b: Array,
    first: NDArray[np.integer],
    k: int,
    windows: NDArray[np.integer],
    config: ShoeDetectorConfig,
) -> Array:
    """SHOE statistic ``(N, k)`` (Skog 2010, eq 11) at samples first_i … first_i + k − 1
    of records ``(N, T, 3)``, lane i over a causal window of ``windows[i]`` samples:
    cumulative sums over the samples the windows reach, in numpy (the former
    :func:`pednav_env.nav.detectors.shoe_statistic_at`, kept as its oracle)."""
    n = omega_b.shape[0]
    first = np.asarray(first, dtype=np.int64)
    windows = np.asarray(windows, dtype=np.int64)
    back = int(windows.max(initial=1)) - 1
    # samples first − back … first + k − 1 of each lane (index < 0: outside the record)
    idx = first[:, None] + np.arange(-back, k)[None, :]
    inside = idx >= 0
    rows = np.arange(n)[:, None]
    f = np.where(inside[..., None], f_b[rows, np.maximum(idx, 0)], 0.0)
    w = np.where(inside[..., None], omega_b[rows, np.maximum(idx, 0)], 0.0)
    zero = np.zeros((n, 1))
    c_f = np.concatenate((np.zeros((n, 1, 3)), np.cumsum(f, axis=1)), axis=1)
    c_f2 = np.concatenate((zero, np.cumsum(np.sum(f * f, axis=-1), axis=1)), axis=1)
    c_w2 = np.concatenate((zero, np.cumsum(np.sum(w * w, axis=-1), axis=1)), axis=1)
    hi = back + 1 + np.arange(k)[None, :]  # prefix index just after sample m
    lo = hi - windows[:, None]
    count = np.minimum(windows[:, None], first[:, None] + np.arange(k)[None, :] + 1)
    f_mean = (c_f[rows, hi] - c_f[rows, lo]) / count[..., None]
    u = f_mean / np.maximum(np.linalg.norm(f_mean, axis=-1, keepdims=True), 1e-12)
    sum_f2 = (c_f2[rows, hi] - c_f2[rows, lo]) / count
    cross = np.sum(u * f_mean, axis=-1)
    acc_term = sum_f2 - 2 * config.g * cross + config.g**2
    gyro_term = (c_w2[rows, hi] - c_w2[rows, lo]) / count
    return acc_term / config.accel_noise_std**2 + gyro_term / config.gyro_noise_std**2
