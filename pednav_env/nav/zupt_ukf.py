"""The zero-velocity-update unscented Kalman filter of paper 003, batched.

State (paper 003): y = [x₁, x₂, x₃, v₁, v₂, v₃, θ, γ, ψ], L = 9 — position and
velocity of the IMU in the navigation frame and pitch, roll, yaw. Process
function f: the strapdown (eq 3, :mod:`pednav_env.nav.strapdown`) integrated
from one correction instant to the next; corrections at every detected stance
start and stance end (eq 5 or SHOE) with

    h(y) = [x₃, v₁, v₂, v₃],   z = [x₃(t₀), 0, 0, 0]   (flat ground, zero velocity).

One engine for every walker: :class:`ZuptUkf` holds the sigma points of N
walkers, ``(N, 2L+1, ·)``, and :meth:`ZuptUkf.advance` moves all of them
through a block of K IMU samples (one decision interval of the env) in one
call of the compiled kernel :func:`pednav_env.nav.zupt_kernel.advance_block`,
which runs walker after walker, sample after sample. Between two ZUPTs a
walker's sigma points only follow the strapdown, which is affine in the
starting state, so they are moved from their last redraw straight to the next
ZUPT by preintegrated increments of the walker's IMU record, not sample by
sample (the kernel's module docstring). After a ZUPT the detector reads the
vertical specific force of eq (5) through the corrected attitude.
:meth:`ZuptUkf.step` is the same call with K = 1, and the result depends on
the blocking only through rounding (tested).

Divergence (a non-finite state or a speed above :data:`DIVERGENCE_SPEED` of
the central sigma point) is checked on the prior of every ZUPT and at every
sample after a walker's last ZUPT of the block; a diverged walker gets no more
ZUPTs and is frozen at its last posterior.

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
  is computed (no second draw; the filterpy oracle test checks the equality);
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
from pednav_env.nav.ukf import MerweWeights, repair_covariance
from pednav_env.nav.zupt_kernel import advance_block, redraw_sigmas
from pednav_env.rotations import (
    euler_to_quat,
    quat_to_euler,
    wrap_angle,
)
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
#: Samples per :meth:`ZuptUkf.advance` call in :meth:`ZuptUkf.run`.
RUN_BLOCK = 100


# --------------------------------------------------------------------------- model functions
def _wrap_angles_inplace(y: Array) -> None:
    """Wrap the angle entries of states ``(..., 9)`` into [−π, π), in place;
    a no-op check when they already are (the usual case for residuals)."""
    a = y[..., ANGLES]
    if a.size and (a.max() >= np.pi or a.min() < -np.pi):
        y[..., ANGLES] = wrap_angle(a)


def state_residual(a: Array, b: Array) -> Array:
    """a − b with wrapped angle differences (filterpy's ``residual_x``)."""
    d = np.asarray(a, dtype=float) - b
    _wrap_angles_inplace(d)
    return d


def state_add(x: Array, dx: Array) -> Array:
    """x + dx with wrapped angles (filterpy's ``state_add``)."""
    y = np.asarray(x, dtype=float) + dx
    _wrap_angles_inplace(y)
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


def process_noise_basis(spec: ImuSpec, rate_hz: float) -> Array:
    """Q(τ) = Σ_{p=1..4} τᵖ M_p: the constant matrices M_p ``(4, 9, 9)`` of the
    process noise below (module docstring), a polynomial in the interval τ."""
    dt = 1.0 / rate_hz
    q_v = spec.accel_noise_std(rate_hz) ** 2 * dt
    q_th = spec.gyro_noise_std(rate_hz) ** 2 * dt
    ba2, bg2 = spec.accel_bias_std**2, spec.gyro_bias_std**2
    drift2 = spec.gyro_step_drift_std**2
    per_step = spec.drift_model is DriftModel.PER_GAIT_STEP
    # coefficients of τ, τ², τ³, τ⁴
    ang = (
        q_th + (0.0 if per_step else drift2 * dt),
        bg2 + (drift2 if per_step else 0.0),
        spec.gyro_bias_rw_density**2 / 3,
        0.0,
    )
    vv = (q_v, ba2, spec.accel_bias_rw_density**2 / 3, 0.0)
    xx = (0.0, 0.0, q_v / 3, ba2 / 4)
    xv = (0.0, q_v / 2, ba2 / 2, 0.0)
    M = np.zeros((4, STATE_DIM, STATE_DIM))
    i3 = np.arange(3)
    for p in range(4):
        M[p, i3, i3] = xx[p]
        M[p, i3 + 3, i3 + 3] = vv[p]
        M[p, i3, i3 + 3] = M[p, i3 + 3, i3] = xv[p]
        M[p, i3 + 6, i3 + 6] = ang[p]
    return M


def process_noise(
    spec: ImuSpec,
    rate_hz: float,
    elapsed_s: Array,
    scale: Array,
    basis: Array | None = None,
) -> Array:
    """Q ``(B, 9, 9)`` for intervals ``elapsed_s`` ``(B,)`` (see module docstring);
    ``basis`` = :func:`process_noise_basis` of the same spec, if computed ahead."""
    tau = np.asarray(elapsed_s, dtype=float)
    if basis is None:
        basis = process_noise_basis(spec, rate_hz)
    powers = tau[:, None] ** np.arange(1, 5) * np.asarray(scale, dtype=float)[:, None]
    # Only the entries of the basis' pattern are formed, elementwise (not a BLAS
    # product: a walker's Q must not depend on the batch size).
    rows, cols = np.nonzero(basis.any(axis=0))
    Q = np.zeros(tau.shape + (STATE_DIM, STATE_DIM))
    Q[:, rows, cols] = (powers[:, :, None] * basis[:, rows, cols]).sum(axis=1)
    return Q


@dataclass
class UpdateRecord:
    """One ZUPT of one walker (kept when ``record_updates`` is on; within a block the
    records come walker by walker, each walker's in time order)."""

    walker: int
    sample: int
    kind: str  # "start", "end" or "stance"
    x_prior: Array
    P_prior: Array
    x: Array
    P: Array
    nis: float
    accepted: bool


@dataclass(frozen=True)
class BlockResult:
    """Output of :meth:`ZuptUkf.advance` over a block of K samples."""

    stance: NDArray[np.bool_]  # (N, K) detected stance after each sample
    start: NDArray[np.bool_]  # (N, K) stance declared at the sample
    end: NDArray[np.bool_]  # (N, K) stance ended at the sample
    accepted: NDArray[np.int64]  # (N,) ZUPTs applied in the block
    nis_log_sum: Array  # (N,) Σ log(1 + NIS) of those ZUPTs
    position: Array  # (N, 3) mean position (m) after each walker's valid samples
    positions: Array | None  # (N, K, 3) mean position after each sample (record)
    states: Array | None  # (N, K, 9) mean state after each sample (record="state")


def dcm_to_state(C_nb: Array, vel_n: Array, pos_n: Array) -> Array:
    """State vectors ``(..., 9)`` from attitude matrix, velocity and position."""
    y = np.empty(np.broadcast_shapes(C_nb.shape[:-2], vel_n.shape[:-1]) + (STATE_DIM,))
    y[..., 0:3], y[..., 3:6] = pos_n, vel_n
    # Euler angles of C_nb as in rotations.dcm_to_euler, written in place
    y[..., 6] = np.arcsin(np.clip(-C_nb[..., 2, 0], -1.0, 1.0))
    y[..., 7] = np.arctan2(C_nb[..., 2, 1], C_nb[..., 2, 2])
    y[..., 8] = np.arctan2(C_nb[..., 1, 0], C_nb[..., 0, 0])
    return y


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
        self.q_basis = process_noise_basis(config.assumed_imu, self.rate_hz)
        #: R at zupt_noise_scale = 1: diag(σ_h², σ_v², σ_v², σ_v²).
        self.zupt_noise_base = np.diag(
            np.array([config.zupt_height_std] + [config.zupt_velocity_std] * 3) ** 2
        )
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
        self._Wm, self._Wc = self.weights.Wm, self.weights.Wc
        self._kernel_params = np.array(
            [
                self.dt,
                config.g,
                det.g,
                np.inf if self.gate_nis is None else self.gate_nis,
                float(self.uses_shoe),
                float(config.update_mode is UpdateMode.STANCE_BOUNDARIES),
                STATE_DIM + self.weights.lam,
                DIVERGENCE_SPEED,
            ]
        )

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
        idx = np.asarray(idx, dtype=np.int64)
        x = np.ascontiguousarray(x, dtype=float)
        P = np.ascontiguousarray(P, dtype=float)
        spread = STATE_DIM + self.weights.lam
        bad = redraw_sigmas(idx, x, P, spread, self.sig_C, self.sig_v, self.sig_p)
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
        lane_params = np.empty((n, 6))
        lane_params[:, 0] = self.omega_max
        lane_params[:, 1] = self.delta_f_max
        lane_params[:, 2] = self.process_noise_scale
        lane_params[:, 3] = self.zupt_noise_base[0, 0] * self.zupt_noise_scale
        lane_params[:, 4] = self.zupt_noise_base[1, 1] * self.zupt_noise_scale
        lane_params[:, 5] = self.height_ref
        stance = np.zeros((n, k), dtype=bool)
        start = np.zeros((n, k), dtype=bool)
        end = np.zeros((n, k), dtype=bool)
        accepted = np.zeros(n, dtype=np.int64)
        nis_log_sum = np.zeros(n)
        position = np.empty((n, 3))
        diverged_at = np.empty(n, dtype=np.int64)
        last_accepted = np.empty(n, dtype=np.int64)
        positions = np.empty((n, k, 3) if record is not None else (0, 0, 3))
        states = np.empty((n, k, STATE_DIM) if record == "state" else (0, 0, STATE_DIM))
        logs = n * k if self.record_updates else 0
        log_index = np.zeros((logs, 4), dtype=np.int64)
        log_x = np.empty((logs, 2, STATE_DIM))
        log_P = np.empty((logs, 2, STATE_DIM, STATE_DIM))
        log_nis = np.empty(logs)
        counters = np.stack((self.updates, self.rejected, self.repairs), axis=1)
        frozen = self.diverged.copy()
        n_log = advance_block(
            omega_b,
            f_b,
            shoe_cond,
            valid,
            frozen,
            self._kernel_params,
            lane_params,
            self.detector.min_samples(self.min_stance_s),
            self.gyro_bias,
            self.q_basis,
            self._Wm,
            self._Wc,
            self.sig_C,
            self.sig_v,
            self.sig_p,
            self.x,
            self.P,
            self.elapsed_s,
            self.detector.history,
            self.detector.count,
            self.detector.run,
            self.detector.in_stance,
            counters,
            self.last_nis,
            stance,
            start,
            end,
            accepted,
            nis_log_sum,
            position,
            diverged_at,
            last_accepted,
            positions,
            states,
            log_index,
            log_x,
            log_P,
            log_nis,
        )
        self.updates[:], self.rejected[:], self.repairs[:] = counters.T
        self.stance_starts += start.sum(axis=1)
        upd = last_accepted >= 0
        self.time_since_update_s = np.where(
            upd, (k - last_accepted) * self.dt, self.time_since_update_s + k * self.dt
        )
        if n_log:
            kinds = ("start", "end", "stance")
            for (w, j, kind, ok), xs, Ps, nis in zip(
                log_index[:n_log], log_x, log_P, log_nis, strict=False
            ):
                self.history.append(
                    UpdateRecord(
                        int(w),
                        int(self.sample[w] + j),
                        kinds[kind],
                        xs[0].copy(),
                        Ps[0].copy(),
                        xs[1].copy(),
                        Ps[1].copy(),
                        float(nis),
                        bool(ok),
                    )
                )
        self.sample += k
        newly = diverged_at <= k
        if newly.any():
            # frozen at the last posterior from the state where they diverged on
            self._freeze(np.flatnonzero(newly))
            held = newly & (diverged_at <= valid)
            position[held] = self.mean_position()[held]
            if record is not None:
                hold = np.arange(1, k + 1)[None, :] >= diverged_at[:, None]
                positions = np.where(hold[..., None], self.mean_position()[:, None, :], positions)
                if record == "state":
                    states = np.where(hold[..., None], self.mean_state()[:, None, :], states)
        return BlockResult(
            stance,
            start,
            end,
            accepted,
            nis_log_sum,
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
        shoe = None
        if self.uses_shoe:
            from pednav_env.nav.detectors import shoe_statistic

            shoe = shoe_statistic(omega_b, f_b, self.config.detector, self.rate_hz)
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
