"""Stance (zero-velocity) detectors: configurations and the record-level pieces.

- :class:`ThresholdDetectorConfig` — paper 003 eq (5): stance where
  |ω'| ≤ ω_max and |f'_x3 − g| ≤ Δf_max, f'_x3 the vertical specific force in
  the navigation frame. It needs the filter's attitude, so it is evaluated
  inside the filter loop, by the compiled ZUPT kernel
  (:func:`pednav_env.nav.detector_kernel.eq5_condition`), with optional causal
  moving averages over ``window_s`` (0 = sample by sample, as printed).
- :class:`ShoeDetectorConfig` — the SHOE / GLRT statistic of Skog, Händel,
  Nilsson, Rantakokko (2010), "Zero-velocity detection — an algorithm
  evaluation", IEEE TBME 57(11), eq (11):

      T_k = (1/W) Σ_{window} [ |f_j − g f̄/|f̄||² / σ_a² + |ω_j|² / σ_ω² ]

  stance where T_k < γ. It uses the IMU only, over the causal window ending
  at sample k, so :func:`shoe_statistic` computes it here for whole records
  and the kernel compares it with γ per sample.

Both take windows and minimum durations in seconds, so a configuration
carries over between sample rates. Minimum-duration logic (in the kernel):
stance is declared once the condition has held for ``min_stance_s`` (online:
the declaration is delayed, never back-dated). Numpy versions of eq (5) and
of the stance logic, the oracle of the kernel's detector in the tests, are in
:mod:`pednav_env.testing.detectors`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.detector_kernel import shoe_statistic_lanes

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


def detector_window(config: DetectorConfig, rate_hz: float) -> int:
    """Causal window W (samples) of a detector: eq (5) averages its inputs over W
    samples (1 when ``window_s`` = 0), SHOE's statistic covers W samples."""
    return window_samples(config.window_s, rate_hz) if config.window_s > 0 else 1


def min_stance_samples(min_stance_s: Array | float, rate_hz: float) -> NDArray[np.int64]:
    """Minimum stance duration(s) in samples (at least 1)."""
    return np.maximum(1, np.round(np.asarray(min_stance_s) * rate_hz)).astype(np.int64)


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


def run_lengths(flags: NDArray[np.bool_], carried: NDArray[np.integer]) -> NDArray[np.int64]:
    """For flags ``(B, K)``, how many samples in a row each flag has been true up to
    and including sample k (0 where it is false); ``carried`` (B,) is the run
    length before the block. k − (last false index), or carried + k + 1 when the
    flag held all block long."""
    k = flags.shape[1]
    idx = np.arange(k)
    last_false = np.maximum.accumulate(np.where(flags, -1, idx[None, :]), axis=1)
    return np.where(last_false >= 0, idx[None, :] - last_false, carried[:, None] + idx + 1)


def shoe_statistic_at(
    omega_b: Array,
    f_b: Array,
    first: NDArray[np.integer],
    k: int,
    windows: NDArray[np.integer],
    config: ShoeDetectorConfig,
) -> Array:
    """SHOE statistic T_m ``(N, k)`` (Skog 2010, eq 11) at samples
    m = first_i … first_i + k − 1 of records ``(N, T, 3)``, lane i over its own
    causal window of ``windows[i]`` samples (fewer at the start of the record, as
    :func:`shoe_statistic`). Only the samples the windows reach are read."""
    n = omega_b.shape[0]
    first = np.asarray(first, dtype=np.int64)
    windows = np.asarray(windows, dtype=np.int64)
    if first.shape != (n,) or windows.shape != (n,) or windows.min(initial=1) < 1:
        raise ValueError(f"first and windows must be ({n},) with windows ≥ 1")
    out = np.empty((n, k))
    shoe_statistic_lanes(
        np.ascontiguousarray(omega_b, dtype=float),
        np.ascontiguousarray(f_b, dtype=float),
        first,
        k,
        windows,
        float(2 * config.g),
        float(config.g**2),
        float(config.accel_noise_std**2),
        float(config.gyro_noise_std**2),
        out,
    )
    return out
