"""Compiled stance detector of the ZUPT kernel, one walker and one sample at a time.

The production implementation of paper 003 eq (5) and of the stance logic
(configurations: :mod:`pednav_env.nav.detectors`), called at every sample by
:func:`pednav_env.nav.zupt_kernel.advance_block` and inlined there by numba:

- :func:`eq5_condition`: |ω'| ≤ ω_max and |f'_x3 − g| ≤ Δf_max on causal means
  over a window of W samples (W = 1: sample by sample, as printed);
- :func:`detect`: that condition with f'_x3 through the filter's attitude, or
  the SHOE condition T_k < γ of the record (Skog et al. 2010 eq 11, computed by
  :func:`pednav_env.nav.detectors.shoe_statistic`);
- :func:`stance_logic`: stance declared once the condition held for the
  minimum stance duration, stance start and end events.

Numpy versions, the tests' oracle, are in :mod:`pednav_env.testing.detectors`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class Eq5Thresholds(NamedTuple):
    """Thresholds of eq (5) for one walker."""

    omega_max: float  # rad/s
    delta_f_max: float  # m/s²
    g: float  # m/s²


@njit(cache=True, inline="always")
def eq5_condition(
    w: np.ndarray, f_n3: float, history: np.ndarray, count: int, thresholds: Eq5Thresholds
) -> tuple[bool, int]:
    """Paper 003 eq (5) on causal means over the window of W = len(history) + 1
    samples (the first samples of a walker average over fewer). ``w`` (rad/s) is
    the sample's rate, ``f_n3`` (m/s²) its vertical specific force; ``history``
    (W − 1, 2), the last inputs (|ω'|, f'_x3) oldest first, is advanced in place
    and ``count`` is the number of samples seen. Returns (condition, samples
    seen capped at W)."""
    window = history.shape[0] + 1
    w_norm = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if window == 1:
        om, fm = w_norm, f_n3
        count = 1
    else:
        s_om, s_f = 0.0, 0.0
        for h in range(window - 1):
            s_om += history[h, 0]
            s_f += history[h, 1]
        s_om += w_norm
        s_f += f_n3
        count = min(count + 1, window)
        om, fm = s_om / count, s_f / count
        for h in range(window - 2):
            history[h, 0] = history[h + 1, 0]
            history[h, 1] = history[h + 1, 1]
        history[window - 2, 0] = w_norm
        history[window - 2, 1] = f_n3
    return (om <= thresholds.omega_max) and (
        abs(fm - thresholds.g) <= thresholds.delta_f_max
    ), count


@njit(cache=True, inline="always")
def detect(
    shoe_condition: np.ndarray,
    j: int,
    w: np.ndarray,
    F: np.ndarray,
    C_central: np.ndarray,
    history: np.ndarray,
    count: int,
    thresholds: Eq5Thresholds,
) -> tuple[bool, int]:
    """Stance condition at sample j: the SHOE condition ``shoe_condition[j]`` when
    the walker's row (K,) is given (empty for eq 5), else eq (5)
    (:func:`eq5_condition`) with f'_x3 = e₃ᵀ C_c F, F = D f_mid (m/s²) the
    specific force in the anchor's axes, through the central sigma point's
    anchor attitude ``C_central`` (its attitude now is C_c D). Returns
    (condition, samples seen)."""
    if shoe_condition.shape[0] > 0:
        return shoe_condition[j], min(count + 1, history.shape[0] + 1)
    f_n3 = C_central[2, 0] * F[0] + C_central[2, 1] * F[1] + C_central[2, 2] * F[2]
    return eq5_condition(w, f_n3, history, count, thresholds)


@njit(cache=True, inline="always")
def stance_logic(
    condition: bool, run: int, in_stance: bool, min_run: int
) -> tuple[int, bool, bool, bool]:
    """Stance declared once the condition held ``min_run`` samples in a row
    (causal: the declaration is delayed, never back-dated). ``run`` counts the
    samples the condition has held before this one. Returns (run, stance,
    start, end)."""
    run = run + 1 if condition else 0
    now = run >= min_run
    return run, now, now and not in_stance, in_stance and not now


@njit(cache=True)
def shoe_statistic_lanes(
    omega_b: np.ndarray,
    f_b: np.ndarray,
    first: np.ndarray,
    k: int,
    windows: np.ndarray,
    two_g: float,
    g2: float,
    accel_var: float,
    gyro_var: float,
    out: np.ndarray,
) -> None:
    """``out`` (N, k) ← the SHOE statistic (Skog et al. 2010 eq 11) of lane i at
    samples first_i … first_i + k − 1 of records ``omega_b``, ``f_b`` (N, T, 3)
    over causal windows of ``windows[i]`` samples (fewer at the start), with
    2g = ``two_g``, g² = ``g2``, σ_a² = ``accel_var``, σ_ω² = ``gyro_var``: the
    arithmetic of the batched numpy version
    (:func:`pednav_env.testing.detectors.shoe_statistic_at_numpy`) in its order,
    bit for bit: prefix sums from sample first_i − (max W − 1) (zeros
    before the record), window sums as differences of prefix sums, divided by
    the window's sample count; T = (Σ|f|²/W − 2g u·f̄ + g²)/σ_a² + (Σ|ω|²/W)/σ_ω²
    with u = f̄/max(|f̄|, 1e-12)."""
    n = omega_b.shape[0]
    back = 0
    for i in range(n):
        back = max(back, windows[i] - 1)
    span = back + k
    cf = np.empty((span + 1, 3))
    cf2 = np.empty(span + 1)
    cw2 = np.empty(span + 1)
    for i in range(n):
        fi, w = first[i], windows[i]
        cf[0, 0] = cf[0, 1] = cf[0, 2] = 0.0
        cf2[0] = cw2[0] = 0.0
        for t in range(span):
            idx = fi - back + t
            if idx >= 0:
                fx, fy, fz = f_b[i, idx, 0], f_b[i, idx, 1], f_b[i, idx, 2]
                wx, wy, wz = omega_b[i, idx, 0], omega_b[i, idx, 1], omega_b[i, idx, 2]
            else:
                fx = fy = fz = wx = wy = wz = 0.0
            f2 = fx * fx + fy * fy + fz * fz
            w2 = wx * wx + wy * wy + wz * wz
            if t == 0:  # numpy's cumsum starts at the first term, not at 0 + it
                cf[1, 0], cf[1, 1], cf[1, 2], cf2[1], cw2[1] = fx, fy, fz, f2, w2
            else:
                cf[t + 1, 0] = cf[t, 0] + fx
                cf[t + 1, 1] = cf[t, 1] + fy
                cf[t + 1, 2] = cf[t, 2] + fz
                cf2[t + 1] = cf2[t] + f2
                cw2[t + 1] = cw2[t] + w2
        for j in range(k):
            hi = back + 1 + j
            lo = hi - w
            count = float(min(w, fi + j + 1))
            mx = (cf[hi, 0] - cf[lo, 0]) / count
            my = (cf[hi, 1] - cf[lo, 1]) / count
            mz = (cf[hi, 2] - cf[lo, 2]) / count
            norm = math.sqrt(mx * mx + my * my + mz * mz)
            den = norm if (norm != norm or norm > 1e-12) else 1e-12  # np.maximum keeps NaN
            cross = (mx / den) * mx + (my / den) * my + (mz / den) * mz
            sum_f2 = (cf2[hi] - cf2[lo]) / count
            acc_term = sum_f2 - two_g * cross + g2
            gyro_term = (cw2[hi] - cw2[lo]) / count
            out[i, j] = acc_term / accel_var + gyro_term / gyro_var
