"""Marker EKF of paper 001 (thesis chapter 5) for N lanes at once.

The EKF estimates the deviations L = [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω] of the
heel–knee model (:mod:`pednav_env.gait.heel_knee_model`, eq 4.9 order) from
the raw UWB positions r = [x₁, z₁, x₂, z₂] of heel and knee (eq 4.12), with
the model it assumes in :mod:`pednav_env.nav.marker_model`:

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
(I − KH) P⁻ (I − KH)ᵀ + K R Kᵀ (equal to it for the optimal gain): it keeps
P exactly symmetric (entries (i, j) and (j, i) are the same products added
in the same order) at a fraction of the Joseph form's cost, but rounding can
still cost positive definiteness when a coordinate is measured much more
precisely than it is predicted. :meth:`MarkerEkfEngine.repair` therefore
tests every lane with a Cholesky factorisation: a lane fails when its largest
variance is not > 0 or a pivot drops below ``eig_floor`` times it; its P
becomes V max(Λ, floor) Vᵀ (floor = ``eig_floor`` × the largest |λ|) and its
``repairs`` counter goes up by one (one per repaired call, not per
eigenvalue). Lanes whose P is not finite are not repaired but returned as
diverged. :class:`~pednav_env.nav.marker_run.MarkerEKF` (and so
:func:`~pednav_env.nav.marker_run.run_marker_ekf` and the paper-001
reproduction) repairs after every update; the marker environment
(:mod:`pednav_env.envs.marker_core`) once per decision interval, so the two
counts are not comparable.

**One filter, two faces.** :class:`MarkerEkfEngine` is the implementation,
lanes first (x is ``(N, 6)``, P ``(N, 6, 6)``), with no loop over lanes and
no inverse. The marker environment drives it directly;
:class:`~pednav_env.nav.marker_run.MarkerEKF` wraps it with input checks,
per-call Q and R scales, filterpy-style prior/posterior copies and the
per-update repair. Every sum over the state or the coordinates adds its
terms in index order, whatever N, so a lane's numbers do not depend on the
batch size or on the other lanes, bit for bit (tests check it).

**Time origin.** The engine writes eq 4.10 about a per-lane anchor
(t_a, X_a): kT → t − t_a and X_a added to both x coordinates. The anchor
(0, 0) — :class:`~pednav_env.nav.marker_run.MarkerEKF` never moves it — is
the thesis's model exactly; the marker environment re-anchors long walks
(see its core's docstring).

The action hooks of the marker environment: ``q`` (the diagonal of Γ Q Γᵀ per
lane and parameter) and ``r`` (the diagonal of R per lane and coordinate);
samples whose ``valid`` flag is False are skipped.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.gait.heel_knee_model import I_A, I_AX, I_AZ, I_CX, I_CZ, I_OMEGA
from pednav_env.nav.marker_model import DIM_X, DIM_Z, MarkerEkfConfig

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class MarkerEkfEngine:
    """The marker EKF of paper 001 for N lanes at once, lanes first.

    Thesis eqs 1.11–1.18 with 4.10–5.8 (module docstring): prediction
    x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ; correction with h of eq 4.10 and H of
    eq 5.3 linearised at the prior, R diagonal, as four sequential scalar
    updates with the covariance downdated as P − Σ w wᵀ; x̂ = 0 and
    P0 = 0.03 diag(p⁰²) at the start. :meth:`repair` is separate so that the
    caller chooses how often to check positive definiteness.

    The model is written about the anchor (t_a, X_a) (module docstring):
    kT → t − t_a and X_a added to both x coordinates.

    Attributes
    ----------
    x : ndarray, shape (N, 6)
        Estimate of the deviations L (units of ``PARAM_UNITS``).
    P : ndarray, shape (N, 6, 6)
        Its covariance (C-contiguous; updated in place).
    q : ndarray, shape (N, 6)
        Diagonal of Γ Q Γᵀ used by :meth:`predict` (``q0`` at construction).
    r : ndarray, shape (N, 4)
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
        # F x and F P Fᵀ (eq 5.1, F diagonal) as elementwise products with F and
        # F Fᵀ repeated per lane, so that predict sweeps the arrays in one pass
        self._F = np.repeat(proc.F[None], n, axis=0)
        self._FF = np.repeat((proc.F[:, None] * proc.F[None, :])[None], n, axis=0)
        self.q0 = proc.process_noise.copy()  # diagonal of Γ Q Γᵀ, eqs 5.2, 5.4
        self.r0 = config.meas_std**2  # eq 5.5
        self.p0 = config.nominal.vector  # (6,)
        self.M = config.nominal.shank_length
        self.P0 = np.diag(proc.P0)  # eq 5.8
        self.x = np.zeros((n, DIM_X))  # eq 5.7
        self.P = np.repeat(self.P0[None], n, axis=0)
        self.q = np.repeat(self.q0[None], n, axis=0)
        self.r = np.full((n, DIM_Z), self.r0)
        self.t_anchor = np.zeros(n)
        self.x_anchor = np.zeros(n)
        self.repairs = np.zeros(n, dtype=np.int64)
        self._H = np.zeros((DIM_Z, DIM_X, n))  # working arrays, component-major
        self._H[1, I_CZ] = self._H[3, I_CZ] = 1.0  # ∂z/∂Δc_z
        self._W = np.zeros((DIM_Z, DIM_X, n))
        self._nu = np.zeros((DIM_Z, n))

    def reset(self, lanes: NDArray[np.integer]) -> None:
        """Initial estimate x̂ = 0, P0 (eqs 5.7, 5.8) and anchor 0 in ``lanes``."""
        self.x[lanes] = 0.0
        self.P[lanes] = self.P0
        self.t_anchor[lanes] = 0.0
        self.x_anchor[lanes] = 0.0

    def predict(self) -> None:
        """x⁻ = F x, P⁻ = F P Fᵀ + Γ Q Γᵀ (thesis eqs 1.11, 1.12, 5.1–5.4)."""
        self.x *= self._F
        self.P *= self._FF
        self.P.reshape(self.n, DIM_X * DIM_X)[:, :: DIM_X + 1] += self.q

    def markers(self, t: Array, x: Array | None = None) -> Array:
        """h(p⁰ + x) at times ``t``: heel x, heel z, knee x, knee z (m).

        ``t`` is ``(N, ...)`` and ``x`` ``(N, ..., 6)`` (default: the current
        estimate, with ``t`` of shape ``(N,)``); returns ``(N, ..., 4)``.
        """
        x = self.x if x is None else x
        p = self.p0 + x
        lane = (self.n,) + (1,) * (t.ndim - 1)
        tau = t - self.t_anchor.reshape(lane)
        s = np.sin(p[..., I_OMEGA] * tau)
        beta = p[..., I_A] * s
        out = np.empty((*tau.shape, DIM_Z))
        out[..., 0] = self.x_anchor.reshape(lane) + p[..., I_CX] * tau + p[..., I_AX] * s
        out[..., 1] = p[..., I_CZ] + p[..., I_AZ] * s
        out[..., 2] = out[..., 0] + self.M * np.sin(beta)
        out[..., 3] = out[..., 1] + self.M * np.cos(beta)
        return out

    def update(self, z: Array, valid: BoolArray, t: Array) -> Array:
        """Correct with one UWB sample per lane (thesis eqs 1.14–1.18, 4.12, 5.3, 5.5).

        Parameters
        ----------
        z : ndarray, shape (N, 4)
            Reported [x₁, z₁, x₂, z₂] (m); must be finite (also where skipped).
        valid : ndarray of bool, shape (N, 4)
            False coordinates are skipped.
        t : ndarray, shape (N,)
            kT of the sample (s).

        Returns
        -------
        ndarray, shape (N, 4)
            Normalised sequential innovations ν (0 where skipped); Σ ν² is the
            NIS yᵀ S⁻¹ y. A view of an internal buffer, overwritten by the next
            call.
        """
        # Working arrays are component-major, (…, N), so that every operation
        # below sweeps all lanes contiguously (about twice as fast at N = 256 as
        # on (N, 4, 6) slices); the state stays lanes first.
        p = self.p0[:, None] + self.x.T
        tau = t - self.t_anchor
        phase = p[I_OMEGA] * tau
        s = np.sin(phase)
        ctau = np.cos(phase) * tau
        beta = p[I_A] * s
        Msb = self.M * np.sin(beta)
        Mcb = self.M * np.cos(beta)
        H = self._H  # eq 5.3, columns in eq 4.9 order, (4, 6, N)
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
        y[0] = z[:, 0] - hx1
        y[1] = z[:, 1] - hz1
        y[2] = z[:, 2] - (hx1 + Msb)
        y[3] = z[:, 3] - (hz1 + Mcb)
        if valid.all():
            Hm = H
        else:
            Hm = H * valid.T[:, None, :]
            y *= valid.T
        # P hₘ for every row m. Every reduction here sums at most 6 terms along a
        # component axis, which numpy adds in index order for any N (also in this
        # einsum), so a lane's numbers do not depend on the batch size (bit for bit).
        P = np.ascontiguousarray(self.P.transpose(1, 2, 0))  # (6, 6, N)
        PH = np.einsum("mjn,jin->min", Hm, P)
        W, nu = self._W, self._nu
        for m in range(DIM_Z):
            s_m = (Hm[m] * PH[m]).sum(axis=0) + self.r[:, m]
            inv = 1.0 / np.sqrt(s_m)
            np.multiply(PH[m], inv, out=W[m])
            np.multiply(y[m], inv, out=nu[m])
            if m < DIM_Z - 1:  # rows after m see the covariance and state after row m
                dots = (W[m] * Hm[m + 1 :]).sum(axis=1)
                PH[m + 1 :] -= W[m][None, :, :] * dots[:, None, :]
                y[m + 1 :] -= dots * nu[m]
        self.x += (W * nu[:, None, :]).sum(axis=0).T
        # Σₘ wₘ wₘᵀ per lane as one batched (6×4)(4×6) product, lanes first
        self.P -= W.transpose(2, 1, 0) @ W.transpose(2, 0, 1)
        return nu.T

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
        # the checks over a lane's entries run along the lanes (component-major copy)
        entries = np.ascontiguousarray(P.reshape(self.n, DIM_X * DIM_X).T)  # (36, N)
        finite = np.isfinite(entries).all(axis=0)
        scale = np.max(entries[:: DIM_X + 1], axis=0)
        floor = self.config.eig_floor * np.maximum(scale, np.finfo(float).tiny)
        try:  # fast path: LAPACK over all lanes; its pivots are L_jj²
            L = np.linalg.cholesky(P)
            pivots = np.diagonal(L, axis1=1, axis2=2) ** 2  # (N, 6)
            bad = ~(scale > 0) | ~np.all(pivots > floor[:, None], axis=1)
        except np.linalg.LinAlgError:  # some lane is not PD: the pivot rule lane by lane
            bad = ~(scale > 0)
            L = np.zeros((self.n, DIM_X, DIM_X))
            for j in range(DIM_X):
                row = L[:, j, :j]
                pivot = P[:, j, j] - (row * row).sum(axis=1)
                ok = pivot > floor
                bad |= ~ok
                L[:, j, j] = np.sqrt(np.where(ok, pivot, 1.0))
                below = (L[:, j + 1 :, :j] * row[:, None, :]).sum(axis=2)
                L[:, j + 1 :, j] = (P[:, j + 1 :, j] - below) / L[:, j, j, None]
        bad &= finite
        if bad.any():
            lanes = np.flatnonzero(bad)
            Pb = P[lanes]
            w, V = np.linalg.eigh(0.5 * (Pb + Pb.transpose(0, 2, 1)))
            w_floor = self.config.eig_floor * np.maximum(np.abs(w[:, -1]), np.finfo(float).tiny)
            w = np.maximum(w, w_floor[:, None])
            fixed = (V * w[:, None, :]) @ V.transpose(0, 2, 1)
            P[lanes] = 0.5 * (fixed + fixed.transpose(0, 2, 1))
            self.repairs[lanes] += 1
        return ~finite
