"""Compiled evaluation of a simulated foot walk (:mod:`pednav_env.gait.foot`).

A walk is one piecewise cubic in time of the heel position x, y, z and the
Euler angles ψ, θ, γ (``scipy.interpolate.PPoly``'s layout), plus, on
realistic routes, the stance roll-over and micro-motion and the heel-strike
transients (module docstring of :mod:`pednav_env.gait.foot`).
:func:`simulate_walk` evaluates it time after time, in one pass over the
sorted times of a walk: the states on the sample grid and the ideal IMU
readings, the 2-point Gauss–Legendre means over every sample interval,
through paper 003's lever-arm formulas (:mod:`pednav_env.gait.lever_arm`).
:func:`gait_labels` and :func:`cumulative_distance` label the samples and
measure the distance walked.

Every value is computed with the operations, in the order, of the plain
formulas evaluated with numpy: PPoly's power sum, numpy's complex128 product
(with fused multiply-adds, as numpy computes it on x86-64 CPUs with FMA), the
realism terms as written, glibc's sin, cos and exp (numpy's too on such
builds); the exact zeros of each kind of piece are typed None
(:mod:`pednav_env.gait.lever_arm`), which changes no value.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from pednav_env.gait.foot_route import Gait
from pednav_env.gait.lever_arm import (
    body_rates,
    dcm,
    imu_position,
    imu_readings,
    imu_velocity,
)
from pednav_env.gait.stance_motion import stance_motion

Vec3 = tuple[float, float, float]

#: Kinds of spline piece, each with its own exact zeros: stances (heel pose
#: constant and level: only realism moves the foot, about the pitch axis and
#: the heel; γ ≡ 0, ψ̇ ≡ 0), straight moving phases (ψ̇ ≡ 0) and turns.
STANCE, STRAIGHT, TURNING = 0, 1, 2

#: Heel-strike transient B·Im[s² e^{λs}], s = (t − t_hs)/τ: time constant τ
#: (s) and complex exponent λ.
HS_TAU = 0.012
HS_LAMBDA = complex(-1.0, 3.0)


def _hs_unit_peak() -> float:
    """max |d²/ds² Im[s² e^{λs}]| over the transient: B scales it to the peak acceleration."""
    s = np.linspace(0, 12, 4001)
    return float(
        np.max(
            np.abs(np.imag((2 + 4 * HS_LAMBDA * s + HS_LAMBDA**2 * s**2) * np.exp(HS_LAMBDA * s)))
        )
    )


HS_PEAK = _hs_unit_peak()
_HS_REACH = 12 * HS_TAU  # the transient is cut 12τ after the strike
_TAU_SQ = HS_TAU**2
_LAM = (HS_LAMBDA.real, HS_LAMBDA.imag)
_LAM_4 = (4 * HS_LAMBDA).real, (4 * HS_LAMBDA).imag
_LAM_SQ = (HS_LAMBDA**2).real, (HS_LAMBDA**2).imag
#: Stance micro-motion angular frequencies 2π·(9, 11, 13 Hz) and their squares.
_MICRO_W = 2 * np.pi * np.array([9.0, 11.0, 13.0])
_MICRO_W_SQ = _MICRO_W**2
_TWO_PI = 2 * np.pi
_TWO_PI_SQ = 2 * np.pi**2
_STANDING = int(Gait.STANDING)


@intrinsic
def _fma(typingctx: object, a: types.Type, b: types.Type, c: types.Type) -> tuple:
    """a·b + c rounded once (IEEE fused multiply-add)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: object, builder: ir.IRBuilder, signature: object, args: tuple) -> object:
        return builder.fma(*args)

    return sig, codegen


@njit(cache=True)
def _cmul(ar: float, ai: float, br: float, bi: float) -> tuple[float, float]:
    """(a_r + i a_i)(b_r + i b_i) as numpy's complex128 multiply computes it:
    re = fma(a_r, b_r, −a_i b_i), im = fma(a_r, b_i, a_i b_r)."""
    return _fma(ar, br, -(ai * bi)), _fma(ar, bi, ai * br)


