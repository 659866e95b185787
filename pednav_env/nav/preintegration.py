"""Compiled strapdown increments and preintegrals of one walker (paper 003 eq 3).

The ZUPT kernel (:mod:`pednav_env.nav.zupt_kernel`) does not step its 19
sigma points sample by sample. The strapdown of eq (3)
(:mod:`pednav_env.nav.strapdown`) is affine in the state it starts from: from
an anchor at sample a with attitude C₀, velocity v₀ and position x₀,

    C_t = C₀ D,   v_t = v₀ + C₀ A − g e₃ τ,   x_t = x₀ + v₀ τ + C₀ B − ½ g e₃ τ²,

τ = (t − a) Δt, D = C(Δq_a) ⋯ C(Δq_{t−1}), A = Σ_j D_j f_mid,j Δt (D_j the
product up to sample j) and B the trapezoid sum of A. D, A and B are
quantities of the IMU record alone, the same for every sigma point (the
preintegration of Lupton & Sukkarieh 2012 and Forster et al. 2017, without
bias states; the same arithmetic as stepping every point, regrouped). The
kernel accumulates them once per sample (:func:`strapdown_increment`,
:func:`accumulate`) and moves the points only when it needs them
(:func:`moved_states`, :func:`move_sigmas`).

A walker's sigma points are a :class:`SigmaPoints` (attitude matrices,
velocities, positions), its preintegrals a :class:`Preintegral`. Helpers
called at every sample are inlined by numba (``inline="always"``): a compiled
call per sample costs more than the sample's arithmetic. Loops index whole
arrays (``C[s, r, c]``) instead of taking a view per point (``C[s]``): every
view of an array costs numba two atomic reference-count updates, which in a
loop over points cost as much as the arithmetic (docs/PERFORMANCE.md).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pednav_env.rotations import dcm_euler_angles

_dcm_euler_angles = njit(cache=True)(dcm_euler_angles)


class SigmaPoints(NamedTuple):
    """The S sigma points of one walker (navigation frame)."""

    C: np.ndarray  # (S, 3, 3) attitude matrices C_nb
    v: np.ndarray  # (S, 3) velocities (m/s)
    p: np.ndarray  # (S, 3) positions (m)


class Preintegral(NamedTuple):
    """Preintegrals of one walker since its anchor (the last sigma-point draw)."""

    D: np.ndarray  # (3, 3) attitude change C(Δq_a) ⋯ C(Δq_{t−1})
    A: np.ndarray  # (3,) Σ D_j f_mid,j Δt (m/s), in anchor body axes
    B: np.ndarray  # (3,) trapezoid sum of A (m)


@njit(cache=True)
def restart(pre: Preintegral) -> None:
    """D = I, A = B = 0: the preintegrals of an empty interval."""
    D, A, B = pre
    for r in range(3):
        for c in range(3):
            D[r, c] = 1.0 if r == c else 0.0
        A[r] = 0.0
        B[r] = 0.0


@njit(cache=True, inline="always")
def _rotvec_quat(kx: float, ky: float, kz: float) -> tuple[float, float, float, float]:
    """Δq = [cos(|k|/2), k/|k| sin(|k|/2)] (paper 003 eq 3; series below 1e-6 rad),
    as :func:`pednav_env.rotations.quat_from_rotvec`."""
    angle = math.sqrt(kx * kx + ky * ky + kz * kz)
    half = 0.5 * angle
    s = 0.5 - angle * angle / 48.0 if angle < 1e-6 else math.sin(half) / angle
    return math.cos(half), kx * s, ky * s, kz * s


@njit(cache=True, inline="always")
def strapdown_increment(
    w: np.ndarray, f: np.ndarray, dt: float, dC: np.ndarray, f_mid: np.ndarray
) -> None:
    """Increments of one sample (paper 003 eq 3, :mod:`pednav_env.nav.strapdown`):
    ``dC`` ← C(Δq) of k = ω'Δt, ``f_mid`` ← Δq(½k) f' Δq(½k)*, the specific force
    ``f`` (m/s²) in mid-interval body axes; ``w`` (rad/s) is the bias-corrected rate."""
    qw, qx, qy, qz = _rotvec_quat(w[0] * dt, w[1] * dt, w[2] * dt)
    dC[0, 0] = 1.0 - 2.0 * (qy * qy + qz * qz)
    dC[0, 1] = 2.0 * (qx * qy - qw * qz)
    dC[0, 2] = 2.0 * (qx * qz + qw * qy)
    dC[1, 0] = 2.0 * (qx * qy + qw * qz)
    dC[1, 1] = 1.0 - 2.0 * (qx * qx + qz * qz)
    dC[1, 2] = 2.0 * (qy * qz - qw * qx)
    dC[2, 0] = 2.0 * (qx * qz - qw * qy)
    dC[2, 1] = 2.0 * (qy * qz + qw * qx)
    dC[2, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)
    hw, hx, hy, hz = _rotvec_quat(w[0] * 0.5 * dt, w[1] * 0.5 * dt, w[2] * 0.5 * dt)
    vx, vy, vz = f[0], f[1], f[2]
    tx = 2.0 * (hy * vz - hz * vy)
    ty = 2.0 * (hz * vx - hx * vz)
    tz = 2.0 * (hx * vy - hy * vx)
    f_mid[0] = vx + hw * tx + hy * tz - hz * ty
    f_mid[1] = vy + hw * ty + hz * tx - hx * tz
    f_mid[2] = vz + hw * tz + hx * ty - hy * tx


@njit(cache=True, inline="always")
def anchor_force(D: np.ndarray, f_mid: np.ndarray, F: np.ndarray) -> None:
    """``F`` ← D f_mid: the sample's specific force in the anchor's body axes."""
    for r in range(3):
        F[r] = D[r, 0] * f_mid[0] + D[r, 1] * f_mid[1] + D[r, 2] * f_mid[2]


@njit(cache=True, inline="always")
def accumulate(pre: Preintegral, F: np.ndarray, dC: np.ndarray, dt: float) -> None:
    """One sample of the preintegrals: A ← A + F Δt, B ← B + ½(A_old + A) Δt,
    D ← D C(Δq), with F = D f_mid (:func:`anchor_force`)."""
    D, A, B = pre.D, pre.A, pre.B
    for r in range(3):
        a_new = A[r] + F[r] * dt
        B[r] += (A[r] + a_new) * (0.5 * dt)
        A[r] = a_new
    for r in range(3):
        d0, d1, d2 = D[r, 0], D[r, 1], D[r, 2]
        for c in range(3):
            D[r, c] = d0 * dC[0, c] + d1 * dC[1, c] + d2 * dC[2, c]


@njit(cache=True, inline="always")
def _row_times(
    C: np.ndarray, s: int, r: int, D: np.ndarray, out: np.ndarray
) -> tuple[float, float, float]:
    """Row r of C_s D into row r of ``out[s]`` (``C``, ``out`` (S, 3, 3); ``out`` may
    be C itself); returns row r of C_s as it was."""
    c0, c1, c2 = C[s, r, 0], C[s, r, 1], C[s, r, 2]
    for c in range(3):
        out[s, r, c] = c0 * D[0, c] + c1 * D[1, c] + c2 * D[2, c]
    return c0, c1, c2


@njit(cache=True)
def moved_states(
    sig: SigmaPoints, pre: Preintegral, tau: float, g: float, chi: np.ndarray, C_moved: np.ndarray
) -> None:
    """State vectors ``chi`` (S, 9) = [x, v, θ, γ, ψ] of the sigma points moved by
    the preintegrals over τ (s) (module docstring; x = (p + v τ) + C B);
    ``C_moved`` (S, 3, 3) receives their attitudes C D. The points are unchanged."""
    C, v, p = sig
    D, A, B = pre.D, pre.A, pre.B
    for s in range(chi.shape[0]):
        for r in range(3):
            c0, c1, c2 = _row_times(C, s, r, D, C_moved)
            ca = c0 * A[0] + c1 * A[1] + c2 * A[2]
            cb = c0 * B[0] + c1 * B[1] + c2 * B[2]
            chi[s, r] = p[s, r] + v[s, r] * tau + cb
            chi[s, 3 + r] = v[s, r] + ca
        chi[s, 2] -= 0.5 * g * (tau * tau)
        chi[s, 5] -= g * tau
        yaw, pitch, roll = _dcm_euler_angles(
            C_moved[s, 0, 0], C_moved[s, 1, 0], C_moved[s, 2, 0], C_moved[s, 2, 1], C_moved[s, 2, 2]
        )
        chi[s, 6] = pitch
        chi[s, 7] = roll
        chi[s, 8] = yaw


@njit(cache=True)
def move_sigmas(sig: SigmaPoints, pre: Preintegral, tau: float, g: float) -> None:
    """Sigma points moved by the preintegrals over τ (s), in place
    (p ← p + (v τ + C B), an association of its own, kept so that results repeat)."""
    C, v, p = sig
    D, A, B = pre.D, pre.A, pre.B
    for s in range(C.shape[0]):
        for r in range(3):
            c0, c1, c2 = _row_times(C, s, r, D, C)
            p[s, r] += v[s, r] * tau + c0 * B[0] + c1 * B[1] + c2 * B[2]
            v[s, r] += c0 * A[0] + c1 * A[1] + c2 * A[2]
        p[s, 2] -= 0.5 * g * (tau * tau)
        v[s, 2] -= g * tau


@njit(cache=True, inline="always")
def central_point_diverges(
    sig: SigmaPoints,
    pre: Preintegral,
    tau: float,
    g: float,
    speed_max: float,
    v_out: np.ndarray,
    p_out: np.ndarray,
) -> bool:
    """Whether the central sigma point (index 0) moved over τ has a non-finite
    anchor attitude, velocity or position, or a speed above ``speed_max`` (m/s);
    its velocity and position go to ``v_out``, ``p_out``."""
    C, v, p = sig
    A, B = pre.A, pre.B
    for r in range(3):
        c0, c1, c2 = C[0, r, 0], C[0, r, 1], C[0, r, 2]
        v_out[r] = v[0, r] + c0 * A[0] + c1 * A[1] + c2 * A[2]
        p_out[r] = p[0, r] + v[0, r] * tau + c0 * B[0] + c1 * B[1] + c2 * B[2]
    v_out[2] -= g * tau
    p_out[2] -= 0.5 * g * (tau * tau)
    return diverging(C, 0, v_out, p_out, speed_max)


@njit(cache=True, inline="always")
def diverging(C: np.ndarray, s: int, v: np.ndarray, p: np.ndarray, speed_max: float) -> bool:
    """Non-finite attitude ``C[s]`` (``C`` (S, 3, 3)), velocity or position, or a
    speed above ``speed_max`` (m/s)."""
    for r in range(3):
        for c in range(3):
            if not math.isfinite(C[s, r, c]):
                return True
        if not (math.isfinite(v[r]) and math.isfinite(p[r])):
            return True
    speed2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    return not (speed2 <= speed_max * speed_max)


@njit(cache=True)
def all_finite(C: np.ndarray, s: int) -> bool:
    """All entries of the 3 × 3 matrix ``C[s]`` finite (``C`` (S, 3, 3))."""
    for r in range(3):
        for c in range(3):
            if not math.isfinite(C[s, r, c]):
                return False
    return True


class AnchorSums(NamedTuple):
    """Σ Wm_s C_s, Σ Wm_s v_s, Σ Wm_s x_s of the anchor's sigma points."""

    C: np.ndarray  # (3, 3)
    v: np.ndarray  # (3,) m/s
    p: np.ndarray  # (3,) m


