"""Paper 003's lever-arm kinematics of the foot IMU at one instant, compiled.

The IMU's sensitive mass M sits at the lever arm r_OM from the heel O in foot
axes (paper 003, the formulas after Fig. 6)::

    x   = B_zxᵀ r_OM + r_CO
    v_x = B_zxᵀ (ω × r_OM) + ṙ_CO
    a_x = B_zxᵀ (ω × ω × r_OM + ω̇ × r_OM) + r̈_CO
    f_z = B_zx a_x − B_zx g_x

Component by component on scalars, every sum in the order in which
:mod:`pednav_env.rotations` and numpy's cross/einsum evaluate it. An operand
typed ``None`` is an exact zero (an angle or rate that vanishes identically in
a phase of the walk, a zero lever-arm component): the term algebra
(:func:`_mul`, :func:`_add`, :func:`_sub`, :func:`_neg`) drops, at compile
time, the operations it would enter (x·0, x + 0 = x, 0 − x = −x), so such a
phase compiles to fewer operations and gets the same values as the full
formulas (at most a zero's sign differs). An exact one (the cosine of an angle
that is exactly zero) is passed as 1.0: x·1 = x exactly.

These functions are compiled into :mod:`pednav_env.gait.foot_kernels`, whose
numba cache checks that module's file only: after editing this one, delete
``pednav_env/gait/__pycache__/foot_kernels.*.nb[ic]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit, types
from numba.extending import overload

Term = float | None
Vec = tuple[Term, Term, Term]


def _mul(a: Term, b: Term) -> Term:
    """a·b; None (an exact zero) if a factor is."""
    return None if a is None or b is None else a * b


def _add(a: Term, b: Term) -> Term:
    """a + b, an exact zero (None) skipped."""
    if a is None:
        return b
    return a if b is None else a + b


def _sub(a: Term, b: Term) -> Term:
    """a − b, an exact zero (None) skipped: 0 − b = −b."""
    if b is None:
        return a
    return _neg(b) if a is None else a - b


def _neg(a: Term) -> Term:
    """−a (None stays None)."""
    return None if a is None else -a


def _value(a: Term) -> float:
    """The number: 0.0 for an exact zero (None)."""
    return 0.0 if a is None else a


# Compiled term algebra: a numba type decides at compile time. (The typing
# functions' parameters must match their implementations', annotations included.)
def _zero(t: types.Type) -> bool:
    """An operand typed None: an exact zero."""
    return isinstance(t, types.NoneType)


@overload(_mul)
def _mul_compiled(a, b) -> Callable:
    if _zero(a) or _zero(b):
        return lambda a, b: None
    return lambda a, b: a * b


@overload(_add)
def _add_compiled(a, b) -> Callable:
    if _zero(a):
        return lambda a, b: b
    if _zero(b):
        return lambda a, b: a
    return lambda a, b: a + b


@overload(_sub)
def _sub_compiled(a, b) -> Callable:
    if _zero(b):
        return lambda a, b: a
    if _zero(a):
        return lambda a, b: -b
    return lambda a, b: a - b


@overload(_neg)
def _neg_compiled(a) -> Callable:
    if _zero(a):
        return lambda a: None
    return lambda a: -a


@overload(_value)
def _value_compiled(a) -> Callable:
    if _zero(a):
        return lambda a: 0.0
    return lambda a: a


@njit(cache=True)
def dcm(sin_e: Vec, cos_e: Vec) -> tuple[Term, ...]:
    """C_nb = B_zxᵀ = R_z(ψ) R_y(θ) R_x(γ) (paper 003 eq 1), row-major 9-tuple,
    from the sines and cosines of ψ, θ, γ."""
    sy, sp, sr = sin_e
    cy, cp, cr = cos_e
    cysp = _mul(cy, sp)
    sysp = _mul(sy, sp)
    return (
        _mul(cy, cp),
        _sub(_mul(cysp, sr), _mul(sy, cr)),
        _add(_mul(cysp, cr), _mul(sy, sr)),
        _mul(sy, cp),
        _add(_mul(sysp, sr), _mul(cy, cr)),
        _sub(_mul(sysp, cr), _mul(cy, sr)),
        _neg(sp),
        _mul(cp, sr),
        _mul(cp, cr),
    )


@njit(cache=True)
def _rotate(C: tuple[Term, ...], v: Vec) -> Vec:
    """C v (body → navigation); sums (term 0 + term 2) + term 1 like numpy's einsum."""
    return (
        _add(_add(_mul(C[0], v[0]), _mul(C[2], v[2])), _mul(C[1], v[1])),
        _add(_add(_mul(C[3], v[0]), _mul(C[5], v[2])), _mul(C[4], v[1])),
        _add(_add(_mul(C[6], v[0]), _mul(C[8], v[2])), _mul(C[7], v[1])),
    )


