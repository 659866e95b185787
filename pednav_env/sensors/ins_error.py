"""Schuler-period INS velocity-error model of papers 000/004, batched over walkers.

Paper 000 (its last section) and paper 004 approximate the horizontal error
of a waist INS by Schuler oscillations, east channel (north is symmetric)::

    δV̇_E = −g β_N + B_E,     β̇_N = δV_E / R_E + ε_N

with δV the velocity error, β the levelling error, B the accelerometer bias,
ε the gyro drift and R_E the Earth radius (period 2π sqrt(R_E/g) = 84.4 min).
Paper 004 discretises it per step k of duration T_k (its state equation)::

    x_E(k) = Φ_E x_E(k−1) + w_E(k−1),   x_E = [δV_E, β_N, ε_N]
    Φ_E = [[1, −g T_k, 0], [T_k/R_E, 1, T_k], [0, 0, 1]]
    Φ_N = [[1,  g T_k, 0], [−T_k/R_E, 1, T_k], [0, 0, 1]],  x_N = [δV_N, β_E, ε_E]
    w = [w_a, 0, w_ε],  Q = diag(σ_a², 0, σ_ε²)  (variances per step)

The INS step-mean velocity is V̄^INS(k) = V̄(k) + δV(k) (paper 004 eq 1; the
error is taken constant within a step). This module is the *true* error
source used to synthesise V̄^INS; the step-fusion filter
(:mod:`pednav_env.nav.step_fusion_kf`) carries its own assumed copy.

Array layout: channel axis of length 2, ``0`` = east ``[δV_E, β_N, ε_N]``,
``1`` = north ``[δV_N, β_E, ε_E]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.constants import EARTH_RADIUS, STANDARD_GRAVITY

Array = NDArray[np.float64]

#: Sign of the g and 1/R terms of Φ per channel: east (+), north (−), paper 004.
CHANNEL_SIGN = np.array([1.0, -1.0])


def schuler_transition(
    step_period: ArrayLike,
    g: float = STANDARD_GRAVITY,
    earth_radius: float = EARTH_RADIUS,
    channel_sign: ArrayLike = CHANNEL_SIGN,
) -> Array:
    """Per-step transition matrices Φ(k, k−1) of paper 004.

    Parameters
    ----------
    step_period : array (...), s
        Step durations T_k.
    g, earth_radius : float
        Gravity (m/s²) and Earth radius (m).
    channel_sign : array broadcasting with ``step_period``
        +1 for Φ_E, −1 for Φ_N. The default (2,) appends a channel axis only
        if ``step_period`` ends with an axis of length 2 or 1; pass ``1.0`` or
        ``-1.0`` for one channel.

    Returns
    -------
    Phi : (..., 3, 3)
    """
    T = np.asarray(step_period, dtype=float)
    sgn = np.asarray(channel_sign, dtype=float)
    T, sgn = np.broadcast_arrays(T, sgn)
    Phi = np.zeros((*T.shape, 3, 3))
    Phi[..., 0, 0] = 1.0
    Phi[..., 0, 1] = -sgn * g * T
    Phi[..., 1, 0] = sgn * T / earth_radius
    Phi[..., 1, 1] = 1.0
    Phi[..., 1, 2] = T
    Phi[..., 2, 2] = 1.0
    return Phi


def schuler_process_noise(accel_noise_std: ArrayLike, drift_noise_std: ArrayLike) -> Array:
    """Q = diag(σ_a², 0, σ_ε²) per step (paper 004), shape ``(..., 3, 3)``."""
    sa = np.asarray(accel_noise_std, dtype=float)
    se = np.asarray(drift_noise_std, dtype=float)
    sa, se = np.broadcast_arrays(sa, se)
    Q = np.zeros((*sa.shape, 3, 3))
    Q[..., 0, 0] = sa * sa
    Q[..., 2, 2] = se * se
    return Q


@dataclass(frozen=True)
class SchulerErrorConfig:
    """True INS velocity-error model (paper 004 values as defaults).

    Attributes
    ----------
    accel_noise_std : float
        σ_a, std of w_a per step (m/s). Paper 004 uses 0.1, 0.5 and 1 m/s; 0.5 here.
    drift_noise_std : float
        σ_ε, std of w_ε per step (1/s = rad/s). Paper 004: 1e-6.
    initial_velocity_std, initial_tilt_std, initial_drift_std : float
        Std of the zero-mean initial δV (m/s), β (rad) and ε (rad/s). Paper 004
        prints no initial truth; defaults 0.3 m/s, 1 mrad and 0.1 °/h are our
        reading (docs/REPRODUCTION.md).
    accel_bias : float
        Constant B of paper 000's continuous model (m/s²), added as B·T_k to δV
        per step; 0 in paper 004.
    g, earth_radius : float
        m/s², m.
    """

    accel_noise_std: float = 0.5
    drift_noise_std: float = 1e-6
    initial_velocity_std: float = 0.3
    initial_tilt_std: float = 1e-3
    initial_drift_std: float = math.radians(0.1) / 3600.0
    accel_bias: float = 0.0
    g: float = STANDARD_GRAVITY
    earth_radius: float = EARTH_RADIUS

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"SchulerErrorConfig.{f.name} must be a finite number, got {v!r}")
            if f.name != "accel_bias" and v < 0:
                raise ValueError(f"SchulerErrorConfig.{f.name} must be ≥ 0, got {v!r}")
        if self.g <= 0 or self.earth_radius <= 0:
            raise ValueError(
                f"SchulerErrorConfig.g and earth_radius must be > 0, got {self.g!r}, "
                f"{self.earth_radius!r}"
            )

    @property
    def initial_std(self) -> Array:
        """[σ_δV0, σ_β0, σ_ε0]."""
        return np.array([self.initial_velocity_std, self.initial_tilt_std, self.initial_drift_std])

    @property
    def schuler_period(self) -> float:
        """2π sqrt(R_E / g) (s) — 5 064 s = 84.4 min for the defaults."""
        return 2.0 * math.pi * math.sqrt(self.earth_radius / self.g)


def simulate_schuler_errors(
    step_periods: ArrayLike,
    config: SchulerErrorConfig | Sequence[SchulerErrorConfig],
    rngs: np.random.Generator | Sequence[np.random.Generator],
) -> Array:
    """Draw the true error states of both channels for every step.

    Parameters
    ----------
    step_periods : (N, K) s
        Step durations T_k of every walker.
    config : SchulerErrorConfig or sequence of N
    rngs : Generator or sequence of N Generators
        Walker i draws only from ``rngs[i]`` (x(0) first, then per step
        [w_a east, w_ε east, w_a north, w_ε north]), so its errors do not
        depend on the batch.

    Returns
    -------
    x : (N, K+1, 2, 3)
        x[:, k] is the state after step k (x[:, 0] the initial state);
        channel 0 east [δV_E, β_N, ε_N], channel 1 north [δV_N, β_E, ε_E].
    """
    T = np.asarray(step_periods, dtype=float)
    if T.ndim != 2:
        raise ValueError(f"step_periods must be (N, K), got shape {T.shape}")
    if not np.all(np.isfinite(T)) or np.any(T <= 0):
        raise ValueError("step_periods must be finite and > 0")
    n, k = T.shape
    cfgs = list(config) if isinstance(config, Sequence) else [config] * n
    gens = [rngs] * n if isinstance(rngs, np.random.Generator) else list(rngs)
    if n > 1 and isinstance(rngs, np.random.Generator):
        raise ValueError("pass one Generator per walker (rngs) when N > 1")
    if len(cfgs) != n or len(gens) != n:
        raise ValueError(f"config and rngs need {n} entries, got {len(cfgs)} and {len(gens)}")
    x0 = np.empty((n, 2, 3))
    w = np.empty((n, k, 2, 3))
    for i, (c, rng) in enumerate(zip(cfgs, gens, strict=True)):
        x0[i] = rng.standard_normal((2, 3)) * c.initial_std
        draws = rng.standard_normal((k, 2, 2))
        w[i, :, :, 0] = draws[..., 0] * c.accel_noise_std
        w[i, :, :, 1] = 0.0
        w[i, :, :, 2] = draws[..., 1] * c.drift_noise_std
    g = np.array([c.g for c in cfgs])[:, None, None]
    R = np.array([c.earth_radius for c in cfgs])[:, None, None]
    bias = np.array([c.accel_bias for c in cfgs])[:, None, None]
    sgn = CHANNEL_SIGN[None, None, :]
    # Φ per walker, step and channel, written out (g and R may differ per walker).
    # ε is a running sum; δV and β are coupled, so they recur step by step on
    # Python floats (the same IEEE operations, in the same order, as arrays).
    Tc = T[:, :, None]
    a = (sgn * g) * Tc  # δV(k) = δV − a β + b + w_a
    b = np.broadcast_to(bias * Tc, a.shape)
    c = (sgn * Tc) / R  # β(k) = c δV + β + T ε
    eps = np.cumsum(np.concatenate((x0[:, None, :, 2], w[:, :, :, 2]), axis=1), axis=1)
    d = Tc * eps[:, :k]
    x = np.empty((n, k + 1, 2, 3))
    x[..., 2] = eps
    for i in range(n):
        for ch in range(2):
            dv, beta = float(x0[i, ch, 0]), float(x0[i, ch, 1])
            dvs, betas = [dv], [beta]
            cols = (a[i, :, ch], b[i, :, ch], w[i, :, ch, 0], c[i, :, ch], d[i, :, ch])
            for aj, bj, wj, cj, dj in zip(*(col.tolist() for col in cols), strict=True):
                dv, beta = dv - aj * beta + bj + wj, cj * dv + beta + dj
                dvs.append(dv)
                betas.append(beta)
            x[i, :, ch, 0] = dvs
            x[i, :, ch, 1] = betas
    return x


def per_sample_velocity_error(x: Array, step_index: NDArray[np.integer]) -> Array:
    """INS velocity error at every IMU sample, held constant within each step.

    Paper 004 takes δV constant during a step. Sample s of walker i in step
    k = ``step_index[i, s]`` gets δV(k+1) (the error over step k); samples
    past the last step keep the last value.

    Parameters
    ----------
    x : (N, K+1, 2, 3)
        Output of :func:`simulate_schuler_errors`.
    step_index : (N, T) int

    Returns
    -------
    dv : (N, T, 2) m/s, [east, north]
    """
    x = np.asarray(x, dtype=float)
    idx = np.clip(np.asarray(step_index) + 1, 1, x.shape[1] - 1)
    return np.take_along_axis(x[..., 0], idx[..., None], axis=1)
