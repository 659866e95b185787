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
