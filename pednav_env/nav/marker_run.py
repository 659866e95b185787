"""Checked interface to the marker EKF of paper 001, and whole-walk runs.

:class:`MarkerEKF` wraps :class:`~pednav_env.nav.marker_ekf.MarkerEkfEngine`
(the filter itself, module docstring there) for library use: it checks its
inputs, takes the Q and R scales per call, keeps filterpy's prior/posterior
copies and repairs the covariance after every update. :func:`run_marker_ekf`
filters whole walks with it (the paper-001 reproduction and the oracle of
the marker environment's tests).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.nav.marker_ekf import MarkerEkfEngine
from pednav_env.nav.marker_model import DIM_X, DIM_Z, MarkerEkfConfig

Array = NDArray[np.float64]
#: A positive multiplier of a noise diagonal: None (1), a scalar, ``(N,)`` (one
#: per walker) or ``(1, dim)`` / ``(N, dim)`` (per component).
Scale = ArrayLike | None


def _as_walker_array(name: str, value: Scale, n: int, dim: int) -> Array:
    """A positive multiplier as ``(N, dim)``: scalar, ``(N,)`` per walker, or ``(1|N, dim)``."""
    if value is None:
        return np.ones((n, dim))
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1:
        if arr.shape[0] != n:
            raise ValueError(
                f"{name} as a 1-D array is per walker and needs length {n}, got shape {arr.shape}"
            )
        arr = arr[:, None]
    if arr.ndim > 2 or (
        arr.ndim == 2 and (arr.shape[0] not in (1, n) or arr.shape[1] not in (1, dim))
    ):
        raise ValueError(
            f"{name} must be a scalar, ({n},), (1, {dim}) or ({n}, {dim}), got {arr.shape}"
        )
    out = np.broadcast_to(arr, (n, dim))
    if not np.all(np.isfinite(out)) or np.any(out <= 0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return out


class MarkerEKF:
    """Checked interface to :class:`MarkerEkfEngine` (N walkers, anchor 0).

    Checks its inputs, takes the Q and R scales per call, keeps filterpy's
    prior/posterior copies and repairs the covariance after every update
    (module docstring). ``x`` and ``P`` are the engine's arrays: writing into
    them writes into the filter.

    Attributes
    ----------
    engine : MarkerEkfEngine
        The filter itself.
    x : ndarray, shape (N, 6)
        Estimate of the deviations L (units of ``PARAM_UNITS``).
    P : ndarray, shape (N, 6, 6)
        Its covariance.
    x_prior, P_prior, x_post, P_post : ndarray
        Prior and posterior of the last step (filterpy's convention; copies).
    nu : ndarray, shape (N, 4)
        Normalised sequential innovations of the last update (0 where skipped).
    nis : ndarray, shape (N,)
        Last normalised innovation squared yᵀ S⁻¹ y = Σ ν² over the valid rows.
    num_valid : ndarray of int, shape (N,)
        Number of valid rows in the last update.
    repairs : ndarray of int, shape (N,)
        Covariance repairs per walker since construction.
    """

    def __init__(self, config: MarkerEkfConfig, num_walkers: int) -> None:
        if not isinstance(num_walkers, (int, np.integer)) or num_walkers < 1:
            raise ValueError(f"num_walkers must be an integer >= 1, got {num_walkers!r}")
        self.config = config
        self.num_walkers = n = int(num_walkers)
        self.engine = MarkerEkfEngine(config, n)
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self.nu = np.zeros((n, DIM_Z))
        self.nis = np.zeros(n)
        self.num_valid = np.zeros(n, dtype=np.int64)

    @property
    def x(self) -> Array:
        """Estimate, ``(N, 6)`` (the engine's array: writing into it writes the filter)."""
        return self.engine.x

    @property
    def P(self) -> Array:
        """Covariance, ``(N, 6, 6)`` (the engine's array, likewise)."""
        return self.engine.P

    @property
    def repairs(self) -> NDArray[np.int64]:
        """Covariance repairs per walker, ``(N,)`` (the engine's counter)."""
        return self.engine.repairs

    @property
    def params(self) -> Array:
        """Estimated full parameters p⁰ + x̂, shape ``(N, 6)``."""
        return self.config.nominal.vector + self.x

    def process_noise(self, q_scale: Scale = None) -> Array:
        """Diagonal of Γ Q Γᵀ times ``q_scale``, shape ``(N, 6)``."""
        return self.engine.q0 * _as_walker_array("q_scale", q_scale, self.num_walkers, DIM_X)

    def measurement_noise(self, r_scale: Scale = None) -> Array:
        """Diagonal of R times ``r_scale``, shape ``(N, 4)``."""
        return self.engine.r0 * _as_walker_array("r_scale", r_scale, self.num_walkers, DIM_Z)

    def predict(self, q_scale: Scale = None) -> None:
        """x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (eqs 4.11, 5.1, 5.2, 5.4; thesis 1.11–1.12).

        Parameters
        ----------
        q_scale : array_like, optional
            Positive multipliers of Γ Q Γᵀ's diagonal: a scalar, ``(N,)`` (one
            per walker), or ``(1, 6)`` / ``(N, 6)`` (per parameter).
        """
        self.engine.q[...] = self.process_noise(q_scale)
        self.engine.predict()
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()

    def update(
        self,
        z: ArrayLike,
        t: ArrayLike,
        valid: ArrayLike | None = None,
        r_scale: Scale = None,
    ) -> None:
        """Correct with one UWB sample per walker (eqs 4.12, 5.3, 5.5; thesis 1.14–1.18).

        Then repair the covariance where it is no longer positive definite
        (counted in ``repairs``).

        Parameters
        ----------
        z : array_like, shape (N, 4) or (N, 2, 2)
            Measured [x₁, z₁, x₂, z₂] (m).
        t : array_like, shape () or (N,)
            kT of the sample (s).
        valid : array_like of bool, shape (N, 2) or (N, 4), optional
            Per marker or per coordinate; False rows are skipped (their values
            in ``z`` are ignored and may be NaN).
        r_scale : array_like, optional
            Positive multipliers of R's diagonal: a scalar, ``(N,)`` (one per
            walker), or ``(1, 4)`` / ``(N, 4)`` (per coordinate).
        """
        n = self.num_walkers
        zz = np.asarray(z, dtype=float)
        if zz.shape == (n, 2, 2):
            zz = zz.reshape(n, DIM_Z)
        if zz.shape != (n, DIM_Z):
            raise ValueError(f"z must have shape ({n}, 4) or ({n}, 2, 2), got {zz.shape}")
        tt = np.asarray(t, dtype=float)
        if tt.shape not in ((), (n,)):
            raise ValueError(f"t must be a scalar or have shape ({n},), got {tt.shape}")
        if not np.all(np.isfinite(tt)):
            raise ValueError(f"t must be finite, got {t!r}")
        if valid is None:
            ok = np.ones((n, DIM_Z), dtype=bool)
        else:
            v = np.asarray(valid)
            if v.dtype != np.bool_:
                raise ValueError(f"valid must be a boolean array, got dtype {v.dtype}")
            if v.shape == (n, 2):
                ok = np.repeat(v, 2, axis=1)
            elif v.shape == (n, DIM_Z):
                ok = v
            else:
                raise ValueError(f"valid must have shape ({n}, 2) or ({n}, 4), got {v.shape}")
        if not np.all(np.isfinite(zz[ok])):
            raise ValueError("z must be finite where valid (found NaN or inf)")
        e = self.engine
        e.r[...] = self.measurement_noise(r_scale)
        if not ok.all():
            zz = np.where(ok, zz, 0.0)  # skipped values are never used (may be NaN)
        nu = e.update(zz, ok, np.broadcast_to(tt, (n,)))
        self.nu = nu.copy()
        self.nis = (nu * nu).sum(axis=1)
        self.num_valid = ok.sum(axis=1)
        e.repair()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()

    def markers(self, t: ArrayLike) -> Array:
        """Estimated marker positions h(p⁰ + x̂) at ``t``, shape ``(N, 2, 2)`` (m)."""
        n = self.num_walkers
        tt = np.broadcast_to(np.asarray(t, dtype=float), (n,))
        return self.engine.markers(tt).reshape(n, 2, 2)


@dataclass(frozen=True)
class MarkerEkfRun:
    """A whole run of :func:`run_marker_ekf`.

    Attributes
    ----------
    x : ndarray, shape (N, K, 6)
        Posterior deviations.
    P_diag : ndarray, shape (N, K, 6)
        Diagonal of the posterior covariance.
    markers : ndarray, shape (N, K, 2, 2)
        Estimated positions h(p⁰ + x̂(k), kT) (m).
    nis : ndarray, shape (N, K)
        NIS of each update; ``num_valid`` gives its degrees of freedom.
    num_valid : ndarray of int, shape (N, K)
    repairs : ndarray of int, shape (N,)
    """

    x: Array
    P_diag: Array
    markers: Array
    nis: Array
    num_valid: NDArray[np.int64]
    repairs: NDArray[np.int64]


def run_marker_ekf(
    config: MarkerEkfConfig,
    z: ArrayLike,
    valid: ArrayLike | None = None,
    q_scale: Scale = None,
    r_scale: Scale = None,
) -> MarkerEkfRun:
    """Filter whole walks sampled at t_k = kT, k = 0 … K−1 (:class:`MarkerEKF`).

    The first sample is corrected from the initial prior (eqs 5.7, 5.8); each
    later one is predicted then corrected.

    Parameters
    ----------
    config : MarkerEkfConfig
    z : array_like, shape (N, K, 2, 2)
        UWB positions (m).
    valid : array_like of bool, shape (N, K, 2), optional
        Per-marker validity (all True if omitted).
    q_scale, r_scale : array_like, optional
        Constant multipliers, as in :meth:`MarkerEKF.predict` / ``update``.
    """
    zz = np.asarray(z, dtype=float)
    if zz.ndim != 4 or zz.shape[2:] != (2, 2):
        raise ValueError(f"z must have shape (N, K, 2, 2), got {zz.shape}")
    n, k = zz.shape[:2]
    if valid is not None:
        valid = np.asarray(valid)
        if valid.shape != (n, k, 2):
            raise ValueError(f"valid must have shape ({n}, {k}, 2), got {valid.shape}")
    ekf = MarkerEKF(config, n)
    xs = np.empty((n, k, DIM_X))
    P_diag = np.empty((n, k, DIM_X))
    nis = np.empty((n, k))
    num_valid = np.empty((n, k), dtype=np.int64)
    T = config.sample_period
    for j in range(k):
        if j > 0:
            ekf.predict(q_scale)
        ekf.update(zz[:, j], j * T, None if valid is None else valid[:, j], r_scale)
        xs[:, j] = ekf.x
        P_diag[:, j] = np.diagonal(ekf.P, axis1=1, axis2=2)
        nis[:, j] = ekf.nis
        num_valid[:, j] = ekf.num_valid
    # h(x̂ₖ) of every sample in one call (elementwise: the same numbers as per step)
    times = np.broadcast_to(np.arange(k) * T, (n, k))
    est = ekf.engine.markers(times, xs)  # (N, K, 4)
    return MarkerEkfRun(
        x=xs,
        P_diag=P_diag,
        markers=est.reshape(n, k, 2, 2),
        nis=nis,
        num_valid=num_valid,
        repairs=ekf.repairs.copy(),
    )