@njit(cache=True)
def _rotate_transposed(C: tuple[Term, ...], v: Vec) -> Vec:
    """Cᵀ v (navigation → body)."""
    return (
        _add(_add(_mul(C[0], v[0]), _mul(C[3], v[1])), _mul(C[6], v[2])),
        _add(_add(_mul(C[1], v[0]), _mul(C[4], v[1])), _mul(C[7], v[2])),
        _add(_add(_mul(C[2], v[0]), _mul(C[5], v[1])), _mul(C[8], v[2])),
    )


@njit(cache=True)
def _cross(a: Vec, b: Vec) -> Vec:
    """a × b."""
    return (
        _sub(_mul(a[1], b[2]), _mul(a[2], b[1])),
        _sub(_mul(a[2], b[0]), _mul(a[0], b[2])),
        _sub(_mul(a[0], b[1]), _mul(a[1], b[0])),
    )


@njit(cache=True)
def body_rates(de: Vec, sin_e: Vec, cos_e: Vec) -> Vec:
    """ω from the Euler rates ``de`` (paper 003): ω₁ = γ̇ − ψ̇ sin θ,
    ω₂ = θ̇ cos γ + ψ̇ cos θ sin γ, ω₃ = −θ̇ sin γ + ψ̇ cos θ cos γ."""
    dy, dp, dr = de
    sp, sr = sin_e[1], sin_e[2]
    cp, cr = cos_e[1], cos_e[2]
    dycp = _mul(dy, cp)
    return (
        _sub(dr, _mul(dy, sp)),
        _add(_mul(dp, cr), _mul(dycp, sr)),
        _add(_neg(_mul(dp, sr)), _mul(dycp, cr)),
    )


@njit(cache=True)
def _body_angular_acceleration(de: Vec, dde: Vec, sin_e: Vec, cos_e: Vec) -> Vec:
    """ω̇, the time derivative of :func:`body_rates` (``dde`` the Euler accelerations)."""
    dy, dp, dr = de
    ay, ap, ar = dde
    sp, sr = sin_e[1], sin_e[2]
    cp, cr = cos_e[1], cos_e[2]
    dydp = _mul(dy, dp)
    dpdr = _mul(dp, dr)
    aycp = _mul(ay, cp)
    dydpsp = _mul(dydp, sp)
    dydrcp = _mul(_mul(dy, dr), cp)
    w1 = _sub(_sub(ar, _mul(ay, sp)), _mul(dydp, cp))
    w2 = _sub(_mul(ap, cr), _mul(dpdr, sr))
    w2 = _add(_sub(_add(w2, _mul(aycp, sr)), _mul(dydpsp, sr)), _mul(dydrcp, cr))
    w3 = _sub(_neg(_mul(ap, sr)), _mul(dpdr, cr))
    w3 = _sub(_sub(_add(w3, _mul(aycp, cr)), _mul(dydpsp, cr)), _mul(dydrcp, sr))
    return w1, w2, w3


@njit(cache=True)
def imu_position(heel: Vec, C: tuple[Term, ...], r: Vec) -> tuple[float, float, float]:
    """x = B_zxᵀ r_OM + r_CO, from the heel position ``heel`` and C = :func:`dcm`."""
    c = _rotate(C, r)
    return _value(_add(heel[0], c[0])), _value(_add(heel[1], c[1])), _value(_add(heel[2], c[2]))


