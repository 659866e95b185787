"""Angle-sum forms of the sigma points' Euler angles: the ZUPT path of the foot
envs' shoe family, which corrects at every stance sample (paper 003's UKF).

With paper 003's α = 1e-3 the 19 sigma points lie within √((L + λ)P) =
3·10⁻³ standard deviations of the central one, so their angles differ from
the central point's by a few milliradians at most. At a ZUPT at every stance
sample the unscented prior is formed some 4 400 times per vector step of the
foot env at N = 256, and glibc's inverse-trigonometric and sincos calls of the
19 points (57 and 51 per ZUPT) were a third of the kernel's time
(docs/PERFORMANCE.md). This module computes the same quantities from the
central point's:

- :func:`moved_residuals`: the moved points' residuals from the central point
  (the unscented transform's wrapped deviations, paper 003 / filterpy's
  ``residual_x``). For the angles, instead of three inverse-trigonometric
  calls per point and a difference, the difference itself: ψ_s − ψ₀ =
  atan2(u₀ × u_s, u₀ · u_s) with u = (C₀₀, C₁₀), γ likewise with (C₂₂, C₂₁),
  and θ_s − θ₀ from sin θ = −C₂₀ by the angle-difference formula; the small
  arc tangent by its series (:func:`atan_small`).
- :func:`sigma_attitudes`: the drawn points' attitudes from the central
  point's cosines and sines by the angle-sum formulas, cos(a₀ ± δ) =
  cos a₀ cos δ ∓ sin a₀ sin δ, sin(a₀ ± δ) = sin a₀ cos δ ± cos a₀ sin δ,
  δ a column entry of the Cholesky factor, cos δ and sin δ by their series
  (:func:`sin_cos_small`).

Both are the same mathematics as the direct formulas
(:func:`pednav_env.nav.preintegration.moved_states`,
:func:`pednav_env.nav.zupt_algebra.draw_sigmas`), with different rounding: the
series are truncated where the next term is below 10⁻¹⁷ of the result, and an
angle outside ±:data:`SMALL_ANGLE` takes the library call. The kernel uses them
when :attr:`pednav_env.nav.zupt_config.ZuptUkfConfig.angle_sums` is set: the foot
envs' shoe family (:func:`pednav_env.envs.foot_filters.family_filter`). Paper
003's filter and the named setups of recordings (``real-fixed``) keep the direct
formulas, so their results repeat bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pednav_env.nav.preintegration import Preintegral, SigmaPoints
from pednav_env.rotations import dcm_euler_angles, euler_dcm_rows, wrap_float

_wrap = njit(cache=True)(wrap_float)
_dcm_euler_angles = njit(cache=True)(dcm_euler_angles)
_euler_dcm_rows = njit(cache=True)(euler_dcm_rows)

#: rad: the series of :func:`atan_small` and :func:`sin_cos_small` are used up to this
#: angle (their first omitted terms are below 10⁻¹⁷ of the result there).
SMALL_ANGLE = 0.02


@njit(cache=True, inline="always")
def atan_small(y: float, x: float) -> float:
    """atan2(y, x) (rad) in [−π, π): the series t − t³/3 + t⁵/5 − t⁷/7 + t⁹/9 of
    atan t, t = y/x, when x > 0 and |t| ≤ :data:`SMALL_ANGLE`; else ``math.atan2``
    wrapped."""
    if x > 0.0:
        t = y / x
        if abs(t) <= SMALL_ANGLE:
            t2 = t * t
            return t * (1.0 - t2 * (1.0 / 3.0 - t2 * (0.2 - t2 * (1.0 / 7.0 - t2 * (1.0 / 9.0)))))
    return _wrap(math.atan2(y, x))


@njit(cache=True, inline="always")
def sin_cos_small(d: float) -> tuple[float, float]:
    """(cos d, sin d) by their series (through d⁸ and d⁷) when |d| ≤
    :data:`SMALL_ANGLE`, else ``math.cos``, ``math.sin``. Odd in d for sin, even
    for cos, and exactly (1, 0) at d = 0."""
    if abs(d) <= SMALL_ANGLE:
        d2 = d * d
        s = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)))
        c = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)))
        return c, s
    return math.cos(d), math.sin(d)


@njit(cache=True, inline="always")
def _clip_unit(a: float) -> float:
    return min(max(a, -1.0), 1.0)


@njit(cache=True)
def moved_residuals(
    sig: SigmaPoints,
    pre: Preintegral,
    tau: float,
    g: float,
    chi: np.ndarray,
    C_moved: np.ndarray,
    dev: np.ndarray,
) -> None:
    """The sigma points moved by the preintegrals over τ (s), as
    :func:`pednav_env.nav.preintegration.moved_states` (the same arithmetic for
    ``chi``'s positions and velocities and for the central point's angles and
    attitude ``C_moved[0]``), and ``dev`` (S, 9): each point's residual from the
    central point, the angles' by the difference forms of the module docstring
    (wrapped into [−π, π)). ``chi``'s angles of the points s ≥ 1 are the central
    angle plus the residual (not wrapped); of ``C_moved`` only the central
    point's attitude is written."""
    C, v, p = sig
    D, A, B = pre.D, pre.A, pre.B
    a0 = b0 = c0_0 = c1_0 = r1_0 = r2_0 = 0.0
    for s in range(chi.shape[0]):
        u0 = u1 = w0 = w1 = a = 0.0  # C₀₀, C₁₀, C₂₂, C₂₁, −C₂₀ of the moved point
        for r in range(3):
            c0, c1, c2 = C[s, r, 0], C[s, r, 1], C[s, r, 2]
            m0 = c0 * D[0, 0] + c1 * D[1, 0] + c2 * D[2, 0]
            if s == 0 or r == 2:
                m1 = c0 * D[0, 1] + c1 * D[1, 1] + c2 * D[2, 1]
                m2 = c0 * D[0, 2] + c1 * D[1, 2] + c2 * D[2, 2]
                if s == 0:
                    C_moved[0, r, 0], C_moved[0, r, 1], C_moved[0, r, 2] = m0, m1, m2
                if r == 2:
                    a, w1, w0 = -m0, m1, m2
            if r == 0:
                u0 = m0
            elif r == 1:
                u1 = m0
            ca = c0 * A[0] + c1 * A[1] + c2 * A[2]
            cb = c0 * B[0] + c1 * B[1] + c2 * B[2]
            chi[s, r] = p[s, r] + v[s, r] * tau + cb
            chi[s, 3 + r] = v[s, r] + ca
        chi[s, 2] -= 0.5 * g * (tau * tau)
        chi[s, 5] -= g * tau
        if s == 0:
            yaw, pitch, roll = _dcm_euler_angles(u0, u1, -a, w1, w0)
            chi[0, 6], chi[0, 7], chi[0, 8] = pitch, roll, yaw
            for d in range(9):
                dev[0, d] = 0.0
            a0 = _clip_unit(a)
            b0 = math.sqrt(1.0 - a0 * a0)  # cos θ₀
            c0_0, c1_0, r1_0, r2_0 = u0, u1, w1, w0
            continue
        for d in range(6):
            dev[s, d] = chi[s, d] - chi[0, d]
        # ψ_s − ψ₀ and γ_s − γ₀: the angle between (C₀₀, C₁₀) and between (C₂₂, C₂₁)
        d_yaw = atan_small(u1 * c0_0 - u0 * c1_0, u0 * c0_0 + u1 * c1_0)
        d_roll = atan_small(w1 * r2_0 - w0 * r1_0, w0 * r2_0 + w1 * r1_0)
        # θ_s − θ₀ from sin θ = a: sin(θ_s − θ₀) = a cos θ₀ − a₀ cos θ_s, written as
        # (a − a₀)(cos θ₀ + a₀ (a + a₀)/(cos θ_s + cos θ₀)) to keep its relative precision
        a = _clip_unit(a)
        ca = math.sqrt(1.0 - a * a)
        den = ca + b0
        if den > 0.0:
            sin_d = (a - a0) * (b0 + a0 * (a + a0) / den)
        else:
            sin_d = a * b0 - a0 * ca
        d_pitch = atan_small(sin_d, ca * b0 + a * a0)
        dev[s, 6], dev[s, 7], dev[s, 8] = d_pitch, d_roll, d_yaw
        for d in range(6, 9):
            chi[s, d] = chi[0, d] + dev[s, d]


