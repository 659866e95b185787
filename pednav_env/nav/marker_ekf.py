"""Marker EKF of paper 001 (thesis chapter 5) and its low-pass baseline.

The EKF estimates the deviations L = [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω] of the
heel–knee model (:mod:`pednav_env.gait.heel_knee`, eq 4.9 order) from the
raw UWB positions r = [x₁, z₁, x₂, z₂] of heel and knee (eq 4.12):

- prediction with the exponentially correlated model (eqs 4.11, 5.1, 5.2,
  5.4): x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (thesis eqs 1.11, 1.12);
- correction with h of eq 4.10 and its Jacobian H (eq 5.3) at the prior,
  R = σ² I (eq 5.5), thesis eqs 1.14–1.18. Because R is diagonal the four
  coordinates are processed one after another as scalar updates with H fixed
  at the prior: for row m, s = hₘᵀ P hₘ + rₘ, w = P hₘ/√s, ν = ỹₘ/√s,
  x ← x + w ν, P ← P − w wᵀ, and the later rows see the state and covariance
  after the earlier ones. This is algebraically the batch update
  K = P Hᵀ S⁻¹, x = x⁻ + K y, P = (I − KH) P⁻ (tests compare it with
  ``filterpy.kalman.ExtendedKalmanFilter`` step by step, ≤ 1e-8 relative),
  and Σ ν² = yᵀ S⁻¹ y is the NIS;
- initialisation x̂ = 0 (eq 5.7), P0 = var_ratio · diag(p⁰²) (eq 5.8).

**Covariance form, repair and counting.** P − w wᵀ is the (I − KH) P⁻ form
written as a symmetric rank-one downdate, not the Joseph form
(I − KH) P⁻ (I − KH)ᵀ + K R Kᵀ (equal to it for the optimal gain, and the
form this module used before the two marker filters were merged): it keeps
P exactly symmetric (entries (i, j) and (j, i) are the same products added
in the same order) at a fraction of the Joseph form's cost, but rounding can
still cost positive definiteness when a coordinate is measured much more
precisely than it is predicted. :meth:`MarkerEkfEngine.repair` therefore
tests every lane with a Cholesky factorisation: a lane fails when its largest
variance is not > 0 or a pivot drops below ``eig_floor`` times it; its P
becomes V max(Λ, floor) Vᵀ (floor = ``eig_floor`` × the largest |λ|) and its
``repairs`` counter goes up by one (one per repaired call, not per
eigenvalue). Lanes whose P is not finite are not repaired but returned as
diverged. :class:`MarkerEKF` (and so :func:`run_marker_ekf` and the paper-001
reproduction) repairs after every update; the marker environment
(:mod:`pednav_env.envs.marker_core`) once per decision interval, so the two
counts are not comparable.

**One filter, two faces.** :class:`MarkerEkfEngine` is the implementation:
lane axis last (x is ``(6, N)``, P ``(6, 6, N)``), so every operation sweeps
all lanes contiguously, with no loop over lanes and no inverse. The marker
environment drives it directly. :class:`MarkerEKF` is its walker-first
interface (x ``(N, 6)`` and P ``(N, 6, 6)`` are views of the engine's arrays)
with input checks, per-call Q and R scales, filterpy-style prior/posterior
copies and the per-update repair; :func:`run_marker_ekf` filters whole walks
with it. Reductions over the state or the coordinates add in the same order
for any N, so a lane's numbers do not depend on the batch size or on the
other lanes, bit for bit (tests check it).

**Time origin.** The engine writes eq 4.10 about a per-lane anchor
(t_a, X_a): kT → t − t_a and X_a added to both x coordinates. The anchor
(0, 0) — :class:`MarkerEKF` never moves it — is the thesis's model exactly;
the marker environment re-anchors long walks (see its core's docstring).

Our column order of H puts ∂/∂ΔA fifth and ∂/∂Δω sixth (the state order of
eq 4.9); the thesis's printed (5.3) and (5.6) list ω before A, i.e. its H15,
H25, H35, H45 are our column 6 and its H36, H46 our column 5.
:func:`marker_measurement` and :func:`marker_jacobian` are h and H as plain
functions (the filterpy oracle and the benchmark's reference use them).

The action hooks of the marker environment: ``q_scale`` multiplies the
diagonal of Γ Q Γᵀ per walker and parameter, ``r_scale`` the diagonal of R per
walker and coordinate (the engine's ``q`` and ``r``); samples whose ``valid``
flag is False are skipped.

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


class MarkerEkfEngine:
    """The marker EKF of paper 001 for N lanes at once, lane axis last.

    Thesis eqs 1.11–1.18 with 4.10–5.8 (module docstring): prediction
    x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ; correction with h of eq 4.10 and H of
    eq 5.3 linearised at the prior, R diagonal, as four sequential scalar
    updates with the covariance downdated as P − Σ w wᵀ; x̂ = 0 and
    P0 = 0.03 diag(p⁰²) at the start. Arrays are ``(…, N)`` so every operation
    runs over the lanes in one contiguous sweep. :meth:`repair` is separate so
    that the caller chooses how often to check positive definiteness.

    The model is written about the anchor (t_a, X_a) (module docstring):
    kT → t − t_a and X_a added to both x coordinates.

    Attributes
    ----------
    x : ndarray, shape (6, N)
        Estimate of the deviations L (units of ``PARAM_UNITS``).
    P : ndarray, shape (6, 6, N)
        Its covariance (C-contiguous; updated in place).
    q : ndarray, shape (6, N)
        Diagonal of Γ Q Γᵀ used by :meth:`predict` (``q0`` at construction).
    r : ndarray, shape (4, N)
        Diagonal of R used by :meth:`update` (``r0`` at construction).
    t_anchor, x_anchor : ndarray, shape (N,)
        Time origin t_a (s) and x offset X_a (m) of the model.
    repairs : ndarray of int, shape (N,)
        Covariance repairs per lane since construction.
    """

    def __init__(self, config: MarkerEkfConfig, num_lanes: int) -> None:
        if not isinstance(num_lanes, (int, np.integer)) or num_lanes < 1:
            raise ValueError(f"num_lanes must be an integer >= 1, got {num_lanes!r}")
        n = int(num_lanes)
        self.config = config
        self.n = n
        proc = config.process
        self.F = proc.F[:, None].copy()  # (6, 1), eq 5.1
        self.FF = (proc.F[:, None] * proc.F[None, :])[:, :, None]
        self.q0 = proc.process_noise.copy()  # diagonal of Γ Q Γᵀ, eqs 5.2, 5.4
        self.r0 = config.meas_std**2  # eq 5.5
        self.p0 = config.nominal.vector[:, None].copy()  # (6, 1)
        self.M = config.nominal.shank_length
        self.P0 = np.diag(proc.P0)  # eq 5.8
        self.x = np.zeros((DIM_X, n))  # eq 5.7
        self.P = np.repeat(self.P0[:, :, None], n, axis=2)
        self.q = np.repeat(self.q0[:, None], n, axis=1)
        self.r = np.full((DIM_Z, n), self.r0)
        self.t_anchor = np.zeros(n)
        self.x_anchor = np.zeros(n)
        self.repairs = np.zeros(n, dtype=np.int64)
        self._H = np.zeros((DIM_Z, DIM_X, n))
        self._H[1, 3] = self._H[3, 3] = 1.0  # ∂z/∂Δc_z
        self._W = np.zeros((DIM_Z, DIM_X, n))
        self._nu = np.zeros((DIM_Z, n))

    def reset(self, lanes: NDArray[np.integer]) -> None:
        """Initial estimate x̂ = 0, P0 (eqs 5.7, 5.8) and anchor 0 in ``lanes``."""
        self.x[:, lanes] = 0.0
        self.P[:, :, lanes] = self.P0[:, :, None]
        self.t_anchor[lanes] = 0.0
        self.x_anchor[lanes] = 0.0

    def predict(self) -> None:
        """x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (thesis eqs 1.11, 1.12, 5.1–5.4)."""
        self.x *= self.F
        self.P *= self.FF
        self.P.reshape(DIM_X * DIM_X, self.n)[:: DIM_X + 1] += self.q

    def markers(self, t: Array, x: Array | None = None) -> Array:
        """h(p⁰ + x) at times ``t``: heel x, heel z, knee x, knee z (m).

        ``t`` is ``(..., N)`` and ``x`` ``(6, ..., N)`` (default: the current
        estimate, with ``t`` of shape ``(N,)``); returns ``(4, ..., N)``.
        """
        x = self.x if x is None else x
        p = self.p0.reshape((DIM_X,) + (1,) * (x.ndim - 1)) + x
        tau = t - self.t_anchor
        s = np.sin(p[I_OMEGA] * tau)
        beta = p[I_A] * s
        out = np.empty((DIM_Z, *tau.shape))
        out[0] = self.x_anchor + p[I_CX] * tau + p[I_AX] * s
        out[1] = p[I_CZ] + p[I_AZ] * s
        out[2] = out[0] + self.M * np.sin(beta)
        out[3] = out[1] + self.M * np.cos(beta)
        return out

    def update(self, z: Array, valid: BoolArray, t: Array) -> Array:
        """Correct with one UWB sample per lane (thesis eqs 1.14–1.18, 4.12, 5.3, 5.5).

        Parameters
        ----------
        z : ndarray, shape (4, N)
            Reported [x₁, z₁, x₂, z₂] (m); must be finite (also where skipped).
        valid : ndarray of bool, shape (4, N)
            False coordinates are skipped.
        t : ndarray, shape (N,)
            kT of the sample (s).

        Returns
        -------
        ndarray, shape (4, N)
            Normalised sequential innovations ν (0 where skipped); Σ ν² is the
            NIS yᵀ S⁻¹ y. An internal buffer, overwritten by the next call.
        """
        p = self.p0 + self.x
        tau = t - self.t_anchor
        phase = p[I_OMEGA] * tau
        s = np.sin(phase)
        ctau = np.cos(phase) * tau
        beta = p[I_A] * s
        Msb = self.M * np.sin(beta)
        Mcb = self.M * np.cos(beta)
        H = self._H  # eq 5.3, columns in eq 4.9 order
        H[0, I_AX] = s
        H[0, I_CX] = tau
        H[0, I_OMEGA] = p[I_AX] * ctau
        H[1, I_AZ] = s
        H[1, I_OMEGA] = p[I_AZ] * ctau
        H[2, I_AX] = s
        H[2, I_CX] = tau
        H[2, I_A] = Mcb * s
        dbeta = p[I_A] * ctau
        H[2, I_OMEGA] = H[0, I_OMEGA] + Mcb * dbeta
        H[3, I_AZ] = s
        H[3, I_A] = -Msb * s
        H[3, I_OMEGA] = H[1, I_OMEGA] - Msb * dbeta
        hx1 = self.x_anchor + p[I_CX] * tau + p[I_AX] * s
        hz1 = p[I_CZ] + p[I_AZ] * s
        y = np.empty((DIM_Z, self.n))
        y[0] = z[0] - hx1
        y[1] = z[1] - hz1
        y[2] = z[2] - (hx1 + Msb)
        y[3] = z[3] - (hz1 + Mcb)
        if valid.all():
            Hm = H
        else:
            Hm = H * valid[:, None, :]
            y *= valid
        # P hₘ for every row m. Reductions here are sums of < 8 terms along a lane-
        # strided axis or einsum/matmul forms that add in the same order for any
        # N, so a lane's numbers do not depend on the batch size (bit for bit;
        # einsum("jn,jn->n") does not have that property at N = 1).
        PH = np.einsum("mjn,jin->min", Hm, self.P)
        W, nu = self._W, self._nu
        for m in range(DIM_Z):
            s_m = (Hm[m] * PH[m]).sum(axis=0) + self.r[m]
            inv = 1.0 / np.sqrt(s_m)
            np.multiply(PH[m], inv, out=W[m])
            np.multiply(y[m], inv, out=nu[m])
            if m < DIM_Z - 1:  # rows after m see the covariance and state after row m
                dots = (W[m] * Hm[m + 1 :]).sum(axis=1)
                PH[m + 1 :] -= W[m][None, :, :] * dots[:, None, :]
                y[m + 1 :] -= dots * nu[m]
        self.x += (W * nu[:, None, :]).sum(axis=0)
        # Σₘ wₘ wₘᵀ per lane as one batched (6×4)(4×6) product
        self.P -= (W.transpose(2, 1, 0) @ W.transpose(2, 0, 1)).transpose(1, 2, 0)
        return nu

    def repair(self) -> BoolArray:
        """Floor the eigenvalues of lanes whose P fails the Cholesky-pivot test.

        A lane fails when its largest variance is not > 0 or a pivot drops
        below ``eig_floor`` times it; its P becomes V max(Λ, floor) Vᵀ and its
        ``repairs`` count goes up by one. Lanes with a non-finite P are left
        alone and returned (diverged).

        Returns
        -------
        ndarray of bool, shape (N,)
            True where P is not finite.
        """
        P = self.P
        diag = P.reshape(DIM_X * DIM_X, self.n)[:: DIM_X + 1]
        finite = np.isfinite(P).all(axis=(0, 1))
        scale = np.max(diag, axis=0)
        floor = self.config.eig_floor * np.maximum(scale, np.finfo(float).tiny)
        try:  # fast path: LAPACK over all lanes; its pivots are L_jj²
            L = np.linalg.cholesky(P.transpose(2, 0, 1))
            pivots = np.diagonal(L, axis1=1, axis2=2) ** 2  # (N, 6)
            bad = ~(scale > 0) | ~np.all(pivots > floor[:, None], axis=1)
        except np.linalg.LinAlgError:  # some lane is not PD: the pivot rule lane by lane
            bad = ~(scale > 0)
            L = np.zeros((DIM_X, DIM_X, self.n))
            for j in range(DIM_X):
                pivot = P[j, j] - np.einsum("kn,kn->n", L[j, :j], L[j, :j])
                ok = pivot > floor
                bad |= ~ok
                L[j, j] = np.sqrt(np.where(ok, pivot, 1.0))
                L[j + 1 :, j] = (
                    P[j + 1 :, j] - np.einsum("ikn,kn->in", L[j + 1 :, :j], L[j, :j])
                ) / L[j, j]
        bad &= finite
        if bad.any():
            lanes = np.flatnonzero(bad)
            Pb = P[:, :, lanes].transpose(2, 0, 1)
            w, V = np.linalg.eigh(0.5 * (Pb + Pb.transpose(0, 2, 1)))
            w_floor = self.config.eig_floor * np.maximum(np.abs(w[:, -1]), np.finfo(float).tiny)
            w = np.maximum(w, w_floor[:, None])
            fixed = (V * w[:, None, :]) @ V.transpose(0, 2, 1)
            P[:, :, lanes] = (0.5 * (fixed + fixed.transpose(0, 2, 1))).transpose(1, 2, 0)
            self.repairs[lanes] += 1
        return ~finite


class MarkerEKF:
    """Walker-first interface to :class:`MarkerEkfEngine` (N walkers, anchor 0).

    Checks its inputs, takes the Q and R scales per call, keeps filterpy's
    prior/posterior copies and repairs the covariance after every update
    (module docstring). ``x`` and ``P`` are views of the engine's arrays:
    writing into them writes into the filter.

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
        """Estimate, ``(N, 6)`` (a view of the engine's ``(6, N)`` array)."""
        return self.engine.x.T

    @x.setter
    def x(self, value: ArrayLike) -> None:
        self.engine.x[...] = np.asarray(value, dtype=float).T

    @property
    def P(self) -> Array:
        """Covariance, ``(N, 6, 6)`` (a view of the engine's ``(6, 6, N)`` array)."""
        return self.engine.P.transpose(2, 0, 1)

    @P.setter
    def P(self, value: ArrayLike) -> None:
        self.engine.P[...] = np.asarray(value, dtype=float).transpose(1, 2, 0)

    @property
    def repairs(self) -> NDArray[np.int64]:
        """Covariance repairs per walker, ``(N,)`` (the engine's counter)."""
        return self.engine.repairs

    @property
    def params(self) -> Array:
        """Estimated full parameters p⁰ + x̂, shape ``(N, 6)``."""
        return self.config.nominal.vector + self.x

    def process_noise(self, q_scale: ArrayLike | None = None) -> Array:
        """Diagonal of Γ Q Γᵀ times ``q_scale``, shape ``(N, 6)``."""
        return self.engine.q0 * _as_walker_array("q_scale", q_scale, self.num_walkers, DIM_X)

    def measurement_noise(self, r_scale: ArrayLike | None = None) -> Array:
        """Diagonal of R times ``r_scale``, shape ``(N, 4)``."""
        return self.engine.r0 * _as_walker_array("r_scale", r_scale, self.num_walkers, DIM_Z)

    def predict(self, q_scale: ArrayLike | None = None) -> None:
        """x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (eqs 4.11, 5.1, 5.2, 5.4; thesis 1.11–1.12).

        Parameters
        ----------
        q_scale : array_like, optional
            Positive multipliers of Γ Q Γᵀ's diagonal: a scalar, ``(N,)`` (one
            per walker), or ``(1, 6)`` / ``(N, 6)`` (per parameter).
        """
        self.engine.q[...] = self.process_noise(q_scale).T
        self.engine.predict()
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()

    def update(
        self,
        z: ArrayLike,
        t: ArrayLike,
        valid: ArrayLike | None = None,
        r_scale: ArrayLike | None = None,
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
        e.r[...] = self.measurement_noise(r_scale).T
        if not ok.all():
            zz = np.where(ok, zz, 0.0)  # skipped values are never used (may be NaN)
        nu = e.update(zz.T, ok.T, np.broadcast_to(tt, (n,)))
        self.nu = nu.T.copy()
        self.nis = (nu * nu).sum(axis=0)
        self.num_valid = ok.sum(axis=1)
        e.repair()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()

    def markers(self, t: ArrayLike) -> Array:
        """Estimated marker positions h(p⁰ + x̂) at ``t``, shape ``(N, 2, 2)`` (m)."""
        n = self.num_walkers
        tt = np.broadcast_to(np.asarray(t, dtype=float), (n,))
        return self.engine.markers(tt).T.reshape(n, 2, 2)


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
    xs = np.empty((DIM_X, k, n))  # lane axis last, as the engine
    P_diag = np.empty((n, k, DIM_X))
    nis = np.empty((n, k))
    num_valid = np.empty((n, k), dtype=np.int64)
    T = config.sample_period
    for j in range(k):
        if j > 0:
            ekf.predict(q_scale)
        ekf.update(zz[:, j], j * T, None if valid is None else valid[:, j], r_scale)
        xs[:, j] = ekf.engine.x
        P_diag[:, j] = np.diagonal(ekf.P, axis1=1, axis2=2)
        nis[:, j] = ekf.nis
        num_valid[:, j] = ekf.num_valid
    # h(x̂ₖ) of every sample in one call (elementwise: the same numbers as per step)
    times = np.broadcast_to((np.arange(k) * T)[:, None], (k, n))
    est = ekf.engine.markers(times, xs)  # (4, K, N)
    return MarkerEkfRun(
        x=xs.transpose(2, 1, 0),
        P_diag=P_diag,
        markers=est.transpose(2, 1, 0).reshape(n, k, 2, 2),
        nis=nis,
        num_valid=num_valid,
        repairs=ekf.repairs.copy(),
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
