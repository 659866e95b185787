"""Preintegrated strapdown increments: many sigma points, one walker, one pass.

The strapdown of paper 003, eq (3) (:mod:`pednav_env.nav.strapdown`), is
affine in the state it starts from. Over samples j = a … t−1 of one walker,
starting from (q₀, v₀, x₀),

    q_t = q₀ ⊗ D,   v_t = v₀ + C(q₀) A − g e₃ τ,
    x_t = x₀ + v₀ τ + C(q₀) B − ½ g e₃ τ²,           τ = (t − a) Δt,

with D = Δq_a ⊗ … ⊗ Δq_{t−1}, A = Σ C(D_j) f_mid,j Δt and B the trapezoid sum
of A — quantities of the IMU record alone, the same for every sigma point
(D_j is the product up to sample j). This is the "preintegration" of
Lupton & Sukkarieh (2012) and Forster et al. (2017) without bias states, and
it is exact: the same arithmetic as stepping every sigma point, regrouped
(results agree to rounding, ~1e-15 relative).

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

from pednav_env.rotations import quat_multiply, quat_rotate

Array = NDArray[np.float64]

_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


@dataclass(frozen=True)
class Preintegrals:
    """Increments from a block's start to each of its samples 0 … K."""

    D: Array  # (N, K+1, 4) attitude increment q_start⁻¹ ⊗ q_t
    F: Array  # (N, K, 3) compensated specific force of sample j in start axes, C(D_j) f_mid,j
    A: Array  # (N, K+1, 3) Σ F_j Δt (m/s)
    B: Array  # (N, K+1, 3) trapezoid integral of A (m)
    tau_rate: Array  # (N,) seconds per sample (0 for walkers that do not move)


def preintegrate(
    dq_matrix_T: Array, f_mid: Array, dt: float, frozen: NDArray[np.bool_] | None = None
) -> Preintegrals:
    """D, A, B over a block: ``dq_matrix_T`` (N, K, 4, 4) = Mᵀ with q ⊗ Δq = M q,
    ``f_mid`` (N, K, 3) (see :func:`pednav_env.nav.strapdown.step_increments`).
    Walkers in ``frozen`` get zero increments (they stay where they are)."""
    n, k = f_mid.shape[:2]
    D = np.empty((n, k + 1, 1, 4))
    D[:, 0] = (1.0, 0.0, 0.0, 0.0)
    for j in range(k):
        D[:, j + 1] = np.matmul(D[:, j], dq_matrix_T[:, j])
    D = D[:, :, 0]
    tau_rate = np.full(n, dt)
    if frozen is not None and frozen.any():
        D[frozen] = (1.0, 0.0, 0.0, 0.0)
        tau_rate[frozen] = 0.0
    F = quat_rotate(D[:, :k], f_mid)
    A = np.zeros((n, k + 1, 3))
    np.cumsum(F * dt, axis=1, out=A[:, 1:])
    B = np.zeros((n, k + 1, 3))
    np.cumsum((A[:, :-1] + A[:, 1:]) * (0.5 * dt), axis=1, out=B[:, 1:])
    if frozen is not None and frozen.any():
        A[frozen] = 0.0
        B[frozen] = 0.0
    return Preintegrals(D, F, A, B, tau_rate)


def relative_increments(
    pre: Preintegrals,
    lanes: NDArray[np.integer],
    anchor: NDArray[np.integer],
    t: NDArray[np.integer],
    dt: float,
) -> tuple[Array, Array, Array, Array]:
    """(D, A, B, τ) from block sample ``anchor`` (B,) to ``t`` ((B,) or (B, T)) for
    walkers ``lanes``, in the axes of the attitude at ``anchor``."""
    two = np.ndim(t) == 2
    li = lanes[:, None] if two else lanes
    Da, Aa, Ba = pre.D[lanes, anchor], pre.A[lanes, anchor], pre.B[lanes, anchor]
    steps = t - (anchor[:, None] if two else anchor)
    if two:
        Da, Aa, Ba = Da[:, None], Aa[:, None], Ba[:, None]
    inv = Da * _CONJ
    D_rel = quat_multiply(inv, pre.D[li, t])
    A_rel = quat_rotate(inv, pre.A[li, t] - Aa)
    B_rel = quat_rotate(inv, pre.B[li, t] - Ba - Aa * (steps * dt)[..., None])
    return D_rel, A_rel, B_rel, steps * pre.tau_rate[li]