@njit(cache=True)
def weighted_sums(Wm: np.ndarray, sig: SigmaPoints, sums: AnchorSums) -> None:
    """Weighted sums of the sigma points with weights ``Wm``: the mean
    position after moving them over τ is affine in them,
    Σ Wm x + τ Σ Wm v + (Σ Wm C) B − ½ g τ² e₃ (:func:`mean_position`)."""
    C, v, p = sig
    for r in range(3):
        sums.p[r] = 0.0
        sums.v[r] = 0.0
        for c in range(3):
            sums.C[r, c] = 0.0
    # points outermost: the 15 sums are independent chains (each in the order s = 0, 1, …)
    for s in range(Wm.shape[0]):
        w = Wm[s]
        for r in range(3):
            sums.p[r] += w * p[s, r]
            sums.v[r] += w * v[s, r]
            for c in range(3):
                sums.C[r, c] += w * C[s, r, c]


@njit(cache=True, inline="always")
def mean_position(
    sums: AnchorSums, pre: Preintegral, tau: float, g: float, out: np.ndarray
) -> None:
    """``out`` (3,) ← the mean position (m) of the sigma points moved over τ (s),
    from the anchor's weighted sums (:func:`weighted_sums`)."""
    Cbar, B = sums.C, pre.B
    for r in range(3):
        mp = sums.p[r] + sums.v[r] * tau
        mp += Cbar[r, 0] * B[0] + Cbar[r, 1] * B[1] + Cbar[r, 2] * B[2]
        if r == 2:
            mp -= 0.5 * g * (tau * tau)
        out[r] = mp
