"""Stance (zero-velocity) detectors, batched and causal.

- :class:`ThresholdDetectorConfig` — paper 003 eq (5): stance where
  |ω'| ≤ ω_max and |f'_x3 − g| ≤ Δf_max, f'_x3 the vertical specific force in
  the navigation frame (it needs the filter's attitude, so it is evaluated
  inside the filter loop). Optional causal moving averages over
  ``window_s`` (0 = sample by sample, as printed).
- :class:`ShoeDetectorConfig` — the SHOE / GLRT statistic of Skog, Händel,
  Nilsson, Rantakokko (2010), "Zero-velocity detection — an algorithm
  evaluation", IEEE TBME 57(11), eq (11):

      T_k = (1/W) Σ_{window} [ |f_j − g f̄/|f̄||² / σ_a² + |ω_j|² / σ_ω² ]

  stance where T_k < γ. It uses the IMU only, over the causal window ending
  at sample k. Because the terms are divided by σ², the threshold γ scales
  like 1/σ² when a configuration moves to a sensor with other noise.

Both take windows and minimum durations in seconds, so a configuration
carries over between sample rates. Minimum-duration logic: stance is declared
once the condition has held for ``min_stance_s`` (online: the declaration is
delayed, never back-dated).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY

Array = NDArray[np.float64]


def _check_positive(obj: object, name: str, allow_zero: bool = False) -> None:
    v = getattr(obj, name)
    ok = isinstance(v, int | float) and math.isfinite(v) and (v >= 0 if allow_zero else v > 0)
    if not ok:
        bound = "≥ 0" if allow_zero else "> 0"
        raise ValueError(f"{type(obj).__name__}.{name} must be a finite number {bound}, got {v!r}")


@dataclass(frozen=True)
class ThresholdDetectorConfig:
    """Paper 003 eq (5). Defaults are sized for paper 003's simulated IMU.

    The paper's real-data thresholds (ω_max = 0.039 rad/s, Δf_max = 0.15 m/s²,
    ``REAL_DATA``) would reject almost every stance sample of its *simulated*
    sensor, whose gyro noise alone is 0.05 rad/s per axis; it prints no
    simulation thresholds. The defaults put them at the 99.9 % quantile of the
    stance statistics of that sensor: |ν + δω| with per-axis std
    √(0.05² + 0.02²) = 0.054 rad/s follows a χ₃ law, 99.9 % → 4.03σ = 0.22
    rad/s; f'_x3 − g with σ = 0.1 m/s², two-sided 99.9 % → 3.29σ = 0.33 m/s².
    """

    omega_max: float = 0.22  # rad/s
    delta_f_max: float = 0.33  # m/s²
    window_s: float = 0.0
    min_stance_s: float = 0.0
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        _check_positive(self, "omega_max")
        _check_positive(self, "delta_f_max")
        _check_positive(self, "window_s", allow_zero=True)
        _check_positive(self, "min_stance_s", allow_zero=True)
        _check_positive(self, "g")

    @classmethod
    def real_data(cls) -> ThresholdDetectorConfig:
        """Paper 003's thresholds for its ADIS16405 walk."""
        return cls(omega_max=0.039, delta_f_max=0.15)

    @classmethod
    def sized_for_noise(
        cls, gyro_std: float, accel_std: float, **kw: float
    ) -> ThresholdDetectorConfig:
        """Thresholds at the 99.9 % stance quantiles for per-axis per-sample
        gyro std (incl. drift) and accelerometer std (see class docstring)."""
        return cls(omega_max=4.03 * gyro_std, delta_f_max=3.29 * accel_std, **kw)


@dataclass(frozen=True)
class ShoeDetectorConfig:
    """SHOE / GLRT detector (Skog et al. 2010).

    Defaults: a 3-sample window at 100 Hz (0.03 s), σ's of paper 003's
    simulated IMU (gyro incl. drift), and γ = 14: with true σ's, W·T_k at
    stance is ≈ χ² with 6W degrees of freedom, whose 99.9 % quantile for
    W = 3 is 42.3, i.e. T_k < 14.1.
    """

    threshold: float = 14.0  # dimensionless, compare T_k < γ
    window_s: float = 0.03
    accel_noise_std: float = 0.1  # m/s², σ_a
    gyro_noise_std: float = 0.054  # rad/s, σ_ω
    min_stance_s: float = 0.0
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        for name in ("threshold", "window_s", "accel_noise_std", "gyro_noise_std", "g"):
            _check_positive(self, name)
        _check_positive(self, "min_stance_s", allow_zero=True)


DetectorConfig = ThresholdDetectorConfig | ShoeDetectorConfig


def window_samples(window_s: float, rate_hz: float) -> int:
    """Number of samples in a window of ``window_s`` seconds (at least 1)."""
    return max(1, int(round(window_s * rate_hz)))


def causal_moving_mean(x: Array, n: int) -> Array:
    """Mean over the last ``n`` samples along axis 1 (shorter at the start)."""
    x = np.asarray(x, dtype=float)
    if n <= 1:
        return x.copy()
    c = np.cumsum(x, axis=1)
    out = c.copy()
    out[:, n:] = c[:, n:] - c[:, :-n]
    counts = np.minimum(np.arange(1, x.shape[1] + 1), n).reshape((1, -1) + (1,) * (x.ndim - 2))
    return out / counts


