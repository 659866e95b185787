"""Unscented-filter pieces shared by the filters: Merwe scaled sigma-point
weights and covariance repair.

The ZUPT-UKF's algebra itself (sigma points, unscented transform, update) is
compiled per walker in :mod:`pednav_env.nav.zupt_kernel`. Its formulas are
paper 003's UKF section (after Wan & van der Merwe 2000) and follow
``filterpy.kalman.UnscentedKalmanFilter`` 2.0 step for step, which is the
oracle of the tests:

- sigma points χ = [x̂, x̂ + √((L+λ)P)_k, x̂ − √((L+λ)P)_k], k = 1 … L, with the
  lower Cholesky factor (columns = rows of filterpy's upper factor);
- weights W₀^(m) = λ/(λ+L), W₀^(c) = λ/(λ+L) + (1 − α² + β),
  W_i = 1/(2(λ+L)), λ = α²(L + κ) − L. Paper 003 prints
  W₀^(c) = λ/(λ+L) + (1 − a²) and λ = a²L − L, i.e. β = 0, κ = 0;
- angles averaged and differenced with wrapping (filterpy's ``x_mean_fn`` /
  ``residual_x``);
- covariances symmetrised and, when they lose positive definiteness, repaired
  by flooring eigenvalues (counted, never NaN).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

Array = NDArray[np.float64]

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


@njit(cache=True)
def floored_covariance(A: np.ndarray, out: np.ndarray) -> bool:
    """Eigenvalue floor of one covariance, the one implementation of the repair.

    ``out`` ← sym(V max(Λ, λ_min) Vᵀ) with V Λ Vᵀ the eigendecomposition of
    sym(A) = (A + Aᵀ)/2 (non-finite entries of A counted as 0) and
    λ_min = max(:data:`EIGEN_FLOOR_RELATIVE` |λ_max|, :data:`EIGEN_FLOOR_ABSOLUTE`).
    Returns whether an eigenvalue was below λ_min (the matrix needed the floor).
    Used by :func:`repair_covariance` and by the ZUPT kernel's sigma-point draw.
    """
    n = A.shape[0]
    S = np.empty((n, n))
    for r in range(n):
        for c in range(n):
            a, b = A[r, c], A[c, r]
            a = a if math.isfinite(a) else 0.0
            b = b if math.isfinite(b) else 0.0
            S[r, c] = 0.5 * (a + b)
    w, V = np.linalg.eigh(S)
    floor = max(EIGEN_FLOOR_RELATIVE * abs(w[n - 1]), EIGEN_FLOOR_ABSOLUTE)
    needed = False
    for k in range(n):
        if not (w[k] >= floor):
            needed = True
        w[k] = max(w[k], floor)
    for r in range(n):
        for c in range(n):
            acc = 0.0
            for k in range(n):
                acc += V[r, k] * w[k] * V[c, k]
            out[r, c] = acc
    for r in range(n):
        for c in range(r + 1, n):
            m = 0.5 * (out[r, c] + out[c, r])
            out[r, c] = m
            out[c, r] = m
    return needed


@njit(cache=True)
def _floored_batch(P: np.ndarray, out: np.ndarray, needed: np.ndarray) -> None:
    for b in range(P.shape[0]):
        needed[b] = floored_covariance(P[b], out[b])


def repair_covariance(P: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Symmetrise covariances ``(..., n, n)`` and floor the eigenvalues of those that
    are not positive definite (:func:`floored_covariance`).

    Returns the repaired ``P`` and a boolean mask of the matrices that needed
    an eigenvalue floor; the others come back symmetrised only.
    """
    P = symmetrize(np.asarray(P, dtype=float))
    n = P.shape[-1]
    flat = np.ascontiguousarray(P.reshape(-1, n, n))
    floored = np.empty_like(flat)
    needed = np.zeros(flat.shape[0], dtype=bool)
    _floored_batch(flat, floored, needed)
    bad = needed.reshape(P.shape[:-2])
    return np.where(bad[..., None, None], floored.reshape(P.shape), P), bad
