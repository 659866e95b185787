"""The zero-velocity-update unscented Kalman filter of paper 003, batched.

State (paper 003): y = [x₁, x₂, x₃, v₁, v₂, v₃, θ, γ, ψ], L = 9 — position and
velocity of the IMU in the navigation frame and pitch, roll, yaw. Process
function f: the strapdown (eq 3, :mod:`pednav_env.nav.strapdown`) integrated
from one correction instant to the next; corrections at every detected stance
start and stance end (eq 5 or SHOE) with

    h(y) = [x₃, v₁, v₂, v₃],   z = [x₃(t₀), 0, 0, 0]   (flat ground, zero velocity).

One engine for every walker: :class:`ZuptUkf` holds the sigma points of N
walkers, ``(N, 2L+1, ·)``, and :meth:`ZuptUkf.advance` moves all of them
through a block of K IMU samples (one decision interval of the env). Between
two ZUPTs a walker's sigma points only follow the strapdown, which is affine
in the starting state, so they are moved from their last redraw straight to
the next ZUPT by preintegrated increments of the walker's IMU record
(:mod:`pednav_env.nav.preintegration`), not sample by sample. The ZUPTs run
in rounds: every walker's first detected stance start or end of the block,
as one batched unscented update, then every walker's second, and so on; after
each round the detector is re-evaluated for the updated walkers, because
eq (5) reads the vertical specific force through the corrected attitude.
No Python loop runs over walkers or sigma points; :meth:`ZuptUkf.step` is
the same call with K = 1, and the result depends on the blocking only
through rounding (tested).

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
    DetectorPass,
    OnlineStanceDetector,
    ShoeDetectorConfig,
    ThresholdDetectorConfig,
)
from pednav_env.nav.preintegration import (
    Preintegrals,
    block_differences,
    preintegrate,
    relative_increments,
)
from pednav_env.nav.strapdown import advance_sigma, step_increments, step_increments_dcm
from pednav_env.nav.ukf import (
    MerweWeights,
    repair_covariance,
    sigma_points,
    update_linear,
)
from pednav_env.rotations import (
    euler_to_dcm,
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


def prior_moments(sigmas: Array, weights: MerweWeights, Q: Array) -> tuple[Array, Array]:
    """Unscented transform of sigma points ``(B, S, 9)`` with wrapped angles,
    plus process noise: the same mean and covariance as
    ``unscented_transform(sigmas, weights, Q, state_mean, state_residual)``
    (filterpy's ``x_mean_fn`` / ``residual_x``), with the residuals from the
    central point (as in :func:`state_mean`) computed once."""
    ref = sigmas[:, 0, :]
    d = state_residual(sigmas, ref[:, None, :])
    mean_d = np.matmul(weights.Wm, d)
    x = state_add(ref, mean_d)
    y = state_residual(d, mean_d[:, None, :])  # = sigmas − x, wrapped
    P = np.matmul(np.swapaxes(y * weights.Wc[:, None], -1, -2), y) + Q
    return x, P


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


def _diverging(C: Array, v: Array, p: Array) -> NDArray[np.bool_]:
    """Walkers ``(..., ·)`` (central sigma point) that have diverged: a non-finite
    state or a speed above :data:`DIVERGENCE_SPEED`."""
    speed2 = np.einsum("...i,...i->...", v, v)
    bad = ~np.isfinite(speed2) | (speed2 > DIVERGENCE_SPEED**2)
    return bad | ~np.isfinite(C).all(axis=(-2, -1)) | ~np.isfinite(p).all(axis=-1)


def state_to_dcm(y: Array) -> tuple[Array, Array, Array]:
    """(C_nb, v, x) from state vectors ``(..., 9)`` (the engine's sigma-point form;
    v and x are views into ``y``)."""
    return euler_to_dcm(y[..., [8, 6, 7]]), y[..., 3:6], y[..., 0:3]


def dcm_to_state(C_nb: Array, vel_n: Array, pos_n: Array) -> Array:
    """State vectors ``(..., 9)`` from attitude matrix, velocity and position."""
    y = np.empty(np.broadcast_shapes(C_nb.shape[:-2], vel_n.shape[:-1]) + (STATE_DIM,))
    y[..., 0:3], y[..., 3:6] = pos_n, vel_n
    # Euler angles of C_nb as in rotations.dcm_to_euler, written in place
    y[..., 6] = np.arcsin(np.clip(-C_nb[..., 2, 0], -1.0, 1.0))
    y[..., 7] = np.arctan2(C_nb[..., 2, 1], C_nb[..., 2, 2])
    y[..., 8] = np.arctan2(C_nb[..., 1, 0], C_nb[..., 0, 0])
    return y


def _vertical_row(C_central: Array, D_anchor: Array) -> Array:
    """Row r with f'_x3 = r · F_j for the block's samples after a redraw at
    ``D_anchor``: e₃ᵀ C_c D_aᵀ, i.e. D_a C_cᵀ e₃ (paper 003 eq 5's vertical
    specific force from the central sigma point's attitude C_c)."""
    return np.matmul(D_anchor, C_central[..., 2, :, None])[..., 0]


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
        self.sig_C[idx], self.sig_v[idx], self.sig_p[idx] = state_to_dcm(chi)
        self.elapsed_s[idx] = 0.0

    # ------------------------------------------------------------------ step
    def increments(self, omega_b: Array, f_b: Array) -> tuple[Array, Array, Array]:
        """Per-sample quantities shared by a walker's sigma points, for any
        number of samples at once: bias-corrected rate, attitude increment
        C(Δq) as a matrix, specific force at mid-interval attitude
        (``omega_b``/``f_b`` (N, ..., 3))."""
        bias = self.gyro_bias.reshape((self.n,) + (1,) * (omega_b.ndim - 2) + (3,))
        omega_c = omega_b - bias
        dC, f_mid = step_increments_dcm(omega_c, f_b, self.dt)
        return omega_c, dC, f_mid

    def step(
        self,
        omega_b: Array,
        f_b: Array,
        shoe_statistic: Array | None = None,
        increments: tuple[Array, Array, Array] | None = None,
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Advance all walkers by one IMU sample ``(N, 3)`` each (:meth:`advance`
        with one sample). Returns the detected (stance_start, stance_end) events."""
        if increments is not None:
            increments = tuple(x[:, None] for x in increments)  # type: ignore[assignment]
        res = self.advance(
            np.asarray(omega_b, dtype=float)[:, None],
            np.asarray(f_b, dtype=float)[:, None],
            None if shoe_statistic is None else np.asarray(shoe_statistic)[:, None],
            increments=increments,
        )
        return res.start[:, 0], res.end[:, 0]

    def advance(
        self,
        omega_b: Array,
        f_b: Array,
        shoe_statistic: Array | None = None,
        valid: NDArray[np.integer] | None = None,
        increments: tuple[Array, Array, Array] | None = None,
        record: str | None = None,
    ) -> BlockResult:
        """Advance all walkers through a block of K IMU samples ``(N, K, 3)``.

        The same filter as one sample at a time — detector, ZUPT at every
        detected stance start and end, strapdown of every sigma point between
        them — computed in a few batched passes (module docstring of
        :mod:`pednav_env.nav.preintegration`): the sigma points of a walker are
        moved to any sample of the block from its last redraw through the
        walker's preintegrated increments, and the updates of all walkers run
        together in rounds (every walker's first event of the block, then every
        walker's second, …). Walker ``i`` only processes its first ``valid[i]``
        samples' events (the rest is padding after the end of its record).
        ``record`` = ``"position"`` or ``"state"`` also returns the mean after
        every sample.
        """
        n = self.n
        if omega_b.ndim != 3 or omega_b.shape[0] != n or omega_b.shape[2] != 3:
            raise ValueError(f"omega_b must be ({n}, K, 3), got {omega_b.shape}")
        if f_b.shape != omega_b.shape:
            raise ValueError(f"f_b must have omega_b's shape {omega_b.shape}, got {f_b.shape}")
        if record not in (None, "position", "state"):
            raise ValueError(f"record must be None, 'position' or 'state', got {record!r}")
        k = omega_b.shape[1]
        dt = self.dt
        if increments is None:
            increments = self.increments(omega_b, f_b)
        omega_c, dC, f_mid = increments
        if self.uses_shoe and shoe_statistic is None:
            raise ValueError("the SHOE detector needs shoe_statistic for each sample")
        valid = np.full(n, k) if valid is None else np.asarray(valid, dtype=np.int64)
        if valid.shape != (n,) or valid.min() < 0 or valid.max() > k:
            raise ValueError(f"valid must be ({n},) sample counts in [0, {k}], got {valid!r}")
        frozen = self.diverged.copy()
        pre = preintegrate(dC, f_mid, dt, frozen)
        kidx = np.arange(k)
        boundaries = self.config.update_mode is UpdateMode.STANCE_BOUNDARIES
        anchor = np.zeros(n, dtype=np.int64)  # sample of each walker's last redraw
        anchor_elapsed = self.elapsed_s.copy()  # time since the redraw before that anchor
        next_from = np.zeros(n, dtype=np.int64)
        diverged_at = np.full(n, k + 1)  # state index t (after sample t−1); k+1 = none
        last_accepted = np.full(n, -1)
        nis_log_sum = np.zeros(n)
        accepted_count = np.zeros(n, dtype=np.int64)
        stance = np.zeros((n, k), dtype=bool)
        start = np.zeros((n, k), dtype=bool)
        end = np.zeros((n, k), dtype=bool)
        det = self.detector
        run_end = np.zeros(n, dtype=np.int64)
        hist_end = np.zeros_like(det.history)
        count_end = np.zeros(n, dtype=np.int64)
        anchors: list[tuple[NDArray[np.int64], NDArray[np.int64], Array, Array, Array]] = []
        if record is not None:
            start_sigmas = (self.sig_C.copy(), self.sig_v.copy(), self.sig_p.copy())
            anchors.append((np.arange(n), anchor.copy(), *start_sigmas))
        if self.uses_shoe:
            shoe_cond = np.asarray(shoe_statistic) <= self.shoe_threshold[:, None]
        else:
            omega_norm = np.sqrt(np.einsum("nki,nki->nk", omega_c, omega_c))
            # f'_x3 at sample j = e₃ᵀ C_c,j f_mid,j = r · F_j, with the row r from the
            # central sigma point's attitude at the walker's last redraw.
            r = _vertical_row(self.sig_C[:, 0], pre.D[:, 0])
            f_n3 = np.matmul(pre.F, r[:, :, None])[..., 0]
        todo = np.arange(n)
        while todo.size:
            if self.uses_shoe:
                res = det.evaluate_condition(todo, shoe_cond[todo], self.min_stance_s[todo])
            else:
                res = det.evaluate_threshold(
                    todo,
                    omega_norm[todo],
                    f_n3[todo],
                    self.omega_max[todo],
                    self.delta_f_max[todo],
                    self.min_stance_s[todo],
                )
            stance[todo], start[todo], end[todo] = res.stance, res.start, res.end
            run_end[todo], hist_end[todo], count_end[todo] = res.run, res.history, res.count
            ev = (res.start | res.end) if boundaries else (res.stance | res.end)
            ev &= (kidx >= next_from[todo, None]) & (kidx < valid[todo, None])
            ev &= ~frozen[todo, None]
            has = ev.any(axis=1)
            idx, e = todo[has], ev[has].argmax(axis=1)
            if idx.size == 0:
                break
            C, v, p = self._sigmas_at(idx, anchor[idx], e, pre)
            # A walker whose prior is non-finite or too fast diverged: no more ZUPTs.
            bad = _diverging(C[:, 0], v[:, 0], p[:, 0])
            if bad.any():
                diverged_at[idx[bad]] = e[bad]
                ok = ~bad
                idx, e, C, v, p = idx[ok], e[ok], C[ok], v[ok], p[ok]
                if idx.size == 0:
                    break
            elapsed = anchor_elapsed[idx] + (e - anchor[idx]) * dt
            kinds = (
                np.where(start[idx, e], "start", np.where(end[idx, e], "end", "stance"))
                if self.record_updates
                else None
            )
            accepted, nis = self._update(idx, C, v, p, elapsed, kinds, self.sample[idx] + e)
            anchor[idx], anchor_elapsed[idx], next_from[idx] = e, 0.0, e + 1
            nis_log_sum[idx] += np.where(accepted, np.log1p(nis), 0.0)
            accepted_count[idx] += accepted
            last_accepted[idx[accepted]] = e[accepted]
            if record is not None:
                anchors.append((idx, e.copy(), self.sig_C[idx], self.sig_v[idx], self.sig_p[idx]))
            if not self.uses_shoe:
                # samples after the ZUPT see the corrected attitude
                r = _vertical_row(self.sig_C[idx, 0], pre.D[idx, e])
                later = kidx[None, :] > e[:, None]
                f_new = np.matmul(pre.F[idx], r[:, :, None])[..., 0]
                f_n3[idx] = np.where(later, f_new, f_n3[idx])
            todo = idx
        det.commit(np.arange(n), DetectorPass(stance, start, end, run_end, hist_end, count_end))
        self.stance_starts += start.sum(axis=1)

        # Mean position after each walker's valid samples (computed here for walkers
        # whose record ends inside the block, below from the block's end for the
        # others), then the sigma points at the block's end (the next block's start).
        all_lanes = np.arange(n)
        position = np.empty((n, 3))
        short = all_lanes[valid < k]
        if short.size:
            _, _, p_valid = self._sigmas_at(short, anchor[short], valid[short], pre)
            position[short] = np.einsum("s,nsd->nd", self.weights.Wm, p_valid)
        live = ~frozen
        if live.any():
            lanes = all_lanes[live]
            # every sample after the last ZUPT: first non-finite or too fast state
            open_ = lanes[diverged_at[lanes] > k]
            v, p = self._central_track(open_, anchor[open_], pre)
            bad = _diverging(self.sig_C[open_, None, 0], v, p)
            bad &= np.arange(1, k + 1)[None, :] > anchor[open_, None]
            hit = bad.any(axis=1)
            diverged_at[open_[hit]] = bad[hit].argmax(axis=1) + 1
            C, v, p = self._sigmas_at(lanes, anchor[lanes], np.full(lanes.size, k), pre)
            self.sig_C[lanes], self.sig_v[lanes], self.sig_p[lanes] = C, v, p
        full = valid == k
        position[full] = np.einsum("s,nsd->nd", self.weights.Wm, self.sig_p[full])
        self.elapsed_s = anchor_elapsed + (k - anchor) * dt
        upd = last_accepted >= 0
        self.time_since_update_s = np.where(
            upd, (k - last_accepted) * dt, self.time_since_update_s + k * dt
        )
        self.sample += k
        newly = diverged_at <= k
        if newly.any():
            self._freeze(all_lanes[newly])
            frozen_pos = self.mean_position()
            held = newly & (diverged_at <= valid)
            position[held] = frozen_pos[held]
        positions = states = None
        if record is not None:
            positions, states = self._record(anchors, pre, k, record, diverged_at)
        return BlockResult(
            stance, start, end, accepted_count, nis_log_sum, position, positions, states
        )

    def _sigmas_at(
        self,
        lanes: NDArray[np.integer],
        anchor: NDArray[np.integer],
        t: NDArray[np.integer],
        pre: Preintegrals,
        sigmas: tuple[Array, Array, Array] | None = None,
    ) -> tuple[Array, Array, Array]:
        """Sigma points of walkers ``lanes`` at block sample ``t`` ((B,) or (B, T)),
        moved from their redraw at ``anchor`` (B,) by the preintegrals; from the
        current sigma points, or from ``sigmas`` (C, v, x of ``lanes``)."""
        D_rel, AB_rel, tau = relative_increments(pre, lanes, anchor, t, self.dt)
        if sigmas is None:
            sigmas = (self.sig_C[lanes], self.sig_v[lanes], self.sig_p[lanes])
        C0, v0, p0 = sigmas
        if np.ndim(t) == 2:
            C0, v0, p0 = C0[:, None], v0[:, None], p0[:, None]
        moved = np.matmul(C0, np.concatenate((D_rel, AB_rel), axis=-1)[..., None, :, :])
        C, rot = moved[..., :3], moved[..., 3:]  # C₀ D and C₀ [A B]: one matmul
        v = v0 + rot[..., 0]
        v[..., 2] -= self.config.g * tau[..., None]
        p = p0 + v0 * tau[..., None, None] + rot[..., 1]
        p[..., 2] -= 0.5 * self.config.g * (tau * tau)[..., None]
        return C, v, p

    def _central_track(
        self, lanes: NDArray[np.integer], anchor: NDArray[np.integer], pre: Preintegrals
    ) -> tuple[Array, Array]:
        """Velocity and position ``(B, K, 3)`` of the central sigma point after each
        sample of the block, moved from the redraw at ``anchor``: the attitude
        products C_c D_aᵀ are formed once per walker, not per sample."""
        k = pre.F.shape[1]
        t = np.broadcast_to(np.arange(1, k + 1), (len(lanes), k))
        Da, dA, dB, steps = block_differences(pre, lanes, anchor, t, self.dt)
        M_T = np.swapaxes(np.matmul(self.sig_C[lanes, 0], np.swapaxes(Da, -1, -2)), -1, -2)
        tau = steps * pre.tau_rate[lanes, None]
        g = self.config.g
        v0, p0 = self.sig_v[lanes, 0, None], self.sig_p[lanes, 0, None]
        v = v0 + np.matmul(dA, M_T)
        v[..., 2] -= g * tau
        p = p0 + v0 * tau[..., None] + np.matmul(dB, M_T)
        p[..., 2] -= 0.5 * g * tau * tau
        return v, p

    def _freeze(self, idx: NDArray[np.integer]) -> None:
        """Declare walkers diverged: they stay at their last posterior (finite)."""
        self.diverged[idx] = True
        x = np.nan_to_num(self.x[idx], nan=0.0, posinf=0.0, neginf=0.0)
        self.set_state(idx, x, repair_covariance(np.nan_to_num(self.P[idx]))[0])
        self.sig_v[idx] = 0.0

    def _record(
        self,
        anchors: list[tuple[NDArray[np.int64], NDArray[np.int64], Array, Array, Array]],
        pre: Preintegrals,
        k: int,
        record: str,
        diverged_at: NDArray[np.int64],
    ) -> tuple[Array, Array | None]:
        """Mean position (and state) after every sample of the block: each time
        from the walker's last redraw before it."""
        n = self.n
        positions = np.zeros((n, k, 3))
        states = np.zeros((n, k, STATE_DIM)) if record == "state" else None
        t_all = np.arange(1, k + 1)
        # owner[i, t-1] = the anchor set (round) whose redraw sample t of walker i follows
        owner = np.zeros((n, k), dtype=np.int64)
        for r, (lanes, a, *_) in enumerate(anchors):
            owner[lanes] = np.where(t_all[None, :] > a[:, None], r, owner[lanes])
        for r, (lanes, a, C0, v0, p0) in enumerate(anchors):
            i, t = np.nonzero(owner[lanes] == r)  # each sample is evaluated once
            if i.size == 0:
                continue
            t = t + 1
            C, v, p = self._sigmas_at(lanes[i], a[i], t, pre, sigmas=(C0[i], v0[i], p0[i]))
            positions[lanes[i], t - 1] = np.einsum("s,bsd->bd", self.weights.Wm, p)
            if states is not None:
                states[lanes[i], t - 1] = state_mean(dcm_to_state(C, v, p), self.weights.Wm)
        hold = t_all[None, :] >= diverged_at[:, None]  # held at the frozen posterior
        if hold.any():
            positions = np.where(hold[..., None], self.mean_position()[:, None, :], positions)
            if states is not None:
                states = np.where(hold[..., None], self.mean_state()[:, None, :], states)
        return positions, states

    def _update(
        self,
        idx: NDArray[np.integer],
        sig_C: Array,
        sig_v: Array,
        sig_p: Array,
        elapsed_s: Array,
        kinds: NDArray[np.str_] | None,
        sample: NDArray[np.integer],
    ) -> tuple[NDArray[np.bool_], Array]:
        """ZUPT of walkers ``idx`` from their propagated sigma points; redraws them."""
        c = self.config
        W = self.weights
        sig = dcm_to_state(sig_C, sig_v, sig_p)
        Q = process_noise(
            c.assumed_imu, self.rate_hz, elapsed_s, self.process_noise_scale[idx], self.q_basis
        )
        x_prior, P_prior = prior_moments(sig, W, Q)
        z = np.zeros((len(idx), 4))
        z[:, 0] = self.height_ref[idx]
        R = self.zupt_noise_base * self.zupt_noise_scale[idx, None, None]
        # h is linear: the update on prior sigma points is the Kalman update (update_linear).
        res = update_linear(x_prior, P_prior, MEASURED, z, R, state_add, self.gate_nis)
        self.updates[idx] += res.accepted
        self.rejected[idx] += ~res.accepted
        self.last_nis[idx] = res.nis
        self.set_state(idx, res.x, res.P)
        if kinds is not None:
            for j, w in enumerate(idx):
                self.history.append(
                    UpdateRecord(
                        int(w),
                        int(sample[j]),
                        str(kinds[j]),
                        x_prior[j].copy(),
                        P_prior[j].copy(),
                        res.x[j].copy(),
                        res.P[j].copy(),
                        float(res.nis[j]),
                        bool(res.accepted[j]),
                    )
                )
        return res.accepted, res.nis

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
