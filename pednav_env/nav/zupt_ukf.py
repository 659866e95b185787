"""The zero-velocity-update unscented Kalman filter of paper 003, batched.

State (paper 003): y = [x₁, x₂, x₃, v₁, v₂, v₃, θ, γ, ψ], L = 9 — position and
velocity of the IMU in the navigation frame and pitch, roll, yaw. Process
function f: the strapdown (eq 3, :mod:`pednav_env.nav.strapdown`) integrated
from one correction instant to the next; corrections at every detected stance
start and stance end (eq 5 or SHOE) with

    h(y) = [x₃, v₁, v₂, v₃],   z = [x₃(t₀), 0, 0, 0]   (flat ground, zero velocity)

(the model functions and Q: :mod:`pednav_env.nav.zupt_model`). The filter
starts from paper 003's static alignment (eq 4, :meth:`ZuptUkf.initialize`).

One engine for every walker: :class:`ZuptUkf` holds the sigma points of N
walkers, ``(N, 2L+1, ·)``, and :meth:`ZuptUkf.advance` moves all of them
through a block of K IMU samples (one decision interval of the env) in one
call of the compiled kernel :func:`pednav_env.nav.zupt_kernel.advance_block`,
walker after walker, sample after sample: between two ZUPTs the sigma points
follow the strapdown by preintegrated increments of the IMU record
(:mod:`pednav_env.nav.preintegration`); after a ZUPT the detector reads the
vertical specific force of eq (5) through the corrected attitude.
:meth:`ZuptUkf.step` is the same call with K = 1, and the result depends on
the blocking only through rounding (tested).

Divergence (a non-finite state or a speed above
:data:`pednav_env.nav.zupt_results.DIVERGENCE_SPEED` of
the central sigma point) is checked on the prior of every ZUPT and at every
sample after a walker's last ZUPT of the block; a diverged walker gets no more
ZUPTs and is frozen at its last posterior.

Like filterpy 2.0 (the oracle), the measurement step uses sigma points redrawn
from the prior (which includes Q), not the propagated ones the paper prints
(which would leave Q out of S); with the linear h the update is then exactly
the Kalman update on the unscented prior, which is how it is computed (no
second draw; the filterpy oracle test checks the equality). The other open
choices (Q, R, gating, angle-sum forms): :mod:`pednav_env.nav.zupt_config`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from pednav_env.nav.alignment import align_static
from pednav_env.nav.detectors import (
    ShoeDetectorConfig,
    detector_window,
    min_stance_samples,
    shoe_statistic,
)
from pednav_env.nav.ukf import repair_covariance
from pednav_env.nav.zupt_algebra import redraw_sigmas
from pednav_env.nav.zupt_config import UpdateMode, ZuptUkfConfig
from pednav_env.nav.zupt_kernel import advance_block
from pednav_env.nav.zupt_kernel_args import (
    BlockInput,
    BlockOutput,
    KernelSettings,
    UkfModel,
    UpdateLog,
    WalkerFilters,
    WalkerKnobs,
    new_block_output,
    new_detector_state,
    new_update_log,
)
from pednav_env.nav.zupt_model import STATE_DIM, dcm_to_state, process_noise_basis, state_mean
from pednav_env.nav.zupt_results import (
    DIVERGENCE_SPEED,
    RUN_BLOCK,
    UPDATE_KINDS,
    BlockResult,
    UpdateRecord,
    ZuptRun,
    ZuptTallies,
)

Array = NDArray[np.float64]


class ZuptUkf:
    """Batched ZUPT-UKF of paper 003 for N walkers.

    Tunable per walker, at any time (the agent's knobs): ``omega_max``,
    ``delta_f_max`` (eq-5 detector) or ``shoe_threshold``, ``min_stance_s``,
    ``process_noise_scale``, ``zupt_noise_scale`` — arrays of shape (N,).
    Per walker too: the sample rate (:meth:`set_rate`; Q's basis stays at ``rate_hz``).
    """

    def __init__(
        self,
        config: ZuptUkfConfig,
        rate_hz: float,
        num_walkers: int,
        record_updates: bool = False,
    ) -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz must be a finite number > 0, got {rate_hz!r}")
        if num_walkers < 1:
            raise ValueError(f"num_walkers must be ≥ 1, got {num_walkers!r}")
        self.config = config
        self.rate_hz = float(rate_hz)
        self.dt = 1.0 / self.rate_hz
        self.n = n = int(num_walkers)
        self.walker_rate_hz = np.full(n, self.rate_hz)
        self.walker_dt = np.full(n, self.dt)
        self.weights = config.weights
        #: R at zupt_noise_scale = 1: diag(σ_h², σ_v², σ_v², σ_v²).
        self.zupt_noise_base = np.diag(
            np.array([config.zupt_height_std] + [config.zupt_velocity_std] * 3) ** 2
        )
        self.num_sigmas = 2 * STATE_DIM + 1
        det = config.detector
        self.uses_shoe = isinstance(det, ShoeDetectorConfig)
        self.gate_nis = (
            None if config.gate_probability is None else float(chi2.ppf(config.gate_probability, 4))
        )
        self.omega_max = np.full(n, getattr(det, "omega_max", np.nan))
        self.delta_f_max = np.full(n, getattr(det, "delta_f_max", np.nan))
        self.shoe_threshold = np.full(n, getattr(det, "threshold", np.nan))
        self.min_stance_s = np.full(n, det.min_stance_s)
        self.process_noise_scale = np.full(n, config.process_noise_scale)
        self.zupt_noise_scale = np.full(n, config.zupt_noise_scale)
        self.record_updates = record_updates
        self.history: list[UpdateRecord] = []
        self.x = np.zeros((n, STATE_DIM))
        self.P = np.zeros((n, STATE_DIM, STATE_DIM))
        #: Sigma points: attitude matrices C_nb, velocities, positions.
        self.sig_C = np.broadcast_to(np.eye(3), (n, self.num_sigmas, 3, 3)).copy()
        self.sig_v = np.zeros((n, self.num_sigmas, 3))
        self.sig_p = np.zeros((n, self.num_sigmas, 3))
        self.elapsed_s = np.zeros(n)
        self.height_ref = np.zeros(n)
        self.sample = np.zeros(n, dtype=np.int64)
        self.updates = np.zeros(n, dtype=np.int64)
        self.rejected = np.zeros(n, dtype=np.int64)
        self.repairs = np.zeros(n, dtype=np.int64)
        self.stance_starts = np.zeros(n, dtype=np.int64)
        self.diverged = np.zeros(n, dtype=bool)
        self.last_nis = np.zeros(n)
        self.time_since_update_s = np.zeros(n)
        self.gyro_bias = np.zeros((n, 3))
        self.detector_state = new_detector_state(n, detector_window(det, self.rate_hz))
        self.model = UkfModel(
            process_noise_basis(config.assumed_imu, self.rate_hz), self.weights.Wm, self.weights.Wc
        )
        self.settings = KernelSettings(
            float(config.g),
            float(det.g),
            np.inf if self.gate_nis is None else self.gate_nis,
            self.uses_shoe,
            config.update_mode is UpdateMode.STANCE_BOUNDARIES,
            STATE_DIM + self.weights.lam,
            DIVERGENCE_SPEED,
            config.angle_sums,
        )

    def set_rate(self, idx: NDArray[np.integer], rate_hz: float) -> None:
        """Walkers ``idx`` sample at ``rate_hz`` (eq 5's window keeps its samples)."""
        det, window = self.config.detector, detector_window
        if not self.uses_shoe and window(det, rate_hz) != window(det, self.rate_hz):
            raise ValueError(f"{rate_hz} Hz: the detector window differs from {self.rate_hz} Hz")
        self.walker_rate_hz[idx] = float(rate_hz)
        self.walker_dt[idx] = 1.0 / float(rate_hz)

    # ------------------------------------------------------------------ init
    def initial_state(self, euler0: Array) -> tuple[Array, Array]:
        """x₀ = [0, 0, (θ, γ, ψ)] and diagonal P₀ for Euler angles ``(B, 3)`` (ψ, θ, γ)."""
        c = self.config
        b = euler0.shape[0]
        x0 = np.zeros((b, STATE_DIM))
        x0[:, 6], x0[:, 7], x0[:, 8] = euler0[:, 1], euler0[:, 2], euler0[:, 0]
        std = np.array(
            [c.initial_position_std] * 3
            + [c.initial_velocity_std] * 3
            + [c.initial_tilt_std] * 2
            + [c.initial_yaw_std]
        )
        return x0, np.broadcast_to(np.diag(std**2), (b, STATE_DIM, STATE_DIM)).copy()

    def initialize(
        self,
        f_align_b: Array,
        mask: NDArray[np.bool_] | None = None,
        omega_align_b: Array | None = None,
    ) -> None:
        """Static alignment (eq 4) from specific force ``(B, W, 3)`` at rest and
        reset of the walkers in ``mask`` (all when None). With
        ``calibrate_gyro_bias`` the mean of ``omega_align_b`` ``(B, W, 3)``
        becomes the gyro bias subtracted from later samples."""
        idx = np.arange(self.n) if mask is None else np.flatnonzero(mask)
        euler0 = align_static(f_align_b, self.config.g)
        if euler0.shape[0] != len(idx):
            raise ValueError(f"f_align_b has {euler0.shape[0]} walkers, expected {len(idx)}")
        if self.config.calibrate_gyro_bias:
            if omega_align_b is None:
                raise ValueError("calibrate_gyro_bias needs omega_align_b")
            self.gyro_bias[idx] = np.asarray(omega_align_b, dtype=float).mean(axis=1)
        else:
            self.gyro_bias[idx] = 0.0
        self.set_state(idx, *self.initial_state(euler0))
        for arr in self.detector_state:
            arr[idx] = 0
        self.height_ref[idx] = 0.0
        for arr in (self.sample, self.updates, self.rejected, self.repairs, self.stance_starts):
            arr[idx] = 0
        self.diverged[idx] = False
        self.last_nis[idx] = 0.0
        self.time_since_update_s[idx] = 0.0

    def set_state(self, idx: NDArray[np.integer], x: Array, P: Array) -> None:
        """Set mean and covariance of walkers ``idx`` and draw their sigma points."""
        idx = np.asarray(idx, dtype=np.int64)
        x, P = np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(P, dtype=float)
        st = self.settings
        bad = redraw_sigmas(idx, x, P, st.spread, self.sig_C, self.sig_v, self.sig_p, st.angle_sums)
        self.repairs[idx] += bad
        self.x[idx], self.P[idx] = x, P
        self.elapsed_s[idx] = 0.0

    # ------------------------------------------------------------------ step
    def step(
        self,
        omega_b: Array,
        f_b: Array,
        shoe_statistic: Array | None = None,
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Advance all walkers by one IMU sample ``(N, 3)`` each (:meth:`advance`
        with one sample). Returns the detected (stance_start, stance_end) events."""
        res = self.advance(
            np.asarray(omega_b, dtype=float)[:, None],
            np.asarray(f_b, dtype=float)[:, None],
            None if shoe_statistic is None else np.asarray(shoe_statistic)[:, None],
        )
        return res.start[:, 0], res.end[:, 0]

    def advance(
        self,
        omega_b: Array,
        f_b: Array,
        shoe_statistic: Array | None = None,
        valid: NDArray[np.integer] | None = None,
        record: str | None = None,
    ) -> BlockResult:
        """Advance all walkers through a block of K IMU samples ``(N, K, 3)``.

        The filter of the module docstring, run by the compiled per-walker kernel
        :func:`pednav_env.nav.zupt_kernel.advance_block`: detector, ZUPT at every
        detected stance start and end, strapdown of every sigma point between
        them (moved from the last redraw by preintegrated increments). Walker
        ``i`` only processes its first ``valid[i]`` samples' events (the rest is
        padding after the end of its record). ``record`` = ``"position"`` or
        ``"state"`` also returns the mean after every sample.
        """
        block = self._block_input(omega_b, f_b, shoe_statistic, valid, record)
        n, k = self.n, block.omega.shape[1]
        out = new_block_output(n, k, record is not None, record == "state")
        log = new_update_log(n * k if self.record_updates else 0)
        counters = self.counters()
        filters = self._filters(counters)
        n_log = advance_block(
            block, self.settings, self._knobs(), self.model, filters, self.detector_state, out, log
        )
        self.updates[:], self.rejected[:], self.repairs[:] = counters.T
        self.stance_starts += out.start.sum(axis=1)
        upd = out.last_accepted >= 0
        dt = self.walker_dt
        self.time_since_update_s = np.where(
            upd, (k - out.last_accepted) * dt, self.time_since_update_s + k * dt
        )
        self._keep_log(log, n_log)
        self.sample += k
        return self._block_result(out, block.valid, record)

    def _block_input(
        self,
        omega_b: Array,
        f_b: Array,
        shoe_statistic: Array | None,
        valid: NDArray[np.integer] | None,
        record: str | None,
    ) -> BlockInput:
        """Checked kernel input of :meth:`advance`."""
        n = self.n
        omega_b = np.ascontiguousarray(omega_b, dtype=float)
        f_b = np.ascontiguousarray(f_b, dtype=float)
        if omega_b.ndim != 3 or omega_b.shape[0] != n or omega_b.shape[2] != 3:
            raise ValueError(f"omega_b must be ({n}, K, 3), got {omega_b.shape}")
        if f_b.shape != omega_b.shape:
            raise ValueError(f"f_b must have omega_b's shape {omega_b.shape}, got {f_b.shape}")
        if record not in (None, "position", "state"):
            raise ValueError(f"record must be None, 'position' or 'state', got {record!r}")
        k = omega_b.shape[1]
        if self.uses_shoe and shoe_statistic is None:
            raise ValueError("the SHOE detector needs shoe_statistic for each sample")
        valid = np.full(n, k) if valid is None else np.asarray(valid, dtype=np.int64)
        if valid.shape != (n,) or valid.min() < 0 or valid.max() > k:
            raise ValueError(f"valid must be ({n},) sample counts in [0, {k}], got {valid!r}")
        if self.uses_shoe:
            shoe_cond = np.asarray(shoe_statistic) <= self.shoe_threshold[:, None]
            if shoe_cond.shape != (n, k):
                raise ValueError(f"shoe_statistic must be ({n}, {k}), got {shoe_cond.shape}")
        else:
            shoe_cond = np.zeros((n, 0), dtype=bool)
        return BlockInput(omega_b, f_b, shoe_cond, valid, self.diverged.copy())

    def _knobs(self) -> WalkerKnobs:
        """The per-walker settings as the kernel reads them."""
        return WalkerKnobs(
            self.walker_dt,
            np.asarray(self.omega_max, dtype=float),
            np.asarray(self.delta_f_max, dtype=float),
            min_stance_samples(self.min_stance_s, self.walker_rate_hz),
            np.asarray(self.process_noise_scale, dtype=float),
            self.zupt_noise_base[0, 0] * self.zupt_noise_scale,
            self.zupt_noise_base[1, 1] * self.zupt_noise_scale,
            self.height_ref,
            self.gyro_bias,
        )

    def counters(self) -> NDArray[np.int64]:
        """(N, 3) [updates, rejected, repairs], a copy."""
        return np.stack((self.updates, self.rejected, self.repairs), axis=1)

    def _filters(self, counters: NDArray[np.int64]) -> WalkerFilters:
        return WalkerFilters(
            self.sig_C,
            self.sig_v,
            self.sig_p,
            self.x,
            self.P,
            self.elapsed_s,
            counters,
            self.last_nis,
        )

    def _keep_log(self, log: UpdateLog, n_log: int) -> None:
        """Append the kernel's logged ZUPTs to :attr:`history`."""
        for (w, j, kind, ok), xs, Ps, nis in zip(
            log.index[:n_log], log.x, log.P, log.nis, strict=False
        ):
            self.history.append(
                UpdateRecord(
                    int(w),
                    int(self.sample[w] + j),
                    UPDATE_KINDS[kind],
                    xs[0].copy(),
                    Ps[0].copy(),
                    xs[1].copy(),
                    Ps[1].copy(),
                    float(nis),
                    bool(ok),
                )
            )

    def _block_result(
        self, out: BlockOutput, valid: NDArray[np.int64], record: str | None
    ) -> BlockResult:
        """Freeze the walkers that diverged in the block and hold their outputs at
        the frozen state from the sample of divergence on."""
        k = out.stance.shape[1]
        position, positions, states = out.position, out.positions, out.states
        newly = out.diverged_at <= k
        if newly.any():
            # frozen at the last posterior from the state where they diverged on
            self._freeze(np.flatnonzero(newly))
            held = newly & (out.diverged_at <= valid)
            position[held] = self.mean_position()[held]
            if record is not None:
                hold = np.arange(1, k + 1)[None, :] >= out.diverged_at[:, None]
                positions = np.where(hold[..., None], self.mean_position()[:, None, :], positions)
                if record == "state":
                    states = np.where(hold[..., None], self.mean_state()[:, None, :], states)
        return BlockResult(
            out.stance,
            out.start,
            out.end,
            out.accepted,
            out.nis_log_sum,
            position,
            positions if record is not None else None,
            states if record == "state" else None,
        )

    def _freeze(self, idx: NDArray[np.integer]) -> None:
        """Declare walkers diverged: they stay at their last posterior (finite)."""
        self.diverged[idx] = True
        x = np.nan_to_num(self.x[idx], nan=0.0, posinf=0.0, neginf=0.0)
        self.set_state(idx, x, repair_covariance(np.nan_to_num(self.P[idx]))[0])
        self.sig_v[idx] = 0.0

    # ------------------------------------------------------------------ queries
    def mean_state(self) -> Array:
        """Mean state ``(N, 9)`` of the propagated sigma points (no Q added)."""
        sig = dcm_to_state(self.sig_C, self.sig_v, self.sig_p)
        return state_mean(sig, self.weights.Wm)

    def mean_position(self) -> Array:
        """Mean IMU position ``(N, 3)`` (m) — cheap: positions are not angles."""
        return np.einsum("s,nsd->nd", self.weights.Wm, self.sig_p)

    def tallies(self) -> ZuptTallies:
        """Copies of the per-walker counts: updates, rejected, repairs, diverged."""
        return ZuptTallies(
            self.updates.copy(), self.rejected.copy(), self.repairs.copy(), self.diverged.copy()
        )

    def stance_statistic(self, omega_b: Array, f_b: Array) -> Array | None:
        """The SHOE statistic of records ``(B, T, 3)`` that :meth:`advance` needs when
        the detector is SHOE (:func:`pednav_env.nav.detectors.shoe_statistic`), or
        None for eq (5), which the kernel evaluates itself."""
        if not self.uses_shoe:
            return None
        return shoe_statistic(omega_b, f_b, self.config.detector, self.rate_hz)

    # ------------------------------------------------------------------ whole records
    def run(
        self, omega_b: Array, f_b: Array, record: bool = True, block_samples: int = RUN_BLOCK
    ) -> ZuptRun:
        """Align on the first ``alignment_s`` (the walker stands still), then filter
        the rest of the records ``(N, T, 3)``: navigation starts at t₀ = the end
        of the alignment, as in paper 003. The records are fed to :meth:`advance`
        in blocks of ``block_samples`` (the result depends on the blocking only
        through rounding)."""
        omega_b = np.asarray(omega_b, dtype=float)
        f_b = np.asarray(f_b, dtype=float)
        if omega_b.shape != f_b.shape or omega_b.ndim != 3 or omega_b.shape[0] != self.n:
            raise ValueError(
                f"omega_b and f_b must be ({self.n}, T, 3), got {omega_b.shape}, {f_b.shape}"
            )
        if not (np.isfinite(omega_b).all() and np.isfinite(f_b).all()):
            raise ValueError("omega_b/f_b contain NaN or inf")
        n_align = max(1, int(round(self.config.alignment_s * self.rate_hz)))
        t = omega_b.shape[1]
        if t < n_align:
            raise ValueError(f"record of {t} samples is shorter than the alignment window")
        self.initialize(f_b[:, :n_align], omega_align_b=omega_b[:, :n_align])
        self.sample[:] = n_align
        shoe = self.stance_statistic(omega_b, f_b)
        xs = np.empty((self.n, t + 1, STATE_DIM)) if record else np.empty((0,))
        stance = np.zeros((self.n, t), dtype=bool)
        if record:
            xs[:, : n_align + 1] = self.mean_state()[:, None, :]
        if block_samples < 1:
            raise ValueError(f"block_samples must be ≥ 1, got {block_samples!r}")
        for m0 in range(n_align, t, block_samples):
            m1 = min(m0 + block_samples, t)
            res = self.advance(
                omega_b[:, m0:m1],
                f_b[:, m0:m1],
                None if shoe is None else shoe[:, m0:m1],
                record="state" if record else None,
            )
            stance[:, m0:m1] = res.stance
            if record:
                xs[:, m0 + 1 : m1 + 1] = res.states
        return ZuptRun(xs, n_align, stance, *self.tallies(), self.P.copy())
