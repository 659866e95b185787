"""Step-velocity fusion Kalman filter of paper 004, batched over walkers.

Kaplin, Stepanov, Yarmolich (paper 004). Once per detected step k (duration
T_k) the INS step-mean velocity V̄^INS(k) is compared with the biomechanical
(pendulum) step velocity V̄^BM(k) of each horizontal channel::

    S(k) = V̄^INS(k) − V̄^BM(k) = δV(k) + n(k)                     (3)

and a Kalman filter on the Schuler error model (see
:mod:`pednav_env.sensors.ins_error`; x = [δV, β, ε], Φ_E / Φ_N, Q =
diag(σ_a², 0, σ_ε²), H = [1, 0, 0], R = σ_n²) estimates δV (eq 4). The
corrected velocity uses the *extrapolated* estimate and integrates position::

    V̄_corr(k) = V̄^INS(k) − H Φ x̂(k−1)                             (5)
    Ê(k) = Ê(k−1) + T_k V̄_corr(k)                                   (6)

Engine layout: walkers on the leading axis N, then the channel axis
(0 = east [δV_E, β_N, ε_N], 1 = north [δV_N, β_E, ε_E]); x ``(N, 2, 3)``,
P ``(N, 2, 3, 3)``. :meth:`StepFusionKF.step` takes one step of the walkers
in a mask; :meth:`StepFusionKF.step_sequence` a batch of steps of some
walkers, computing only their rows. The stateless functions :func:`kf_predict`,
:func:`kf_gain`, :func:`joseph_update` and :func:`kf_update` broadcast over
any leading axes (a shared covariance ``(…, 1, 3, 3)`` serves many state
vectors ``(…, M, 3)`` — the Monte Carlo of paper 004 uses that). The update is
filterpy's ``KalmanFilter.update`` (Joseph form) with ``np.linalg.solve``
instead of ``inv(S)``; the covariance is then symmetrised and, if an
eigenvalue fell below ``−repair_tol·λ_max``, rebuilt with the eigenvalues
floored (counted per walker, never a crash).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.constants import EARTH_RADIUS, STANDARD_GRAVITY
from pednav_env.sensors.ins_error import CHANNEL_SIGN, schuler_process_noise, schuler_transition

Array = NDArray[np.float64]

#: Measurement matrix H = [1, 0, 0] (paper 004, eq 4).
H_DV = np.array([[1.0, 0.0, 0.0]])


def _swap(a: Array) -> Array:
    return np.swapaxes(a, -1, -2)


def kf_predict(x: Array, P: Array, F: Array, Q: Array) -> tuple[Array, Array]:
    """x⁻ = F x,  P⁻ = F P Fᵀ + Q (filterpy ``KalmanFilter.predict`` with α = 1).

    Shapes: x ``(..., n)``, P/F/Q ``(..., n, n)`` broadcasting over leading axes.
    """
    x_prior = np.matmul(F, x[..., None])[..., 0]
    P_prior = np.matmul(np.matmul(F, P), _swap(F)) + Q
    return x_prior, P_prior


def kf_gain(P: Array, H: Array, R: Array) -> tuple[Array, Array]:
    """Gain K = P Hᵀ S⁻¹ (via solve) and innovation covariance S = H P Hᵀ + R."""
    PHT = np.matmul(P, _swap(H))
    S = np.matmul(H, PHT) + R
    K = _swap(np.linalg.solve(S, _swap(PHT)))
    return K, S


def joseph_update(P: Array, K: Array, H: Array, R: Array) -> Array:
    """P⁺ = (I − K H) P (I − K H)ᵀ + K R Kᵀ (filterpy's form)."""
    n = P.shape[-1]
    I_KH = np.eye(n) - np.matmul(K, H)
    return np.matmul(np.matmul(I_KH, P), _swap(I_KH)) + np.matmul(np.matmul(K, R), _swap(K))


def kf_update(
    x: Array, P: Array, z: Array, H: Array, R: Array
) -> tuple[Array, Array, Array, Array, Array]:
    """Kalman update, filterpy ``KalmanFilter.update`` step by step.

    Parameters
    ----------
    x : (..., n)
    P : (..., n, n)
    z : (..., m)
    H : (..., m, n)
    R : (..., m, m)

    Returns
    -------
    x_post, P_post, y, S, K
        Posterior state and covariance (Joseph form, not yet symmetrised),
        innovation ``(..., m)``, its covariance ``(..., m, m)`` and the gain
        ``(..., n, m)``.
    """
    K, S = kf_gain(P, H, R)
    y = z - np.matmul(H, x[..., None])[..., 0]
    x_post = x + np.matmul(K, y[..., None])[..., 0]
    return x_post, joseph_update(P, K, H, R), y, S, K


def repair_covariance(
    P: Array, repair_tol: float = 1e-12, eig_floor: float = 0.0
) -> tuple[Array, NDArray[np.bool_]]:
    """Symmetrise P and floor its eigenvalues where it lost positive semi-definiteness.

    A matrix counts as broken when its smallest eigenvalue is below
    ``−repair_tol · max(λ_max, 1)``; broken matrices are rebuilt as
    V diag(max(λ, eig_floor)) Vᵀ. Non-finite matrices are returned unchanged
    (the caller flags divergence).

    Returns
    -------
    P_sym : (..., n, n)
    repaired : (...) bool
    """
    P = 0.5 * (P + _swap(P))
    finite = np.all(np.isfinite(P), axis=(-1, -2))
    safe = np.where(finite[..., None, None], P, 0.0)
    lam = np.linalg.eigvalsh(safe)
    bad = finite & (lam[..., 0] < -repair_tol * np.maximum(lam[..., -1], 1.0))
    if np.any(bad):
        lam_b, V = np.linalg.eigh(safe[bad])
        lam_b = np.maximum(lam_b, eig_floor)
        P = P.copy()
        P[bad] = np.matmul(V * lam_b[..., None, :], _swap(V))
    return P, bad


@dataclass(frozen=True)
class StepFusionConfig:
    """The filter's assumed model (paper 004 values; per channel, both channels alike).

    Attributes
    ----------
    accel_noise_std : float
        σ_a of Q (m/s per step). Paper 004 sweeps 0.1, 0.5, 1; default 0.5.
    drift_noise_std : float
        σ_ε of Q (rad/s per step). Paper 004: 1e-6 "1/s".
    bm_noise_std : float
        σ_n, std of V̄^BM (m/s). Paper 004: 0.5 (printed "m").
    initial_estimate : tuple
        x̂(0) = (δV̂, β̂, ε̂). Paper 004 prints δV̂_E(0) = 0.3 m/s, β̂_N(0) = 0,
        ε̂_N(0) = 0.1 "1/s"; we read the last as 0.1 °/h (docs/REPRODUCTION.md).
    initial_std : tuple
        sqrt(diag P(0)) (m/s, rad, rad/s). Not printed; 0.3 m/s, 1 mrad,
        0.1 °/h (our reading).
    g, earth_radius : float
    repair_tol, eig_floor : float
        Covariance repair (:func:`repair_covariance`).
    """

    accel_noise_std: float = 0.5
    drift_noise_std: float = 1e-6
    bm_noise_std: float = 0.5
    initial_estimate: tuple[float, float, float] = (0.3, 0.0, math.radians(0.1) / 3600.0)
    initial_std: tuple[float, float, float] = (0.3, 1e-3, math.radians(0.1) / 3600.0)
    g: float = STANDARD_GRAVITY
    earth_radius: float = EARTH_RADIUS
    repair_tol: float = 1e-12
    eig_floor: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            vals = v if isinstance(v, tuple) else (v,)
            if f.name.startswith("initial"):
                if len(vals) != 3:
                    raise ValueError(f"StepFusionConfig.{f.name} needs 3 values, got {v!r}")
                object.__setattr__(self, f.name, tuple(float(a) for a in vals))
            for a in vals:
                if not isinstance(a, int | float) or not math.isfinite(a):
                    raise ValueError(f"StepFusionConfig.{f.name} must be finite, got {v!r}")
            if f.name != "initial_estimate" and any(a < 0 for a in vals):
                raise ValueError(f"StepFusionConfig.{f.name} must be ≥ 0, got {v!r}")
        if self.bm_noise_std <= 0:
            raise ValueError(
                f"StepFusionConfig.bm_noise_std must be > 0, got {self.bm_noise_std!r}"
            )
        if self.g <= 0 or self.earth_radius <= 0:
            raise ValueError("StepFusionConfig.g and earth_radius must be > 0")

    @property
    def Q(self) -> Array:
        """Q = diag(σ_a², 0, σ_ε²) (3, 3)."""
        return schuler_process_noise(self.accel_noise_std, self.drift_noise_std)

    @property
    def R(self) -> Array:
        """R = [[σ_n²]] (1, 1)."""
        return np.array([[self.bm_noise_std**2]])

    @property
    def P0(self) -> Array:
        """P(0) = diag(initial_std²) (3, 3)."""
        return np.diag(np.square(self.initial_std))


class StepFusionKF:
    """Paper 004's filter for N walkers, both horizontal channels.

    Parameters
    ----------
    config : StepFusionConfig
    n_walkers : int
    q_scale, r_scale : float or (N,)
        Per-walker multipliers of Q and R (an agent's action later); settable
        attributes (stored as read-only (N,) copies), validated at the next
        step (finite, > 0).

    Attributes
    ----------
    x : (N, 2, 3)   posterior estimates [δV̂, β̂, ε̂] per channel
    P : (N, 2, 3, 3)
    pos : (N, 2)    corrected position estimate [Ê, N̂] (m), eq (6)
    x_prior, P_prior, y, S, K : last prior, innovation (N, 2), its variance
        (N, 2), gain (N, 2, 3) — like filterpy, kept after each step
    repairs : (N,) int   covariance repairs so far
    steps : (N,) int     updates so far
    diverged : (N,) bool non-finite state or covariance seen
    """

    def __init__(
        self,
        config: StepFusionConfig,
        n_walkers: int,
        q_scale: ArrayLike = 1.0,
        r_scale: ArrayLike = 1.0,
        pos0: ArrayLike = (0.0, 0.0),
    ) -> None:
        if not isinstance(n_walkers, int | np.integer) or n_walkers < 1:
            raise ValueError(f"n_walkers must be a positive integer, got {n_walkers!r}")
        self.config = config
        self.n = int(n_walkers)
        self._Q, self._R = config.Q, config.R
        self.q_scale = q_scale
        self.r_scale = r_scale
        self.reset(pos0)

    def reset(self, pos0: ArrayLike = (0.0, 0.0)) -> None:
        """Back to x̂(0), P(0) and the start position ``pos0`` ((2,) or (N, 2), m)."""
        n, c = self.n, self.config
        pos0 = np.broadcast_to(np.asarray(pos0, dtype=float), (n, 2))
        if not np.all(np.isfinite(pos0)):
            raise ValueError(f"pos0 must be finite, got {pos0!r}")
        self.x = np.broadcast_to(np.asarray(c.initial_estimate), (n, 2, 3)).copy()
        self.P = np.broadcast_to(c.P0, (n, 2, 3, 3)).copy()
        self.pos = pos0.copy()
        self.x_prior = self.x.copy()
        self.P_prior = self.P.copy()
        self.y = np.zeros((n, 2))
        self.S = np.zeros((n, 2))
        self.K = np.zeros((n, 2, 3))
        self.repairs = np.zeros(n, dtype=np.int64)
        self.steps = np.zeros(n, dtype=np.int64)
        self.diverged = np.zeros(n, dtype=bool)

    @property
    def q_scale(self) -> Array:
        """Per-walker multiplier of Q, (N,)."""
        return self._q_scale

    @q_scale.setter
    def q_scale(self, value: ArrayLike) -> None:
        self._q_scale = self._per_walker("q_scale", value)

    @property
    def r_scale(self) -> Array:
        """Per-walker multiplier of R, (N,)."""
        return self._r_scale

    @r_scale.setter
    def r_scale(self, value: ArrayLike) -> None:
        self._r_scale = self._per_walker("r_scale", value)

    def _per_walker(self, name: str, value: ArrayLike) -> Array:
        try:
            v = np.array(value, dtype=float)
            if v.shape != (self.n,):
                v = np.array(np.broadcast_to(v, (self.n,)))
        except ValueError:
            raise ValueError(f"StepFusionKF.{name} must be a number or ({self.n},)") from None
        v.flags.writeable = False
        self._scales_checked = False
        return v

    def _scales(self) -> tuple[Array, Array]:
        """Q and R scales, checked (finite, > 0) once after each assignment."""
        if not self._scales_checked:
            for name, v in (("q_scale", self._q_scale), ("r_scale", self._r_scale)):
                if not (v.min() > 0 and v.max() < np.inf):  # NaN fails both
                    raise ValueError(f"StepFusionKF.{name} must be finite and > 0, got {v!r}")
            self._scales_checked = True
        return self._q_scale, self._r_scale

    def step(
        self,
        vbar_ins: ArrayLike,
        vbar_bm: ArrayLike,
        step_period: ArrayLike,
        mask: ArrayLike | None = None,
    ) -> Array:
        """Process one step of every walker in ``mask`` (eqs 3–6).

        Parameters
        ----------
        vbar_ins : (N, 2) m/s
            INS step-mean velocity [east, north].
        vbar_bm : (N, 2) m/s
            Biomechanical step velocity [east, north] (V̄^BM sin α, V̄^BM cos α).
        step_period : (N,) s
            T_k, > 0 where masked in.
        mask : (N,) bool, optional
            Walkers that completed a step; others are left untouched.

        Returns
        -------
        vbar_corr : (N, 2) m/s
            Corrected step velocity (eq 5); for masked-out walkers V̄^INS.
        """
        n = self.n
        m = np.ones(n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if m.shape != (n,):
            raise ValueError(f"mask must be ({n},), got {m.shape}")
        vi, vb, T = self._inputs(vbar_ins, vbar_bm, step_period, n, m)
        qs, rs = self._scales()
        Tm = np.where(m, T, 1.0)
        F, Q, R = self._model(Tm, qs, rs)
        u = self._update(self.x, self.P, vi, vb, F, Q, R)
        sel = m[:, None]
        self.x = np.where(sel[..., None], u.x, self.x)
        self.P = np.where(sel[..., None, None], u.P, self.P)
        self.x_prior = np.where(sel[..., None], u.x_prior, self.x_prior)
        self.P_prior = np.where(sel[..., None, None], u.P_prior, self.P_prior)
        self.y = np.where(sel, u.y, self.y)
        self.S = np.where(sel, u.S, self.S)
        self.K = np.where(sel[..., None], u.K, self.K)
        self.pos = np.where(sel, self.pos + Tm[:, None] * u.vbar_corr, self.pos)  # eq (6)
        self.repairs += (m & u.repaired).astype(np.int64)
        self.steps += m.astype(np.int64)
        self.diverged |= m & ~u.ok
        return np.where(sel, u.vbar_corr, vi)

    def step_sequence(
        self,
        walker: ArrayLike,
        vbar_ins: ArrayLike,
        vbar_bm: ArrayLike,
        step_period: ArrayLike,
    ) -> tuple[Array, Array]:
        """Process E steps of some walkers, each walker's steps in order (eqs 3–6).

        Round j updates the j-th step of every walker that has one, on those
        walkers' rows only; walkers without a step are left untouched. Every
        walker's numbers equal those of :meth:`step` called once per step with
        a mask, bit for bit (tested), without the masked work on the others.

        Parameters
        ----------
        walker : (E,) int
            Walker of each step, non-decreasing: steps grouped by walker, each
            walker's in time order (the order ``np.nonzero`` gives for an
            (N, T) array of step ends).
        vbar_ins, vbar_bm : (E, 2) m/s
            As in :meth:`step`, one row per step.
        step_period : (E,) s
            T_k, > 0.

        Returns
        -------
        y, S : (E, 2)
            Each step's innovation (eq 3 minus the prediction) and its variance.
        """
        n = self.n
        w = np.asarray(walker)
        if w.ndim != 1 or w.dtype.kind not in "iu":
            raise ValueError(f"walker must be a 1-D integer array, got {w.dtype} {w.shape}")
        if w.size and (w[0] < 0 or w[-1] >= n or np.any(w[1:] < w[:-1])):
            raise ValueError(f"walker must be non-decreasing indices in [0, {n}), got {w.tolist()}")
        vi, vb, T = self._inputs(vbar_ins, vbar_bm, step_period, w.size, None)
        qs, rs = self._scales()
        F, Q, R = self._model(T, qs[w], rs[w])
        counts = np.bincount(w, minlength=n)
        first = np.cumsum(counts) - counts  # each walker's first step
        y_out = np.empty((w.size, 2))
        S_out = np.empty((w.size, 2))
        for j in range(int(counts.max(initial=0))):
            rows = np.flatnonzero(counts > j)
            e = first[rows] + j
            u = self._update(self.x[rows], self.P[rows], vi[e], vb[e], F[e], Q[e], R[e])
            self.x[rows], self.P[rows] = u.x, u.P
            self.x_prior[rows], self.P_prior[rows] = u.x_prior, u.P_prior
            self.y[rows], self.S[rows], self.K[rows] = u.y, u.S, u.K
            self.pos[rows] = self.pos[rows] + T[e][:, None] * u.vbar_corr  # eq (6)
            self.repairs[rows] += u.repaired
            self.steps[rows] += 1
            self.diverged[rows] |= ~u.ok
            y_out[e], S_out[e] = u.y, u.S
        return y_out, S_out

    @staticmethod
    def _inputs(
        vbar_ins: ArrayLike,
        vbar_bm: ArrayLike,
        step_period: ArrayLike,
        n: int,
        m: NDArray[np.bool_] | None,
    ) -> tuple[Array, Array, Array]:
        """Shape and finiteness checks of n rows, of which ``m`` (default all) step."""
        vi = np.asarray(vbar_ins, dtype=float)
        vb = np.asarray(vbar_bm, dtype=float)
        if vi.shape != (n, 2) or vb.shape != (n, 2):
            raise ValueError(f"vbar_ins and vbar_bm must be ({n}, 2), got {vi.shape}, {vb.shape}")
        T = np.broadcast_to(np.asarray(step_period, dtype=float), (n,))
        vi_m, vb_m, T_m = (vi, vb, T) if m is None else (vi[m], vb[m], T[m])
        if not (np.isfinite(vi_m).all() and np.isfinite(vb_m).all()):
            raise ValueError("vbar_ins/vbar_bm contain NaN or inf for active walkers")
        if T_m.size and not (T_m.min() > 0 and T_m.max() < np.inf):  # NaN fails both
            raise ValueError(f"step_period must be finite and > 0, got {T_m!r}")
        return vi, vb, T

    def _model(self, T: Array, qs: Array, rs: Array) -> tuple[Array, Array, Array]:
        """Φ(T) per row and channel, Q × q_scale and R × r_scale per row."""
        c = self.config
        F = schuler_transition(T[:, None], c.g, c.earth_radius, CHANNEL_SIGN[None, :])
        return F, self._Q * qs[:, None, None, None], self._R * rs[:, None, None, None]

    def _update(
        self, x: Array, P: Array, vi: Array, vb: Array, F: Array, Q: Array, R: Array
    ) -> _StepUpdate:
        """Eqs (3)–(5) on the given rows: predict, update, repair P."""
        c = self.config
        x_prior, P_prior = kf_predict(x, P, F, Q)
        vbar_corr = vi - x_prior[..., 0]  # eq (5): V̄^INS − H Φ x̂(k−1)
        z = (vi - vb)[..., None]  # eq (3)
        x_post, P_post, y, S, K = kf_update(x_prior, P_prior, z, H_DV, R)
        P_post, repaired = repair_covariance(P_post, c.repair_tol, c.eig_floor)
        ok = np.all(np.isfinite(x_post), axis=(1, 2)) & np.all(np.isfinite(P_post), axis=(1, 2, 3))
        return _StepUpdate(
            x=x_post,
            P=P_post,
            x_prior=x_prior,
            P_prior=P_prior,
            y=y[..., 0],
            S=S[..., 0, 0],
            K=K[..., 0],
            vbar_corr=vbar_corr,
            repaired=np.any(repaired, axis=1),
            ok=ok,
        )


class _StepUpdate(NamedTuple):
    """One update of M walkers' rows (both channels)."""

    x: Array  #: (M, 2, 3) posterior
    P: Array  #: (M, 2, 3, 3) posterior, symmetrised and repaired
    x_prior: Array
    P_prior: Array
    y: Array  #: (M, 2) innovation
    S: Array  #: (M, 2) its variance
    K: Array  #: (M, 2, 3) gain
    vbar_corr: Array  #: (M, 2) eq (5)
    repaired: NDArray[np.bool_]  #: (M,) a channel's covariance was repaired
    ok: NDArray[np.bool_]  #: (M,) finite state and covariance
