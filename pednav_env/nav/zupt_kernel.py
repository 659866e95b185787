"""Compiled per-walker kernels of the ZUPT-UKF of paper 003.

:meth:`pednav_env.nav.zupt_ukf.ZuptUkf.advance` hands a whole block of IMU
samples of all N walkers to :func:`advance_block`, which runs, walker after
walker and sample after sample, exactly the filter that the module docstring
of :mod:`pednav_env.nav.zupt_ukf` describes:

1. the strapdown increments of the sample (paper 003 eq 3: the attitude
   increment C(Δq), Δq from k = ω'Δt, and the specific force rotated to the
   mid-interval attitude);
2. the stance detector (eq 5 on |ω'| and f'_x3, the vertical specific force
   through the central sigma point's attitude; or a SHOE condition computed
   from the raw record), its causal window and minimum stance duration;
3. at a detected stance start or end (or every stance sample), a ZUPT: the 19
   sigma points are moved from their last redraw to this instant, their
   unscented mean and covariance plus Q(τ) form the prior, the linear update
   h(y) = [x₃, v₁, v₂, v₃] gives the posterior, and new sigma points are drawn;
4. between ZUPTs the sigma points are not stepped one by one. The strapdown
   is affine in the state it starts from: from a redraw at sample a, with
   attitude C₀, velocity v₀ and position x₀,

       C_t = C₀ D,   v_t = v₀ + C₀ A − g e₃ τ,   x_t = x₀ + v₀ τ + C₀ B − ½ g e₃ τ²,

   τ = (t − a) Δt, D = C(Δq_a) ⋯ C(Δq_{t−1}), A = Σ_j D_j f_mid,j Δt (D_j the
   product up to sample j) and B the trapezoid sum of A: quantities of the
   IMU record alone, the same for every sigma point (the preintegration of
   Lupton & Sukkarieh 2012 and Forster et al. 2017, without bias states; the
   same arithmetic as stepping every sigma point, regrouped). The kernel
   accumulates D, A, B once per sample and moves the 19 points only at a ZUPT
   and at the end of the block.

Why compiled code here, against the rule of one batched numpy call chain
(docs/CONVENTIONS.md): a ZUPT happens at data-dependent samples of each
walker (stance detection flickers on consumer-grade IMUs, up to 20
boundaries per walker and 0.5 s interval),
so a batched numpy engine must run the updates in rounds across walkers with
a fixed per-call cost; that cost, not arithmetic, bounded its throughput
(docs/PERFORMANCE.md). The kernel is still the one implementation of the
filter for every walker count: walker i's arithmetic never depends on the
others, so lane i of a vector env equals a scalar env bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pednav_env.nav.ukf import EIGEN_FLOOR_ABSOLUTE, EIGEN_FLOOR_RELATIVE

_TWO_PI = 2.0 * math.pi
_HALF_OVER_PI = 0.5 / math.pi
#: Kinds of ZUPT in the update log: stance start, stance end, stance sample.
KIND_START, KIND_END, KIND_STANCE = 0, 1, 2


@njit(cache=True)
def _wrap(a: float) -> float:
    """Angle (rad) into [−π, π): a − 2π ⌊(a + π)/2π⌋ (as :func:`rotations.wrap_angle`)."""
    return a - _TWO_PI * math.floor((a + math.pi) * _HALF_OVER_PI)


@njit(cache=True)
def _rotvec_quat(kx: float, ky: float, kz: float) -> tuple[float, float, float, float]:
    """Δq = [cos(|k|/2), k/|k| sin(|k|/2)] (paper 003 eq 3; series below 1e-6 rad)."""
    angle = math.sqrt(kx * kx + ky * ky + kz * kz)
    half = 0.5 * angle
    s = 0.5 - angle * angle / 48.0 if angle < 1e-6 else math.sin(half) / angle
    return math.cos(half), kx * s, ky * s, kz * s


@njit(cache=True)
def _increment(w: np.ndarray, f: np.ndarray, dt: float, dC: np.ndarray, f_mid: np.ndarray) -> None:
    """Strapdown increments of one sample (:mod:`pednav_env.nav.strapdown`):
    C(Δq) of k = ω'Δt into ``dC`` and the specific force in mid-interval axes,
    Δq(½k) f' Δq(½k)*, into ``f_mid``."""
    qw, qx, qy, qz = _rotvec_quat(w[0] * dt, w[1] * dt, w[2] * dt)
    dC[0, 0] = 1.0 - 2.0 * (qy * qy + qz * qz)
    dC[0, 1] = 2.0 * (qx * qy - qw * qz)
    dC[0, 2] = 2.0 * (qx * qz + qw * qy)
    dC[1, 0] = 2.0 * (qx * qy + qw * qz)
    dC[1, 1] = 1.0 - 2.0 * (qx * qx + qz * qz)
    dC[1, 2] = 2.0 * (qy * qz - qw * qx)
    dC[2, 0] = 2.0 * (qx * qz - qw * qy)
    dC[2, 1] = 2.0 * (qy * qz + qw * qx)
    dC[2, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)
    hw, hx, hy, hz = _rotvec_quat(w[0] * 0.5 * dt, w[1] * 0.5 * dt, w[2] * 0.5 * dt)
    vx, vy, vz = f[0], f[1], f[2]
    tx = 2.0 * (hy * vz - hz * vy)
    ty = 2.0 * (hz * vx - hx * vz)
    tz = 2.0 * (hx * vy - hy * vx)
    f_mid[0] = vx + hw * tx + hy * tz - hz * ty
    f_mid[1] = vy + hw * ty + hz * tx - hx * tz
    f_mid[2] = vz + hw * tz + hx * ty - hy * tx


