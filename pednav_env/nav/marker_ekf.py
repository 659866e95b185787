"""Marker EKF of paper 001 (thesis chapter 5) and its low-pass baseline.

The EKF estimates the deviations L = [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω] of the
heel–knee model (:mod:`pednav_env.gait.heel_knee`, eq 4.9 order) from the
raw UWB positions r = [x₁, z₁, x₂, z₂] of heel and knee (eq 4.12):

- prediction with the exponentially correlated model (eqs 4.11, 5.1, 5.2,
  5.4): x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (thesis eqs 1.11, 1.12);
- correction with h of eq 4.10 and its Jacobian H (eq 5.3), R = σ² I (eq 5.5),
  S = H P Hᵀ + R, K = P Hᵀ S⁻¹, x = x⁻ + K y (eqs 1.14–1.17), and the
  covariance in Joseph form P = (I − KH) P⁻ (I − KH)ᵀ + K R Kᵀ, algebraically
  equal to the thesis's (1.18) but robust to rounding;
- initialisation x̂ = 0 (eq 5.7), P0 = var_ratio · diag(p⁰²) (eq 5.8).

Everything runs on a leading walker axis N with batched ``matmul`` and
``np.linalg.solve`` (no inverse, no loop over walkers). After each update P is
symmetrised; a walker whose P fails a Cholesky test (a pivot below
``eig_floor`` times its largest variance) gets its eigenvalues floored at
``eig_floor`` times the largest and is counted in ``repairs``.

Our column order of H puts ∂/∂ΔA fifth and ∂/∂Δω sixth (the state order of
eq 4.9); the thesis's printed (5.3) and (5.6) list ω before A, i.e. its H15,
H25, H35, H45 are our column 6 and its H36, H46 our column 5.

The action hooks of the marker environment: ``q_scale`` multiplies the
diagonal of Γ Q Γᵀ per walker and parameter, ``r_scale`` the diagonal of R per
walker and coordinate; samples whose ``valid`` flag is False are skipped.

:func:`lowpass_filter` is the thesis's comparison filter ("the simplest
low-pass filter", chapter 6): a causal first-order Butterworth (RC) filter of
each raw coordinate. :func:`lowpass_cutoff_for_gait` documents how its cut-off
is chosen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar
from scipy.signal import butter, sosfilt, sosfilt_zi, sosfiltfilt

from pednav_env.gait.heel_knee import (
    I_A,
    I_AX,
    I_AZ,
    I_CX,
    I_CZ,
    I_OMEGA,
    HeelKneeConfig,
    HeelKneeNominal,
    ProcessModel,
    heel_knee_positions,
    process_model,
)
from pednav_env.sensors.uwb import UwbSpec, hold_last_valid

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

DIM_X = 6
DIM_Z = 4


def marker_measurement(params: ArrayLike, t: ArrayLike, shank_length: float) -> Array:
    """h(L) of thesis eq 4.12: [x₁, z₁, x₂, z₂] from eq 4.10.

    Parameters
    ----------
    params : array_like, shape (..., 6)
        Full parameters p = p⁰ + L (:data:`~pednav_env.gait.heel_knee.PARAM_NAMES`).
    t : array_like, shape (...)
        kT (s).
    shank_length : float
        M (m).

    Returns
    -------
    ndarray, shape (..., 4)
        Heel x, heel z, knee x, knee z (m).
    """
    pos = heel_knee_positions(params, t, shank_length)
    return pos.reshape((*pos.shape[:-2], DIM_Z))


def marker_jacobian(params: ArrayLike, t: ArrayLike, shank_length: float) -> Array:
    """H = ∂h/∂L of thesis eq 5.3 (our column order, see the module docstring).

    Parameters
    ----------
    params : array_like, shape (..., 6)
        Full parameters p = p⁰ + L at the linearisation point.
    t : array_like, shape (...)
        kT (s).
    shank_length : float
        M (m).

    Returns
    -------
    ndarray, shape (..., 4, 6)
        Rows x₁, z₁, x₂, z₂; columns ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω.
    """
    p = np.asarray(params, dtype=float)
    tt = np.broadcast_to(np.asarray(t, dtype=float), p.shape[:-1])
    M = shank_length
    phase = p[..., I_OMEGA] * tt
    s, c = np.sin(phase), np.cos(phase)
    beta = p[..., I_A] * s
    cb, sb = np.cos(beta), np.sin(beta)
    dbeta_dw = p[..., I_A] * c * tt
    H = np.zeros((*p.shape[:-1], DIM_Z, DIM_X))
    H[..., 0, I_AX] = s  # H11
    H[..., 0, I_CX] = tt  # H13 = kT
    H[..., 0, I_OMEGA] = p[..., I_AX] * c * tt  # thesis H15
    H[..., 1, I_AZ] = s  # H22
    H[..., 1, I_CZ] = 1.0  # H24
    H[..., 1, I_OMEGA] = p[..., I_AZ] * c * tt  # thesis H25
    H[..., 2, I_AX] = s  # H31
    H[..., 2, I_CX] = tt  # H33
    H[..., 2, I_A] = M * cb * s  # thesis H36
    H[..., 2, I_OMEGA] = H[..., 0, I_OMEGA] + M * cb * dbeta_dw  # thesis H35
    H[..., 3, I_AZ] = s  # H42
    H[..., 3, I_CZ] = 1.0  # H44
    H[..., 3, I_A] = -M * sb * s  # thesis H46
    H[..., 3, I_OMEGA] = H[..., 1, I_OMEGA] - M * sb * dbeta_dw  # thesis H45
    return H


def _require_positive(name: str, value: float) -> None:
    if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


@dataclass(frozen=True)
class MarkerEkfConfig:
    """The filter's assumed model (thesis chapter 5).

    Attributes
    ----------
    nominal : HeelKneeNominal
        p⁰ the filter linearises around (thesis §4.2).
    sample_period : float
        T (s) between UWB samples (not in the thesis; 10 Hz, see
        :class:`~pednav_env.sensors.uwb.UwbSpec`).
    param_var_ratio : float
        The 0.03 of eq 5.4 (stationary variance / nominal²).
    param_corr_time : float
        τ (s), d = exp(−T/τ) in eq 5.1 (not in the thesis).
    meas_std : float
        σ (m) of R = σ² I, eq 5.5 (0.1 m).
    eig_floor : float
        Relative eigenvalue floor of the covariance repair.
    """

    nominal: HeelKneeNominal = field(default_factory=HeelKneeNominal)
    sample_period: float = 0.1  # ours: 10 Hz DecaWave TWR rate (as HeelKneeConfig)
    param_var_ratio: float = 0.03  # thesis eq 5.4
    param_corr_time: float = 1e4  # ours, as HeelKneeConfig (not in the thesis)
    meas_std: float = 0.1  # thesis eq 5.5: R = 0.01 I
    eig_floor: float = 1e-12  # ours: numerical floor, relative to the largest eigenvalue

    def __post_init__(self) -> None:
        if not isinstance(self.nominal, HeelKneeNominal):
            raise ValueError(
                f"MarkerEkfConfig.nominal must be a HeelKneeNominal, got {self.nominal!r}"
            )
        _require_positive("MarkerEkfConfig.sample_period", self.sample_period)
        _require_positive("MarkerEkfConfig.param_corr_time", self.param_corr_time)
        _require_positive("MarkerEkfConfig.meas_std", self.meas_std)
        if not (
            isinstance(self.param_var_ratio, (int, float))
            and math.isfinite(self.param_var_ratio)
            and self.param_var_ratio >= 0
        ):
            raise ValueError(
                f"MarkerEkfConfig.param_var_ratio must be a finite number >= 0, "
                f"got {self.param_var_ratio!r}"
            )
        if (
            not (isinstance(self.eig_floor, (int, float)) and math.isfinite(self.eig_floor))
            or not 0 < self.eig_floor < 1
        ):
            raise ValueError(f"MarkerEkfConfig.eig_floor must be in (0, 1), got {self.eig_floor!r}")

    @property
    def inertia(self) -> float:
        """d = exp(−T/τ) (eq 5.1)."""
        return math.exp(-self.sample_period / self.param_corr_time)

    @property
    def process(self) -> ProcessModel:
        """F, Γ, Q, P0 diagonals of eqs 5.1, 5.2, 5.4, 5.8."""
        return process_model(self.inertia, self.param_var_ratio, self.nominal.vector)

    @property
    def R(self) -> Array:
        """Measurement covariance σ² I, eq 5.5, shape ``(4, 4)``."""
        return self.meas_std**2 * np.eye(DIM_Z)

    @classmethod
    def matched(cls, gait: HeelKneeConfig, uwb: UwbSpec) -> MarkerEkfConfig:
        """The thesis filter for a simulator: same p⁰, T, 0.03, τ and σ."""
        if not math.isclose(gait.sample_period, uwb.sample_period, rel_tol=1e-12):
            raise ValueError(
                f"gait.sample_period={gait.sample_period} differs from the UWB period "
                f"{uwb.sample_period}"
            )
        return cls(
            nominal=gait.nominal,
            sample_period=gait.sample_period,
            param_var_ratio=gait.param_var_ratio,
            param_corr_time=gait.param_corr_time,
            meas_std=uwb.noise_std,
        )


def _as_walker_array(name: str, value: ArrayLike | None, n: int, dim: int) -> Array:
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
    """Batched EKF over N walkers (thesis eqs 1.11–1.18 with 4.10–5.8).

    Attributes
    ----------
    x : ndarray, shape (N, 6)
        Estimate of the deviations L (units of ``PARAM_UNITS``).
    P : ndarray, shape (N, 6, 6)
        Its covariance.
    x_prior, P_prior, x_post, P_post : ndarray
        Prior and posterior of the last step (filterpy's convention).
    y : ndarray, shape (N, 4)
        Last innovation (0 in skipped rows).
    S : ndarray, shape (N, 4, 4)
        Last innovation covariance (identity rows/columns where skipped).
    K : ndarray, shape (N, 6, 4)
        Last gain (zero columns where skipped).
    nis : ndarray, shape (N,)
        Last normalised innovation squared yᵀ S⁻¹ y over the valid rows.
    num_valid : ndarray of int, shape (N,)
        Number of valid rows in the last update.
    repairs : ndarray of int, shape (N,)
        Covariance repairs per walker since construction.
    """

    def __init__(self, config: MarkerEkfConfig, num_walkers: int) -> None:
        if not isinstance(num_walkers, (int, np.integer)) or num_walkers < 1:
            raise ValueError(f"num_walkers must be an integer >= 1, got {num_walkers!r}")
        self.config = config
        self.num_walkers = int(num_walkers)
        proc = config.process
        self._F = proc.F
        self._FF = np.outer(proc.F, proc.F)
        self._q = proc.process_noise
        self._p0 = config.nominal.vector
        self._M = config.nominal.shank_length
        self._r = np.full(DIM_Z, config.meas_std**2)
        n = self.num_walkers
        self.x = np.zeros((n, DIM_X))  # eq 5.7
        self.P = np.broadcast_to(np.diag(proc.P0), (n, DIM_X, DIM_X)).copy()  # eq 5.8
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self.y = np.zeros((n, DIM_Z))
        self.S = np.zeros((n, DIM_Z, DIM_Z))
        self.K = np.zeros((n, DIM_X, DIM_Z))
        self.nis = np.zeros(n)
        self.num_valid = np.zeros(n, dtype=np.int64)
        self.repairs = np.zeros(n, dtype=np.int64)

    @property
    def params(self) -> Array:
        """Estimated full parameters p⁰ + x̂, shape ``(N, 6)``."""
        return self._p0 + self.x

    def process_noise(self, q_scale: ArrayLike | None = None) -> Array:
        """Diagonal of Γ Q Γᵀ times ``q_scale``, shape ``(N, 6)``."""
        return self._q * _as_walker_array("q_scale", q_scale, self.num_walkers, DIM_X)

    def measurement_noise(self, r_scale: ArrayLike | None = None) -> Array:
        """Diagonal of R times ``r_scale``, shape ``(N, 4)``."""
        return self._r * _as_walker_array("r_scale", r_scale, self.num_walkers, DIM_Z)

    def predict(self, q_scale: ArrayLike | None = None) -> None:
        """x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (eqs 4.11, 5.1, 5.2, 5.4; thesis 1.11–1.12).

        Parameters
        ----------
        q_scale : array_like, optional
            Positive multipliers of Γ Q Γᵀ's diagonal: a scalar, ``(N,)`` (one
            per walker), or ``(1, 6)`` / ``(N, 6)`` (per parameter).
        """
        q = self.process_noise(q_scale)
        self.x = self._F * self.x
        self.P = self.P * self._FF
        self.P[:, np.arange(DIM_X), np.arange(DIM_X)] += q
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()

    def update(
        self,
        z: ArrayLike,
        t: ArrayLike,
        valid: ArrayLike | None = None,
        r_scale: ArrayLike | None = None,
    ) -> None:
        """Correct with one UWB sample per walker (eqs 4.12, 5.3, 5.5; thesis 1.14–1.18).

        Parameters
        ----------
        z : array_like, shape (N, 4) or (N, 2, 2)
            Measured [x₁, z₁, x₂, z₂] (m).
        t : array_like, shape () or (N,)
            kT of the sample (s).
        valid : array_like of bool, shape (N, 2) or (N, 4), optional
            Per marker or per coordinate; False rows are skipped (their values
            in ``z`` are ignored).
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
        r = self.measurement_noise(r_scale)

        params = self._p0 + self.x
        H = marker_jacobian(params, tt, self._M)  # (N, 4, 6)
        y = zz - marker_measurement(params, tt, self._M)
        H = np.where(ok[:, :, None], H, 0.0)
        y = np.where(ok, y, 0.0)
        r = np.where(ok, r, 1.0)  # decoupled unit rows where skipped: K column = 0

        HP = H @ self.P  # (N, 4, 6)
        S = HP @ H.transpose(0, 2, 1)
        S[:, np.arange(DIM_Z), np.arange(DIM_Z)] += r
        # One solve for K and the NIS: S⁻¹ [H P | y] (S is symmetric).
        sol = np.linalg.solve(S, np.concatenate((HP, y[:, :, None]), axis=2))
        K = sol[:, :, :DIM_X].transpose(0, 2, 1)  # (N, 6, 4) = P Hᵀ S⁻¹
        self.nis = np.einsum("ni,ni->n", y, sol[:, :, DIM_X])
        self.x = self.x + np.einsum("nij,nj->ni", K, y)
        I_KH = np.eye(DIM_X) - K @ H
        KRKt = (K * np.where(ok, r, 0.0)[:, None, :]) @ K.transpose(0, 2, 1)
        P = I_KH @ self.P @ I_KH.transpose(0, 2, 1) + KRKt  # Joseph form
        self.P = self._repair(0.5 * (P + P.transpose(0, 2, 1)))
        self.y, self.S, self.K = y, S, K
        self.num_valid = ok.sum(axis=1)
        self.x_post, self.P_post = self.x.copy(), self.P.copy()

    def _repair(self, P: Array) -> Array:
        """Floor the eigenvalues of walkers whose P is not positive definite.

        The test is a Cholesky factorisation vectorised over walkers: a walker
        fails when a pivot drops below ``eig_floor`` times its largest
        diagonal element. Failing walkers get P = V max(Λ, floor) Vᵀ.
        """
        scale = np.max(np.diagonal(P, axis1=1, axis2=2), axis=1)
        floor = self.config.eig_floor * np.maximum(scale, np.finfo(float).tiny)
        bad = ~(scale > 0)
        L = np.zeros_like(P)
        for j in range(DIM_X):
            pivot = P[:, j, j] - np.einsum("nk,nk->n", L[:, j, :j], L[:, j, :j])
            bad |= ~(pivot > floor)
            L[:, j, j] = np.sqrt(np.where(pivot > floor, pivot, 1.0))
            L[:, j + 1 :, j] = (
                P[:, j + 1 :, j] - np.einsum("nik,nk->ni", L[:, j + 1 :, :j], L[:, j, :j])
            ) / L[:, j, j, None]
        if np.any(bad):
            w, V = np.linalg.eigh(P[bad])
            w_floor = self.config.eig_floor * np.maximum(np.abs(w[:, -1]), np.finfo(float).tiny)
            w = np.maximum(w, w_floor[:, None])
            P = P.copy()
            fixed = (V * w[:, None, :]) @ V.transpose(0, 2, 1)
            P[bad] = 0.5 * (fixed + fixed.transpose(0, 2, 1))
            self.repairs[bad] += 1
        return P

    def markers(self, t: ArrayLike) -> Array:
        """Estimated marker positions h(p⁰ + x̂) at ``t``, shape ``(N, 2, 2)`` (m)."""
        return heel_knee_positions(self.params, t, self._M)


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
    q_scale: ArrayLike | None = None,
    r_scale: ArrayLike | None = None,
) -> MarkerEkfRun:
    """Filter whole walks sampled at t_k = kT, k = 0 … K−1.

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
    x = np.empty((n, k, DIM_X))
    P_diag = np.empty((n, k, DIM_X))
    nis = np.empty((n, k))
    num_valid = np.empty((n, k), dtype=np.int64)
    est = np.empty((n, k, 2, 2))
    T = config.sample_period
    for j in range(k):
        if j > 0:
            ekf.predict(q_scale)
        ekf.update(zz[:, j], j * T, None if valid is None else valid[:, j], r_scale)
        x[:, j] = ekf.x
        P_diag[:, j] = np.diagonal(ekf.P, axis1=1, axis2=2)
        nis[:, j] = ekf.nis
        num_valid[:, j] = ekf.num_valid
        est[:, j] = ekf.markers(j * T)
    return MarkerEkfRun(
        x=x, P_diag=P_diag, markers=est, nis=nis, num_valid=num_valid, repairs=ekf.repairs.copy()
    )


# --------------------------------------------------------------------------- low-pass baseline


def lowpass_filter(
    z: ArrayLike,
    cutoff_hz: float,
    rate_hz: float,
    valid: ArrayLike | None = None,
    order: int = 1,
    zero_phase: bool = False,
) -> Array:
    """Butterworth low-pass of raw positions (the thesis's "simplest LPF").

    Causal by default (``scipy.signal.sosfilt``), starting in steady state at
    the first sample (``sosfilt_zi``) so no start-up transient from zero is
    added. ``zero_phase=True`` runs it forwards and backwards
    (``sosfiltfilt``), which is not causal and is offered only to analyse
    the reproduction. Dropped samples are replaced by the last valid one
    before filtering.

    Parameters
    ----------
    z : array_like, shape (N, K, ...)
        Raw positions (m), time on axis 1.
    cutoff_hz : float
        −3 dB cut-off (Hz) of one pass, below the Nyquist frequency.
    rate_hz : float
        Sample rate (Hz).
    valid : array_like of bool, shape (N, K, 2), optional
        Per-marker validity of ``z`` shaped ``(N, K, 2, 2)``.
    order : int
        Filter order (1: RC filter, the thesis's simplest LPF).
    zero_phase : bool
        Forward-backward filtering instead of the causal filter.

    Returns
    -------
    ndarray, same shape as ``z``
    """
    _require_positive("rate_hz", rate_hz)
    _require_positive("cutoff_hz", cutoff_hz)
    if cutoff_hz >= rate_hz / 2:
        raise ValueError(f"cutoff_hz must be below rate_hz/2 = {rate_hz / 2}, got {cutoff_hz!r}")
    if not isinstance(order, (int, np.integer)) or order < 1:
        raise ValueError(f"order must be an integer >= 1, got {order!r}")
    zz = np.asarray(z, dtype=float)
    if zz.ndim < 2 or zz.shape[1] < 1:
        raise ValueError(f"z must have shape (N, K, ...) with K >= 1, got {zz.shape}")
    if valid is not None:
        v = np.asarray(valid)
        if zz.shape[2:] != (2, 2) or v.shape != zz.shape[:3] or v.dtype != np.bool_:
            raise ValueError(
                f"valid must be boolean (N, K, 2) for z of shape (N, K, 2, 2), got {v.shape}"
            )
        zz = hold_last_valid(zz, v)
    if not np.all(np.isfinite(zz)):
        raise ValueError("z must be finite (found NaN or inf)")
    sos = butter(order, cutoff_hz, btype="low", fs=rate_hz, output="sos")
    if zero_phase:
        return sosfiltfilt(sos, zz, axis=1)
    zi_unit = sosfilt_zi(sos)  # (sections, 2): steady state for a unit input
    # sosfilt wants zi shaped (sections, N, 2, ...): the state axis replaces time.
    zi = zi_unit.reshape((zi_unit.shape[0], 1, 2) + (1,) * (zz.ndim - 2)) * zz[None, :, 0:1]
    y, _ = sosfilt(sos, zz, axis=1, zi=zi)
    return y


def lowpass_noise_gain(
    cutoff_hz: float, rate_hz: float, order: int = 1, zero_phase: bool = False
) -> float:
    """Output variance of :func:`lowpass_filter` per unit white-noise input variance.

    Σ g_k² of the filter's impulse response g, computed numerically (for the
    causal first-order filter it equals (1 − a)/2, a the pole).
    """
    # 40 time constants of the slowest pole (order ≤ a few): the tail is < e⁻⁴⁰.
    n = int(40 * order * rate_hz / (2 * math.pi * cutoff_hz)) + 64
    impulse = np.zeros((1, 2 * n + 1))
    impulse[0, n] = 1.0
    response = lowpass_filter(impulse, cutoff_hz, rate_hz, order=order, zero_phase=zero_phase)
    return float(np.sum(response**2))


def lowpass_cutoff_for_gait(
    nominal: HeelKneeNominal,
    rate_hz: float,
    noise_std: float,
    duration: float,
    zero_phase: bool = False,
) -> float:
    """Cut-off (Hz) of the first-order LPF that is best for the nominal gait.

    Minimises, over the cut-off, the predicted mean squared error summed over
    the four coordinates x₁, z₁, x₂, z₂: the error of the filter on the
    noise-free nominal trajectory over ``duration`` (lag on the trend,
    attenuation and phase lag of the gait harmonic) plus its white-noise
    output variance (:func:`lowpass_noise_gain`). It uses only the
    information the EKF is given (p⁰, σ), no truth and no random draw, so the
    baseline is the best "simplest LPF" for the scenario rather than a straw
    man.

    Parameters
    ----------
    nominal : HeelKneeNominal
        p⁰ of the gait.
    rate_hz : float
        Sample rate (Hz).
    noise_std : float
        σ (m) of the raw positions.
    duration : float
        Length (s) of the walks the filter is scored on.
    zero_phase : bool
        Optimise the forward-backward variant instead.

    Returns
    -------
    float
        Cut-off (Hz) in (0.01, 0.99) × Nyquist.
    """
    _require_positive("rate_hz", rate_hz)
    _require_positive("noise_std", noise_std)
    _require_positive("duration", duration)
    k = max(2, round(duration * rate_hz))
    t = np.arange(k) / rate_hz
    truth = heel_knee_positions(nominal.vector, t, nominal.shank_length)[None]  # (1, K, 2, 2)
    nyq = rate_hz / 2

    def cost(log_fc: float) -> float:
        fc = math.exp(log_fc)
        out = lowpass_filter(truth, fc, rate_hz, zero_phase=zero_phase)
        bias_mse = np.mean((out - truth) ** 2)
        gain = lowpass_noise_gain(fc, rate_hz, zero_phase=zero_phase)
        return float(bias_mse + noise_std**2 * gain)

    res = minimize_scalar(
        cost, bounds=(math.log(0.01 * nyq), math.log(0.99 * nyq)), method="bounded"
    )
    return float(math.exp(res.x))
