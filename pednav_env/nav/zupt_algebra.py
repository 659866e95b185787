"""Compiled unscented algebra of one walker of the ZUPT-UKF (paper 003).

Paper 003's UKF section (after Wan & van der Merwe 2000) for the state
y = [x₁, x₂, x₃, v₁, v₂, v₃, θ, γ, ψ] (L = 9), step for step as
``filterpy.kalman.UnscentedKalmanFilter`` 2.0 computes it (the oracle of the
tests; :mod:`pednav_env.nav.ukf` gives the weights):

- :func:`draw_sigmas`: χ₀ = x̂, χ_k = x̂ + √((L+λ)P)_k, χ_{L+k} = x̂ − √((L+λ)P)_k
  with the lower Cholesky factor's columns, angles wrapped;
- :func:`prior_moments`: the unscented mean and covariance of the propagated
  points plus Q, angles averaged and differenced with wrapping;
- :func:`zupt_update`: the update with the ZUPT pseudo-measurement
  h(y) = [x₃, v₁, v₂, v₃], z = [x₃(t₀), 0, 0, 0].

Scalar loops over one walker's arrays, called from
:func:`pednav_env.nav.zupt_kernel.advance_block`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pednav_env.nav.preintegration import SigmaPoints
from pednav_env.nav.sigma_angles import sigma_attitudes
from pednav_env.nav.ukf import floored_covariance
from pednav_env.rotations import euler_dcm_rows, wrap_float

_wrap = njit(cache=True)(wrap_float)
_euler_dcm_rows = njit(cache=True)(euler_dcm_rows)

#: Index of the first angle (θ) in the state; angles are 6, 7, 8.
FIRST_ANGLE = 6


class AlgebraScratch(NamedTuple):
    """Work arrays of :func:`zupt_update` and :func:`draw_sigmas`, reused from one
    ZUPT to the next (an allocation per ZUPT costs about as much as a 4 × 4
    inverse)."""

    SI: np.ndarray  # (4, 4) S, then S⁻¹
    KT: np.ndarray  # (4, 9) Kᵀ
    aug: np.ndarray  # (4, 8) [S | I] of the Gauss–Jordan inverse
    y: np.ndarray  # (4,) innovation
    Pxz: np.ndarray  # (9, 4) P_xz
    A: np.ndarray  # (9, 9) (L + λ) P
    L: np.ndarray  # (9, 9) its lower Cholesky factor
    chi: np.ndarray  # (9,) one sigma point


@njit(cache=True)
def new_algebra_scratch() -> AlgebraScratch:
    """Work arrays for :func:`zupt_update` and :func:`draw_sigmas`."""
    return AlgebraScratch(
        np.empty((4, 4)),
        np.empty((4, 9)),
        np.empty((4, 8)),
        np.empty(4),
        np.empty((9, 4)),
        np.empty((9, 9)),
        np.zeros((9, 9)),
        np.empty(9),
    )


@njit(cache=True)
def state_mean(chi: np.ndarray, Wm: np.ndarray, out: np.ndarray) -> None:
    """Weighted mean of states ``chi`` (S, 9) with angles averaged as wrapped
    deviations from the central point (filterpy's ``x_mean_fn``; the numpy twin is
    :func:`pednav_env.nav.zupt_model.state_mean`)."""
    for d in range(9):
        acc = 0.0
        for s in range(chi.shape[0]):
            dev = chi[s, d] - chi[0, d]
            acc += Wm[s] * (_wrap(dev) if d >= FIRST_ANGLE else dev)
        out[d] = _wrap(chi[0, d] + acc) if d >= FIRST_ANGLE else chi[0, d] + acc


@njit(cache=True)
def residual_mean(chi: np.ndarray, dev: np.ndarray, Wm: np.ndarray, out: np.ndarray) -> None:
    """``out`` (9,) ← the central point of ``chi`` (S, 9) plus the ``Wm``-weighted
    sum of the residuals ``dev`` (S, 9), angles wrapped: :func:`state_mean` from
    residuals computed elsewhere (:func:`pednav_env.nav.sigma_angles.moved_residuals`)."""
    for d in range(9):
        acc = 0.0
        for s in range(chi.shape[0]):
            acc += Wm[s] * dev[s, d]
        out[d] = _wrap(chi[0, d] + acc) if d >= FIRST_ANGLE else chi[0, d] + acc


@njit(cache=True)
def residuals(chi: np.ndarray, dev: np.ndarray) -> None:
    """``dev`` (S, 9) ← the residuals of sigma states ``chi`` (S, 9) from the
    central point, angles wrapped (filterpy's ``residual_x``)."""
    for s in range(chi.shape[0]):
        for d in range(9):
            v = chi[s, d] - chi[0, d]
            dev[s, d] = _wrap(v) if d >= FIRST_ANGLE else v


@njit(cache=True)
def prior_moments(
    chi: np.ndarray,
    Wm: np.ndarray,
    Wc: np.ndarray,
    basis: np.ndarray,
    powers: np.ndarray,
    dev: np.ndarray,
    x: np.ndarray,
    P: np.ndarray,
) -> None:
    """Unscented mean ``x`` (9,) and covariance ``P`` (9, 9) of sigma states ``chi``
    (S, 9) plus Q = Σ_p powers_p basis_p (:func:`pednav_env.nav.zupt_model.process_noise`):
    filterpy's ``unscented_transform`` with the wrapped-angle mean and residual.
    ``dev`` (S, 9) holds the residuals from the central point (:func:`residuals`
    or :func:`pednav_env.nav.sigma_angles.moved_residuals`) and is overwritten
    with the residuals from the mean; of ``chi`` only the central point is read.

    Every entry is the sum filterpy's formula gives, in its order: the weighted
    terms of s = 0 … S − 1 from 0, then Q's powers. The loops run over the sigma
    points outermost, so that the sums of different entries are independent
    chains the CPU overlaps (one chain at a time is bound by the latency of an
    addition), and Wc_s · dev_sr is formed once per (s, r)."""
    ns = chi.shape[0]
    for d in range(9):
        x[d] = 0.0  # the weighted sum of the residuals from the central point
    for s in range(ns):
        w = Wm[s]
        for d in range(9):
            x[d] += w * dev[s, d]
    for d in range(9):
        acc = x[d]
        x[d] = _wrap(chi[0, d] + acc) if d >= FIRST_ANGLE else chi[0, d] + acc
        for s in range(ns):
            v = dev[s, d] - acc
            dev[s, d] = _wrap(v) if d >= FIRST_ANGLE else v
    for r in range(9):
        for c in range(r, 9):
            P[r, c] = 0.0
    for s in range(ns):
        w = Wc[s]
        for r in range(9):
            wd = w * dev[s, r]
            for c in range(r, 9):
                P[r, c] += wd * dev[s, c]
    for r in range(9):
        for c in range(r, 9):
            acc = P[r, c]
            for p in range(powers.shape[0]):
                acc += powers[p] * basis[p, r, c]
            P[r, c] = acc
            P[c, r] = acc


@njit(cache=True)
def inverse4(S: np.ndarray, out: np.ndarray, a: np.ndarray) -> None:
    """Inverse of a 4 × 4 matrix by Gauss–Jordan elimination with partial pivoting
    (NaN for a singular matrix, never an exception); ``a`` (4, 8) is scratch, and
    ``out`` may be ``S`` itself (S is read before ``out`` is written)."""
    for r in range(4):
        for c in range(4):
            a[r, c] = S[r, c]
            a[r, 4 + c] = 1.0 if r == c else 0.0
    for c in range(4):
        piv = c
        for r in range(c + 1, 4):
            if abs(a[r, c]) > abs(a[piv, c]):
                piv = r
        if piv != c:
            for k in range(8):
                a[c, k], a[piv, k] = a[piv, k], a[c, k]
        inv_p = 1.0 / a[c, c]
        for k in range(8):
            a[c, k] *= inv_p
        for r in range(4):
            if r != c:
                m = a[r, c]
                for k in range(8):
                    a[r, k] -= m * a[c, k]
    for r in range(4):
        for c in range(4):
            out[r, c] = a[r, 4 + c]


@njit(cache=True)
def zupt_update(
    x: np.ndarray,
    P: np.ndarray,
    height_ref: float,
    R_diag: np.ndarray,
    gate_nis: float,
    work: AlgebraScratch,
) -> tuple[float, bool]:
    """The UKF update with the linear h(y) = [x₃, v₁, v₂, v₃], z = [x₃(t₀), 0, 0, 0]
    (m, m/s; ``height_ref`` = x₃(t₀)) and R = diag(``R_diag``) on the prior (x, P),
    in place; ``work`` holds S⁻¹ and Kᵀ afterwards.

    Sigma points drawn from (x⁻, P⁻) through a linear h give exactly ẑ = h(x⁻),
    S = H P⁻ Hᵀ + R, P_xz = P⁻ Hᵀ, so this is filterpy 2.0's update on redrawn
    prior sigma points, without drawing them: Kᵀ = S⁻¹ P_xzᵀ, x ← x + K y
    (angles wrapped), P ← sym(P − P_xz Kᵀ). Returns (NIS, accepted by the χ²
    gate ``gate_nis``; inf accepts all)."""
    SI, KT, y = work.SI, work.KT, work.y
    for r in range(4):
        for c in range(4):
            SI[r, c] = P[2 + r, 2 + c]
        SI[r, r] += R_diag[r]
    inverse4(SI, SI, work.aug)
    y[0] = height_ref - x[2]
    for r in range(1, 4):
        y[r] = -x[2 + r]
    nis = 0.0
    for r in range(4):
        acc = 0.0
        for c in range(4):
            acc += SI[r, c] * y[c]
        nis += acc * y[r]
    for r in range(4):
        for c in range(9):
            acc = 0.0
            for m in range(4):
                acc += SI[r, m] * P[c, 2 + m]
            KT[r, c] = acc
    accepted = nis <= gate_nis
    if accepted:
        for c in range(9):
            acc = 0.0
            for r in range(4):
                acc += y[r] * KT[r, c]
            x[c] += acc
        _subtract_gain(P, KT, work.Pxz)
    for d in range(FIRST_ANGLE, 9):
        x[d] = _wrap(x[d])
    for r in range(9):
        for c in range(r + 1, 9):
            m = 0.5 * (P[r, c] + P[c, r])
            P[r, c] = m
            P[c, r] = m
    return nis, accepted


@njit(cache=True)
def _subtract_gain(P: np.ndarray, KT: np.ndarray, Pxz: np.ndarray) -> None:
    """P ← P − P_xz Kᵀ with P_xz = P[:, 2:6] read into ``Pxz`` (9, 4) before any
    entry changes."""
    for r in range(9):
        for m in range(4):
            Pxz[r, m] = P[r, 2 + m]
    for r in range(9):
        for c in range(9):
            acc = 0.0
            for m in range(4):
                acc += Pxz[r, m] * KT[m, c]
            P[r, c] -= acc


@njit(cache=True)
def cholesky_lower(A: np.ndarray, L: np.ndarray) -> bool:
    """Lower Cholesky factor of a symmetric matrix into ``L``; False when it is not
    positive definite (a pivot ≤ 0 or not finite)."""
    n = A.shape[0]
    for j in range(n):
        acc = A[j, j]
        for k in range(j):
            acc -= L[j, k] * L[j, k]
        if not (acc > 0.0) or not math.isfinite(acc):
            return False
        d = math.sqrt(acc)
        L[j, j] = d
        for i in range(j + 1, n):
            acc = A[i, j]
            for k in range(j):
                acc -= L[i, k] * L[j, k]
            L[i, j] = acc / d
        for i in range(j):
            L[i, j] = 0.0
    return True


@njit(cache=True)
def draw_sigmas(
    x: np.ndarray,
    P: np.ndarray,
    spread: float,
    sig: SigmaPoints,
    work: AlgebraScratch,
    angle_sums: bool = False,
) -> bool:
    """Sigma points of (x, P) with ``spread`` = L + λ, written into ``sig`` as
    attitude matrices, velocities and positions (module docstring;
    filterpy's ``MerweScaledSigmaPoints``, whose upper factor's rows are the lower
    factor's columns; the factor is left in ``work.L``). Returns True when (L + λ)P
    had no Cholesky factor and was repaired first
    (:func:`pednav_env.nav.ukf.floored_covariance`).

    An angle of a point equal to the central point's (a zero in the factor's
    column: θ for the last two columns, γ for the last) takes the central
    point's cosine and sine instead of computing them again (the same values).
    With ``angle_sums`` the attitudes come from the central point's cosines and
    sines by the angle-sum formulas (:func:`pednav_env.nav.sigma_angles.sigma_attitudes`;
    the same rotations, other rounding)."""
    C, v, p = sig
    A, L, chi = work.A, work.L, work.chi
    n = 9
    for r in range(n):
        for c in range(n):
            A[r, c] = spread * P[r, c]
    repaired = False
    if not cholesky_lower(A, L):
        repaired = True
        floored = np.empty((n, n))
        floored_covariance(A, floored)
        cholesky_lower(floored, L)
    if angle_sums:
        for s in range(2 * n + 1):
            sign = 0.0 if s == 0 else (1.0 if s <= n else -1.0)
            k = (s - 1) % n
            for r in range(3):
                p[s, r] = x[r] + sign * L[r, k] if s > 0 else x[r]
                v[s, r] = x[3 + r] + sign * L[3 + r, k] if s > 0 else x[3 + r]
        sigma_attitudes(x, L, C)
        return repaired
    yaw0, pitch0, roll0 = _wrap(x[8]), _wrap(x[6]), _wrap(x[7])
    cy0, sy0 = math.cos(yaw0), math.sin(yaw0)
    cp0, sp0 = math.cos(pitch0), math.sin(pitch0)
    cr0, sr0 = math.cos(roll0), math.sin(roll0)
    for s in range(2 * n + 1):
        sign = 0.0 if s == 0 else (1.0 if s <= n else -1.0)
        k = (s - 1) % n
        for d in range(n):
            val = x[d] + sign * L[d, k] if s > 0 else x[d]
            chi[d] = _wrap(val) if d >= FIRST_ANGLE else val
        for r in range(3):
            p[s, r] = chi[r]
            v[s, r] = chi[3 + r]
        yaw, pitch, roll = chi[8], chi[6], chi[7]
        # equal and non-zero: the same bits as the central angle (±0 would not be)
        if yaw == yaw0 and yaw != 0.0:
            cy, sy = cy0, sy0
        else:
            cy, sy = math.cos(yaw), math.sin(yaw)
        if pitch == pitch0 and pitch != 0.0:
            cp, sp = cp0, sp0
        else:
            cp, sp = math.cos(pitch), math.sin(pitch)
        if roll == roll0 and roll != 0.0:
            cr, sr = cr0, sr0
        else:
            cr, sr = math.cos(roll), math.sin(roll)
        rows = _euler_dcm_rows(cy, sy, cp, sp, cr, sr)
        for r in range(3):
            for c in range(3):
                C[s, r, c] = rows[r][c]
    return repaired


@njit(cache=True)
def redraw_sigmas(
    lanes: np.ndarray,
    x: np.ndarray,
    P: np.ndarray,
    spread: float,
    sig_C: np.ndarray,
    sig_v: np.ndarray,
    sig_p: np.ndarray,
    angle_sums: bool = False,
) -> np.ndarray:
    """Draw the sigma points ``sig_C``, ``sig_v``, ``sig_p`` (N, S, ·) of walkers
    ``lanes`` from their (x, P) rows (``x`` (B, 9), ``P`` (B, 9, 9);
    :func:`draw_sigmas`, ``angle_sums`` as there); returns the mask of
    covariances that had to be repaired."""
    work = new_algebra_scratch()
    bad = np.zeros(lanes.shape[0], dtype=np.bool_)
    for j in range(lanes.shape[0]):
        i = lanes[j]
        points = SigmaPoints(sig_C[i], sig_v[i], sig_p[i])
        bad[j] = draw_sigmas(x[j], P[j], spread, points, work, angle_sums)
    return bad