@njit(cache=True)
def _power_sum(
    c0: float, c1: float, c2: float, c3: float, s: float, s2: float, s3: float
) -> tuple[float, float, float]:
    """c₃ + c₂s + c₁s² + c₀s³ and its derivatives c₂ + 2c₁s + 3c₀s², 2c₁ + 6c₀s,
    term by term in the order ``PPoly.__call__`` adds them."""
    return (
        ((c2 * s + c3) + c1 * s2) + c0 * s3,
        ((c1 * s) * 2.0 + c2) + (c0 * s2) * 3.0,
        (c0 * s) * 6.0 + c1 * 2.0,
    )


@njit(cache=True)
def _rollover(
    n_values: int, t: float, start: float, end: float, speed: float, phases: tuple
) -> tuple[tuple[float, float, float], tuple[tuple[float, float, float], ...]]:
    """Stance roll-over and heel micro-motion at time ``t`` in its window: the pitch
    and the heel x, y, z offsets, each with ``n_values − 1`` time derivatives (the
    others 0).

    w = sin²(πs), s = (t − start)/(end − start), and its time derivatives ẇ,
    ẅ; the pitch bump A w, A = 0.011 v² rad, and the micro-motion
    A_mm w sin(ωt + φ) per heel axis, A_mm = 0.2 v² mm, ω = 2π·(9, 11, 13 Hz)
    (module docstring of :mod:`pednav_env.gait.foot`).
    """
    d = end - start
    s = (t - start) / d
    sin_pi_s = math.sin(math.pi * s)
    w0 = sin_pi_s * sin_pi_s
    w1 = w2 = 0.0
    if n_values > 1:  # (sine and cosine side by side: one sincos call)
        sin_2pi_s, cos_2pi_s = math.sin(_TWO_PI * s), math.cos(_TWO_PI * s)
        w1 = math.pi / d * sin_2pi_s
        w2 = _TWO_PI_SQ / (d * d) * cos_2pi_s
    sq = speed * speed
    amp = 0.011 * sq
    a_mm = 2e-4 * sq
    x = _micro_motion(0, n_values, t, phases[0], a_mm, w0, w1, w2)
    y = _micro_motion(1, n_values, t, phases[1], a_mm, w0, w1, w2)
    z = _micro_motion(2, n_values, t, phases[2], a_mm, w0, w1, w2)
    heel = ((x[0], y[0], z[0]), (x[1], y[1], z[1]), (x[2], y[2], z[2]))
    return (amp * w0, amp * w1, amp * w2), heel


@njit(cache=True)
def _micro_motion(
    axis: int, n_values: int, t: float, phase: float, a_mm: float, w0: float, w1: float, w2: float
) -> tuple[float, float, float]:
    """Heel micro-motion A_mm w sin(ωt + φ) along ``axis`` and its time derivatives
    A_mm (ẇ sin + w ω cos) and A_mm (ẅ sin + 2 ẇ ω cos − w ω² sin) (0 beyond
    ``n_values``), given w, ẇ, ẅ = ``w0``, ``w1``, ``w2``."""
    omega = _MICRO_W[axis]
    arg = t * omega + phase
    if n_values == 1:
        return a_mm * w0 * math.sin(arg), 0.0, 0.0
    sn, cs = math.sin(arg), math.cos(arg)  # (side by side: one sincos call)
    v = (w1 * sn + w0 * omega * cs) * a_mm
    a = 0.0
    if n_values > 2:
        a = ((w2 * sn + 2.0 * w1 * omega * cs) - w0 * _MICRO_W_SQ[axis] * sn) * a_mm
    return a_mm * w0 * sn, v, a


