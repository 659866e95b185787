"""Batched unscented Kalman filter algebra (Merwe scaled sigma points).

Stateless functions over explicit ``(B, n)`` means and ``(B, n, n)``
covariances (B = walkers being updated), written so that one call serves a
whole batch: no Python loop over walkers or sigma points. The formulas are
paper 003's UKF section (after Wan & van der Merwe 2000) and follow
``filterpy.kalman.UnscentedKalmanFilter`` 2.0 step for step, which is the
oracle of the tests:

- sigma points χ = [x̂, x̂ + √((L+λ)P)_k, x̂ − √((L+λ)P)_k], k = 1 … L, with the
  lower Cholesky factor (columns = rows of filterpy's upper factor);
- weights W₀^(m) = λ/(λ+L), W₀^(c) = λ/(λ+L) + (1 − α² + β),
  W_i = 1/(2(λ+L)), λ = α²(L + κ) − L. Paper 003 prints
  W₀^(c) = λ/(λ+L) + (1 − a²) and λ = a²L − L, i.e. β = 0, κ = 0;
- mean and covariance through injectable ``mean_fn`` / ``residual_fn`` so that
  angles are averaged and differenced with wrapping;
- the update uses a linear solve with S, never ``inv(S)``, and covariances
  are symmetrised and, when they lose positive definiteness, repaired by
  flooring eigenvalues (counted, never NaN).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
MeanFn = Callable[[Array, Array], Array]
ResidualFn = Callable[[Array, Array], Array]

#: Smallest eigenvalue kept when a covariance is repaired, relative to its largest.
EIGEN_FLOOR_RELATIVE = 1e-12
#: Absolute eigenvalue floor.
EIGEN_FLOOR_ABSOLUTE = 1e-18


@dataclass(frozen=True)
class MerweWeights:
    """Merwe scaled sigma-point weights for dimension ``n``."""

    n: int
    alpha: float
    beta: float
    kappa: float

    def __post_init__(self) -> None:
        if self.n < 1:
            raise ValueError(f"MerweWeights.n must be ≥ 1, got {self.n}")
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ValueError(f"MerweWeights.alpha must be > 0, got {self.alpha!r}")
        if not np.isfinite(self.beta):
            raise ValueError(f"MerweWeights.beta must be finite, got {self.beta!r}")
        if not (np.isfinite(self.kappa) and self.n + self.kappa > 0):
            raise ValueError(f"MerweWeights.kappa must make n + κ > 0, got {self.kappa!r}")

    @property
    def lam(self) -> float:
        """λ = α²(n + κ) − n."""
        return self.alpha**2 * (self.n + self.kappa) - self.n

    @property
    def Wm(self) -> Array:
        c = 0.5 / (self.n + self.lam)
        w = np.full(2 * self.n + 1, c)
        w[0] = self.lam / (self.n + self.lam)
        return w

    @property
    def Wc(self) -> Array:
        w = self.Wm.copy()
        w[0] += 1.0 - self.alpha**2 + self.beta
        return w


def symmetrize(P: Array) -> Array:
    """(P + Pᵀ)/2 over the last two axes."""
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def repair_covariance(P: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Symmetrise and floor the eigenvalues of covariances that are not PD.

    Returns the repaired ``P`` and a boolean mask of the matrices that needed
    an eigenvalue floor.
    """
    P = symmetrize(P)
    w, V = np.linalg.eigh(P)
    floor = np.maximum(EIGEN_FLOOR_RELATIVE * np.abs(w[..., -1:]), EIGEN_FLOOR_ABSOLUTE)
    bad = np.any(w < floor, axis=-1) | ~np.all(np.isfinite(w), axis=-1)
    if np.any(bad):
        wf = np.maximum(np.nan_to_num(w[bad], nan=0.0), floor[bad])
        P = P.copy()
        P[bad] = symmetrize(np.einsum("bij,bj,bkj->bik", V[bad], wf, V[bad]))
    return P, bad


