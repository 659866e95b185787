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

from dataclasses import dataclass

import numpy as np
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