@njit(cache=True)
def _heel_strike(t: float, t_hs: float, speed: float) -> tuple[float, float, float]:
    """The heel-strike transient p = B·Im[s² e^{λs}], s = (t − t_hs)/τ, and its first
    two time derivatives; B scales the peak acceleration to 10 v² m/s²."""
    s = (t - t_hs) / HS_TAU
    lam_s = _cmul(_LAM[0], _LAM[1], s, 0.0)
    e = cmath.exp(complex(lam_s[0], lam_s[1]))
    er, ei = e.real, e.imag
    B = 10.0 * (speed * speed) * _TAU_SQ / HS_PEAK
    s2 = s * s
    p0 = B * _cmul(s2, 0.0, er, ei)[1]
    # (2s + λs²) e
    q = _cmul(_LAM[0], _LAM[1], s2, 0.0)
    p1 = B / HS_TAU * _cmul(2.0 * s + q[0], 0.0 + q[1], er, ei)[1]
    # (2 + 4λs + λ²s²) e
    q = _cmul(_LAM_4[0], _LAM_4[1], s, 0.0)
    u = _cmul(_LAM_SQ[0], _LAM_SQ[1], s2, 0.0)
    p2 = B / _TAU_SQ * _cmul((2.0 + q[0]) + u[0], (0.0 + q[1]) + u[1], er, ei)[1]
    return p0, p1, p2


@njit(cache=True)
def _stance_angles(e: Vec3, de: Vec3, dde: Vec3, sin_psi: float, cos_psi: float) -> tuple:
    """Euler rates, accelerations, sines and cosines in a stance: ψ is the piece's
    constant (``sin_psi``, ``cos_psi``), γ ≡ 0; only θ moves."""
    return (
        (None, de[1], None),
        (None, dde[1], None),
        (sin_psi, math.sin(e[1]), None),
        (cos_psi, math.cos(e[1]), 1.0),
    )


@njit(cache=True)
def _straight_angles(e: Vec3, de: Vec3, dde: Vec3, sin_psi: float, cos_psi: float) -> tuple:
    """Euler rates, accelerations, sines and cosines in a straight moving phase: ψ is
    the piece's constant."""
    return (
        (None, de[1], de[2]),
        (None, dde[1], dde[2]),
        (sin_psi, math.sin(e[1]), math.sin(e[2])),
        (cos_psi, math.cos(e[1]), math.cos(e[2])),
    )


@njit(cache=True)
def _turning_angles(e: Vec3, de: Vec3, dde: Vec3, sin_psi: float, cos_psi: float) -> tuple:
    """Euler rates, accelerations, sines and cosines in a turn (``sin_psi`` and
    ``cos_psi`` unused)."""
    return (
        de,
        dde,
        (math.sin(e[0]), math.sin(e[1]), math.sin(e[2])),
        (math.cos(e[0]), math.cos(e[1]), math.cos(e[2])),
    )


@njit(cache=True)
def _kinematics(
    reading: bool,
    full_state: bool,
    heel: tuple[Vec3, Vec3, Vec3],
    de: tuple,
    dde: tuple,
    sin_e: tuple,
    cos_e: tuple,
    r: tuple,
    g: float,
) -> tuple[float, float, float, float, float, float]:
    """Lever-arm kinematics (:mod:`pednav_env.gait.lever_arm`) of one time: the body
    rate and specific force if ``reading``, else the position and (``full_state``)
    the velocity of the IMU (zeros without it)."""
    if reading:
        return imu_readings(heel[2], de, dde, sin_e, cos_e, r, g)
    C = dcm(sin_e, cos_e)
    x = imu_position(heel[0], C, r)
    v = (0.0, 0.0, 0.0)
    if full_state:
        v = imu_velocity(heel[1], C, body_rates(de, sin_e, cos_e), r)
    return x[0], x[1], x[2], v[0], v[1], v[2]