def cholesky_lower(A: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Lower Cholesky factors of a batch; non-PD members are repaired first.

    Returns the factors and the mask of repaired members.
    """
    try:
        return np.linalg.cholesky(A), np.zeros(A.shape[:-2], dtype=bool)
    except np.linalg.LinAlgError:
        A_fixed, bad = repair_covariance(A)
        return np.linalg.cholesky(A_fixed), bad


def sigma_points(
    x: Array, P: Array, weights: MerweWeights, add_fn: ResidualFn | None = None
) -> tuple[Array, NDArray[np.bool_]]:
    """Sigma points ``(B, 2n+1, n)`` around ``x`` ``(B, n)`` with covariance ``P``.

    ``add_fn(x, delta)`` (default ``x + delta``) adds offsets to the mean.
    Returns the points and the mask of covariances that had to be repaired.
    """
    n = weights.n
    L, bad = cholesky_lower((n + weights.lam) * P)
    offsets = np.swapaxes(L, -1, -2)  # row k = column k of L = filterpy's U[k]
    # [0, +U, −U] added to the mean in one call: χ₀ = x, χ_k = x + U_k, χ_{L+k} = x − U_k
    d = np.concatenate((np.zeros_like(x[:, None, :]), offsets, -offsets), axis=1)
    return (x[:, None, :] + d if add_fn is None else add_fn(x[:, None, :], d)), bad


def unscented_transform(
    sigmas: Array,
    weights: MerweWeights,
    noise_cov: Array | None = None,
    mean_fn: MeanFn | None = None,
    residual_fn: ResidualFn | None = None,
) -> tuple[Array, Array]:
    """Weighted mean ``(B, d)`` and covariance ``(B, d, d)`` of ``sigmas`` ``(B, S, d)``."""
    Wm, Wc = weights.Wm, weights.Wc
    x = np.einsum("s,bsd->bd", Wm, sigmas) if mean_fn is None else mean_fn(sigmas, Wm)
    y = sigmas - x[:, None, :] if residual_fn is None else residual_fn(sigmas, x[:, None, :])
    P = np.matmul(np.swapaxes(y * Wc[:, None], -1, -2), y)  # Σ_s Wc_s y_s y_sᵀ
    if noise_cov is not None:
        P = P + noise_cov
    return x, P


@dataclass(frozen=True)
class UpdateResult:
    """Posterior and diagnostics of a batched UKF update."""

    x: Array  # (B, n) posterior mean
    P: Array  # (B, n, n) posterior covariance
    innovation: Array  # (B, m) z − ẑ
    S: Array  # (B, m, m) innovation covariance
    nis: Array  # (B,) normalised innovation squared yᵀ S⁻¹ y
    accepted: NDArray[np.bool_]  # (B,) passed the gate (all True without a gate)


def update(
    x_prior: Array,
    P_prior: Array,
    sigmas_f: Array,
    sigmas_h: Array,
    z: Array,
    R: Array,
    weights: MerweWeights,
    residual_x: ResidualFn | None = None,
    add_x: ResidualFn | None = None,
    gate_nis: float | Array | None = None,
) -> UpdateResult:
    """UKF measurement update (paper 003 / filterpy ``update``), batched.

    ``sigmas_f`` are the prior sigma points ``(B, S, n)``, ``sigmas_h`` their
    images under h ``(B, S, m)``; ``z`` ``(B, m)``; ``R`` ``(B, m, m)``.
    Measurements whose NIS exceeds ``gate_nis`` are rejected (posterior =
    prior).
    """
    zp, S = unscented_transform(sigmas_h, weights, R)
    dx = (
        sigmas_f - x_prior[:, None, :]
        if residual_x is None
        else residual_x(sigmas_f, x_prior[:, None, :])
    )
    dz = sigmas_h - zp[:, None, :]
    Pxz = np.einsum("s,bsi,bsj->bij", weights.Wc, dx, dz)
    # K = Pxz S⁻¹  ⇔  S Kᵀ = Pxzᵀ (S symmetric)
    K = np.swapaxes(np.linalg.solve(S, np.swapaxes(Pxz, -1, -2)), -1, -2)
    y = z - zp
    nis = np.einsum("bi,bi->b", y, np.linalg.solve(S, y[..., None])[..., 0])
    accepted = np.ones(len(y), dtype=bool) if gate_nis is None else nis <= gate_nis
    Ky = np.einsum("bij,bj->bi", K, y) * accepted[:, None]
    x = x_prior + Ky if add_x is None else add_x(x_prior, Ky)
    KSK = np.einsum("bij,bjk,blk->bil", K, S, K) * accepted[:, None, None]
    P = symmetrize(P_prior - KSK)
    return UpdateResult(x, P, y, S, nis, accepted)


def update_linear(
    x_prior: Array,
    P_prior: Array,
    measured: list[int],
    z: Array,
    R: Array,
    add_x: ResidualFn | None = None,
    gate_nis: float | Array | None = None,
) -> UpdateResult:
    """UKF update for a linear h(x) = x[measured], batched.

    Sigma points drawn from (x⁻, P⁻) and passed through a linear h give
    exactly ẑ = h(x⁻), S = H P⁻ Hᵀ + R and P_xz = P⁻ Hᵀ, so this is the same
    update as :func:`update` on redrawn prior sigma points (filterpy 2.0) —
    without drawing them. The filterpy oracle test checks the equality.
    """
    m = np.asarray(measured)
    if np.array_equal(m, np.arange(m[0], m[0] + m.size)):  # contiguous: views, no gather
        sl = slice(int(m[0]), int(m[0]) + m.size)
        S = P_prior[:, sl, sl] + R
        Pxz = P_prior[:, :, sl]
        y = z - x_prior[:, sl]
    else:
        S = P_prior[:, m[:, None], m[None, :]] + R
        Pxz = P_prior[:, :, m]
        y = z - x_prior[:, m]
    # S⁻¹ once (as filterpy does), then Kᵀ = S⁻¹ P_xzᵀ (S symmetric) and S⁻¹ y.
    SI = np.linalg.inv(S)
    KT = np.matmul(SI, np.swapaxes(Pxz, -1, -2))
    # elementwise products and sums: the same rounding whatever the batch size
    nis = ((SI * y[:, None, :]).sum(axis=-1) * y).sum(axis=-1)
    accepted = np.ones(len(y), dtype=bool) if gate_nis is None else nis <= gate_nis
    Ky = np.matmul(y[:, None, :], KT)[:, 0] * accepted[:, None]
    x = x_prior + Ky if add_x is None else add_x(x_prior, Ky)
    KSK = np.matmul(Pxz, KT) * accepted[:, None, None]  # K S Kᵀ = P_xz Kᵀ
    return UpdateResult(x, symmetrize(P_prior - KSK), y, S, nis, accepted)