@njit(cache=True)
def _accumulate(
    D: np.ndarray, A: np.ndarray, B: np.ndarray, F: np.ndarray, dC: np.ndarray, dt: float
) -> None:
    """One sample of the preintegrals: A ← A + F Δt, B ← B + ½(A_old + A) Δt,
    D ← D C(Δq), with F = D f_mid computed by the caller (module docstring)."""
    for r in range(3):
        a_new = A[r] + F[r] * dt
        B[r] += (A[r] + a_new) * (0.5 * dt)
        A[r] = a_new
    for r in range(3):
        d0, d1, d2 = D[r, 0], D[r, 1], D[r, 2]
        for c in range(3):
            D[r, c] = d0 * dC[0, c] + d1 * dC[1, c] + d2 * dC[2, c]


@njit(cache=True)
def _euler_dcm(yaw: float, pitch: float, roll: float, C: np.ndarray) -> None:
    """C_nb of Euler angles, 3-2-1 order (as :func:`rotations.euler_to_dcm`)."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    C[0, 0] = cy * cp
    C[0, 1] = cy * sp * sr - sy * cr
    C[0, 2] = cy * sp * cr + sy * sr
    C[1, 0] = sy * cp
    C[1, 1] = sy * sp * sr + cy * cr
    C[1, 2] = sy * sp * cr - cy * sr
    C[2, 0] = -sp
    C[2, 1] = cp * sr
    C[2, 2] = cp * cr


@njit(cache=True)
def _moved_states(
    sC: np.ndarray,
    sv: np.ndarray,
    sp: np.ndarray,
    D: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
    tau: float,
    g: float,
    chi: np.ndarray,
    C: np.ndarray,
) -> None:
    """State vectors ``chi`` (S, 9) of sigma points (C₀, v₀, x₀) moved by (D, A, B, τ);
    ``C`` (S, 3, 3) receives their attitudes C₀ D."""
    for s in range(chi.shape[0]):
        for r in range(3):
            c0, c1, c2 = sC[s, r, 0], sC[s, r, 1], sC[s, r, 2]
            for c in range(3):
                C[s, r, c] = c0 * D[0, c] + c1 * D[1, c] + c2 * D[2, c]
            ca = c0 * A[0] + c1 * A[1] + c2 * A[2]
            cb = c0 * B[0] + c1 * B[1] + c2 * B[2]
            chi[s, r] = sp[s, r] + sv[s, r] * tau + cb
            chi[s, 3 + r] = sv[s, r] + ca
        chi[s, 2] -= 0.5 * g * (tau * tau)
        chi[s, 5] -= g * tau
        chi[s, 6] = math.asin(min(max(-C[s, 2, 0], -1.0), 1.0))
        chi[s, 7] = math.atan2(C[s, 2, 1], C[s, 2, 2])
        chi[s, 8] = math.atan2(C[s, 1, 0], C[s, 0, 0])


@njit(cache=True)
def _move_sigmas(
    sC: np.ndarray,
    sv: np.ndarray,
    sp: np.ndarray,
    D: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
    tau: float,
    g: float,
) -> None:
    """Sigma points (C₀, v₀, x₀) moved by (D, A, B, τ), in place."""
    for s in range(sC.shape[0]):
        for r in range(3):
            c0, c1, c2 = sC[s, r, 0], sC[s, r, 1], sC[s, r, 2]
            for c in range(3):
                sC[s, r, c] = c0 * D[0, c] + c1 * D[1, c] + c2 * D[2, c]
            sp[s, r] += sv[s, r] * tau + c0 * B[0] + c1 * B[1] + c2 * B[2]
            sv[s, r] += c0 * A[0] + c1 * A[1] + c2 * A[2]
        sp[s, 2] -= 0.5 * g * (tau * tau)
        sv[s, 2] -= g * tau


@njit(cache=True)
def _weighted_sums(
    Wm: np.ndarray,
    sC: np.ndarray,
    sv: np.ndarray,
    sp: np.ndarray,
    Cbar: np.ndarray,
    vbar: np.ndarray,
    pbar: np.ndarray,
) -> None:
    """Σ Wm_s C_s, Σ Wm_s v_s, Σ Wm_s x_s of sigma points: the mean position after
    moving them by (D, A, B, τ) is Σ Wm x + τ Σ Wm v + (Σ Wm C) B − ½ g τ² e₃."""
    for r in range(3):
        pbar[r] = 0.0
        vbar[r] = 0.0
        for c in range(3):
            Cbar[r, c] = 0.0
        for s in range(Wm.shape[0]):
            pbar[r] += Wm[s] * sp[s, r]
            vbar[r] += Wm[s] * sv[s, r]
            for c in range(3):
                Cbar[r, c] += Wm[s] * sC[s, r, c]


@njit(cache=True)
def _finite(C: np.ndarray) -> bool:
    """All entries of a 3 × 3 matrix finite."""
    for r in range(3):
        for c in range(3):
            if not math.isfinite(C[r, c]):
                return False
    return True


@njit(cache=True)
def _state_mean(chi: np.ndarray, Wm: np.ndarray, out: np.ndarray) -> None:
    """Weighted mean of states with angles averaged as wrapped deviations from
    the central point (:func:`zupt_ukf.state_mean`)."""
    for d in range(9):
        acc = 0.0
        for s in range(chi.shape[0]):
            dev = chi[s, d] - chi[0, d]
            acc += Wm[s] * (_wrap(dev) if d >= 6 else dev)
        out[d] = _wrap(chi[0, d] + acc) if d >= 6 else chi[0, d] + acc


@njit(cache=True)
def _prior_moments(
    chi: np.ndarray,
    Wm: np.ndarray,
    Wc: np.ndarray,
    basis: np.ndarray,
    powers: np.ndarray,
    dev: np.ndarray,
    x: np.ndarray,
    P: np.ndarray,
) -> None:
    """Unscented mean and covariance of sigma states ``chi`` plus Q = Σ_p powers_p
    M_p (:func:`zupt_ukf.process_noise`): filterpy's ``unscented_transform`` with
    the wrapped-angle mean and residual of :mod:`zupt_ukf`, the residuals from the
    central point computed once."""
    ns = chi.shape[0]
    for d in range(9):
        acc = 0.0
        for s in range(ns):
            v = chi[s, d] - chi[0, d]
            if d >= 6:
                v = _wrap(v)
            dev[s, d] = v
            acc += Wm[s] * v
        x[d] = _wrap(chi[0, d] + acc) if d >= 6 else chi[0, d] + acc
        for s in range(ns):
            v = dev[s, d] - acc
            dev[s, d] = _wrap(v) if d >= 6 else v
    for r in range(9):
        for c in range(r, 9):
            acc = 0.0
            for s in range(ns):
                acc += Wc[s] * dev[s, r] * dev[s, c]
            for p in range(powers.shape[0]):
                acc += powers[p] * basis[p, r, c]
            P[r, c] = acc
            P[c, r] = acc


@njit(cache=True)
def _inverse4(S: np.ndarray, out: np.ndarray) -> None:
    """Inverse of a 4 × 4 matrix by Gauss–Jordan elimination with partial pivoting
    (NaN for a singular matrix, never an exception)."""
    a = np.empty((4, 8))
    for r in range(4):
        for c in range(4):
            a[r, c] = S[r, c]
            a[r, 4 + c] = 1.0 if r == c else 0.0
    for c in range(4):
        piv = c
        for r in range(c + 1, 4):
            if abs(a[r, c]) > abs(a[piv, c]):
                piv = r
        if piv != c:
            for k in range(8):
                a[c, k], a[piv, k] = a[piv, k], a[c, k]
        inv_p = 1.0 / a[c, c]
        for k in range(8):
            a[c, k] *= inv_p
        for r in range(4):
            if r != c:
                m = a[r, c]
                for k in range(8):
                    a[r, k] -= m * a[c, k]
    for r in range(4):
        for c in range(4):
            out[r, c] = a[r, 4 + c]


@njit(cache=True)
def _zupt_update(
    x: np.ndarray,
    P: np.ndarray,
    height_ref: float,
    R_diag: np.ndarray,
    gate_nis: float,
    SI: np.ndarray,
    KT: np.ndarray,
) -> tuple[float, bool]:
    """The UKF update with the linear h(y) = [x₃, v₁, v₂, v₃], z = [x₃(t₀), 0, 0, 0]
    on prior (x, P), in place. Sigma points drawn from (x⁻, P⁻) through a linear h
    give exactly ẑ = h(x⁻), S = H P⁻ Hᵀ + R, P_xz = P⁻ Hᵀ, so this is filterpy
    2.0's update on redrawn prior sigma points, without drawing them:
    S = H P Hᵀ + R, Kᵀ = S⁻¹ P_xzᵀ, x ← x + K y (angles wrapped),
    P ← sym(P − P_xz Kᵀ). Returns (NIS, accepted by the χ² gate)."""
    S = np.empty((4, 4))
    for r in range(4):
        for c in range(4):
            S[r, c] = P[2 + r, 2 + c]
        S[r, r] += R_diag[r]
    _inverse4(S, SI)
    y = np.empty(4)
    y[0] = height_ref - x[2]
    for r in range(1, 4):
        y[r] = -x[2 + r]
    nis = 0.0
    for r in range(4):
        acc = 0.0
        for c in range(4):
            acc += SI[r, c] * y[c]
        nis += acc * y[r]
    for r in range(4):
        for c in range(9):
            acc = 0.0
            for m in range(4):
                acc += SI[r, m] * P[c, 2 + m]
            KT[r, c] = acc
    accepted = nis <= gate_nis
    if accepted:
        for c in range(9):
            acc = 0.0
            for r in range(4):
                acc += y[r] * KT[r, c]
            x[c] += acc
        _subtract_gain(P, KT)
    for d in range(6, 9):
        x[d] = _wrap(x[d])
    for r in range(9):
        for c in range(r + 1, 9):
            m = 0.5 * (P[r, c] + P[c, r])
            P[r, c] = m
            P[c, r] = m
    return nis, accepted


@njit(cache=True)
def _subtract_gain(P: np.ndarray, KT: np.ndarray) -> None:
    """P ← P − P_xz Kᵀ with P_xz = P[:, 2:6] read before any entry changes."""
    Pxz = np.empty((9, 4))
    for r in range(9):
        for m in range(4):
            Pxz[r, m] = P[r, 2 + m]
    for r in range(9):
        for c in range(9):
            acc = 0.0
            for m in range(4):
                acc += Pxz[r, m] * KT[m, c]
            P[r, c] -= acc


@njit(cache=True)
def _cholesky_lower(A: np.ndarray, L: np.ndarray) -> bool:
    """Lower Cholesky factor of a symmetric matrix into ``L``; False when it is not
    positive definite (a pivot ≤ 0 or not finite)."""
    n = A.shape[0]
    for j in range(n):
        acc = A[j, j]
        for k in range(j):
            acc -= L[j, k] * L[j, k]
        if not (acc > 0.0) or not math.isfinite(acc):
            return False
        d = math.sqrt(acc)
        L[j, j] = d
        for i in range(j + 1, n):
            acc = A[i, j]
            for k in range(j):
                acc -= L[i, k] * L[j, k]
            L[i, j] = acc / d
        for i in range(j):
            L[i, j] = 0.0
    return True


@njit(cache=True)
def _repaired(A: np.ndarray) -> np.ndarray:
    """Symmetrised ``A`` with eigenvalues floored at max(1e-12 λ_max, 1e-18)
    (:func:`pednav_env.nav.ukf.repair_covariance`); non-finite entries count as 0."""
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
    for k in range(n):
        w[k] = max(w[k], floor)
    out = np.empty((n, n))
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
    return out


@njit(cache=True)
def _redraw(
    x: np.ndarray,
    P: np.ndarray,
    spread: float,
    sC: np.ndarray,
    sv: np.ndarray,
    sp: np.ndarray,
    L: np.ndarray,
) -> bool:
    """Sigma points χ₀ = x, χ_k = x + √((L+λ)P)_k, χ_{L+k} = x − √((L+λ)P)_k
    (lower Cholesky factor's columns; angles wrapped) written as attitude
    matrices, velocities and positions (filterpy's ``MerweScaledSigmaPoints``,
    whose upper factor's rows are these columns). Returns True when P had to be
    repaired first (:func:`pednav_env.nav.ukf.repair_covariance`)."""
    n = 9
    A = np.empty((n, n))
    for r in range(n):
        for c in range(n):
            A[r, c] = spread * P[r, c]
    repaired = False
    if not _cholesky_lower(A, L):
        repaired = True
        _cholesky_lower(_repaired(A), L)
    chi = np.empty(n)
    for s in range(2 * n + 1):
        sign = 0.0 if s == 0 else (1.0 if s <= n else -1.0)
        k = (s - 1) % n
        for d in range(n):
            v = x[d] + sign * L[d, k] if s > 0 else x[d]
            chi[d] = _wrap(v) if d >= 6 else v
        for r in range(3):
            sp[s, r] = chi[r]
            sv[s, r] = chi[3 + r]
        _euler_dcm(chi[8], chi[6], chi[7], sC[s])
    return repaired


@njit(cache=True)
def redraw_sigmas(
    lanes: np.ndarray,
    x: np.ndarray,
    P: np.ndarray,
    spread: float,
    sig_C: np.ndarray,
    sig_v: np.ndarray,
    sig_p: np.ndarray,
) -> np.ndarray:
    """Draw the sigma points of walkers ``lanes`` from their (x, P) rows; returns
    the mask of covariances that had to be repaired."""
    L = np.zeros((9, 9))
    bad = np.zeros(lanes.shape[0], dtype=np.bool_)
    for j in range(lanes.shape[0]):
        i = lanes[j]
        bad[j] = _redraw(x[j], P[j], spread, sig_C[i], sig_v[i], sig_p[i], L)
    return bad


@njit(cache=True)
def _diverging(C: np.ndarray, v: np.ndarray, p: np.ndarray, speed_max: float) -> bool:
    """Non-finite attitude, velocity or position, or a speed above ``speed_max``."""
    for r in range(3):
        for c in range(3):
            if not math.isfinite(C[r, c]):
                return True
        if not (math.isfinite(v[r]) and math.isfinite(p[r])):
            return True
    speed2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    return not (speed2 <= speed_max * speed_max)


@njit(cache=True)
def advance_block(
    omega: np.ndarray,
    f: np.ndarray,
    shoe_cond: np.ndarray,
    valid: np.ndarray,
    frozen: np.ndarray,
    params: np.ndarray,
    lane_params: np.ndarray,
    min_samples: np.ndarray,
    gyro_bias: np.ndarray,
    q_basis: np.ndarray,
    Wm: np.ndarray,
    Wc: np.ndarray,
    sig_C: np.ndarray,
    sig_v: np.ndarray,
    sig_p: np.ndarray,
    x_post: np.ndarray,
    P_post: np.ndarray,
    elapsed: np.ndarray,
    det_history: np.ndarray,
    det_count: np.ndarray,
    det_run: np.ndarray,
    det_in_stance: np.ndarray,
    counters: np.ndarray,
    last_nis: np.ndarray,
    stance: np.ndarray,
    start: np.ndarray,
    end: np.ndarray,
    accepted_count: np.ndarray,
    nis_log_sum: np.ndarray,
    position: np.ndarray,
    diverged_at: np.ndarray,
    last_accepted: np.ndarray,
    positions: np.ndarray,
    states: np.ndarray,
    log_index: np.ndarray,
    log_x: np.ndarray,
    log_P: np.ndarray,
    log_nis: np.ndarray,
) -> int:
    """Advance every walker through a block of K samples (module docstring).

    ``params`` = [Δt, g, detector g, gate NIS (inf: none), uses SHOE, boundaries
    mode, spread L + λ, divergence speed, height reference is per lane (unused)];
    ``lane_params`` (N, 7) = [ω_max, Δf_max, process-noise scale, R scale × σ_h²,
    R scale × σ_v², height reference, —]. State arrays are updated in place;
    ``counters`` (N, 3) = [updates, rejected, repairs]. Outputs: detector flags
    (N, K), accepted ZUPTs and Σ log(1 + NIS) per walker, the mean position after
    each walker's ``valid`` samples, the state index of divergence (K + 1: none),
    the last accepted ZUPT's sample (−1: none), and, when their arrays are not
    empty, the mean position / state after every sample and the update log
    (``log_index`` rows [walker, sample, kind, accepted], ``log_x`` (·, 2, 9)
    prior/posterior means, ``log_P`` (·, 2, 9, 9) covariances, ``log_nis``).
    Returns the number of logged updates.
    """
    n, k = omega.shape[0], omega.shape[1]
    dt, g, det_g, gate_nis = params[0], params[1], params[2], params[3]
    uses_shoe, boundaries = params[4] > 0.5, params[5] > 0.5
    spread, speed_max = params[6], params[7]
    ns = Wm.shape[0]
    window = det_history.shape[1] + 1
    record_pos = positions.shape[0] > 0
    record_state = states.shape[0] > 0
    logging = log_index.shape[0] > 0
    n_log = 0
    D = np.empty((3, 3))
    A = np.empty(3)
    B = np.empty(3)
    F = np.empty(3)
    dC = np.empty((3, 3))
    f_mid = np.empty(3)
    w = np.empty(3)
    chi = np.empty((ns, 9))
    Cm = np.empty((ns, 3, 3))
    dev = np.empty((ns, 9))
    xp = np.empty(9)
    Pp = np.empty((9, 9))
    SI = np.empty((4, 4))
    KT = np.empty((4, 9))
    L = np.zeros((9, 9))
    powers = np.empty(q_basis.shape[0])
    R_diag = np.empty(4)
    pbar = np.empty(3)
    vbar = np.empty(3)
    Cbar = np.empty((3, 3))
    vc = np.empty(3)
    pc = np.empty(3)
    mean = np.empty(9)
    for i in range(n):
        omax, dfmax, q_scale = lane_params[i, 0], lane_params[i, 1], lane_params[i, 2]
        R_diag[0] = lane_params[i, 3]
        R_diag[1] = R_diag[2] = R_diag[3] = lane_params[i, 4]
        height_ref = lane_params[i, 5]
        moving = not frozen[i]
        sC, sv, sp = sig_C[i], sig_v[i], sig_p[i]
        hist = det_history[i]
        cnt, run, in_stance = det_count[i], det_run[i], det_in_stance[i]
        min_run = min_samples[i]
        # preintegrals from the last redraw (the anchor)
        D[:] = 0.0
        D[0, 0] = D[1, 1] = D[2, 2] = 1.0
        A[:] = 0.0
        B[:] = 0.0
        anchor = 0
        elapsed0 = elapsed[i]
        first_bad = k + 1
        div_at = k + 1
        last_acc = -1
        n_acc = 0
        nis_sum = 0.0
        # weighted sums of the anchor's sigma points: the mean position is affine in them
        _weighted_sums(Wm, sC, sv, sp, Cbar, vbar, pbar)
        anchor_bad = not _finite(sC[0])
        if valid[i] == 0:
            position[i, :] = pbar
        for j in range(k):
            w[0] = omega[i, j, 0] - gyro_bias[i, 0]
            w[1] = omega[i, j, 1] - gyro_bias[i, 1]
            w[2] = omega[i, j, 2] - gyro_bias[i, 2]
            _increment(w, f[i, j], dt, dC, f_mid)
            for r in range(3):
                F[r] = D[r, 0] * f_mid[0] + D[r, 1] * f_mid[1] + D[r, 2] * f_mid[2]
            # ---- stance detector at this sample
            if uses_shoe:
                cond = shoe_cond[i, j]
                cnt = min(cnt + 1, window)
            else:
                w_norm = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
                # f'_x3 = e₃ᵀ C_c f_mid: the central sigma point's attitude C₀,c D
                f_n3 = sC[0, 2, 0] * F[0] + sC[0, 2, 1] * F[1] + sC[0, 2, 2] * F[2]
                if window == 1:
                    om, fm = w_norm, f_n3
                    cnt = 1
                else:
                    s_om, s_f = 0.0, 0.0
                    for h in range(window - 1):
                        s_om += hist[h, 0]
                        s_f += hist[h, 1]
                    s_om += w_norm
                    s_f += f_n3
                    cnt = min(cnt + 1, window)
                    om, fm = s_om / cnt, s_f / cnt
                    for h in range(window - 2):
                        hist[h, 0] = hist[h + 1, 0]
                        hist[h, 1] = hist[h + 1, 1]
                    hist[window - 2, 0] = w_norm
                    hist[window - 2, 1] = f_n3
                cond = (om <= omax) and (abs(fm - det_g) <= dfmax)
            run = run + 1 if cond else 0
            now = run >= min_run
            is_start = now and not in_stance
            is_end = in_stance and not now
            stance[i, j], start[i, j], end[i, j] = now, is_start, is_end
            in_stance = now
            event = (is_start or is_end) if boundaries else (now or is_end)
            # ---- ZUPT at this instant (the state before sample j is integrated)
            if event and moving and j < valid[i] and div_at > k:
                tau = (j - anchor) * dt
                _moved_states(sC, sv, sp, D, A, B, tau, g, chi, Cm)
                if anchor_bad or _diverging(Cm[0], chi[0, 3:6], chi[0, 0:3], speed_max):
                    div_at = j
                else:
                    e_tau = elapsed0 + tau
                    pw = e_tau
                    for p in range(powers.shape[0]):
                        powers[p] = pw * q_scale
                        pw *= e_tau
                    _prior_moments(chi, Wm, Wc, q_basis, powers, dev, xp, Pp)
                    if logging:
                        log_x[n_log, 0] = xp
                        log_P[n_log, 0] = Pp
                    nis, ok = _zupt_update(xp, Pp, height_ref, R_diag, gate_nis, SI, KT)
                    if ok:
                        counters[i, 0] += 1
                        n_acc += 1
                        nis_sum += math.log1p(nis)
                        last_acc = j
                    else:
                        counters[i, 1] += 1
                    last_nis[i] = nis
                    x_post[i] = xp
                    P_post[i] = Pp
                    if _redraw(xp, Pp, spread, sC, sv, sp, L):
                        counters[i, 2] += 1
                    if logging:
                        log_index[n_log, 0] = i
                        log_index[n_log, 1] = j
                        log_index[n_log, 2] = (
                            KIND_START if is_start else (KIND_END if is_end else KIND_STANCE)
                        )
                        log_index[n_log, 3] = 1 if ok else 0
                        log_x[n_log, 1] = xp
                        log_P[n_log, 1] = Pp
                        log_nis[n_log] = nis
                        n_log += 1
                    anchor, elapsed0, first_bad = j, 0.0, k + 1
                    D[:] = 0.0
                    D[0, 0] = D[1, 1] = D[2, 2] = 1.0
                    A[:] = 0.0
                    B[:] = 0.0
                    F[:] = f_mid  # = D f_mid from the new anchor
                    _weighted_sums(Wm, sC, sv, sp, Cbar, vbar, pbar)
                    anchor_bad = not _finite(sC[0])
            # ---- integrate sample j: state index t = j + 1
            if moving:
                _accumulate(D, A, B, F, dC, dt)
            t = j + 1
            tau = (t - anchor) * dt if moving else 0.0
            if moving and div_at > k and first_bad > k:
                for r in range(3):
                    c0, c1, c2 = sC[0, r, 0], sC[0, r, 1], sC[0, r, 2]
                    vc[r] = sv[0, r] + c0 * A[0] + c1 * A[1] + c2 * A[2]
                    pc[r] = sp[0, r] + sv[0, r] * tau + c0 * B[0] + c1 * B[1] + c2 * B[2]
                vc[2] -= g * tau
                pc[2] -= 0.5 * g * (tau * tau)
                if anchor_bad or _diverging(sC[0], vc, pc, speed_max):
                    first_bad = t
            if record_pos or t == valid[i]:
                for r in range(3):
                    mp = pbar[r] + vbar[r] * tau
                    mp += Cbar[r, 0] * B[0] + Cbar[r, 1] * B[1] + Cbar[r, 2] * B[2]
                    if r == 2:
                        mp -= 0.5 * g * (tau * tau)
                    if record_pos:
                        positions[i, j, r] = mp
                    if t == valid[i]:
                        position[i, r] = mp
            if record_state:
                _moved_states(sC, sv, sp, D, A, B, tau, g, chi, Cm)
                _state_mean(chi, Wm, mean)
                states[i, j] = mean
        # ---- end of the block: divergence after the last ZUPT, sigma points at K
        if div_at > k and first_bad <= k:
            div_at = first_bad
        if moving:
            _move_sigmas(sC, sv, sp, D, A, B, (k - anchor) * dt, g)
        elapsed[i] = elapsed0 + (k - anchor) * dt
        det_count[i], det_run[i], det_in_stance[i] = cnt, run, in_stance
        accepted_count[i] = n_acc
        nis_log_sum[i] = nis_sum
        diverged_at[i] = div_at
        last_accepted[i] = last_acc
    return n_log