@njit(cache=True)
def simulate_walk(
    t_grid: np.ndarray,
    nodes: np.ndarray,
    weights: np.ndarray,
    walk: tuple,
    r: tuple,
    g: float,
    full_state: bool,
    pos: np.ndarray,
    vel: np.ndarray,
    euler: np.ndarray,
    omega: np.ndarray,
    f_b: np.ndarray,
) -> None:
    """States on the grid ``t_grid`` (T+1,) and ideal readings of one walk, in place.

    States: the IMU position into ``pos`` (T+1, 3) and, with ``full_state``,
    its velocity and the Euler angles into ``vel`` and ``euler``. Readings of
    sample m: the means of body rate and specific force over [t_m, t_m+1] by
    2-point Gauss–Legendre quadrature, w₀h(t_m + o₀) + w₁h(t_m + o₁)
    (``nodes`` o, ``weights`` w), + 0 so that a reading that is exactly zero
    is +0, into ``omega`` and ``f_b`` (T, 3).

    ``walk`` is the walk's tuple of arrays (:func:`pednav_env.gait.foot._kernel_walk`),
    ``r`` the lever arm r_OM (an exact zero component None), ``g`` the gravity.

    One pass over the times in increasing order, t_m then its two nodes: the
    piece of the time, and the latest roll-over window starting before it and
    heel strike at or before it, move forward only. At each time: the heel
    position and Euler angles of the spline piece with their derivatives
    (:func:`_power_sum`; a stance piece is its constant; past the end of the
    walk the foot stands still), plus, in a roll-over window (start_j < t <
    end_j and t < start_{j+1}), :func:`_rollover`, and within 12τ after a heel
    strike, :func:`_heel_strike` (vertical, and half of it along the heading
    after the strike); then the lever-arm kinematics with the exact zeros of
    the piece's kind. (Arrays are touched here only: array arguments of
    helpers cost reference counting at every call.)
    """
    breaks, coefs, kinds, sin_psi, cos_psi = walk[0], walk[1], walk[2], walk[3], walk[4]
    w_start, w_end, w_speed, phases = walk[5], walk[6], walk[7], walk[8]
    s_time, s_speed, s_forward = walk[9], walk[10], walk[11]
    c_start, c_end, c_par = walk[12], walk[13], walk[14]
    micro_phases = (phases[0], phases[1], phases[2])
    last, t_end = breaks.size - 2, breaks[-1]
    n_windows, n_strikes, n_calibrated = w_start.size, s_time.size, c_start.size
    n = omega.shape[0]
    y = np.zeros((3, 6))  # rows x, y, z, ψ, θ, γ of [value, first, second derivative]
    h = np.zeros((2, 6))  # readings at the two nodes
    p, window, strike, calibrated = 0, -1, -1, -1
    for m in range(n + 1):
        for k in range(-1, 2 if m < n else 0):  # −1: the state at t_m; 0, 1: the nodes
            reading = k >= 0
            t = t_grid[m] + nodes[k] if reading else t_grid[m]
            n_values = 3 if reading else (2 if full_state else 1)
            while p < last and breaks[p + 1] <= t:
                p += 1
            kind = kinds[p]
            s = min(t, t_end) - breaks[p]
            s2 = s * s
            s3 = s2 * s
            for row in range(6):
                value, rate, acc = coefs[3, row, p], 0.0, 0.0
                if kind != STANCE:
                    value, rate, acc = _power_sum(
                        coefs[0, row, p], coefs[1, row, p], coefs[2, row, p], value, s, s2, s3
                    )
                    if t > t_end:
                        rate = acc = 0.0
                y[0, row], y[1, row], y[2, row] = value, rate, acc
            while window + 1 < n_windows and w_start[window + 1] < t:
                window += 1
            j = window
            if j >= 0 and t < w_end[j] and (j + 1 == n_windows or t < w_start[j + 1]):
                pitch, heel = _rollover(n_values, t, w_start[j], w_end[j], w_speed[j], micro_phases)
                for d in range(n_values):
                    y[d, 4] += pitch[d]
                for d in range(n_values):
                    for i in range(3):
                        y[d, i] += heel[d][i]
            while strike + 1 < n_strikes and s_time[strike + 1] <= t:
                strike += 1
            j = strike
            if j >= 0 and t - s_time[j] < _HS_REACH:
                bump = _heel_strike(t, s_time[j], s_speed[j])
                fx, fy = 0.5 * s_forward[j, 0], 0.5 * s_forward[j, 1]
                for d in range(n_values):
                    y[d, 0] += bump[d] * fx
                    y[d, 1] += bump[d] * fy
                    y[d, 2] += bump[d]
            while calibrated + 1 < n_calibrated and c_start[calibrated + 1] <= t:
                calibrated += 1
            j = calibrated
            if j >= 0 and t < c_end[j]:
                pitch, roll = stance_motion(n_values, t, c_start[j], c_end[j], c_par[j])
                for d in range(n_values):
                    y[d, 4] += pitch[d]
                    y[d, 5] += roll[d]
            heel_rows = (
                (y[0, 0], y[0, 1], y[0, 2]),
                (y[1, 0], y[1, 1], y[1, 2]),
                (y[2, 0], y[2, 1], y[2, 2]),
            )
            e = (y[0, 3], y[0, 4], y[0, 5])
            de = (y[1, 3], y[1, 4], y[1, 5])
            dde = (y[2, 3], y[2, 4], y[2, 5])
            sp, cp = sin_psi[p], cos_psi[p]
            if kind == STANCE:
                v = _kinematics(
                    reading, full_state, heel_rows, *_stance_angles(e, de, dde, sp, cp), r, g
                )
            elif kind == STRAIGHT:
                v = _kinematics(
                    reading, full_state, heel_rows, *_straight_angles(e, de, dde, sp, cp), r, g
                )
            else:
                v = _kinematics(
                    reading, full_state, heel_rows, *_turning_angles(e, de, dde, sp, cp), r, g
                )
            if reading:
                for i in range(6):
                    h[k, i] = v[i]
            else:
                for i in range(3):
                    pos[m, i] = v[i]
                    if full_state:
                        vel[m, i] = v[3 + i]
                        euler[m, i] = e[i]
        if m < n:
            for i in range(3):
                omega[m, i] = (h[0, i] * weights[0] + h[1, i] * weights[1]) + 0.0
                f_b[m, i] = (h[0, 3 + i] * weights[0] + h[1, 3 + i] * weights[1]) + 0.0