@njit(cache=True)
def imu_velocity(
    heel_rate: Vec, C: tuple[Term, ...], omega: Vec, r: Vec
) -> tuple[float, float, float]:
    """v_x = B_zxᵀ (ω × r_OM) + ṙ_CO (``omega`` from :func:`body_rates`)."""
    c = _rotate(C, _cross(omega, r))
    return (
        _value(_add(heel_rate[0], c[0])),
        _value(_add(heel_rate[1], c[1])),
        _value(_add(heel_rate[2], c[2])),
    )


@njit(cache=True)
def imu_acceleration(heel_acc: Vec, C: tuple[Term, ...], omega: Vec, omega_dot: Vec, r: Vec) -> Vec:
    """a_x = B_zxᵀ (ω × ω × r_OM + ω̇ × r_OM) + r̈_CO."""
    wwr = _cross(omega, _cross(omega, r))
    wdr = _cross(omega_dot, r)
    rel = (_add(wwr[0], wdr[0]), _add(wwr[1], wdr[1]), _add(wwr[2], wdr[2]))
    c = _rotate(C, rel)
    return _add(heel_acc[0], c[0]), _add(heel_acc[1], c[1]), _add(heel_acc[2], c[2])


@njit(cache=True)
def imu_readings(
    heel_acc: Vec, de: Vec, dde: Vec, sin_e: Vec, cos_e: Vec, r: Vec, g: float
) -> tuple[float, float, float, float, float, float]:
    """Body rate ω and specific force f_z = B_zx (a_x − g_x), g_x = (0, 0, −g), at one
    instant: ``heel_acc`` is r̈_CO, ``de`` and ``dde`` the Euler rates and accelerations."""
    C = dcm(sin_e, cos_e)
    omega = body_rates(de, sin_e, cos_e)
    acc = imu_acceleration(heel_acc, C, omega, _body_angular_acceleration(de, dde, sin_e, cos_e), r)
    f = _rotate_transposed(C, (acc[0], acc[1], _add(acc[2], g)))
    return (
        _value(omega[0]),
        _value(omega[1]),
        _value(omega[2]),
        _value(f[0]),
        _value(f[1]),
        _value(f[2]),
    )


@njit(cache=True)
def lever_arm_rows(
    heel: np.ndarray, euler: np.ndarray, r: tuple[float, float, float], g: float, out: np.ndarray
) -> None:
    """IMU position, velocity, acceleration, body rate and specific force of M points.

    ``heel`` (3, 3, M): r_CO, ṙ_CO, r̈_CO rows; ``euler`` (3, 3, M): ψ, θ, γ,
    their rates and accelerations; ``out`` (5, 3, M) receives x, v_x, a_x, ω, f_z.
    """
    for m in range(heel.shape[2]):
        e = euler[0, :, m]
        sin_e = (math.sin(e[0]), math.sin(e[1]), math.sin(e[2]))
        cos_e = (math.cos(e[0]), math.cos(e[1]), math.cos(e[2]))
        de = (euler[1, 0, m], euler[1, 1, m], euler[1, 2, m])
        dde = (euler[2, 0, m], euler[2, 1, m], euler[2, 2, m])
        C = dcm(sin_e, cos_e)
        omega = body_rates(de, sin_e, cos_e)
        omega_dot = _body_angular_acceleration(de, dde, sin_e, cos_e)
        h = heel[:, :, m]
        pos = imu_position((h[0, 0], h[0, 1], h[0, 2]), C, r)
        vel = imu_velocity((h[1, 0], h[1, 1], h[1, 2]), C, omega, r)
        acc = imu_acceleration((h[2, 0], h[2, 1], h[2, 2]), C, omega, omega_dot, r)
        f = _rotate_transposed(C, (acc[0], acc[1], acc[2] + g))
        for i in range(3):
            out[0, i, m] = pos[i]
            out[1, i, m] = vel[i]
            out[2, i, m] = acc[i]
            out[3, i, m] = omega[i]
            out[4, i, m] = f[i]