def shoe_statistic(omega_b: Array, f_b: Array, config: ShoeDetectorConfig, rate_hz: float) -> Array:
    """SHOE test statistic T_k ``(N, T)`` over causal windows (Skog 2010, eq 11)."""
    omega_b = np.asarray(omega_b, dtype=float)
    f_b = np.asarray(f_b, dtype=float)
    if omega_b.ndim != 3 or omega_b.shape != f_b.shape:
        raise ValueError(f"omega_b and f_b must be (N, T, 3), got {omega_b.shape}, {f_b.shape}")
    n = window_samples(config.window_s, rate_hz)
    f_mean = causal_moving_mean(f_b, n)
    u = f_mean / np.maximum(np.linalg.norm(f_mean, axis=-1, keepdims=True), 1e-12)
    # Σ |f_j − g u_k|² over the window = Σ|f_j|² − 2g u_k·Σf_j + W g², with u_k from window k.
    sum_f2 = causal_moving_mean(np.sum(f_b * f_b, axis=-1), n)
    cross = np.sum(u * f_mean, axis=-1)
    acc_term = sum_f2 - 2 * config.g * cross + config.g**2
    gyro_term = causal_moving_mean(np.sum(omega_b * omega_b, axis=-1), n)
    return acc_term / config.accel_noise_std**2 + gyro_term / config.gyro_noise_std**2


def threshold_condition(
    omega_b: Array, f_n3: Array, config: ThresholdDetectorConfig, rate_hz: float
) -> NDArray[np.bool_]:
    """Eq (5) on whole records: ``omega_b`` (N, T, 3), ``f_n3`` (N, T) (m/s²)."""
    n = window_samples(config.window_s, rate_hz) if config.window_s > 0 else 1
    w = causal_moving_mean(np.linalg.norm(omega_b, axis=-1), n)
    f = causal_moving_mean(np.asarray(f_n3, dtype=float), n)
    return (w <= config.omega_max) & (np.abs(f - config.g) <= config.delta_f_max)


def apply_min_duration(condition: NDArray[np.bool_], min_samples: int) -> NDArray[np.bool_]:
    """Stance declared once ``condition`` held for ``min_samples`` samples (causal)."""
    condition = np.asarray(condition, dtype=bool)
    if min_samples <= 1:
        return condition.copy()
    run = np.zeros(condition.shape[0], dtype=np.int64)
    out = np.zeros_like(condition)
    for m in range(condition.shape[1]):
        run = np.where(condition[:, m], run + 1, 0)
        out[:, m] = run >= min_samples
    return out


def run_lengths(flags: NDArray[np.bool_], carried: NDArray[np.integer]) -> NDArray[np.int64]:
    """For flags ``(B, K)``, how many samples in a row each flag has been true up to
    and including sample k (0 where it is false); ``carried`` (B,) is the run
    length before the block. k − (last false index), or carried + k + 1 when the
    flag held all block long."""
    k = flags.shape[1]
    idx = np.arange(k)
    last_false = np.maximum.accumulate(np.where(flags, -1, idx[None, :]), axis=1)
    return np.where(last_false >= 0, idx[None, :] - last_false, carried[:, None] + idx + 1)


@dataclass(frozen=True)
class DetectorPass:
    """Detector output over K samples of B walkers (not yet committed)."""

    stance: NDArray[np.bool_]  # (B, K) in stance after each sample
    start: NDArray[np.bool_]  # (B, K) stance declared at this sample
    end: NDArray[np.bool_]  # (B, K) stance ended at this sample
    run: NDArray[np.int64]  # (B,) samples the condition has held at the last sample
    history: Array  # (B, W-1, 2) last window inputs, oldest first (eq 5 only)
    count: NDArray[np.int64]  # (B,) samples seen, capped at the window length


