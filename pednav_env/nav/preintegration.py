"""Preintegrated strapdown increments: many sigma points, one walker, one pass.

The strapdown of paper 003, eq (3) (:mod:`pednav_env.nav.strapdown`), is
affine in the state it starts from. Over samples j = a … t−1 of one walker,
starting from attitude C₀ = C(q₀), velocity v₀ and position x₀,

    C_t = C₀ D,   v_t = v₀ + C₀ A − g e₃ τ,
    x_t = x₀ + v₀ τ + C₀ B − ½ g e₃ τ²,           τ = (t − a) Δt,

with D = C(Δq_a) ⋯ C(Δq_{t−1}), A = Σ_j D_j f_mid,j Δt (D_j the product up to
sample j) and B the trapezoid sum of A — quantities of the IMU record alone,
the same for every sigma point. This is the "preintegration" of Lupton &
Sukkarieh (2012) and Forster et al. (2017) without bias states, and it is
exact: the same arithmetic as stepping every sigma point, regrouped (results
agree to rounding).

:func:`preintegrate` computes D, A, B for every sample of a block, counted
from the block's start; :func:`relative_increments` turns them into the
increments between any two samples of the block. The ZUPT-UKF
(:class:`pednav_env.nav.zupt_ukf.ZuptUkf`) uses them to move each walker's
19 sigma points from its last redraw straight to its next ZUPT.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Preintegrals:
    """Increments from a block's start to each of its samples 0 … K."""

    D: Array  # (N, K+1, 3, 3) attitude increment C(q_start)ᵀ C(q_t)
    F: Array  # (N, K, 3) compensated specific force of sample j in start axes, D_j f_mid,j
    A: Array  # (N, K+1, 3) Σ F_j Δt (m/s)
    B: Array  # (N, K+1, 3) trapezoid integral of A (m)
    tau_rate: Array  # (N,) seconds per sample (0 for walkers that do not move)


def preintegrate(
    dC: Array, f_mid: Array, dt: float, frozen: NDArray[np.bool_] | None = None
) -> Preintegrals:
    """D, A, B over a block from per-sample attitude increments ``dC`` (N, K, 3, 3)
    and compensated specific force ``f_mid`` (N, K, 3) (see
    :func:`pednav_env.nav.strapdown.step_increments_dcm`). Walkers in ``frozen``
    get zero increments (they stay where they are)."""
    n, k = f_mid.shape[:2]
    D = np.empty((n, k + 1, 3, 3))
    D[:, 0] = np.eye(3)
    for j in range(k):
        np.matmul(D[:, j], dC[:, j], out=D[:, j + 1])
    tau_rate = np.full(n, dt)
    if frozen is not None and frozen.any():
        D[frozen] = np.eye(3)
        tau_rate[frozen] = 0.0
    F = np.matmul(D[:, :k], f_mid[..., None])[..., 0]
    A = np.zeros((n, k + 1, 3))
    np.cumsum(F * dt, axis=1, out=A[:, 1:])
    B = np.zeros((n, k + 1, 3))
    np.cumsum((A[:, :-1] + A[:, 1:]) * (0.5 * dt), axis=1, out=B[:, 1:])
    if frozen is not None and frozen.any():
        A[frozen] = 0.0
        B[frozen] = 0.0
    return Preintegrals(D, F, A, B, tau_rate)


def block_differences(
    pre: Preintegrals,
    lanes: NDArray[np.integer],
    anchor: NDArray[np.integer],
    t: NDArray[np.integer],
    dt: float,
) -> tuple[Array, Array, Array, Array]:
    """(D_a, ΔA, ΔB, steps) from block sample ``anchor`` (B,) to ``t`` ((B,) or (B, T))
    for walkers ``lanes``, still in the block's starting axes: D_a the attitude
    increment up to the anchor, ΔA = A_t − A_a and ΔB = B_t − B_a − A_a (t − a)Δt.
    Rotated by D_aᵀ they are the increments from the anchor (:func:`relative_increments`)."""
    two = np.ndim(t) == 2
    li = lanes[:, None] if two else lanes
    Da, Aa, Ba = pre.D[lanes, anchor], pre.A[lanes, anchor], pre.B[lanes, anchor]
    steps = t - (anchor[:, None] if two else anchor)
    if two:
        Aa, Ba = Aa[:, None], Ba[:, None]
    dA = pre.A[li, t] - Aa
    dB = pre.B[li, t] - Ba - Aa * (steps * dt)[..., None]
    return Da, dA, dB, steps


def relative_increments(
    pre: Preintegrals,
    lanes: NDArray[np.integer],
    anchor: NDArray[np.integer],
    t: NDArray[np.integer],
    dt: float,
) -> tuple[Array, Array, Array]:
    """(D, [A B], τ) from block sample ``anchor`` (B,) to ``t`` ((B,) or (B, T)) for
    walkers ``lanes``, in the axes of the attitude at ``anchor``; A and B are the
    two columns of a ``(..., 3, 2)`` array."""
    two = np.ndim(t) == 2
    li = lanes[:, None] if two else lanes
    Da, dA, dB, steps = block_differences(pre, lanes, anchor, t, dt)
    inv = np.swapaxes(Da[:, None] if two else Da, -1, -2)
    D_rel = np.matmul(inv, pre.D[li, t])
    AB_rel = np.matmul(inv, np.stack((dA, dB), axis=-1))
    return D_rel, AB_rel, steps * pre.tau_rate[li]
