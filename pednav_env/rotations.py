"""Attitude algebra, batched over any leading axes.

Conventions (docs/CONVENTIONS.md): navigation frame east-north-up; body frame x
forward, y left, z up; quaternions ``q_nb`` rotate body vectors into the
navigation frame, scalar first, Hamilton product. Euler angles are paper
003's yaw ψ, pitch θ, roll γ in the 3-2-1 order (its eq 1)::

    B_zx = B(γ) B(θ) B(ψ)   (navigation → body),   C_nb = B_zxᵀ = R_z(ψ) R_y(θ) R_x(γ)

With y pointing left, positive pitch θ turns the nose (toes) down, which is
why paper 003's alignment reads f₁ = −g sin θ (its eq 4).

:func:`wrap_float`, :func:`euler_dcm_rows` and :func:`dcm_euler_angles` use
only arithmetic and numpy ufuncs, so numba compiles the very same functions
for the scalar code of the ZUPT kernel (:mod:`pednav_env.nav.zupt_kernel`):
one implementation, the same results bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def wrap_angle(angle: ArrayLike) -> Array:
    """Wrap angles (rad) into [−π, π): :func:`wrap_float` of the input as float64."""
    return wrap_float(np.asarray(angle, dtype=float))


def wrap_float(a: Array) -> Array:
    """Wrap float64 angles (rad, a scalar or an array) into [−π, π), no conversion:
    a − 2π ⌊(a + π)/2π⌋ (the same as (a + π) mod 2π − π, several times faster than
    fmod). Numba compiles this function for the ZUPT kernel's scalars."""
    return a - (2.0 * np.pi) * np.floor((a + np.pi) * (0.5 / np.pi))


def euler_to_quat(euler: ArrayLike) -> Array:
    """Quaternion ``q_nb`` from Euler angles ``[..., (ψ, θ, γ)]`` (rad), 3-2-1 order.

    ``q_nb = q_z(ψ) ⊗ q_y(θ) ⊗ q_x(γ)``, paper 003 eq (1).
    """
    e = np.asarray(euler, dtype=float)
    half = 0.5 * e
    cy, sy = np.cos(half[..., 0]), np.sin(half[..., 0])
    cp, sp = np.cos(half[..., 1]), np.sin(half[..., 1])
    cr, sr = np.cos(half[..., 2]), np.sin(half[..., 2])
    return np.stack(
        (
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        ),
        axis=-1,
    )