class OnlineStanceDetector:
    """Causal detector state for N walkers, fed any number of samples at a time.

    Thresholds can change between calls (per walker) — they are what an agent
    tunes. For the SHOE detector the statistic is computed from the raw IMU
    record (:func:`shoe_statistic`) and its condition passed in; for eq (5)
    the caller passes |ω'| and f'_x3, and the detector keeps the causal window
    inputs. :meth:`evaluate_threshold` / :meth:`evaluate_condition` compute a
    :class:`DetectorPass` for a block of samples without changing the state
    (the filter may re-evaluate a block after a correction changed its
    attitude); :meth:`commit` stores the state at the block's end.
    """

    def __init__(self, config: DetectorConfig, rate_hz: float, num_walkers: int) -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz must be > 0, got {rate_hz!r}")
        self.config = config
        self.rate_hz = rate_hz
        self.n = num_walkers
        w = window_samples(config.window_s, rate_hz) if config.window_s > 0 else 1
        self.window = w
        # Window inputs (|ω'|, f'_x3) of the last W−1 samples, oldest first; zeros
        # before the first sample, which the count leaves out of the mean.
        self.history = np.zeros((num_walkers, w - 1, 2))
        self.count = np.zeros(num_walkers, dtype=np.int64)
        self.run = np.zeros(num_walkers, dtype=np.int64)
        self.in_stance = np.zeros(num_walkers, dtype=bool)

    def reset(self, mask: NDArray[np.bool_] | None = None) -> None:
        sel = slice(None) if mask is None else mask
        self.history[sel] = 0.0
        self.count[sel] = 0
        self.run[sel] = 0
        self.in_stance[sel] = False

    def min_samples(self, min_stance_s: Array | float) -> NDArray[np.int64]:
        """Minimum stance duration in samples (at least 1)."""
        return np.maximum(1, np.round(np.asarray(min_stance_s) * self.rate_hz)).astype(np.int64)

    def window_condition(
        self,
        lanes: NDArray[np.integer],
        omega_norm: Array,
        f_n3: Array,
        omega_max: Array,
        delta_f_max: Array,
    ) -> tuple[NDArray[np.bool_], Array, NDArray[np.int64]]:
        """Eq (5) with causal window means over ``(B, K)`` inputs of walkers
        ``lanes``: the condition and the window state after the block."""
        w = self.window
        count = self.count[lanes]
        k = omega_norm.shape[1]
        if w == 1:
            om, fm, hist = omega_norm, f_n3, self.history[lanes]
        else:
            x = np.concatenate((self.history[lanes], np.stack((omega_norm, f_n3), axis=-1)), axis=1)
            sums = np.lib.stride_tricks.sliding_window_view(x, w, axis=1).sum(axis=-1)
            seen = np.minimum(count[:, None] + np.arange(1, k + 1)[None, :], w)
            om, fm = sums[..., 0] / seen, sums[..., 1] / seen
            hist = x[:, k:]
        cond = (om <= omega_max[:, None]) & (np.abs(fm - self.config.g) <= delta_f_max[:, None])
        return cond, hist, np.minimum(count + k, w)

    def evaluate_threshold(
        self,
        lanes: NDArray[np.integer],
        omega_norm: Array,
        f_n3: Array,
        omega_max: Array,
        delta_f_max: Array,
        min_stance_s: Array,
    ) -> DetectorPass:
        """Eq (5) and the stance logic over ``(B, K)`` inputs of walkers ``lanes``."""
        cond, hist, count = self.window_condition(lanes, omega_norm, f_n3, omega_max, delta_f_max)
        return self._machine(lanes, cond, min_stance_s, hist, count)

    def evaluate_condition(
        self, lanes: NDArray[np.integer], condition: NDArray[np.bool_], min_stance_s: Array
    ) -> DetectorPass:
        """Stance logic over a given condition ``(B, K)`` (e.g. SHOE's T_k < γ)."""
        k = condition.shape[1]
        count = np.minimum(self.count[lanes] + k, self.window)
        return self._machine(lanes, condition, min_stance_s, self.history[lanes], count)

    def _machine(
        self,
        lanes: NDArray[np.integer],
        cond: NDArray[np.bool_],
        min_stance_s: Array,
        history: Array,
        count: NDArray[np.int64],
    ) -> DetectorPass:
        run = run_lengths(cond, self.run[lanes])
        now = run >= self.min_samples(min_stance_s)[:, None]
        before = np.concatenate((self.in_stance[lanes, None], now[:, :-1]), axis=1)
        return DetectorPass(now, now & ~before, before & ~now, run[:, -1], history, count)

    def commit(self, lanes: NDArray[np.integer], result: DetectorPass) -> None:
        """Store the state at the end of an evaluated block."""
        self.run[lanes] = result.run
        self.in_stance[lanes] = result.stance[:, -1]
        self.history[lanes] = result.history
        self.count[lanes] = result.count

    # one-sample interface ---------------------------------------------------------
    def condition_threshold(
        self, omega_norm: Array, f_n3: Array, omega_max: Array, delta_f_max: Array
    ) -> NDArray[np.bool_]:
        """Eq (5) for one sample of every walker with causal window means;
        advances the window (use with :meth:`advance`)."""
        lanes = np.arange(self.n)
        cond, self.history[:], self.count[:] = self.window_condition(
            lanes,
            np.asarray(omega_norm, dtype=float).reshape(self.n, 1),
            np.asarray(f_n3, dtype=float).reshape(self.n, 1),
            np.broadcast_to(np.asarray(omega_max, dtype=float), (self.n,)),
            np.broadcast_to(np.asarray(delta_f_max, dtype=float), (self.n,)),
        )
        return cond[:, 0]

    def advance(
        self, condition: NDArray[np.bool_], min_stance_s: Array | float
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Feed one sample's condition; return (stance_start, stance_end) events."""
        lanes = np.arange(self.n)
        ms = np.broadcast_to(np.asarray(min_stance_s, dtype=float), (self.n,))
        res = self.evaluate_condition(lanes, np.asarray(condition).reshape(self.n, 1), ms)
        self.run[:] = res.run
        self.in_stance[:] = res.stance[:, 0]
        return res.start[:, 0], res.end[:, 0]

