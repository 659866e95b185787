"""The zero-velocity-update unscented Kalman filter of paper 003, batched.

State (paper 003): y = [x₁, x₂, x₃, v₁, v₂, v₃, θ, γ, ψ], L = 9 — position and
velocity of the IMU in the navigation frame and pitch, roll, yaw. Process
function f: the strapdown (eq 3, :mod:`pednav_env.nav.strapdown`) integrated
from one correction instant to the next; corrections at every detected stance
start and stance end (eq 5 or SHOE) with

    h(y) = [x₃, v₁, v₂, v₃],   z = [x₃(t₀), 0, 0, 0]   (flat ground, zero velocity).

One engine for every walker: :class:`ZuptUkf` holds the sigma points of N
walkers, ``(N, 2L+1, ·)``, and :meth:`ZuptUkf.step` advances all of them by
one IMU sample in a single chain of numpy calls. Walkers whose stance starts
or ends at that sample get their prediction closed (unscented transform plus
process noise for the elapsed interval) and their ZUPT update, together, as
one batched update; the others keep integrating. No Python loop runs over
walkers or sigma points.

Choices the paper leaves open (docs/REPRODUCTION.md):

- process noise Q for an interval τ from the filter's *assumed* IMU model:
  velocity random walk q_v = σ_f² Δt (σ_f per sample), Q_xx = q_v τ³/3,
  Q_xv = q_v τ²/2, Q_vv = q_v τ; attitude q_θ = σ_ω² Δt, Q_θθ = q_θ τ plus the
  gyro drift, (σ_ν τ)² per gait step or σ_ν² Δt τ per sample, plus turn-on
  biases as (σ_b τ)² terms; all times ``process_noise_scale``. The paper's
  printed P⁻ has no Q at all;
- ZUPT noise R = diag(σ_h², σ_v², σ_v², σ_v²) · ``zupt_noise_scale`` with
  σ_h = σ_v = 0.01 (m, m/s);
- like filterpy 2.0 (the oracle), the measurement step uses sigma points
  redrawn from the prior (which includes Q), not the propagated ones the
  paper prints (which would leave Q out of S); with the linear h the update
  is then exactly the Kalman update on the unscented prior, which is how it
  is computed (:func:`pednav_env.nav.ukf.update_linear`, no second draw);
- optional χ² gating of a ZUPT on its NIS (off in the paper scenario).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.alignment import align_static
from pednav_env.nav.detectors import (
    DetectorConfig,
    OnlineStanceDetector,
    ShoeDetectorConfig,
    ThresholdDetectorConfig,
)
from pednav_env.nav.strapdown import advance_sigma, step_increments
from pednav_env.nav.ukf import (
    MerweWeights,
    repair_covariance,
    sigma_points,
    unscented_transform,
    update_linear,
)
from pednav_env.rotations import euler_to_quat, quat_rotate, quat_to_euler, wrap_angle
from pednav_env.sensors.imu import DriftModel, ImuSpec

Array = NDArray[np.float64]

STATE_DIM = 9
#: State layout of paper 003: position, velocity, pitch θ, roll γ, yaw ψ.
STATE_NAMES = ("x1", "x2", "x3", "v1", "v2", "v3", "pitch", "roll", "yaw")
ANGLES = slice(6, 9)
#: Indices of h(y) = [x₃, v₁, v₂, v₃].
MEASURED = [2, 3, 4, 5]
#: Velocity norm beyond which a walker is declared diverged (m/s).
DIVERGENCE_SPEED = 50.0


# --------------------------------------------------------------------------- model functions
def state_residual(a: Array, b: Array) -> Array:
    """a − b with wrapped angle differences (filterpy's ``residual_x``)."""
    d = np.asarray(a, dtype=float) - b
    d[..., ANGLES] = wrap_angle(d[..., ANGLES])
    return d


def state_add(x: Array, dx: Array) -> Array:
    """x + dx with wrapped angles (filterpy's ``state_add``)."""
    y = np.asarray(x, dtype=float) + dx
    y[..., ANGLES] = wrap_angle(y[..., ANGLES])
    return y


def state_mean(sigmas: Array, Wm: Array) -> Array:
    """Weighted mean of sigma points ``(..., S, 9)``; angles averaged as wrapped
    deviations from the central point (filterpy's ``x_mean_fn``)."""
    sigmas = np.asarray(sigmas, dtype=float)
    ref = sigmas[..., 0, :]
    d = state_residual(sigmas, ref[..., None, :])
    return state_add(ref, np.einsum("s,...sd->...d", Wm, d))


def state_to_nav(y: Array) -> tuple[Array, Array, Array]:
    """(q_nb, v, x) from state vectors ``(..., 9)``."""
    euler = np.stack((y[..., 8], y[..., 6], y[..., 7]), axis=-1)
    return euler_to_quat(euler), y[..., 3:6].copy(), y[..., 0:3].copy()


def nav_to_state(q_nb: Array, vel_n: Array, pos_n: Array) -> Array:
    """State vectors ``(..., 9)`` from attitude, velocity and position."""
    e = quat_to_euler(q_nb)
    return np.concatenate((pos_n, vel_n, e[..., 1:2], e[..., 2:3], e[..., 0:1]), axis=-1)


def propagate_state(
    y: Array, omega_b: Array, f_b: Array, rate_hz: float, g: float = STANDARD_GRAVITY
) -> Array:
    """Process function f: integrate states ``(B, S, 9)`` through IMU samples
    ``(B, M, 3)`` (paper 003: f = integration of eq 3 over the interval)."""
    dt = 1.0 / rate_hz
    q, v, p = state_to_nav(y)
    dqT, f_mid = step_increments(omega_b, f_b, dt)
    for m in range(omega_b.shape[1]):
        q, v, p = advance_sigma(q, v, p, dqT[:, m], f_mid[:, m], dt, g)
    return nav_to_state(q, v, p)


def measure(y: Array) -> Array:
    """h(y) = [x₃, v₁, v₂, v₃] (paper 003)."""
    return y[..., MEASURED]


class UpdateMode(StrEnum):
    """When ZUPTs are applied."""

    #: At each detected stance start and stance end (paper 003).
    STANCE_BOUNDARIES = "stance_boundaries"
    #: At every sample of a detected stance (common practice, e.g. OpenShoe).
    EVERY_STANCE_SAMPLE = "every_stance_sample"


@dataclass(frozen=True)
class ZuptUkfConfig:
    """Configuration of the ZUPT-UKF; defaults = paper 003's simulation."""

    detector: DetectorConfig = field(default_factory=ThresholdDetectorConfig)
    #: The filter's assumed IMU model, source of Q (paper 003's sensor).
    assumed_imu: ImuSpec = field(default_factory=ImuSpec.paper003)
    alpha: float = 1e-3  # paper 003: a ~ 1e-3
    beta: float = 0.0  # paper 003 prints W0c = λ/(λ+L) + (1 − a²), i.e. β = 0
    kappa: float = 0.0  # paper 003: λ = a²L − L
    zupt_height_std: float = 0.01  # m, not printed
    zupt_velocity_std: float = 0.01  # m/s, not printed
    process_noise_scale: float = 1.0
    zupt_noise_scale: float = 1.0
    update_mode: UpdateMode = UpdateMode.STANCE_BOUNDARIES
    #: χ² gate probability for ZUPTs (None = no gate, paper 003).
    gate_probability: float | None = None
    initial_position_std: float = 1e-3  # m: the start position is known
    initial_velocity_std: float = 1e-2  # m/s: standing still
    initial_tilt_std: float = 1e-2  # rad: eq (4) from noisy data
    initial_yaw_std: float = 1e-3  # rad: ψ = 0 defines the frame
    #: Static alignment window at the start (s); paper 003 eq (4).
    alignment_s: float = 1.0
    #: Subtract the mean gyro reading of the alignment window from every later
    #: sample (paper 003's real-data calibration, "b_ω = ⟨ω''⟩ before walking").
    #: Off for the paper's simulation, whose drift changes every step.
    calibrate_gyro_bias: bool = False
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        object.__setattr__(self, "update_mode", UpdateMode(self.update_mode))
        for name in (
            "alpha",
            "zupt_height_std",
            "zupt_velocity_std",
            "process_noise_scale",
            "zupt_noise_scale",
            "initial_position_std",
            "initial_velocity_std",
            "initial_tilt_std",
            "initial_yaw_std",
            "alignment_s",
            "g",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"ZuptUkfConfig.{name} must be a finite number > 0, got {v!r}")
        if not math.isfinite(self.beta):
            raise ValueError(f"ZuptUkfConfig.beta must be finite, got {self.beta!r}")
        if self.gate_probability is not None and not (0 < self.gate_probability < 1):
            raise ValueError(
                f"ZuptUkfConfig.gate_probability must be in (0, 1), got {self.gate_probability!r}"
            )
        MerweWeights(STATE_DIM, self.alpha, self.beta, self.kappa)  # validates α, κ

    @property
    def weights(self) -> MerweWeights:
        return MerweWeights(STATE_DIM, self.alpha, self.beta, self.kappa)


def process_noise(spec: ImuSpec, rate_hz: float, elapsed_s: Array, scale: Array) -> Array:
    """Q ``(B, 9, 9)`` for intervals ``elapsed_s`` ``(B,)`` (see module docstring)."""
    tau = np.asarray(elapsed_s, dtype=float)
    dt = 1.0 / rate_hz
    q_v = spec.accel_noise_std(rate_hz) ** 2 * dt
    q_th = spec.gyro_noise_std(rate_hz) ** 2 * dt
    if spec.drift_model is DriftModel.PER_GAIT_STEP:
        drift = (spec.gyro_step_drift_std * tau) ** 2
    else:
        drift = spec.gyro_step_drift_std**2 * dt * tau
    ang = q_th * tau + drift + (spec.gyro_bias_std * tau) ** 2
    ang = ang + spec.gyro_bias_rw_density**2 * tau**3 / 3
    vv = q_v * tau + (spec.accel_bias_std * tau) ** 2 + spec.accel_bias_rw_density**2 * tau**3 / 3
    xx = q_v * tau**3 / 3 + (0.5 * spec.accel_bias_std * tau**2) ** 2
    xv = q_v * tau**2 / 2 + 0.5 * spec.accel_bias_std**2 * tau**3
    Q = np.zeros(tau.shape + (STATE_DIM, STATE_DIM))
    i3 = np.arange(3)
    Q[:, i3, i3] = xx[:, None]
    Q[:, i3 + 3, i3 + 3] = vv[:, None]
    Q[:, i3, i3 + 3] = xv[:, None]
    Q[:, i3 + 3, i3] = xv[:, None]
    Q[:, i3 + 6, i3 + 6] = ang[:, None]
    return Q * np.asarray(scale, dtype=float)[:, None, None]


@dataclass
class UpdateRecord:
    """One ZUPT of one walker (kept when ``record_updates`` is on)."""

    walker: int
    sample: int
    kind: str  # "start", "end" or "stance"
    x_prior: Array
    P_prior: Array
    x: Array
    P: Array
    nis: float
    accepted: bool


@dataclass
class ZuptRun:
    """Output of :meth:`ZuptUkf.run` over whole records."""

    x: Array  # (N, T+1, 9) mean state on the sample grid (held at x₀ during alignment)
    start_sample: int  # first sample filtered (= alignment window length)
    stance: NDArray[np.bool_]  # (N, T) detected stance per sample
    updates: NDArray[np.int64]  # (N,) ZUPTs applied
    rejected: NDArray[np.int64]  # (N,) ZUPTs rejected by the gate
    repairs: NDArray[np.int64]  # (N,) covariance repairs
    diverged: NDArray[np.bool_]  # (N,)
    P_final: Array  # (N, 9, 9)


class ZuptUkf:
    """Batched ZUPT-UKF of paper 003 for N walkers.

    Tunable per walker, at any time (the agent's knobs): ``omega_max``,
    ``delta_f_max`` (eq-5 detector) or ``shoe_threshold``, ``min_stance_s``,
    ``process_noise_scale``, ``zupt_noise_scale`` — arrays of shape (N,).
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
        self.n = int(num_walkers)
        self.weights = config.weights
        self.num_sigmas = 2 * STATE_DIM + 1
        self.detector = OnlineStanceDetector(config.detector, self.rate_hz, self.n)
        self.uses_shoe = isinstance(config.detector, ShoeDetectorConfig)
        self.gate_nis = (
            None if config.gate_probability is None else float(chi2.ppf(config.gate_probability, 4))
        )
        det = config.detector
        n = self.n
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
        self.sig_q = np.zeros((n, self.num_sigmas, 4))
        self.sig_q[..., 0] = 1.0
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
        self.detector.reset(None if mask is None else mask)
        self.height_ref[idx] = 0.0
        for arr in (self.sample, self.updates, self.rejected, self.repairs, self.stance_starts):
            arr[idx] = 0
        self.diverged[idx] = False
        self.last_nis[idx] = 0.0
        self.time_since_update_s[idx] = 0.0

    def set_state(self, idx: NDArray[np.integer], x: Array, P: Array) -> None:
        """Set mean and covariance of walkers ``idx`` and draw their sigma points."""
        chi, bad = sigma_points(x, P, self.weights, add_fn=state_add)
        self.repairs[idx] += bad
        self.x[idx], self.P[idx] = x, P
        self.sig_q[idx], self.sig_v[idx], self.sig_p[idx] = state_to_nav(chi)
        self.elapsed_s[idx] = 0.0

    # ------------------------------------------------------------------ step
    def increments(self, omega_b: Array, f_b: Array) -> tuple[Array, Array, Array]:
        """Per-sample quantities shared by a walker's sigma points, for any
        number of samples at once: bias-corrected rate, Δq matrix, specific
        force at mid-interval attitude (``omega_b``/``f_b`` (N, ..., 3))."""
        bias = self.gyro_bias.reshape((self.n,) + (1,) * (omega_b.ndim - 2) + (3,))
        omega_c = omega_b - bias
        dqT, f_mid = step_increments(omega_c, f_b, self.dt)
        return omega_c, dqT, f_mid

    def step(
        self,
        omega_b: Array,
        f_b: Array,
        shoe_statistic: Array | None = None,
        increments: tuple[Array, Array, Array] | None = None,
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Advance all walkers by one IMU sample ``(N, 3)`` each.

        ``increments`` may carry :meth:`increments` of this sample, computed
        ahead for many samples at once. Returns the detected (stance_start,
        stance_end) events of this sample.
        """
        if increments is None:
            increments = self.increments(omega_b, f_b)
        omega_b, dqT, f_mid = increments
        if self.uses_shoe:
            if shoe_statistic is None:
                raise ValueError("the SHOE detector needs shoe_statistic for each sample")
            cond = shoe_statistic <= self.shoe_threshold
        else:
            f_n3 = quat_rotate(self.sig_q[:, 0], f_mid)[:, 2]
            omega_norm = np.sqrt(np.einsum("ni,ni->n", omega_b, omega_b))
            cond = self.detector.condition_threshold(
                omega_norm, f_n3, self.omega_max, self.delta_f_max
            )
        start, end = self.detector.advance(cond, self.min_stance_s)
        self.stance_starts += start
        if self.config.update_mode is UpdateMode.STANCE_BOUNDARIES:
            event = start | end
        else:
            event = self.detector.in_stance | end
        event &= ~self.diverged
        if event.any():
            idx = np.flatnonzero(event)
            kinds = np.where(start[idx], "start", np.where(end[idx], "end", "stance"))
            self._update(idx, kinds)
        q, v, p = advance_sigma(
            self.sig_q, self.sig_v, self.sig_p, dqT, f_mid, self.dt, self.config.g
        )
        if self.diverged.any():  # diverged walkers stay frozen where they were declared so
            frozen = self.diverged[:, None, None]
            q = np.where(frozen, self.sig_q, q)
            v = np.where(frozen, self.sig_v, v)
            p = np.where(frozen, self.sig_p, p)
        self.sig_q, self.sig_v, self.sig_p = q, v, p
        self.elapsed_s += self.dt
        self.time_since_update_s += self.dt
        self.sample += 1
        self._check_divergence()
        return start, end

    def _check_divergence(self) -> None:
        # The central sigma point stands for the walker: sigma points are drawn
        # within a few mm of it, and a non-finite one reaches it at the next update.
        v0 = self.sig_v[:, 0]
        speed2 = np.einsum("ni,ni->n", v0, v0)
        bad = ~np.isfinite(speed2) | (speed2 > DIVERGENCE_SPEED**2)
        bad |= ~np.isfinite(self.sig_q[:, 0]).all(axis=1) | ~np.isfinite(self.sig_p[:, 0]).all(
            axis=1
        )
        new = bad & ~self.diverged
        if new.any():
            self.diverged |= new
            # Freeze diverged walkers at a finite state so nothing downstream sees NaN.
            idx = np.flatnonzero(new)
            x = np.nan_to_num(self.x[idx], nan=0.0, posinf=0.0, neginf=0.0)
            self.set_state(idx, x, repair_covariance(np.nan_to_num(self.P[idx]))[0])
            self.sig_v[idx] = 0.0

    def _update(self, idx: NDArray[np.integer], kinds: NDArray[np.str_]) -> None:
        c = self.config
        W = self.weights
        sig = nav_to_state(self.sig_q[idx], self.sig_v[idx], self.sig_p[idx])
        Q = process_noise(
            c.assumed_imu, self.rate_hz, self.elapsed_s[idx], self.process_noise_scale[idx]
        )
        x_prior, P_prior = unscented_transform(sig, W, Q, state_mean, state_residual)
        b = len(idx)
        z = np.zeros((b, 4))
        z[:, 0] = self.height_ref[idx]
        r = (
            np.array(
                [c.zupt_height_std, c.zupt_velocity_std, c.zupt_velocity_std, c.zupt_velocity_std]
            )
            ** 2
        )
        R = np.zeros((b, 4, 4))
        R[:, np.arange(4), np.arange(4)] = r[None, :] * self.zupt_noise_scale[idx, None]
        # h is linear: the update on prior sigma points is the Kalman update (update_linear).
        res = update_linear(x_prior, P_prior, MEASURED, z, R, state_add, self.gate_nis)
        self.updates[idx] += res.accepted
        self.rejected[idx] += ~res.accepted
        self.last_nis[idx] = res.nis
        self.time_since_update_s[idx[res.accepted]] = 0.0
        self.set_state(idx, res.x, res.P)
        if self.record_updates:
            for j, w in enumerate(idx):
                self.history.append(
                    UpdateRecord(
                        int(w),
                        int(self.sample[w]),
                        str(kinds[j]),
                        x_prior[j].copy(),
                        P_prior[j].copy(),
                        res.x[j].copy(),
                        res.P[j].copy(),
                        float(res.nis[j]),
                        bool(res.accepted[j]),
                    )
                )

    # ------------------------------------------------------------------ queries
    def mean_state(self) -> Array:
        """Mean state ``(N, 9)`` of the propagated sigma points (no Q added)."""
        sig = nav_to_state(self.sig_q, self.sig_v, self.sig_p)
        return state_mean(sig, self.weights.Wm)

    def mean_position(self) -> Array:
        """Mean IMU position ``(N, 3)`` (m) — cheap: positions are not angles."""
        return np.einsum("s,nsd->nd", self.weights.Wm, self.sig_p)

    # ------------------------------------------------------------------ whole records
    def run(self, omega_b: Array, f_b: Array, record: bool = True) -> ZuptRun:
        """Align on the first ``alignment_s`` (the walker stands still), then filter
        the rest of the records ``(N, T, 3)``: navigation starts at t₀ = the end
        of the alignment, as in paper 003."""
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
        shoe = None
        if self.uses_shoe:
            from pednav_env.nav.detectors import shoe_statistic

            shoe = shoe_statistic(omega_b, f_b, self.config.detector, self.rate_hz)
        xs = np.empty((self.n, t + 1, STATE_DIM)) if record else np.empty((0,))
        stance = np.zeros((self.n, t), dtype=bool)
        if record:
            xs[:, : n_align + 1] = self.mean_state()[:, None, :]
        for m in range(n_align, t):
            self.step(omega_b[:, m], f_b[:, m], None if shoe is None else shoe[:, m])
            stance[:, m] = self.detector.in_stance
            if record:
                xs[:, m + 1] = self.mean_state()
        return ZuptRun(
            xs,
            n_align,
            stance,
            self.updates.copy(),
            self.rejected.copy(),
            self.repairs.copy(),
            self.diverged.copy(),
            self.P.copy(),
        )
