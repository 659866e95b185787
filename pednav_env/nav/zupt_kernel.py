"""Compiled per-walker kernel of the ZUPT-UKF of paper 003.

:meth:`pednav_env.nav.zupt_ukf.ZuptUkf.advance` hands a whole block of K IMU
samples of all N walkers to :func:`advance_block`, which runs each walker (on the
calling thread and helper threads, :mod:`pednav_env.nav.kernel_threads`) sample
after sample through the filter of :mod:`pednav_env.nav.zupt_ukf`'s docstring.
Per sample j:

1. :func:`pednav_env.nav.preintegration.strapdown_increment`: the strapdown
   increments of paper 003 eq (3) (attitude increment C(Δq), Δq from
   k = ω'Δt, and the specific force in mid-interval axes);
2. :func:`pednav_env.nav.detector_kernel.detect`: the stance detector, eq (5)
   on |ω'| and f'_x3 (the vertical specific force through the central sigma
   point's attitude) with its causal window, or a SHOE condition computed from
   the raw record; then the minimum stance duration
   (:func:`pednav_env.nav.detector_kernel.stance_logic`);
3. at a detected stance start or end (or at every stance sample),
   :func:`zupt`: the 19 sigma points are moved from their last draw to this
   instant, their unscented mean and covariance plus Q(τ) form the prior, the
   update with h(y) = [x₃, v₁, v₂, v₃] gives the posterior and new sigma
   points are drawn (:mod:`pednav_env.nav.zupt_algebra`; paper 003's UKF);
   the prior's central point is first checked for divergence;
4. the sample is added to the preintegrals D, A, B (the points themselves are
   moved only at a ZUPT and at the end of the block,
   :mod:`pednav_env.nav.preintegration`), the central point is checked for
   divergence after the walker's last ZUPT
   (:func:`pednav_env.nav.preintegration.central_point_diverges`) and the mean
   position or state is recorded
   (:func:`pednav_env.nav.preintegration.mean_position`, :func:`mean_state_after`).

(The static alignment of eq (4) comes before: :meth:`~pednav_env.nav.zupt_ukf.ZuptUkf.initialize`.)

Arguments are grouped in NamedTuples of arrays and scalars
(:mod:`pednav_env.nav.zupt_kernel_args`: :class:`KernelSettings`,
:class:`WalkerKnobs`, :class:`UkfModel`, :class:`WalkerFilters`,
:class:`DetectorState`, :class:`BlockInput`,
:class:`BlockOutput`, :class:`UpdateLog`), which numba passes to compiled code
as they are; scratch arrays (:mod:`pednav_env.nav.kernel_threads`) are allocated
once per thread and block. :func:`advance_walker` takes a
walker's arrays out of the tuples before its sample loop, and the helpers
called at every sample are inlined by numba: a compiled call per sample, with
whole tuples as arguments, would cost more than the sample's arithmetic
(docs/PERFORMANCE.md).

Compiled, against the rule of one numpy call chain (docs/CONVENTIONS.md), as
ZUPTs fall at data-dependent samples of each walker (docs/PERFORMANCE.md);
walker i's arithmetic never depends on the others (lanes equal scalar envs).

Numba caches compiled code per source file, keyed by the file's content (numba
0.68: a hash of it; touching the file does not refresh the cache): after editing a
compiled function of a module this one calls, clear ``__pycache__``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pednav_env.nav.detector_kernel import Eq5Thresholds, detect, stance_logic
from pednav_env.nav.kernel_threads import (
    SHARED_RUN,
    SampleScratch,
    ZuptScratch,
    fetch_add,
    new_sample_scratch,
    new_zupt_scratch,
    thread_parts,
)
from pednav_env.nav.preintegration import (
    AnchorSums,
    Preintegral,
    SigmaPoints,
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
from pednav_env.nav.sigma_angles import moved_residuals
from pednav_env.nav.zupt_algebra import (
    draw_sigmas,
    prior_moments,
    residual_mean,
    residuals,
    state_mean,
    zupt_update,
)
from pednav_env.nav.zupt_kernel_args import (
    KIND_END,
    KIND_STANCE,
    KIND_START,
    BlockInput,
    BlockOutput,
    DetectorState,
    KernelSettings,
    UkfModel,
    UpdateLog,
    WalkerFilters,
    WalkerKnobs,
)


# ------------------------------------------------------------------ ZUPT
@njit(cache=True, inline="always")
def zupt(
    i: int,
    j: int,
    kind: int,
    interval_s: float,
    s: KernelSettings,
    knobs: WalkerKnobs,
    model: UkfModel,
    filt: WalkerFilters,
    sig: SigmaPoints,
    log: UpdateLog,
    n_log: int,
    zs: ZuptScratch,
) -> tuple[bool, float, int]:
    """ZUPT of walker i at sample j on the moved sigma states ``zs.chi``: prior
    (unscented moments plus Q of the ``interval_s`` since the last draw), update,
    new sigma points ``sig`` (walker i's); counters, last posterior and (when
    logging) the log row ``n_log`` are written. Returns (accepted, NIS, next log row)."""
    q_scale = knobs.process_noise_scale[i]
    pw = interval_s
    for p in range(zs.powers.shape[0]):
        zs.powers[p] = pw * q_scale
        pw *= interval_s
    if not s.angle_sums:  # else moved_residuals gave them
        residuals(zs.chi, zs.dev)
    prior_moments(zs.chi, model.Wm, model.Wc, model.q_basis, zs.powers, zs.dev, zs.x, zs.P)
    logging = log.index.shape[0] > 0
    if logging:
        log.x[n_log, 0] = zs.x
        log.P[n_log, 0] = zs.P
    zs.R_diag[0] = knobs.zupt_var_height[i]
    zs.R_diag[1] = zs.R_diag[2] = zs.R_diag[3] = knobs.zupt_var_velocity[i]
    nis, ok = zupt_update(zs.x, zs.P, knobs.height_ref[i], zs.R_diag, s.gate_nis, zs.alg)
    filt.counters[i, 0 if ok else 1] += 1
    filt.last_nis[i] = nis
    for r in range(9):  # element by element: no views (module docstring of preintegration)
        filt.x[i, r] = zs.x[r]
        for c in range(9):
            filt.P[i, r, c] = zs.P[r, c]
    if draw_sigmas(zs.x, zs.P, s.spread, sig, zs.alg, s.angle_sums):
        filt.counters[i, 2] += 1
    if logging:
        log.index[n_log, 0] = i
        log.index[n_log, 1] = j
        log.index[n_log, 2] = kind
        log.index[n_log, 3] = 1 if ok else 0
        log.x[n_log, 1] = zs.x
        log.P[n_log, 1] = zs.P
        log.nis[n_log] = nis
        n_log += 1
    return ok, nis, n_log


@njit(cache=True, inline="always")
def new_anchor(Wm: np.ndarray, sig: SigmaPoints, pre: Preintegral, sums: AnchorSums) -> bool:
    """Preintegrals restarted at the sigma points and their weighted sums taken.
    Returns whether the central attitude is non-finite."""
    restart(pre)
    weighted_sums(Wm, sig, sums)
    return not all_finite(sig.C, 0)


# ------------------------------------------------------------------ records
@njit(cache=True)
def mean_state_after(
    sig: SigmaPoints,
    pre: Preintegral,
    tau: float,
    g: float,
    Wm: np.ndarray,
    zs: ZuptScratch,
    out: np.ndarray,
    angle_sums: bool,
) -> None:
    """``out`` (9,) ← the mean state of the sigma points moved over τ (s)."""
    if angle_sums:
        moved_residuals(sig, pre, tau, g, zs.chi, zs.C_moved, zs.dev)
        residual_mean(zs.chi, zs.dev, Wm, out)
    else:
        moved_states(sig, pre, tau, g, zs.chi, zs.C_moved)
        state_mean(zs.chi, Wm, out)


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
    ss: SampleScratch,
    zs: ZuptScratch,
) -> int:
    """Walker i through the block (module docstring). Returns the next log row."""
    # walker i's arrays, out of the tuples once: the sample loop passes no tuple (module doc)
    k, dt, g = block.omega.shape[1], knobs.dt[i], s.g
    omega, f, bias, valid = block.omega[i], block.f[i], knobs.gyro_bias[i], block.valid[i]
    shoe_condition = block.shoe_cond[i]
    moving = not block.frozen[i]
    sig, Wm = SigmaPoints(filt.sig_C[i], filt.sig_v[i], filt.sig_p[i]), model.Wm
    C_central, history, min_run = sig.C[0], det.history[i], knobs.min_stance_samples[i]
    thresholds = Eq5Thresholds(knobs.omega_max[i], knobs.delta_f_max[i], s.detector_g)
    stance, start, end = out.stance[i], out.start[i], out.end[i]
    positions, states = out.positions, out.states
    record_pos, record_state = positions.shape[0] > 0, states.shape[0] > 0
    w, f_j, dC, f_mid, F, pre, sums = ss.w, ss.f_j, ss.dC, ss.f_mid, ss.F, ss.pre, ss.sums
    v_c, p_c, p_mean = ss.v_c, ss.p_c, ss.p_mean
    count, run, in_stance = det.count[i], det.run[i], det.in_stance[i]
    anchor = 0  # sample of the last sigma-point draw
    elapsed0 = filt.elapsed_s[i]  # s from the draw before the block to sample 0
    first_bad = k + 1  # first state index whose central point diverged (after the last ZUPT)
    div_at = k + 1  # state index of divergence (at a ZUPT's prior, or first_bad)
    last_acc, n_acc, nis_sum = -1, 0, 0.0
    anchor_bad = new_anchor(Wm, sig, pre, sums)
    if valid == 0:
        out.position[i, :] = sums.p
    for j in range(k):
        for r in range(3):
            w[r] = omega[j, r] - bias[r]
            f_j[r] = f[j, r]
        strapdown_increment(w, f_j, dt, dC, f_mid)
        anchor_force(pre.D, f_mid, F)
        cond, count = detect(shoe_condition, j, w, F, C_central, history, count, thresholds)
        run, now, is_start, is_end = stance_logic(cond, run, in_stance, min_run)
        stance[j], start[j], end[j] = now, is_start, is_end
        in_stance = now
        event = (is_start or is_end) if s.boundaries_only else (now or is_end)
        # ZUPT at this instant: the state before sample j is integrated
        if event and moving and j < valid and div_at > k:
            tau = (j - anchor) * dt
            if s.angle_sums:
                moved_residuals(sig, pre, tau, g, zs.chi, zs.C_moved, zs.dev)
            else:
                moved_states(sig, pre, tau, g, zs.chi, zs.C_moved)
            for r in range(3):  # the central point's velocity and position
                v_c[r], p_c[r] = zs.chi[0, 3 + r], zs.chi[0, r]
            if anchor_bad or diverging(zs.C_moved, 0, v_c, p_c, s.speed_max):
                div_at = j
            else:
                kind = KIND_START if is_start else (KIND_END if is_end else KIND_STANCE)
                ok, nis, n_log = zupt(
                    i, j, kind, elapsed0 + tau, s, knobs, model, filt, sig, log, n_log, zs
                )
                if ok:
                    n_acc += 1
                    nis_sum += math.log1p(nis)
                    last_acc = j
                anchor, elapsed0, first_bad = j, 0.0, k + 1
                anchor_bad = new_anchor(Wm, sig, pre, sums)
                for r in range(3):
                    F[r] = f_mid[r]  # = D f_mid from the new anchor
        # integrate sample j: state index t = j + 1
        if moving:
            accumulate(pre, F, dC, dt)
        t = j + 1
        tau = (t - anchor) * dt if moving else 0.0
        if moving and div_at > k and first_bad > k:
            if anchor_bad or central_point_diverges(sig, pre, tau, g, s.speed_max, v_c, p_c):
                first_bad = t
        # record the mean position / state after the sample
        if record_pos or t == valid:
            mean_position(sums, pre, tau, g, p_mean)
            if record_pos:
                for r in range(3):
                    positions[i, j, r] = p_mean[r]
            if t == valid:
                out.position[i] = p_mean
        if record_state:
            mean_state_after(sig, pre, tau, g, Wm, zs, states[i, j], s.angle_sums)
    # end of the block: divergence after the last ZUPT, sigma points moved to K
    if div_at > k and first_bad <= k:
        div_at = first_bad
    if moving:
        move_sigmas(sig, pre, (k - anchor) * dt, g)
    filt.elapsed_s[i] = elapsed0 + (k - anchor) * dt
    det.count[i], det.run[i], det.in_stance[i] = count, run, in_stance
    out.accepted[i] = n_acc
    out.nis_log_sum[i] = nis_sum
    out.diverged_at[i] = div_at
    out.last_accepted[i] = last_acc
    return n_log


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
    empty, room for N·K rows) every ZUPT, walker by walker. Returns the number
    of logged ZUPTs. On this thread and helper threads together
    (:func:`advance_share`, :mod:`pednav_env.nav.kernel_threads`), or walker after
    walker with one thread, one walker or the helpers busy (:func:`advance_serial`):
    the same outputs.
    """
    args = (block, settings, knobs, model, filters, detector, out, log)
    parts = thread_parts(block.omega.shape[0])
    if parts > 1 and SHARED_RUN.acquire():
        try:
            return SHARED_RUN.run(advance_share, args, parts)
        finally:
            SHARED_RUN.release()
    return advance_serial(*args)


