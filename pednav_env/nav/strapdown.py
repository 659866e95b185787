"""Strapdown mechanisation of paper 003, eq (3), batched over leading axes.

Continuous model: q̇ = ½ q ⊗ (0, ω'), ẋ = v, v̇ = C_nb f' + g_vec. Discrete
form, sample m covering [t_m, t_m + Δt] (the IMU reports the mean rate and
specific force over that interval):

- attitude: q_{m+1} = q_m ⊗ Δq,  Δq = [cos|k/2|, k/|k| sin|k/2|],  k = ω'Δt
  (paper 003's Δq; with ``q_nb`` body→navigation the increment multiplies on
  the right, the same rotation as the paper's Δq ⊙ q for q navigation→body);
- velocity: v_{m+1} = v_m + (C(q_m ⊗ Δq(k/2)) f' + g_vec) Δt — the specific
  force rotated with the mid-interval attitude (rotation compensation; a
  midpoint rule), which makes the scheme second order in Δt;
- position: x_{m+1} = x_m + ½ (v_m + v_{m+1}) Δt (trapezoid).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.rotations import (
    quat_from_rotvec,
    quat_multiply,
    quat_rotate,
    right_product_matrix,
)

Array = NDArray[np.float64]


def rotation_compensated_force(omega_b: Array, f_b: Array, dt: float) -> Array:
    """Δq(½ω'Δt) f' Δq(½ω'Δt)*: the mean specific force expressed in the body
    axes of mid-interval, so that C(q_m) times it is a midpoint rule for
    ∫ C(t) f(t) dt / Δt."""
    return quat_rotate(quat_from_rotvec(np.asarray(omega_b, dtype=float) * (0.5 * dt)), f_b)


def strapdown_step(
    q_nb: Array,
    vel_n: Array,
    pos_n: Array,
    omega_b: Array,
    f_b: Array,
    dt: float,
    g: float = STANDARD_GRAVITY,
) -> tuple[Array, Array, Array]:
    """Advance attitude, velocity and position by one IMU sample.

    ``q_nb`` (..., 4), ``vel_n``/``pos_n`` (..., 3); ``omega_b``/``f_b`` (..., 3)
    broadcast against the state's leading axes (e.g. one measurement per walker
    shared by all of its sigma points).
    """
    dq = quat_from_rotvec(np.asarray(omega_b, dtype=float) * dt)
    f_mid = rotation_compensated_force(omega_b, f_b, dt)
    acc_n = quat_rotate(q_nb, f_mid)
    acc_n[..., 2] -= g
    vel_next = vel_n + acc_n * dt
    pos_next = pos_n + (vel_n + vel_next) * (0.5 * dt)
    return quat_multiply(q_nb, dq), vel_next, pos_next


def advance_sigma(
    q_nb: Array, vel_n: Array, pos_n: Array, dq_matrix_T: Array, f_mid: Array, dt: float, g: float
) -> tuple[Array, Array, Array]:
    """Hot-path step for ``S`` states per walker (e.g. sigma points).

    ``q_nb`` (N, S, 4), ``vel_n``/``pos_n`` (N, S, 3); per-walker precomputed
    ``dq_matrix_T`` (N, 4, 4) = Mᵀ with q ⊗ Δq = M q, and compensated specific
    force ``f_mid`` (N, 3). Same arithmetic as :func:`strapdown_step`.
    """
    acc_n = quat_rotate(q_nb, f_mid[:, None, :])
    acc_n[..., 2] -= g
    vel_next = vel_n + acc_n * dt
    pos_next = pos_n + (vel_n + vel_next) * (0.5 * dt)
    return np.matmul(q_nb, dq_matrix_T), vel_next, pos_next


def step_increments(omega_b: Array, f_b: Array, dt: float) -> tuple[Array, Array]:
    """Per-sample quantities shared by all states of a walker: (Mᵀ of Δq, f_mid)."""
    dq_matrix_T = np.swapaxes(right_product_matrix(quat_from_rotvec(omega_b * dt)), -1, -2)
    return dq_matrix_T, rotation_compensated_force(omega_b, f_b, dt)


def integrate(
    q0: Array,
    v0: Array,
    p0: Array,
    omega_b: Array,
    f_b: Array,
    dt: float,
    g: float = STANDARD_GRAVITY,
) -> tuple[Array, Array, Array]:
    """Integrate a whole record.

    Parameters
    ----------
    q0, v0, p0 : (N, 4), (N, 3), (N, 3)
        Initial attitude ``q_nb``, velocity (m/s) and position (m).
    omega_b, f_b : (N, T, 3)
        Measured angular rate (rad/s) and specific force (m/s²).

    Returns
    -------
    q, v, p : (N, T+1, 4), (N, T+1, 3), (N, T+1, 3)
        States at t_0 … t_T.
    """
    omega_b = np.asarray(omega_b, dtype=float)
    f_b = np.asarray(f_b, dtype=float)
    if omega_b.ndim != 3 or omega_b.shape != f_b.shape or omega_b.shape[-1] != 3:
        raise ValueError(f"omega_b and f_b must be (N, T, 3), got {omega_b.shape}, {f_b.shape}")
    if not dt > 0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    n, t, _ = omega_b.shape
    dq_matrix_T, f_mid = step_increments(omega_b, f_b, dt)
    q = np.empty((n, t + 1, 1, 4))
    v = np.empty((n, t + 1, 1, 3))
    p = np.empty((n, t + 1, 1, 3))
    q[:, 0, 0], v[:, 0, 0], p[:, 0, 0] = q0, v0, p0
    for m in range(t):
        q[:, m + 1], v[:, m + 1], p[:, m + 1] = advance_sigma(
            q[:, m], v[:, m], p[:, m], dq_matrix_T[:, m], f_mid[:, m], dt, g
        )
    return q[:, :, 0], v[:, :, 0], p[:, :, 0]