@njit(cache=True)
def gait_labels(
    t_grid: np.ndarray,
    stance_start: np.ndarray,
    stance_end: np.ndarray,
    t_end: float,
    span_start: np.ndarray,
    span_end: np.ndarray,
    span_gait: np.ndarray,
    stance: np.ndarray,
    gait_step: np.ndarray,
    gait: np.ndarray,
) -> None:
    """Labels of samples m = 0 … T−1, the intervals [t_m, t_m+1], in place.

    With k the latest stance starting at or before t_m (1e-12 s tolerance on
    every comparison): ``stance`` if the interval lies inside stance k or
    starts past the end of the walk ``t_end``; ``gait_step`` max(k, 0), the
    gait-cycle number; ``gait`` the label of the latest moving phase
    (``span_*``) starting at or before t_m if t_m is before its end, else
    STANDING, and STANDING in stances.
    """
    k = j = -1
    for m in range(stance.size):
        lo, hi = t_grid[m], t_grid[m + 1]
        while k + 1 < stance_start.size and stance_start[k + 1] <= lo + 1e-12:
            k += 1
        c = max(k, 0)
        inside = k >= 0 and lo >= stance_start[c] - 1e-12 and hi <= stance_end[c] + 1e-12
        inside = inside or lo >= t_end - 1e-12
        while j + 1 < span_start.size and span_start[j + 1] <= lo + 1e-12:
            j += 1
        label = _STANDING
        if j >= 0 and lo < span_end[j] - 1e-12:
            label = span_gait[j]
        stance[m] = inside
        gait_step[m] = c
        gait[m] = _STANDING if inside else label


@njit(cache=True)
def cumulative_distance(pos: np.ndarray, out: np.ndarray) -> None:
    """``out[i, k]`` = Σ_{j<k} √(Δx_j² + Δy_j²), the horizontal distance walked by
    walker i up to sample k, Δ the step of ``pos[i, :, :2]`` from sample j to j+1
    (the norm as ``np.linalg.norm`` and the sum in order as ``np.cumsum``)."""
    for i in range(pos.shape[0]):
        total = 0.0
        out[i, 0] = 0.0
        for k in range(1, pos.shape[1]):
            dx = pos[i, k, 0] - pos[i, k - 1, 0]
            dy = pos[i, k, 1] - pos[i, k - 1, 1]
            total += math.sqrt(dx * dx + dy * dy)
            out[i, k] = total
