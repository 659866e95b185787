"""Compiled per-walker kernel of the ZUPT-UKF of paper 003.

:meth:`pednav_env.nav.zupt_ukf.ZuptUkf.advance` hands a whole block of K IMU
samples of all N walkers to :func:`advance_block`, which runs, walker after
walker and sample after sample, the filter that the module docstring of
:mod:`pednav_env.nav.zupt_ukf` describes. Per sample j of a walker:

1. :func:`pednav_env.nav.preintegration.strapdown_increment`: the strapdown
   increments of paper 003 eq (3) (attitude increment C(Δq), Δq from
   k = ω'Δt, and the specific force in mid-interval axes);
2. :func:`detect`: the stance detector, eq (5) on |ω'| and f'_x3 (the
   vertical specific force through the central sigma point's attitude) with
   its causal window, or a SHOE condition computed from the raw record;
   then the minimum stance duration (:func:`stance_logic`);
3. at a detected stance start or end (or at every stance sample),
   :func:`zupt`: the 19 sigma points are moved from their last draw to this
   instant, their unscented mean and covariance plus Q(τ) form the prior, the
   update with h(y) = [x₃, v₁, v₂, v₃] gives the posterior and new sigma
   points are drawn (:mod:`pednav_env.nav.zupt_algebra`; paper 003's UKF);
   the prior's central point is first checked for divergence;
4. the sample is added to the preintegrals D, A, B (the points themselves are
   moved only at a ZUPT and at the end of the block,
   :mod:`pednav_env.nav.preintegration`), the central point is checked for
   divergence after the walker's last ZUPT and the mean position or state is
   recorded (:func:`record_sample`).

The static alignment of eq (4) happens before, in
:meth:`~pednav_env.nav.zupt_ukf.ZuptUkf.initialize`.

Arguments are grouped in NamedTuples of arrays and scalars
(:class:`KernelSettings`, :class:`WalkerKnobs`, :class:`UkfModel`,
:class:`WalkerFilters`, :class:`DetectorState`, :class:`BlockInput`,
:class:`BlockOutput`, :class:`UpdateLog`), which numba passes to compiled code
as they are; per-walker scratch arrays are a :class:`Workspace`.

Why compiled code here, against the rule of one batched numpy call chain
(docs/CONVENTIONS.md): a ZUPT happens at data-dependent samples of each walker (stance detection flickers on
consumer-grade IMUs, up to 20 boundaries per walker and 0.5 s interval), so a
batched numpy engine must run the updates in rounds across walkers with a
fixed per-call cost; that cost, not arithmetic, bounded its throughput
(docs/PERFORMANCE.md). The kernel is still the one implementation of the
filter for every walker count: walker i's arithmetic never depends on the
others, so lane i of a vector env equals a scalar env bit for bit.

Numba caches the compiled functions on disk per source file; after editing a
compiled function of another module that this one calls, touch this file (or
clear ``__pycache__``) so that the cache is rebuilt.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pednav_env.nav.preintegration import (
    AnchorSums,
    Preintegral,
    accumulate,
    all_finite,
    anchor_force,
    central_point_diverges,
    diverging,
    mean_position,
    move_sigmas,
    moved_states,
    restart,
    strapdown_increment,
    weighted_sums,
)
from pednav_env.nav.zupt_algebra import draw_sigmas, prior_moments, state_mean, zupt_update

#: Kinds of ZUPT in the update log: stance start, stance end, stance sample.
KIND_START, KIND_END, KIND_STANCE = 0, 1, 2


class KernelSettings(NamedTuple):
    """Constants shared by all walkers."""

    dt: float  # s, sample interval
    g: float  # m/s², gravity of the strapdown
    detector_g: float  # m/s², the g of eq (5)
    gate_nis: float  # χ² gate on the NIS of a ZUPT (inf: no gate)
    uses_shoe: bool  # stance condition given per sample (SHOE), not eq (5)
    boundaries_only: bool  # ZUPTs at stance start and end (paper 003), else at every stance sample
    spread: float  # L + λ of the sigma points
    speed_max: float  # m/s, divergence speed of the central sigma point


class WalkerKnobs(NamedTuple):
    """Per-walker settings, arrays over N walkers (the agent's knobs among them)."""

    omega_max: np.ndarray  # (N,) rad/s, eq (5)
    delta_f_max: np.ndarray  # (N,) m/s², eq (5)
    min_stance_samples: np.ndarray  # (N,) int, minimum stance duration
    process_noise_scale: np.ndarray  # (N,) multiplies Q
    zupt_var_height: np.ndarray  # (N,) m², R entry of x₃
    zupt_var_velocity: np.ndarray  # (N,) m²/s², R entries of v
    height_ref: np.ndarray  # (N,) m, x₃(t₀) of the ZUPT measurement
    gyro_bias: np.ndarray  # (N, 3) rad/s, subtracted from every sample


class UkfModel(NamedTuple):
    """The filter's fixed model: Q(τ) = Σ_p τᵖ q_basis_p, sigma-point weights."""

    q_basis: np.ndarray  # (4, 9, 9)
    Wm: np.ndarray  # (S,) mean weights
    Wc: np.ndarray  # (S,) covariance weights


class WalkerFilters(NamedTuple):
    """The filter state of N walkers, updated in place."""

    sig_C: np.ndarray  # (N, S, 3, 3) sigma-point attitudes C_nb
    sig_v: np.ndarray  # (N, S, 3) m/s
    sig_p: np.ndarray  # (N, S, 3) m
    x: np.ndarray  # (N, 9) last posterior mean
    P: np.ndarray  # (N, 9, 9) last posterior covariance
    elapsed_s: np.ndarray  # (N,) s since the last sigma-point draw
    counters: np.ndarray  # (N, 3) int: [updates, rejected, covariance repairs]
    last_nis: np.ndarray  # (N,) NIS of the last ZUPT


class DetectorState(NamedTuple):
    """Causal detector state of N walkers, updated in place."""

    history: np.ndarray  # (N, W−1, 2) last eq-(5) window inputs (|ω'|, f'_x3), oldest first
    count: np.ndarray  # (N,) int, samples seen, capped at the window length W
    run: np.ndarray  # (N,) int, samples the condition has held
    in_stance: np.ndarray  # (N,) bool


class BlockInput(NamedTuple):
    """A block of K samples of N walkers."""

    omega: np.ndarray  # (N, K, 3) rad/s, body rate
    f: np.ndarray  # (N, K, 3) m/s², specific force
    shoe_cond: np.ndarray  # (N, K) bool SHOE condition; (N, 0) for eq (5)
    valid: np.ndarray  # (N,) int, samples before the end of each record (later: no ZUPT)
    frozen: np.ndarray  # (N,) bool, diverged walkers (not moved)


class BlockOutput(NamedTuple):
    """What :func:`advance_block` reports (arrays filled in place)."""

    stance: np.ndarray  # (N, K) bool, detected stance after each sample
    start: np.ndarray  # (N, K) bool, stance declared at the sample
    end: np.ndarray  # (N, K) bool, stance ended at the sample
    accepted: np.ndarray  # (N,) int, ZUPTs applied in the block
    nis_log_sum: np.ndarray  # (N,) Σ log(1 + NIS) of those ZUPTs
    position: np.ndarray  # (N, 3) m, mean position after each walker's valid samples
    diverged_at: np.ndarray  # (N,) int, state index of divergence (K + 1: none)
    last_accepted: np.ndarray  # (N,) int, sample of the last accepted ZUPT (−1: none)
    positions: np.ndarray  # (N, K, 3) m, mean position after every sample, or (0, 0, 3)
    states: np.ndarray  # (N, K, 9) mean state after every sample, or (0, 0, 9)


class UpdateLog(NamedTuple):
    """Every ZUPT of the block (rows 0 … returned count − 1), or empty arrays."""

    index: np.ndarray  # (M, 4) int: [walker, sample, kind, accepted]
    x: np.ndarray  # (M, 2, 9) prior and posterior mean
    P: np.ndarray  # (M, 2, 9, 9) prior and posterior covariance
    nis: np.ndarray  # (M,)


class Workspace(NamedTuple):
    """Scratch arrays of one walker, reused across walkers."""

    w: np.ndarray  # (3,) bias-corrected rate
    dC: np.ndarray  # (3, 3) C(Δq) of the sample
    f_mid: np.ndarray  # (3,) specific force in mid-interval axes
    F: np.ndarray  # (3,) the same in anchor axes
    pre: Preintegral
    sums: AnchorSums
    chi: np.ndarray  # (S, 9) moved sigma states
    C_moved: np.ndarray  # (S, 3, 3) their attitudes
    dev: np.ndarray  # (S, 9) residuals
    x: np.ndarray  # (9,) prior / posterior mean
    P: np.ndarray  # (9, 9) prior / posterior covariance
    SI: np.ndarray  # (4, 4) S⁻¹
    KT: np.ndarray  # (4, 9) Kᵀ
    L: np.ndarray  # (9, 9) Cholesky factor
    powers: np.ndarray  # (4,) τᵖ · process-noise scale
    R_diag: np.ndarray  # (4,)
    v_c: np.ndarray  # (3,) central point's velocity
    p_c: np.ndarray  # (3,) central point's position
    mean: np.ndarray  # (9,) mean state


@njit(cache=True)
def new_workspace(num_sigmas: int, num_powers: int) -> Workspace:
    """Scratch arrays for :func:`advance_block`."""
    return Workspace(
        np.empty(3),
        np.empty((3, 3)),
        np.empty(3),
        np.empty(3),
        Preintegral(np.empty((3, 3)), np.empty(3), np.empty(3)),
        AnchorSums(np.empty((3, 3)), np.empty(3), np.empty(3)),
        np.empty((num_sigmas, 9)),
        np.empty((num_sigmas, 3, 3)),
        np.empty((num_sigmas, 9)),
        np.empty(9),
        np.empty((9, 9)),
        np.empty((4, 4)),
        np.empty((4, 9)),
        np.zeros((9, 9)),
        np.empty(num_powers),
        np.empty(4),
        np.empty(3),
        np.empty(3),
        np.empty(9),
    )


# ------------------------------------------------------------------ detector
@njit(cache=True)
def eq5_condition(
    w: np.ndarray,
    f_n3: float,
    history: np.ndarray,
    count: int,
    omega_max: float,
    delta_f_max: float,
    g: float,
) -> tuple[bool, int]:
    """Paper 003 eq (5), |ω'| ≤ ω_max and |f'_x3 − g| ≤ Δf_max, on causal means over
    the window of W = len(history) + 1 samples (the first samples of a walker
    average over fewer). ``w`` (rad/s) is the sample's rate, ``f_n3`` (m/s²) its
    vertical specific force; ``history`` (W − 1, 2) is advanced in place.
    Returns (condition, samples seen capped at W)."""
    window = history.shape[0] + 1
    w_norm = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if window == 1:
        om, fm = w_norm, f_n3
        count = 1
    else:
        s_om, s_f = 0.0, 0.0
        for h in range(window - 1):
            s_om += history[h, 0]
            s_f += history[h, 1]
        s_om += w_norm
        s_f += f_n3
        count = min(count + 1, window)
        om, fm = s_om / count, s_f / count
        for h in range(window - 2):
            history[h, 0] = history[h + 1, 0]
            history[h, 1] = history[h + 1, 1]
        history[window - 2, 0] = w_norm
        history[window - 2, 1] = f_n3
    return (om <= omega_max) and (abs(fm - g) <= delta_f_max), count


@njit(cache=True)
def detect(
    i: int,
    j: int,
    block: BlockInput,
    s: KernelSettings,
    knobs: WalkerKnobs,
    history: np.ndarray,
    count: int,
    C_central: np.ndarray,
    ws: Workspace,
) -> tuple[bool, int]:
    """Stance condition of walker i at sample j: the SHOE condition of the block, or
    eq (5) with f'_x3 = e₃ᵀ C_c D f_mid through the central sigma point's attitude
    ``C_central`` at the anchor (its attitude now is C_c D). Returns (condition,
    samples seen)."""
    window = history.shape[0] + 1
    if s.uses_shoe:
        return block.shoe_cond[i, j], min(count + 1, window)
    F = ws.F
    f_n3 = C_central[2, 0] * F[0] + C_central[2, 1] * F[1] + C_central[2, 2] * F[2]
    return eq5_condition(
        ws.w, f_n3, history, count, knobs.omega_max[i], knobs.delta_f_max[i], s.detector_g
    )


@njit(cache=True)
def stance_logic(
    condition: bool, run: int, in_stance: bool, min_run: int
) -> tuple[int, bool, bool, bool]:
    """Stance declared once the condition held ``min_run`` samples (causal; the
    declaration is delayed, never back-dated). Returns (run, stance, start, end)."""
    run = run + 1 if condition else 0
    now = run >= min_run
    return run, now, now and not in_stance, in_stance and not now


# ------------------------------------------------------------------ ZUPT
@njit(cache=True)
def zupt(
    i: int,
    j: int,
    kind: int,
    interval_s: float,
    s: KernelSettings,
    knobs: WalkerKnobs,
    model: UkfModel,
    filt: WalkerFilters,
    log: UpdateLog,
    n_log: int,
    ws: Workspace,
) -> tuple[bool, float, int]:
    """ZUPT of walker i at sample j on the moved sigma states ``ws.chi``: prior
    (unscented moments plus Q of the ``interval_s`` since the last draw), update,
    new sigma points; counters, last posterior and (when logging) the log row
    ``n_log`` are written. Returns (accepted, NIS, next log row)."""
    q_scale = knobs.process_noise_scale[i]
    pw = interval_s
    for p in range(ws.powers.shape[0]):
        ws.powers[p] = pw * q_scale
        pw *= interval_s
    prior_moments(ws.chi, model.Wm, model.Wc, model.q_basis, ws.powers, ws.dev, ws.x, ws.P)
    logging = log.index.shape[0] > 0
    if logging:
        log.x[n_log, 0] = ws.x
        log.P[n_log, 0] = ws.P
    ws.R_diag[0] = knobs.zupt_var_height[i]
    ws.R_diag[1] = ws.R_diag[2] = ws.R_diag[3] = knobs.zupt_var_velocity[i]
    nis, ok = zupt_update(ws.x, ws.P, knobs.height_ref[i], ws.R_diag, s.gate_nis, ws.SI, ws.KT)
    filt.counters[i, 0 if ok else 1] += 1
    filt.last_nis[i] = nis
    filt.x[i] = ws.x
    filt.P[i] = ws.P
    if draw_sigmas(ws.x, ws.P, s.spread, filt.sig_C[i], filt.sig_v[i], filt.sig_p[i], ws.L):
        filt.counters[i, 2] += 1
    if logging:
        log.index[n_log, 0] = i
        log.index[n_log, 1] = j
        log.index[n_log, 2] = kind
        log.index[n_log, 3] = 1 if ok else 0
        log.x[n_log, 1] = ws.x
        log.P[n_log, 1] = ws.P
        log.nis[n_log] = nis
        n_log += 1
    return ok, nis, n_log


@njit(cache=True)
def new_anchor(i: int, model: UkfModel, filt: WalkerFilters, ws: Workspace) -> bool:
    """Preintegrals restarted at walker i's current sigma points; their weighted
    sums taken. Returns whether the central attitude is non-finite."""
    restart(ws.pre)
    sC = filt.sig_C[i]
    weighted_sums(model.Wm, sC, filt.sig_v[i], filt.sig_p[i], ws.sums)
    return not all_finite(sC[0])


# ------------------------------------------------------------------ records
@njit(cache=True)
def record_sample(
    i: int,
    j: int,
    tau: float,
    s: KernelSettings,
    block: BlockInput,
    model: UkfModel,
    filt: WalkerFilters,
    out: BlockOutput,
    ws: Workspace,
) -> None:
    """After sample j (state index t = j + 1, τ since the anchor): the mean
    position for ``positions`` and, at the walker's last valid sample,
    ``position``; the mean state for ``states`` when recorded."""
    t = j + 1
    record_pos = out.positions.shape[0] > 0
    if record_pos or t == block.valid[i]:
        for r in range(3):
            mp = mean_position(ws.sums, ws.pre, tau, s.g, r)
            if record_pos:
                out.positions[i, j, r] = mp
            if t == block.valid[i]:
                out.position[i, r] = mp
    if out.states.shape[0] > 0:
        moved_states(
            filt.sig_C[i], filt.sig_v[i], filt.sig_p[i], ws.pre, tau, s.g, ws.chi, ws.C_moved
        )
        state_mean(ws.chi, model.Wm, ws.mean)
        out.states[i, j] = ws.mean


# ------------------------------------------------------------------ walker and block
@njit(cache=True)
def advance_walker(
    i: int,
    block: BlockInput,
    s: KernelSettings,
    knobs: WalkerKnobs,
    model: UkfModel,
    filt: WalkerFilters,
    det: DetectorState,
    out: BlockOutput,
    log: UpdateLog,
    n_log: int,
    ws: Workspace,
) -> int:
    """Walker i through the block (module docstring). Returns the next log row."""
    k = block.omega.shape[1]
    dt, g = s.dt, s.g
    moving = not block.frozen[i]
    sC, sv, sp = filt.sig_C[i], filt.sig_v[i], filt.sig_p[i]
    count, run, in_stance = det.count[i], det.run[i], det.in_stance[i]
    anchor = 0  # sample of the last sigma-point draw
    elapsed0 = filt.elapsed_s[i]  # s from that draw's predecessor to sample 0
    first_bad = k + 1  # first state index whose central point diverged (after the last ZUPT)
    div_at = k + 1  # state index of divergence (at a ZUPT's prior, or first_bad)
    last_acc, n_acc, nis_sum = -1, 0, 0.0
    anchor_bad = new_anchor(i, model, filt, ws)
    if block.valid[i] == 0:
        out.position[i, :] = ws.sums.p
    for j in range(k):
        for r in range(3):
            ws.w[r] = block.omega[i, j, r] - knobs.gyro_bias[i, r]
        strapdown_increment(ws.w, block.f[i, j], dt, ws.dC, ws.f_mid)
        anchor_force(ws.pre.D, ws.f_mid, ws.F)
        cond, count = detect(i, j, block, s, knobs, det.history[i], count, sC[0], ws)
        run, now, is_start, is_end = stance_logic(cond, run, in_stance, knobs.min_stance_samples[i])
        out.stance[i, j], out.start[i, j], out.end[i, j] = now, is_start, is_end
        in_stance = now
        event = (is_start or is_end) if s.boundaries_only else (now or is_end)
        # ZUPT at this instant: the state before sample j is integrated
        if event and moving and j < block.valid[i] and div_at > k:
            tau = (j - anchor) * dt
            moved_states(sC, sv, sp, ws.pre, tau, g, ws.chi, ws.C_moved)
            if anchor_bad or diverging(ws.C_moved[0], ws.chi[0, 3:6], ws.chi[0, 0:3], s.speed_max):
                div_at = j
            else:
                kind = KIND_START if is_start else (KIND_END if is_end else KIND_STANCE)
                ok, nis, n_log = zupt(
                    i, j, kind, elapsed0 + tau, s, knobs, model, filt, log, n_log, ws
                )
                if ok:
                    n_acc += 1
                    nis_sum += math.log1p(nis)
                    last_acc = j
                anchor, elapsed0, first_bad = j, 0.0, k + 1
                anchor_bad = new_anchor(i, model, filt, ws)
                ws.F[:] = ws.f_mid  # = D f_mid from the new anchor
        # integrate sample j: state index t = j + 1
        if moving:
            accumulate(ws.pre, ws.F, ws.dC, dt)
        t = j + 1
        tau = (t - anchor) * dt if moving else 0.0
        if moving and div_at > k and first_bad > k:
            if anchor_bad or central_point_diverges(
                sC, sv, sp, ws.pre, tau, g, s.speed_max, ws.v_c, ws.p_c
            ):
                first_bad = t
        record_sample(i, j, tau, s, block, model, filt, out, ws)
    # end of the block: divergence after the last ZUPT, sigma points moved to K
    if div_at > k and first_bad <= k:
        div_at = first_bad
    if moving:
        move_sigmas(sC, sv, sp, ws.pre, (k - anchor) * dt, g)
    filt.elapsed_s[i] = elapsed0 + (k - anchor) * dt
    det.count[i], det.run[i], det.in_stance[i] = count, run, in_stance
    out.accepted[i] = n_acc
    out.nis_log_sum[i] = nis_sum
    out.diverged_at[i] = div_at
    out.last_accepted[i] = last_acc
    return n_log


@njit(cache=True)
def advance_block(
    block: BlockInput,
    settings: KernelSettings,
    knobs: WalkerKnobs,
    model: UkfModel,
    filters: WalkerFilters,
    detector: DetectorState,
    out: BlockOutput,
    log: UpdateLog,
) -> int:
    """Advance every walker through a block of K samples (module docstring).

    ``filters`` and ``detector`` are updated in place; ``out`` receives the
    detector flags, accepted ZUPTs, Σ log(1 + NIS), mean positions, divergence
    index and last accepted ZUPT of each walker, and, when their arrays are
    not empty, the mean position / state after every sample; ``log`` (when not
    empty, room for N·K rows) every ZUPT. Returns the number of logged ZUPTs.
    """
    ws = new_workspace(model.Wm.shape[0], model.q_basis.shape[0])
    n_log = 0
    for i in range(block.omega.shape[0]):
        n_log = advance_walker(
            i, block, settings, knobs, model, filters, detector, out, log, n_log, ws
        )
    return n_log


@njit(cache=True)
def redraw_sigmas(
    lanes: np.ndarray, x: np.ndarray, P: np.ndarray, spread: float, filters: WalkerFilters
) -> np.ndarray:
    """Draw the sigma points of walkers ``lanes`` from their (x, P) rows
    (``x`` (B, 9), ``P`` (B, 9, 9); :func:`pednav_env.nav.zupt_algebra.draw_sigmas`);
    returns the mask of covariances that had to be repaired."""
    L = np.zeros((9, 9))
    bad = np.zeros(lanes.shape[0], dtype=np.bool_)
    for j in range(lanes.shape[0]):
        i = lanes[j]
        bad[j] = draw_sigmas(
            x[j], P[j], spread, filters.sig_C[i], filters.sig_v[i], filters.sig_p[i], L
        )
    return bad