def quat_to_euler(q: ArrayLike) -> Array:
    """Euler angles ``[..., (ψ, θ, γ)]`` (rad) of a unit quaternion ``q_nb``.

    Pitch is clipped to [−π/2, π/2]; yaw and roll are in (−π, π].
    """
    q = np.asarray(q, dtype=float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return np.stack((yaw, pitch, roll), axis=-1)


def euler_to_dcm(euler: ArrayLike) -> Array:
    """Direction cosine matrix ``C_nb`` (body → navigation), shape ``(..., 3, 3)``.

    ``C_nb = B_zxᵀ`` with paper 003's elementary rotations B(γ), B(θ), B(ψ).
    """
    e = np.asarray(euler, dtype=float)
    c, s = np.cos(e), np.sin(e)  # one call each for the three angles
    rows = euler_dcm_rows(c[..., 0], s[..., 0], c[..., 1], s[..., 1], c[..., 2], s[..., 2])
    C = np.empty(e.shape[:-1] + (3, 3))
    for r in range(3):
        for col in range(3):
            C[..., r, col] = rows[r][col]
    return C


def euler_dcm_rows(
    cos_yaw: Array,
    sin_yaw: Array,
    cos_pitch: Array,
    sin_pitch: Array,
    cos_roll: Array,
    sin_roll: Array,
) -> tuple[tuple[Array, Array, Array], ...]:
    """Rows of ``C_nb = R_z(ψ) R_y(θ) R_x(γ)`` (paper 003 eq 1) from the cosines and
    sines of ψ, θ, γ: the one formula behind :func:`euler_to_dcm` (arrays) and the
    ZUPT kernel's sigma-point attitudes (numba compiles it for scalars)."""
    cy, sy, cp, sp, cr, sr = cos_yaw, sin_yaw, cos_pitch, sin_pitch, cos_roll, sin_roll
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def dcm_euler_angles(
    c00: Array, c10: Array, c20: Array, c21: Array, c22: Array
) -> tuple[Array, Array, Array]:
    """(ψ, θ, γ) (rad) of ``C_nb`` from its entries C₀₀, C₁₀, C₂₀, C₂₁, C₂₂, 3-2-1 order:
    ψ = atan2(C₁₀, C₀₀), θ = asin(−C₂₀) (argument clipped to [−1, 1]),
    γ = atan2(C₂₁, C₂₂). The one formula behind :func:`dcm_to_euler` (arrays) and
    the ZUPT kernel's sigma-point angles (numba compiles it for scalars)."""
    yaw = np.arctan2(c10, c00)
    pitch = np.arcsin(np.minimum(np.maximum(-c20, -1.0), 1.0))
    roll = np.arctan2(c21, c22)
    return yaw, pitch, roll


def dcm_to_euler(C: ArrayLike) -> Array:
    """Euler angles ``[..., (ψ, θ, γ)]`` (rad) of ``C_nb`` ``(..., 3, 3)``, 3-2-1 order
    (the inverse of :func:`euler_to_dcm`; same conventions as :func:`quat_to_euler`)."""
    C = np.asarray(C, dtype=float)
    angles = dcm_euler_angles(C[..., 0, 0], C[..., 1, 0], C[..., 2, 0], C[..., 2, 1], C[..., 2, 2])
    return np.stack(angles, axis=-1)


def quat_to_dcm(q: ArrayLike) -> Array:
    """``C_nb`` of a unit quaternion ``q_nb``, shape ``(..., 3, 3)``."""
    q = np.asarray(q, dtype=float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    C = np.empty(q.shape[:-1] + (3, 3))
    C[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    C[..., 0, 1] = 2.0 * (x * y - w * z)
    C[..., 0, 2] = 2.0 * (x * z + w * y)
    C[..., 1, 0] = 2.0 * (x * y + w * z)
    C[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    C[..., 1, 2] = 2.0 * (y * z - w * x)
    C[..., 2, 0] = 2.0 * (x * z - w * y)
    C[..., 2, 1] = 2.0 * (y * z + w * x)
    C[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return C


def quat_multiply(p: ArrayLike, q: ArrayLike) -> Array:
    """Hamilton product ``p ⊗ q`` (broadcasting over leading axes)."""
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    pw, px, py, pz = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qw, qx, qy, qz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        (
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ),
        axis=-1,
    )


def right_product_matrix(p: ArrayLike) -> Array:
    """Matrix ``M`` with ``q ⊗ p = M q`` (for batched matmul propagation)."""
    p = np.asarray(p, dtype=float)
    w, x, y, z = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    M = np.empty(p.shape[:-1] + (4, 4))
    M[..., 0, :] = np.stack((w, -x, -y, -z), axis=-1)
    M[..., 1, :] = np.stack((x, w, z, -y), axis=-1)
    M[..., 2, :] = np.stack((y, -z, w, x), axis=-1)
    M[..., 3, :] = np.stack((z, y, -x, w), axis=-1)
    return M


def quat_from_rotvec(k: ArrayLike) -> Array:
    """Δq = [cos(|k|/2), k/|k| sin(|k|/2)] for a rotation vector k (rad), paper 003 eq (3)."""
    k = np.asarray(k, dtype=float)
    angle = np.sqrt(np.sum(k * k, axis=-1))
    half = 0.5 * angle
    # sin(|k|/2)/|k| → 1/2 − |k|²/48 as |k| → 0 (series keeps full precision).
    small = angle < 1e-6
    safe = np.where(small, 1.0, angle)
    scale = np.where(small, 0.5 - angle * angle / 48.0, np.sin(half) / safe)
    return np.concatenate((np.cos(half)[..., None], k * scale[..., None]), axis=-1)


def quat_rotate(q: ArrayLike, v: ArrayLike) -> Array:
    """Rotate body vectors ``v`` into the navigation frame: ``C(q) v``.

    Uses ``t = 2 u × v``, ``v' = v + w t + u × t`` (u, w the vector and scalar
    parts), broadcasting ``v`` against ``q``'s leading axes.
    """
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    w, ux, uy, uz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    vx, vy, vz = v[..., 0], v[..., 1], v[..., 2]
    tx = 2.0 * (uy * vz - uz * vy)
    ty = 2.0 * (uz * vx - ux * vz)
    tz = 2.0 * (ux * vy - uy * vx)
    return np.stack(
        (
            vx + w * tx + uy * tz - uz * ty,
            vy + w * ty + uz * tx - ux * tz,
            vz + w * tz + ux * ty - uy * tx,
        ),
        axis=-1,
    )


def body_rates_from_euler(euler: ArrayLike, euler_rate: ArrayLike) -> Array:
    """Body angular rate ω (rad/s) from Euler angles and their rates.

    Paper 003: ω_z = B(γ)B(θ) ψ̇ e₃ + B(γ) θ̇ e₂ + γ̇ e₁, i.e.
    ω₁ = γ̇ − ψ̇ sin θ, ω₂ = θ̇ cos γ + ψ̇ cos θ sin γ, ω₃ = −θ̇ sin γ + ψ̇ cos θ cos γ.
    """
    e = np.asarray(euler, dtype=float)
    d = np.asarray(euler_rate, dtype=float)
    sp, cp = np.sin(e[..., 1]), np.cos(e[..., 1])
    sr, cr = np.sin(e[..., 2]), np.cos(e[..., 2])
    dy, dp, dr = d[..., 0], d[..., 1], d[..., 2]
    return np.stack((dr - dy * sp, dp * cr + dy * cp * sr, -dp * sr + dy * cp * cr), axis=-1)


def body_angular_acceleration_from_euler(
    euler: ArrayLike, euler_rate: ArrayLike, euler_acc: ArrayLike
) -> Array:
    """Time derivative ω̇ (rad/s², body axes) of :func:`body_rates_from_euler`."""
    e = np.asarray(euler, dtype=float)
    d = np.asarray(euler_rate, dtype=float)
    a = np.asarray(euler_acc, dtype=float)
    sp, cp = np.sin(e[..., 1]), np.cos(e[..., 1])
    sr, cr = np.sin(e[..., 2]), np.cos(e[..., 2])
    dy, dp, dr = d[..., 0], d[..., 1], d[..., 2]
    ay, ap, ar = a[..., 0], a[..., 1], a[..., 2]
    w1 = ar - ay * sp - dy * dp * cp
    w2 = ap * cr - dp * dr * sr + ay * cp * sr - dy * dp * sp * sr + dy * dr * cp * cr
    w3 = -ap * sr - dp * dr * cr + ay * cp * cr - dy * dp * sp * cr - dy * dr * cp * sr
    return np.stack((w1, w2, w3), axis=-1)