@njit(cache=True)
def sigma_attitudes(x: np.ndarray, L: np.ndarray, C: np.ndarray) -> None:
    """``C`` (2n + 1, 3, 3) ← the attitudes C_nb (paper 003 eq 1) of the sigma
    points x̂, x̂ + L_k, x̂ − L_k (k = 1 … n, n = 9) of :func:`pednav_env.nav.
    zupt_algebra.draw_sigmas`: the central point's from the cosines and sines of
    its wrapped angles, the others' by the angle-sum formulas with δ = ±L[d, k]
    (module docstring)."""
    n = L.shape[0]
    yaw0, pitch0, roll0 = _wrap(x[8]), _wrap(x[6]), _wrap(x[7])
    cy0, sy0 = math.cos(yaw0), math.sin(yaw0)
    cp0, sp0 = math.cos(pitch0), math.sin(pitch0)
    cr0, sr0 = math.cos(roll0), math.sin(roll0)
    rows = _euler_dcm_rows(cy0, sy0, cp0, sp0, cr0, sr0)
    for r in range(3):
        for c in range(3):
            C[0, r, c] = rows[r][c]
    for k in range(n):
        ccp, scp = sin_cos_small(L[6, k])
        ccr, scr = sin_cos_small(L[7, k])
        ccy, scy = sin_cos_small(L[8, k])
        for s in (1 + k, 1 + n + k):
            sign = 1.0 if s <= n else -1.0
            cy, sy = cy0 * ccy - sign * (sy0 * scy), sy0 * ccy + sign * (cy0 * scy)
            cp, sp = cp0 * ccp - sign * (sp0 * scp), sp0 * ccp + sign * (cp0 * scp)
            cr, sr = cr0 * ccr - sign * (sr0 * scr), sr0 * ccr + sign * (cr0 * scr)
            rows = _euler_dcm_rows(cy, sy, cp, sp, cr, sr)
            for r in range(3):
                for c in range(3):
                    C[s, r, c] = rows[r][c]
