"""Foot gait simulator of paper 003, generalised for domain randomisation.

Paper 003's model ("Имитационное моделирование"): each cycle of the foot is
Γ₀ static stance, Γ₁ heel-off, Γ₂ swing, Γ₃ heel-strike. The heel position O
and the Euler angles are given at stance and at mid-swing and joined by cubic
splines; the IMU's sensitive mass M sits at a constant lever arm r_OM from the
heel in foot axes, so that (paper 003, the formulas after Fig. 6)::

    x   = B_zxᵀ r_OM + r_CO
    v_x = B_zxᵀ (ω × r_OM) + ṙ_CO
    a_x = B_zxᵀ (ω × ω × r_OM + ω̇ × r_OM) + r̈_CO
    f_z = B_zx a_x − B_zx g_x

Here each moving phase (Γ₁ + Γ₂ + Γ₃) is one clamped C² cubic spline (zero
rate at both stances; all swings of a walk solved at once by
:func:`pednav_env.gait.splines.clamped_cubic_coefficients`, checked against
``scipy.interpolate.CubicSpline``) through the knots; stances are constant
pieces; the whole walk is one piecewise cubic in ``scipy.interpolate.PPoly``'s
layout, evaluated with PPoly's own arithmetic. The paper scenario uses exactly
its knots (stance, mid-swing). The ``realistic`` routes add, beyond the paper:

- knots at toe-off (foot pitched toes-down, rotated about the toe) and at
  heel-strike (toes up, heel on the ground);
- stance roll-over: a pitch bump A sin²(πs) over the last T₀ of each stance,
  A = 0.011 v² rad (v the walking speed in m/s: ≈ 0.1 rad/s peak rate at
  1 m/s, growing with speed; running stances are short and never still);
- stance micro-motion of the heel, A_mm sin²(πs) sin(2πf t + φ) per axis with
  A_mm = 0.2 v² mm and f = 9, 11, 13 Hz;
- a heel-strike transient B·Im[s² e^{λs}], s = (t − t_hs)/τ, τ = 12 ms,
  λ = −1 + 3i, vertical and half of it forward, scaled to a peak acceleration
  of 10 v² m/s²; it is C² at contact and decays within ~0.1 s;
- optionally (``StanceMotion.heel_rocker``) a heel that lands at rest on its
  footfall and stays there while the foot rolls down
  (:func:`pednav_env.gait.heel_rocker.heel_rocker_coefficients`);
- optionally (``StanceMotion.monotone_pitch``) a swing pitch that is monotone between
  its knots, turning back only at a knot
  (:func:`pednav_env.gait.splines.monotone_clamped_cubic_coefficients`).

All outputs are batched over walkers: ``(N, T, ...)``.

Speed (an episode reset simulates a walk): the walk is evaluated time after
time by compiled kernels (:mod:`pednav_env.gait.foot_kernels`), with the
exact zeros of each kind of piece (stance, straight or turning moving phase)
skipped at compile time, which changes no value. The results are bit for bit
those of the plain formulas.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.gait.foot_kernels import (
    STANCE,
    STRAIGHT,
    TURNING,
    cumulative_distance,
    gait_labels,
    simulate_walk,
)
from pednav_env.gait.foot_route import Route
from pednav_env.gait.heel_rocker import heel_rocker_coefficients
from pednav_env.gait.lever_arm import Vec, lever_arm_rows
from pednav_env.gait.splines import clamped_cubic_coefficients, monotone_clamped_cubic_coefficients
from pednav_env.gait.stance_motion import COLUMNS as STANCE_COLUMNS
from pednav_env.gait.stance_motion import stance_table

Array = NDArray[np.float64]

#: Heel-to-toe-pivot distance used for the toe-off knot (m).
FOOT_LENGTH_M = 0.18
#: The values of a StrideShape :func:`build_schedule` tabulates, in its columns' order.
_SHAPE_VALUES = operator.attrgetter(
    "stance_s",
    "heel_off_s",
    "swing_s",
    "heel_strike_s",
    "stride_length_m",
    "swing_height_m",
    "mid_swing_pitch",
    "mid_swing_roll",
    "toe_off_pitch",
    "heel_strike_pitch",
)
#: 2-point Gauss–Legendre nodes and weights on [−1, 1].
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(2)


@dataclass(frozen=True)
class FootSimConfig:
    """Simulator settings.

    ``lever_arm_m`` is r_OM, heel → IMU in foot axes (x forward, y left, z up);
    paper 003 shows the IMU on top of the foot, ahead of the heel, without a
    number: we take 10 cm forward, 5 cm up.
    """

    rate_hz: float = 100.0  # paper 003: Δt = 0.01 s
    lever_arm_m: tuple[float, float, float] = (0.10, 0.0, 0.05)
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"FootSimConfig.rate_hz must be > 0, got {self.rate_hz!r}")
        if len(self.lever_arm_m) != 3 or not all(math.isfinite(c) for c in self.lever_arm_m):
            raise ValueError(
                f"FootSimConfig.lever_arm_m must be 3 finite numbers, got {self.lever_arm_m!r}"
            )
        if not (math.isfinite(self.g) and self.g > 0):
            raise ValueError(f"FootSimConfig.g must be > 0, got {self.g!r}")

    @property
    def dt(self) -> float:
        return 1.0 / self.rate_hz


@dataclass(frozen=True)
class FootTrajectory:
    """Truth of a batch of walks.

    States on the grid t_m = m Δt, m = 0 … T (``(N, T+1, ·)``); ideal IMU
    readings for sample m are the means of body rate and specific force over
    [t_m, t_{m+1}] (2-point Gauss–Legendre), as an integrating IMU reports
    them (``(N, T, 3)``). The navigation origin is the IMU's initial position.
    ``vel_n`` and ``euler`` are None when simulated without them
    (``simulate_foot(..., full_state=False)``).
    """

    rate_hz: float
    t: Array  # (T+1,)
    pos_n: Array  # (N, T+1, 3) IMU position (m)
    vel_n: Array | None  # (N, T+1, 3) IMU velocity (m/s)
    euler: Array | None  # (N, T+1, 3) ψ, θ, γ (rad), ψ unwrapped
    omega_b: Array  # (N, T, 3) ideal body rate (rad/s)
    f_b: Array  # (N, T, 3) ideal specific force (m/s²)
    stance: NDArray[np.bool_]  # (N, T) sample inside a Γ₀ stance
    gait_step: NDArray[np.int64]  # (N, T) cycle number (stance k … next stance)
    gait: NDArray[np.int8]  # (N, T) Gait label (STANDING in stances)
    duration_s: Array  # (N,) route duration before padding

    @property
    def num_walkers(self) -> int:
        return self.pos_n.shape[0]

    @property
    def num_samples(self) -> int:
        return self.omega_b.shape[1]

    @property
    def distance_m(self) -> Array:
        """Cumulative horizontal distance walked by the IMU, (N, T+1)."""
        out = np.empty(self.pos_n.shape[:2])
        cumulative_distance(self.pos_n, out)
        return out


@dataclass(frozen=True)
class HeelSchedule:
    """One walk: heel position and Euler angles as a piecewise cubic, and its events.

    The cubic pieces use ``scipy.interpolate.PPoly``'s layout and arithmetic
    (:mod:`pednav_env.gait.foot_kernels`); :attr:`pp` builds the PPoly itself.
    """

    breaks: Array  # (P+1,) piece boundaries (s)
    coefs: Array  # (4, 6, P) heel x, y, z, ψ, θ, γ; highest power first
    stance_start: Array  # (K,) Γ₀ stances (s)
    stance_end: Array  # (K,)
    stance_speed: Array  # (K,) walking speed of the stride (m/s), 0 for the final stand
    stance_nominal_s: Array  # (K,) T₀ of the stride (the whole final stand)
    strike_t: Array  # (H,) heel-strike times (realistic routes)
    strike_speed: Array  # (H,)
    strike_forward: Array  # (H, 2) horizontal heading after the strike
    span_start: Array  # (S,) moving phases Γ₁ + Γ₂ + Γ₃
    span_end: Array  # (S,)
    span_gait: NDArray[np.int64]  # (S,) Gait label
    piece_kind: NDArray[np.int8]  # (P,) STANCE, STRAIGHT or TURNING

    @property
    def pp(self) -> PPoly:
        """The same piecewise cubic as a ``scipy.interpolate.PPoly`` (x, y, z, ψ, θ, γ)."""
        return PPoly(self.coefs.transpose(0, 2, 1), self.breaks, extrapolate=True)


def build_schedule(route: Route) -> HeelSchedule:
    """Piecewise polynomial of heel position and Euler angles for one walk.

    Stride by stride (paper 003, "Имитационное моделирование"): a constant Γ₀
    stance piece at the current footfall, then one clamped cubic through the
    knots of the moving phase (stance, [toe-off,] mid-swing, [heel-strike,]
    next stance). Vectorised over strides; every time and position is the same
    sequential sum as stepping through the strides one by one (``cumsum``).
    """
    strides = route.strides
    n_str = len(strides)
    with_toe = [st.shape.toe_off_pitch is not None for st in strides]
    if any(with_toe) and not all(with_toe):
        raise ValueError(
            "Route: either all strides or none set toe_off_pitch/heel_strike_pitch "
            "(realistic and paper knots cannot be mixed in one walk)"
        )
    realistic_knots = bool(with_toe) and with_toe[0]
    table = np.array(
        [(st.stop_s, st.heading_change, *_SHAPE_VALUES(st.shape)) for st in strides], dtype=float
    ).reshape(n_str, 12)
    if realistic_knots:
        table[:, 10:] += 0.0  # −0 → +0, as ``pitch or 0.0``
    else:
        table[:, 10:] = 0.0  # toe-off and heel-strike pitch None: no such knots
    # speed = length / cycle_s, the cycle summed as StrideShape.cycle_s sums it
    cycle = ((table[:, 2] + table[:, 3]) + table[:, 4]) + table[:, 5]
    speed = table[:, 6] / cycle
    gait = np.array([int(st.shape.gait) for st in strides], dtype=np.int64)
    stop, turn, t0_s, t1_s, t2_s, t3_s, length, height, pitch_mid, roll_mid = table[:, :10].T
    toe_pitch, strike_pitch = table[:, 10:].T

    # Times: t ← t + stance, then the knots t₀ + T₁, (t₀ + T₁) + T₂, … in that order.
    stand = np.zeros(n_str)
    if n_str:
        stand[0] = route.initial_stand_s
    stance_len = (stand + stop) + t0_s
    clock = np.cumsum(np.stack((stance_len, t1_s, t2_s, t3_s), axis=1).ravel()).reshape(-1, 4)
    t_start, t_heel_off, t_strike, t_end = clock.T  # t_start = end of the stance
    t_mid = t_heel_off + 0.5 * t2_s

    # Footfalls: ψ and the heel advance stride by stride along the new heading.
    psi_after = np.cumsum(turn)
    cos_after = np.array([math.cos(p) for p in psi_after])
    sin_after = np.array([math.sin(p) for p in psi_after])
    x_after = np.cumsum(length * cos_after)
    y_after = np.cumsum(length * sin_after)
    psi_before, x_before, y_before = (
        np.concatenate(([0.0], v))[:-1] for v in (psi_after, x_after, y_after)
    )
    zero = np.zeros(n_str)
    pose = np.stack((x_before, y_before, zero, psi_before, zero, zero), axis=-1)
    end = np.stack((x_after, y_after, zero, psi_after, zero, zero), axis=-1)
    mid = np.stack(
        (
            0.5 * (x_before + x_after),
            0.5 * (y_before + y_after),
            zero + height,
            0.5 * (psi_before + psi_after),
            pitch_mid,
            roll_mid,
        ),
        axis=-1,
    )
    if realistic_knots:
        # Toe-off: the foot pitched toes-down by a about the toe, FOOT_LENGTH_M ahead.
        cos_before = np.concatenate(([1.0], cos_after))[:-1]
        sin_before = np.concatenate(([0.0], sin_after))[:-1]
        lift = np.array([FOOT_LENGTH_M * (1 - math.cos(a)) for a in toe_pitch])
        rise = np.array([FOOT_LENGTH_M * math.sin(a) for a in toe_pitch])
        toe_off = np.stack(
            (
                x_before + lift * cos_before,
                y_before + lift * sin_before,
                rise,
                psi_before,
                toe_pitch,
                zero,
            ),
            axis=-1,
        )
        strike = np.stack((x_after, y_after, zero, psi_after, strike_pitch, zero), axis=-1)
        knots_t = np.stack((t_start, t_heel_off, t_mid, t_strike, t_end), axis=1)
        knots_y = np.stack((pose, toe_off, mid, strike, end), axis=1)
    else:
        knots_t = np.stack((t_start, t_mid, t_end), axis=1)
        knots_y = np.stack((pose, mid, end), axis=1)
    n_int = knots_t.shape[1] - 1
    motion = route.stance_motion

    # Pieces per stride: the constant stance, then the n_int cubic pieces.
    coefs = np.zeros((4, n_str, 1 + n_int, 6))
    coefs[3, :, 0] = pose
    if n_str and realistic_knots and motion is not None and motion.heel_rocker:
        coefs[:, :, 1:] = heel_rocker_coefficients(knots_t, knots_y)
    elif n_str:
        coefs[:, :, 1:] = clamped_cubic_coefficients(knots_t, knots_y).reshape(4, n_str, n_int, 6)
    if n_str and realistic_knots and motion is not None and motion.monotone_pitch:
        pitch = monotone_clamped_cubic_coefficients(knots_t, knots_y[..., 4:5])
        coefs[:, :, 1:, 4] = pitch.reshape(4, n_str, n_int)
    coefs = coefs.reshape(4, -1, 6)
    breaks = np.concatenate(([0.0], knots_t.ravel()))
    stance_start = t_start - stance_len
    stance_end = t_start
    stance_speed = speed
    stance_nominal = t0_s
    final_len = (0.0 if n_str else route.initial_stand_s) + route.final_stand_s
    if final_len > 0:
        t_last = breaks[-1]
        t_final = t_last + final_len
        final = np.zeros((4, 1, 6))
        final[3, 0] = end[-1] if n_str else 0.0
        coefs = np.concatenate((coefs, final), axis=1)
        breaks = np.append(breaks, t_final)
        stance_start = np.append(stance_start, t_final - final_len)
        stance_end = np.append(stance_end, t_final)
        stance_speed = np.append(stance_speed, 0.0)
        stance_nominal = np.append(stance_nominal, final_len)
    if breaks.size < 2:
        raise ValueError("route has no strides and no standing time")
    if realistic_knots:
        strikes = (t_strike, speed, np.stack((cos_after, sin_after), axis=-1))
    else:
        strikes = (np.zeros(0), np.zeros(0), np.zeros((0, 2)))
    coefs = np.ascontiguousarray(coefs.transpose(0, 2, 1))
    moving = np.any(coefs[:3] != 0, axis=0)  # (6, P): the row varies in the piece
    level = (coefs[3, 4] == 0) & (coefs[3, 5] == 0)
    kind = np.where(~moving.any(axis=0) & level, STANCE, np.where(moving[3], TURNING, STRAIGHT))
    return HeelSchedule(
        breaks,
        coefs,
        stance_start,
        stance_end,
        stance_speed,
        stance_nominal,
        *strikes,
        t_start,
        t_end,
        gait,
        kind.astype(np.int8),
    )


def _lever(lever_arm_m: Array | Sequence[float]) -> Vec:
    """r_OM as floats, an exact zero component as None."""
    return tuple(float(c) if c != 0 else None for c in np.asarray(lever_arm_m, dtype=float))


def imu_kinematics(
    heel: list[Array], euler: list[Array], lever_arm_m: Array, g: float
) -> tuple[Array, Array, Array, Array, Array]:
    """IMU position, velocity, acceleration, body rate and specific force.

    ``heel`` = [r_CO, ṙ_CO, r̈_CO] and ``euler`` = [e, ė, ë] (each (..., 3));
    paper 003's lever-arm formulas (module docstring).
    """
    shape = np.broadcast_shapes(*(np.shape(a) for a in (*heel, *euler)))

    def rows(arrays: list[Array]) -> Array:
        return np.stack(
            [np.broadcast_to(np.asarray(a, dtype=float), shape).reshape(-1, 3).T for a in arrays]
        )

    h, e = rows(heel), rows(euler)
    r = tuple(float(c) for c in np.asarray(lever_arm_m, dtype=float))
    out = np.empty((5, 3, h.shape[2]))
    lever_arm_rows(h, e, r, float(g), out)
    pos, vel, acc, omega, f_b = (v.T.reshape(shape) for v in out)
    return pos, vel, acc, omega, f_b


def _kernel_walk(sched: HeelSchedule, route: Route) -> tuple[Array, ...]:
    """The walk as the tuple of arrays the kernels of :mod:`pednav_env.gait.foot_kernels`
    take: breaks, coefficients, piece kinds, sin ψ and cos ψ of every piece's constant
    term; roll-over windows (start, end, speed) and micro-motion phases; heel strikes
    (time, speed, heading after); the stances of the calibrated model (start, end,
    parameters). Routes without realism get no windows and strikes; routes without
    ``stance_motion`` no calibrated stances. With ``stance_motion``, the realistic
    roll-over windows are left out (the calibrated model replaces them) and stance
    pieces are evaluated as straight pieces (their roll moves)."""
    psi = sched.coefs[3, 3]
    kinds = sched.piece_kind
    calibrated = (np.zeros(0), np.zeros(0), np.zeros((0, len(STANCE_COLUMNS))))
    if route.stance_motion is not None:
        moving = sched.stance_speed > 0  # the last T₀ of every moving stance (no stops)
        start = np.maximum(sched.stance_start, sched.stance_end - sched.stance_nominal_s)
        table = stance_table(route.stance_motion, sched.stance_speed[moving])
        calibrated = (start[moving], sched.stance_end[moving], table)
        kinds = np.where(kinds == STANCE, STRAIGHT, kinds).astype(np.int8)
    if route.realistic and route.stance_motion is not None:
        windows = (np.zeros(0), np.zeros(0), np.zeros(0))
        phases = np.zeros(3)
        strikes = (sched.strike_t, sched.strike_speed, sched.strike_forward)
    elif route.realistic:
        moving = sched.stance_speed > 0  # roll-over: the last T₀ of every moving stance
        start = np.maximum(sched.stance_start, sched.stance_end - sched.stance_nominal_s)
        windows = (start[moving], sched.stance_end[moving], sched.stance_speed[moving])
        phases = np.broadcast_to(np.asarray(route.seed_phases or 0.0, dtype=float), (3,)).copy()
        strikes = (sched.strike_t, sched.strike_speed, sched.strike_forward)
    else:
        windows = (np.zeros(0), np.zeros(0), np.zeros(0))
        phases = np.zeros(3)
        strikes = (np.zeros(0), np.zeros(0), np.zeros((0, 2)))
    arrays = (sched.breaks, sched.coefs, kinds, np.sin(psi), np.cos(psi))
    return tuple(
        np.ascontiguousarray(a) for a in (*arrays, *windows, phases, *strikes, *calibrated)
    )


def _simulate_walk(
    sched: HeelSchedule,
    route: Route,
    t_grid: Array,
    cfg: FootSimConfig,
    pos: Array,
    vel: Array | None,
    eul: Array | None,
    omega: Array,
    f_b: Array,
) -> None:
    """States on ``t_grid`` and ideal readings of one walker, written in place.

    ``vel`` and ``eul`` None: position only. Sensor sample m is the mean over
    [t_m, t_m+1] by 2-point Gauss–Legendre quadrature (exact for cubics;
    O(Δt⁴) for the trigonometric kinematics).
    """
    full = vel is not None and eul is not None
    unused = np.empty((0, 3))
    simulate_walk(
        t_grid,
        0.5 * cfg.dt * (1.0 + _GL_NODES),
        0.5 * _GL_WEIGHTS,
        _kernel_walk(sched, route),
        _lever(cfg.lever_arm_m),
        cfg.g,
        full,
        pos,
        vel if full else unused,
        eul if full else unused,
        omega,
        f_b,
    )


def simulate_foot(
    routes: Route | Sequence[Route],
    config: FootSimConfig | None = None,
    *,
    full_state: bool = True,
) -> FootTrajectory:
    """Simulate the instrumented foot of N walkers.

    Walks shorter than the longest are padded by standing still at the end.
    ``full_state=False`` leaves out the velocity and Euler-angle truth
    (``vel_n``, ``euler`` None), which IMU episodes do not need: faster.
    """
    cfg = config or FootSimConfig()
    routes = [routes] if isinstance(routes, Route) else list(routes)
    if not routes:
        raise ValueError("routes is empty")
    durations = np.array([r.duration_s for r in routes])
    n_samples = int(math.ceil(durations.max() * cfg.rate_hz - 1e-9))
    t_grid = np.arange(n_samples + 1) * cfg.dt

    n = len(routes)
    pos = np.empty((n, n_samples + 1, 3))
    vel = np.empty_like(pos) if full_state else None
    eul = np.empty_like(pos) if full_state else None
    omega = np.empty((n, n_samples, 3))
    f_b = np.empty_like(omega)
    stance = np.zeros((n, n_samples), dtype=bool)
    gait_step = np.zeros((n, n_samples), dtype=np.int64)
    gait = np.zeros((n, n_samples), dtype=np.int8)
    for i, route in enumerate(routes):
        sched = build_schedule(route)
        _simulate_walk(
            sched,
            route,
            t_grid,
            cfg,
            pos[i],
            None if vel is None else vel[i],
            None if eul is None else eul[i],
            omega[i],
            f_b[i],
        )
        events = (sched.stance_start, sched.stance_end, sched.span_start, sched.span_end)
        stance_start, stance_end, span_start, span_end = map(np.ascontiguousarray, events)
        gait_labels(
            t_grid,
            stance_start,
            stance_end,
            sched.breaks[-1],
            span_start,
            span_end,
            sched.span_gait,
            stance[i],
            gait_step[i],
            gait[i],
        )
    pos -= pos[:, :1].copy()
    return FootTrajectory(
        rate_hz=cfg.rate_hz,
        t=t_grid,
        pos_n=pos,
        vel_n=vel,
        euler=eul,
        omega_b=omega,
        f_b=f_b,
        stance=stance,
        gait_step=gait_step,
        gait=gait,
        duration_s=durations,
    )