@njit(cache=True)
def advance_serial(
    block: BlockInput,
    settings: KernelSettings,
    knobs: WalkerKnobs,
    model: UkfModel,
    filters: WalkerFilters,
    detector: DetectorState,
    out: BlockOutput,
    log: UpdateLog,
) -> int:
    """:func:`advance_block` on this thread, walker after walker."""
    ss = new_sample_scratch()
    zs = new_zupt_scratch(model.Wm.shape[0], model.q_basis.shape[0])
    n_log = 0
    for i in range(block.omega.shape[0]):
        n_log = advance_walker(
            i, block, settings, knobs, model, filters, detector, out, log, n_log, ss, zs
        )
    return n_log


@njit(cache=True, nogil=True)
def advance_share(
    block: BlockInput,
    settings: KernelSettings,
    knobs: WalkerKnobs,
    model: UkfModel,
    filters: WalkerFilters,
    detector: DetectorState,
    out: BlockOutput,
    log: UpdateLog,
    taken: np.ndarray,
    logged: np.ndarray,
) -> int:
    """One thread's share of :func:`advance_block` (several threads call it at once,
    without the GIL: :class:`pednav_env.nav.kernel_threads.SharedRun`): walkers taken
    one at a time from the shared counter ``taken`` (1,) until none is left, with this
    thread's own scratch; walker i writes only its own rows and its log rows from
    i·K on (when logging), their count in ``logged[i]``."""
    n, k = block.omega.shape[0], block.omega.shape[1]
    region = k if log.index.shape[0] > 0 else 0  # log rows of a walker
    ss = new_sample_scratch()
    zs = new_zupt_scratch(model.Wm.shape[0], model.q_basis.shape[0])
    i = fetch_add(taken, 1)
    while i < n:
        first = i * region
        last = advance_walker(
            i, block, settings, knobs, model, filters, detector, out, log, first, ss, zs
        )
        logged[i] = last - first
        i = fetch_add(taken, 1)
    return 0
