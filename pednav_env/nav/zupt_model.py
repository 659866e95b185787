"""The state-space model of paper 003's ZUPT-UKF, in numpy.

State y = [x₁, x₂, x₃, v₁, v₂, v₃, θ, γ, ψ], L = 9: position (m) and velocity
(m/s) of the IMU in the navigation frame, pitch, roll and yaw (rad). Process
function f: the strapdown of eq (3) (:mod:`pednav_env.nav.strapdown`)
integrated over the interval between two corrections; measurement function
of a zero-velocity update on flat ground

    h(y) = [x₃, v₁, v₂, v₃],   z = [x₃(t₀), 0, 0, 0].

Angles are averaged and differenced with wrapping (filterpy's ``x_mean_fn``,
``residual_x``, ``state_add``). These functions serve the filterpy reference
implementations and the engine's queries; the engine's own arithmetic is the
compiled kernel (:mod:`pednav_env.nav.zupt_kernel`), checked against them.

Process noise Q for an interval τ from the filter's *assumed* IMU model
(paper 003 prints no Q): velocity random walk q_v = σ_f² Δt (σ_f per sample),
Q_xx = q_v τ³/3, Q_xv = q_v τ²/2, Q_vv = q_v τ; attitude q_θ = σ_ω² Δt,
Q_θθ = q_θ τ plus the gyro drift, (σ_ν τ)² per gait step or σ_ν² Δt τ per
sample, plus turn-on biases as (σ_b τ)² terms — a polynomial in τ
(:func:`process_noise_basis`) times a per-walker scale.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.strapdown import advance_sigma, step_increments
from pednav_env.rotations import (
    dcm_euler_angles,
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


def dcm_to_state(C_nb: Array, vel_n: Array, pos_n: Array) -> Array:
    """State vectors ``(..., 9)`` from attitude matrix, velocity and position."""
    y = np.empty(np.broadcast_shapes(C_nb.shape[:-2], vel_n.shape[:-1]) + (STATE_DIM,))
    y[..., 0:3], y[..., 3:6] = pos_n, vel_n
    C = C_nb
    y[..., 8], y[..., 6], y[..., 7] = dcm_euler_angles(
        C[..., 0, 0], C[..., 1, 0], C[..., 2, 0], C[..., 2, 1], C[..., 2, 2]
    )
    return y


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


def process_noise_basis(spec: ImuSpec, rate_hz: float) -> Array:
    """Q(τ) = Σ_{p=1..4} τᵖ M_p: the constant matrices M_p ``(4, 9, 9)`` of the
    process noise (module docstring), a polynomial in the interval τ."""
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
