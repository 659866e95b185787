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
  of 10 v² m/s²; it is C² at contact and decays within ~0.1 s.

All outputs are batched over walkers: ``(N, T, ...)``.

Speed (an episode reset simulates a walk): the evaluation times are grouped by
the kind of piece they fall in (stance, straight or turning moving phase) and
processed a few thousand at a time, in reused work arrays, component by
component; where an angle or rate is exactly zero or constant in a kind of
piece, the operations it would enter are skipped, which changes no value. The
results are bit for bit those of the plain formulas.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.gait.foot_route import Gait, Route
from pednav_env.gait.splines import clamped_cubic_coefficients

Array = NDArray[np.float64]

#: Evaluation times processed at once: the temporaries of one chunk stay in cache.
_CHUNK_POINTS = 4096
#: Evaluation times prepared at once (piece lookup, realism terms): bounds
#: memory on long walks.
_BLOCK_POINTS = 65536
#: Heel-to-toe-pivot distance used for the toe-off knot (m).
FOOT_LENGTH_M = 0.18
#: Heel-strike transient time constant τ (s) and complex exponent λ.
_HS_TAU = 0.012
_HS_LAMBDA = complex(-1.0, 3.0)


def _hs_unit_peak() -> float:
    s = np.linspace(0, 12, 4001)
    return float(
        np.max(
            np.abs(
                np.imag((2 + 4 * _HS_LAMBDA * s + _HS_LAMBDA**2 * s**2) * np.exp(_HS_LAMBDA * s))
            )
        )
    )


_HS_PEAK = _hs_unit_peak()
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
        x, y = self.pos_n[..., 0], self.pos_n[..., 1]
        dx = x[:, 1:] - x[:, :-1]
        dy = y[:, 1:] - y[:, :-1]
        step = dx * dx
        step += dy * dy
        np.sqrt(step, out=step)  # the Euclidean norm, summed as np.linalg.norm does
        out = np.zeros((self.num_walkers, step.shape[1] + 1))
        np.cumsum(step, axis=1, out=out[:, 1:])
        return out


@dataclass(frozen=True)
class _Schedule:
    """One walk: heel position and Euler angles as a piecewise cubic, and its events.

    The cubic pieces use ``scipy.interpolate.PPoly``'s layout and arithmetic
    (:func:`_evaluate_pieces`); :attr:`pp` builds the PPoly itself.
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
    piece_kind: NDArray[np.int8]  # (P,) _STANCE, _STRAIGHT or _TURNING

    @property
    def pp(self) -> PPoly:
        """The same piecewise cubic as a ``scipy.interpolate.PPoly`` (x, y, z, ψ, θ, γ)."""
        return PPoly(self.coefs.transpose(0, 2, 1), self.breaks, extrapolate=True)


def _build_schedule(route: Route) -> _Schedule:
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
        [
            (
                st.stop_s,
                st.heading_change,
                sh.stance_s,
                sh.heel_off_s,
                sh.swing_s,
                sh.heel_strike_s,
                sh.stride_length_m,
                sh.swing_height_m,
                sh.mid_swing_pitch,
                sh.mid_swing_roll,
                sh.toe_off_pitch or 0.0,
                sh.heel_strike_pitch or 0.0,
                sh.speed,
                int(sh.gait),
            )
            for st in strides
            for sh in (st.shape,)
        ],
        dtype=float,
    ).reshape(n_str, 14)
    stop, turn, t0_s, t1_s, t2_s, t3_s, length, height, pitch_mid, roll_mid = table[:, :10].T
    toe_pitch, strike_pitch, speed, gait = table[:, 10:].T

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

    # Pieces per stride: the constant stance, then the n_int cubic pieces.
    coefs = np.zeros((4, n_str, 1 + n_int, 6))
    coefs[3, :, 0] = pose
    if n_str:
        coefs[:, :, 1:] = clamped_cubic_coefficients(knots_t, knots_y).reshape(4, n_str, n_int, 6)
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
    kind = np.where(~moving.any(axis=0) & level, _STANCE, np.where(moving[3], _TURNING, _STRAIGHT))
    return _Schedule(
        breaks,
        coefs,
        stance_start,
        stance_end,
        stance_speed,
        stance_nominal,
        *strikes,
        t_start,
        t_end,
        gait.astype(np.int64),
        kind.astype(np.int8),
    )


def _interval_index(edges: Array, t: Array) -> NDArray[np.intp]:
    """``searchsorted(edges, t, side="right") − 1`` for sorted ``t``.

    One ``searchsorted`` of the few edges into the many times gives how many
    times fall in each interval; the interval numbers are repeated.
    """
    first = np.searchsorted(t, edges, side="left")
    counts = np.empty(edges.size + 1, dtype=np.intp)
    counts[0] = first[0]
    counts[1:-1] = np.diff(first)
    counts[-1] = t.size - first[-1]
    return np.repeat(np.arange(-1, edges.size), counts)


def _points_inside(
    t: Array, start: Array, end: Array, closed_start: bool
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Indices i and windows j of the sorted times with start_j < t_i < end_j
    (start_j ≤ t_i if ``closed_start``); the windows are ordered and disjoint."""
    first = np.searchsorted(t, start, side="left" if closed_start else "right")
    count = np.searchsorted(t, end, side="left") - first
    np.maximum(count, 0, out=count)
    window = np.repeat(np.arange(start.size), count)
    shift = first - (np.cumsum(count) - count)
    return np.arange(window.size) + np.repeat(shift, count), window


def _sin2_window(t: Array, start: Array, end: Array, n_values: int) -> list[Array]:
    """w = sin²(πs), s = (t − start)/(end − start), and its first two time derivatives.

    ``t`` must lie strictly inside (start, end); the first ``n_values`` of
    [w, ẇ, ẅ] are returned.
    """
    d = end - start
    s = (t - start) / d
    out = [np.sin(np.pi * s) ** 2]
    if n_values > 1:
        out.append(np.pi / d * np.sin(2 * np.pi * s))
    if n_values > 2:
        out.append(2 * np.pi**2 / d**2 * np.cos(2 * np.pi * s))
    return out


@dataclass(frozen=True)
class _RealismPoints:
    """Which evaluation times carry realism terms (module docstring).

    ``window_points`` (increasing indices into the times) lie in the roll-over
    windows ``window_of`` (into :meth:`windows`), ``strike_points`` within
    12τ after the heel strikes ``strike_of``; every time belongs to the latest
    window (strike) that starts at or before it.
    """

    window_points: NDArray[np.intp]
    window_of: NDArray[np.intp]
    strike_points: NDArray[np.intp]
    strike_of: NDArray[np.intp]

    @staticmethod
    def windows(sched: _Schedule) -> tuple[Array, Array, Array]:
        """Roll-over windows, the last T₀ of every moving stance: start, end, speed."""
        moving = sched.stance_speed > 0
        start = np.maximum(sched.stance_start, sched.stance_end - sched.stance_nominal_s)
        return start[moving], sched.stance_end[moving], sched.stance_speed[moving]

    @classmethod
    def find(cls, sched: _Schedule, t: Array) -> _RealismPoints:
        """The points among the sorted times ``t``."""
        ws, we, _ = cls.windows(sched)
        sel, k = _points_inside(t, ws, np.minimum(we, np.append(ws[1:], np.inf)), False)
        ths = sched.strike_t
        # Candidates: from a strike to the next one, at most 12τ (+ margin) after it.
        reach = np.minimum(ths + (12 * _HS_TAU + 1e-6), np.append(ths[1:], np.inf))
        hit, j = _points_inside(t, ths, reach, True)
        keep = t[hit] - ths[j] < 12 * _HS_TAU
        return cls(sel, k, hit[keep], j[keep])

    def moved(self, new_place: NDArray[np.intp], key: NDArray[np.int8]) -> _RealismPoints:
        """The points after the times were reordered by a stable sort on ``key``,
        time i going to ``new_place[i]``."""
        ow = np.argsort(key[self.window_points], kind="stable")
        oh = np.argsort(key[self.strike_points], kind="stable")
        return _RealismPoints(
            new_place[self.window_points[ow]],
            self.window_of[ow],
            new_place[self.strike_points[oh]],
            self.strike_of[oh],
        )


def _add_rollover(
    y: Array, lo: int, t: Array, start: Array, end: Array, speed: Array, phases: Array
) -> None:
    """Add the stance roll-over and the heel micro-motion at times ``t`` in place.

    ``y`` (n_values, 6, M): rows x, y, z, ψ, θ, γ and their derivatives; the
    times are its columns lo, lo+1, …; ``start``, ``end`` and ``speed`` those
    of each time's window; ``phases`` (3, 1) the micro-motion phases.
    """
    n_values = y.shape[0]
    cols = slice(lo, lo + t.size)
    w = _sin2_window(t, start, end, n_values)
    amp = 0.011 * speed**2  # roll-over pitch bump (rad)
    for d in range(n_values):
        y[d, 4, cols] += amp * w[d]
    a_mm = 2e-4 * speed**2  # heel micro-motion (m)
    fq = 2 * np.pi * np.array([9.0, 11.0, 13.0])[:, None]
    arg = t * fq + phases  # (3, n)
    sn = np.sin(arg)
    term = a_mm * w[0] * sn
    y[0, :3, cols] += term
    if n_values > 1:
        cs = np.cos(arg)
        # a_mm (ẇ sin + w ω cos), term by term in place
        np.multiply(w[1], sn, out=term)
        part = w[0] * fq
        part *= cs
        term += part
        term *= a_mm
        y[1, :3, cols] += term
    if n_values > 2:
        # a_mm (ẅ sin + 2 ẇ ω cos − w ω² sin)
        np.multiply(w[2], sn, out=term)
        np.multiply(2 * w[1], fq, out=part)
        part *= cs
        term += part
        np.multiply(w[0], fq**2, out=part)
        part *= sn
        term -= part
        term *= a_mm
        y[2, :3, cols] += term


def _add_heel_strike(
    y: Array, lo: int, t: Array, t_hs: Array, speed: Array, forward: Array
) -> None:
    """Add the heel-strike transients at times ``t`` in place (columns lo, lo+1, … of
    ``y``); ``t_hs``, ``speed`` and ``forward`` (n, 2) those of each time's strike."""
    n_values = y.shape[0]
    cols = slice(lo, lo + t.size)
    lam = _HS_LAMBDA
    s = (t - t_hs) / _HS_TAU
    e = np.exp(lam * s)
    B = 10.0 * speed**2 * _HS_TAU**2 / _HS_PEAK
    p = [B * np.imag(s**2 * e)]
    if n_values > 1:
        p.append(B / _HS_TAU * np.imag((2 * s + lam * s**2) * e))
    if n_values > 2:
        p.append(B / _HS_TAU**2 * np.imag((2 + 4 * lam * s + lam**2 * s**2) * e))
    fx = 0.5 * forward[:, 0]
    fy = 0.5 * forward[:, 1]
    for d in range(n_values):
        y[d, 0, cols] += p[d] * fx
        y[d, 1, cols] += p[d] * fy
        y[d, 2, cols] += p[d]


# ---------------------------------------------------------------- kinematics
# Paper 003's lever-arm formulas (module docstring) component by component on
# (M,) arrays, each in the same order as pednav_env.rotations and numpy's
# cross/einsum evaluated them. An operand may be None, an exact zero, or _ONE,
# an exact one: the helpers skip such products (x·1 = x, x + 0 = x and
# 0 − x = −x exactly), so a walk phase where some angles or rates vanish
# identically runs fewer operations and gets the same values (at most a
# zero's sign differs).


class _One:
    """An exact 1 (a cosine of an angle that is exactly zero)."""


_ONE = _One()
_Term = Array | float | _One | None
_Vec = tuple[_Term, _Term, _Term]


def _mul(a: _Term, b: _Term) -> _Term:
    if a is None or b is None:
        return None
    if b is _ONE:
        return a
    if a is _ONE:
        return b
    return a * b


def _add(a: _Term, b: _Term) -> _Term:
    if a is None:
        return b
    if b is None:
        return a
    return a + b


def _sub(a: _Term, b: _Term) -> _Term:
    if b is None:
        return a
    if a is None:
        return -b
    return a - b


def _neg(a: _Term) -> _Term:
    return None if a is None else -a


def _dcm(sin_e: _Vec, cos_e: _Vec) -> tuple[_Term, ...]:
    """C_nb = B_zxᵀ = R_z(ψ) R_y(θ) R_x(γ) (paper 003 eq 1), row-major 9-tuple."""
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


def _rotate(C: tuple[_Term, ...], v: _Vec) -> _Vec:
    """C v (body → navigation); sums (term 0 + term 2) + term 1 like numpy's einsum."""
    return tuple(
        _add(_add(_mul(C[3 * i], v[0]), _mul(C[3 * i + 2], v[2])), _mul(C[3 * i + 1], v[1]))
        for i in range(3)
    )


def _rotate_transposed(C: tuple[_Term, ...], v: _Vec) -> _Vec:
    """Cᵀ v (navigation → body)."""
    return tuple(
        _add(_add(_mul(C[i], v[0]), _mul(C[3 + i], v[1])), _mul(C[6 + i], v[2])) for i in range(3)
    )


def _cross(a: _Vec, b: _Vec) -> _Vec:
    """a × b."""
    return (
        _sub(_mul(a[1], b[2]), _mul(a[2], b[1])),
        _sub(_mul(a[2], b[0]), _mul(a[0], b[2])),
        _sub(_mul(a[0], b[1]), _mul(a[1], b[0])),
    )


def _body_rates(de: _Vec, sin_e: _Vec, cos_e: _Vec) -> _Vec:
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


def _body_angular_acceleration(de: _Vec, dde: _Vec, sin_e: _Vec, cos_e: _Vec) -> _Vec:
    """ω̇, the time derivative of :func:`_body_rates` (``dde`` the Euler accelerations)."""
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


def _lever(lever_arm_m: Array | Sequence[float]) -> _Vec:
    """r_OM as floats, an exact zero component as None."""
    return tuple(float(c) if c != 0 else None for c in np.asarray(lever_arm_m, dtype=float))


def _imu_states(
    heel: Sequence[Array], de: _Vec | None, sin_e: _Vec, cos_e: _Vec, r: _Vec, out: Array
) -> None:
    """IMU position x = B_zxᵀ r_OM + r_CO into ``out[0:3]`` and, given the Euler
    rates ``de``, the velocity v_x = B_zxᵀ (ω × r_OM) + ṙ_CO into ``out[3:6]``.

    ``heel`` = [r_CO rows] or [r_CO rows, ṙ_CO rows], each (3, M).
    """
    C = _dcm(sin_e, cos_e)
    for i, c in enumerate(_rotate(C, r)):
        _store(_add(heel[0][i], c), out[i])
    if de is not None:
        omega = _body_rates(de, sin_e, cos_e)
        for i, c in enumerate(_rotate(C, _cross(omega, r))):
            _store(_add(heel[1][i], c), out[3 + i])


def _imu_readings(
    heel: Sequence[Array],
    de: _Vec,
    dde: _Vec,
    sin_e: _Vec,
    cos_e: _Vec,
    r: _Vec,
    g: float,
    out: Array,
) -> None:
    """Body rate ω into ``out[0:3]`` and specific force f_z = B_zx (a_x − g_x) into
    ``out[3:6]``, a_x = B_zxᵀ (ω × ω × r_OM + ω̇ × r_OM) + r̈_CO (paper 003).

    ``heel`` = [r_CO, ṙ_CO, r̈_CO] rows, each (3, M); ``de``, ``dde`` the Euler
    rates and accelerations.
    """
    C = _dcm(sin_e, cos_e)
    omega = _body_rates(de, sin_e, cos_e)
    omega_dot = _body_angular_acceleration(de, dde, sin_e, cos_e)
    rel = tuple(
        _add(a, b)
        for a, b in zip(_cross(omega, _cross(omega, r)), _cross(omega_dot, r), strict=True)
    )
    acc = [_add(h, c) for h, c in zip(heel[2], _rotate(C, rel), strict=True)]
    acc[2] = _add(acc[2], g)  # a − g_vec, g_vec = (0, 0, −g)
    for i, v in enumerate((*omega, *_rotate_transposed(C, (acc[0], acc[1], acc[2])))):
        _store(v, out[i])


def _store(value: _Term, out: Array) -> None:
    """out ← value (an exact zero for None)."""
    out[:] = 0.0 if value is None else value


def imu_kinematics(
    heel: list[Array], euler: list[Array], lever_arm_m: Array, g: float
) -> tuple[Array, Array, Array, Array, Array]:
    """IMU position, velocity, acceleration, body rate and specific force.

    ``heel`` = [r_CO, ṙ_CO, r̈_CO] and ``euler`` = [e, ė, ë] (each (..., 3));
    paper 003's lever-arm formulas (module docstring).
    """
    shape = np.broadcast_shapes(*(np.shape(a) for a in (*heel, *euler)))

    def rows(a: Array) -> _Vec:
        return tuple(np.broadcast_to(np.asarray(a, dtype=float), shape).reshape(-1, 3).T)

    h, e = [rows(a) for a in heel], [rows(a) for a in euler]
    sin_e, cos_e = tuple(np.sin(e[0])), tuple(np.cos(e[0]))
    C = _dcm(sin_e, cos_e)
    r = tuple(float(c) for c in np.asarray(lever_arm_m, dtype=float))
    omega = _body_rates(e[1], sin_e, cos_e)
    omega_dot = _body_angular_acceleration(e[1], e[2], sin_e, cos_e)
    w_x_r = _cross(omega, r)
    rel = tuple(_add(a, b) for a, b in zip(_cross(omega, w_x_r), _cross(omega_dot, r), strict=True))
    pos = [_add(a, c) for a, c in zip(h[0], _rotate(C, r), strict=True)]
    vel = [_add(a, c) for a, c in zip(h[1], _rotate(C, w_x_r), strict=True)]
    acc = [_add(a, c) for a, c in zip(h[2], _rotate(C, rel), strict=True)]
    f_b = _rotate_transposed(C, (acc[0], acc[1], _add(acc[2], g)))

    def out(v: Sequence[_Term]) -> Array:
        stacked = np.zeros((3, h[0][0].size))
        for i, a in enumerate(v):
            _store(a, stacked[i])
        return stacked.T.reshape(shape)

    return out(pos), out(vel), out(acc), out(omega), out(f_b)


# --------------------------------------------------------------- evaluation
#: Kinds of spline piece, each with its own exact shortcuts: stances (heel
#: pose constant and level: only realism moves the foot, about the pitch axis
#: and the heel), straight moving phases (heading constant) and turns.
_STANCE, _STRAIGHT, _TURNING = 0, 1, 2


class _Scratch(threading.local):
    """Work arrays reused from chunk to chunk and from call to call, one set per
    thread (a few MB): fresh large arrays cost a page fault per 4 kB on first
    touch, which dominated short walks."""

    def __init__(self) -> None:
        self.buffers: dict[str, Array] = {}

    def view(self, name: str, shape: tuple[int, ...]) -> Array:
        """A C-contiguous ``shape`` float view on buffer ``name`` (grown as needed)."""
        size = math.prod(shape)
        buf = self.buffers.get(name)
        if buf is None or buf.size < size:
            buf = self.buffers[name] = np.empty(size)
        return buf[:size].reshape(shape)


_SCRATCH = _Scratch()


def _evaluate_pieces(
    sched: _Schedule, t: Array, piece: NDArray[np.intp], n_values: int, scratch: _Scratch
) -> Array:
    """Heel position, Euler angles and their derivatives at times ``t`` in pieces ``piece``.

    Returns ``(n_values, 6, M)``, a view on ``scratch``: [value, first,
    second derivative][:n_values] of the rows x, y, z, ψ, θ, γ. Past the end
    of the walk the foot stands still. With s = t − tₖ in piece k this is the
    power sum c₃ + c₂s + c₁s² + c₀s³ and its derivatives c₂ + 2c₁s + 3c₀s²,
    2c₁ + 6c₀s, term by term in the order ``PPoly.__call__`` adds them, so the
    results are those of ``sched.pp(t, nu)`` bit for bit.
    """
    m = t.size
    b = sched.breaks
    t_end = b[-1]
    y = scratch.view("values", (n_values, 6, m))
    c = scratch.view("coefs", (24, m))
    np.take(sched.coefs.reshape(24, -1), piece, axis=1, out=c, mode="clip")
    c0, c1, c2, c3 = c.reshape(4, 6, m)
    s = np.minimum(t, t_end)
    s -= np.take(b, piece)
    if n_values == 1:  # s, s², s³ broadcast over the six rows
        s1, s2 = s, s * s
        s3 = s2 * s
    else:  # spread over the six rows: same-shape products are faster
        s1, s2, s3 = scratch.view("powers", (3, 6, m))
        s1[:] = s
        np.multiply(s1, s1, out=s2)
        np.multiply(s2, s1, out=s3)
    tmp = scratch.view("tmp", (6, m))
    if n_values > 1:
        np.multiply(c1, s1, out=y[1])
        y[1] *= 2.0
        y[1] += c2
        np.multiply(c0, s2, out=tmp)
        tmp *= 3.0
        y[1] += tmp
    if n_values > 2:
        np.multiply(c0, s1, out=y[2])
        y[2] *= 6.0
        np.multiply(c1, 2.0, out=tmp)
        y[2] += tmp
    np.multiply(c2, s1, out=y[0])
    y[0] += c3
    np.multiply(c1, s2, out=tmp)
    y[0] += tmp
    np.multiply(c0, s3, out=tmp)
    y[0] += tmp
    if n_values > 1 and t[-1] > t_end:
        y[1:, :, t > t_end] = 0.0
    return y


def _evaluate_stance(
    sched: _Schedule, piece: NDArray[np.intp], n_values: int, scratch: _Scratch
) -> Array:
    """:func:`_evaluate_pieces` for times in stance pieces: c₃, then zero derivatives."""
    y = scratch.view("values", (n_values, 6, piece.size))
    np.take(sched.coefs[3], piece, axis=1, out=y[0], mode="clip")
    y[1:] = 0.0
    return y


def _kinematics(
    y: Array,
    piece: NDArray[np.intp],
    kind: int,
    heading: tuple[Array, Array],
    r: _Vec,
    g: float,
    out: Array,
) -> None:
    """States (``y`` with 1 or 2 values) or readings (3 values) of times in pieces
    of one ``kind``, into ``out``.

    Exact zeros: ψ̇, ψ̈ but in turns (ψ is then the piece's constant term, whose
    sine and cosine ``heading`` tabulates); γ, γ̇, γ̈ in stances.
    """
    turning, stance = kind == _TURNING, kind == _STANCE
    sin_e: _Vec = (
        np.sin(y[0, 3]) if turning else np.take(heading[0], piece),
        np.sin(y[0, 4]),
        None if stance else np.sin(y[0, 5]),
    )
    cos_e: _Vec = (
        np.cos(y[0, 3]) if turning else np.take(heading[1], piece),
        np.cos(y[0, 4]),
        _ONE if stance else np.cos(y[0, 5]),
    )
    n_values = y.shape[0]
    rates = [
        (y[d, 3] if turning else None, y[d, 4], None if stance else y[d, 5])
        for d in range(1, n_values)
    ]
    if n_values == 3:
        _imu_readings(y[:, :3], rates[0], rates[1], sin_e, cos_e, r, g, out)
    else:
        _imu_states(y[:, :3], rates[0] if rates else None, sin_e, cos_e, r, out)
        if n_values > 1:
            out[6:] = y[0, 3:]


def _evaluate_block(
    sched: _Schedule,
    route: Route,
    t: Array,
    n_values: int,
    r: _Vec,
    g: float,
    heading: tuple[Array, Array],
    scratch: _Scratch,
) -> Array:
    """IMU states or ideal readings at the sorted times ``t``.

    ``n_values`` 1: position; 2: position, velocity and Euler angles; 3: body
    rate and specific force. Returns their rows, ``(3, 9 or 6, M)`` in the
    order of ``t``, a view on ``scratch``.

    The times are regrouped by the kind of piece they fall in, and within a
    kind those in a roll-over window come first, then those in a window and a
    heel-strike transient, then those in a transient only, so that every
    realism term adds to a slice; each kind is evaluated
    :data:`_CHUNK_POINTS` at a time with its exact shortcuts. ``heading``
    holds sin ψ and cos ψ of every piece's constant term.
    """
    m = t.size
    b = sched.breaks
    piece = _interval_index(b, np.minimum(t, b[-1]))  # ≥ 0: t ≥ 0 = b[0]
    np.minimum(piece, b.size - 2, out=piece)
    key = np.take(sched.piece_kind * 4, piece)
    where = _RealismPoints.find(sched, t) if route.realistic else None
    if where is None:
        key += 3
    else:
        group = np.full(m, 3, dtype=np.int8)  # 0 window only, 1 both, 2 transient only, 3 none
        group[where.window_points] = 0
        hit = where.strike_points
        group[hit] = np.where(group[hit] == 0, 1, 2)
        key += group
    order = np.argsort(key, kind="stable")
    counts = np.bincount(key, minlength=12).reshape(3, 4)
    start = np.cumsum(counts.sum(axis=1)) - counts.sum(axis=1)
    t, piece = t[order], piece[order]
    inverse = np.empty_like(order)
    inverse[order] = np.arange(m)
    if where is not None:
        # In the new order every kind's window (transient) times form a slice.
        where = where.moved(inverse, key)
        ws, we, w_speed = _RealismPoints.windows(sched)
        phases = np.asarray(route.seed_phases or (0.0, 0.0, 0.0))[:, None]
    out = scratch.view("permuted", ({1: 3, 2: 9, 3: 6}[n_values], m))
    n_window = n_strike = 0  # terms of the kinds before
    for k in (_STANCE, _STRAIGHT, _TURNING):
        lo, hi = int(start[k]), int(start[k] + counts[k].sum())
        c0, c1, c2 = counts[k, :3].tolist()
        windows = (lo, lo + c0 + c1)
        strikes = (lo + c0, lo + c0 + c1 + c2)
        for a in range(lo, hi, _CHUNK_POINTS):
            z = min(a + _CHUNK_POINTS, hi)
            p = piece[a:z]
            if k == _STANCE:
                y = _evaluate_stance(sched, p, n_values, scratch)
            else:
                y = _evaluate_pieces(sched, t[a:z], p, n_values, scratch)
            if where is not None:
                u, v = max(a, windows[0]), min(z, windows[1])
                if v > u:
                    j = where.window_of[u - windows[0] + n_window : v - windows[0] + n_window]
                    _add_rollover(y, u - a, t[u:v], ws[j], we[j], w_speed[j], phases)
                u, v = max(a, strikes[0]), min(z, strikes[1])
                if v > u:
                    j = where.strike_of[u - strikes[0] + n_strike : v - strikes[0] + n_strike]
                    hs = sched.strike_t[j], sched.strike_speed[j], sched.strike_forward[j]
                    _add_heel_strike(y, u - a, t[u:v], *hs)
            _kinematics(y, p, k, heading, r, g, out[:, a:z])
        n_window += c0 + c1
        n_strike += c1 + c2
    # (mode="clip": the indices are valid; it spares take's buffering of ``out``)
    return np.take(out, inverse, axis=1, out=scratch.view("outputs", out.shape), mode="clip")


def _simulate_walk(
    sched: _Schedule,
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

    ``vel`` and ``eul`` None: position only. Evaluation times: the grid
    (states), then the two Gauss–Legendre nodes of every sample (readings),
    :data:`_BLOCK_POINTS` at a time.
    """
    n = t_grid.size - 1
    # Sensor sample m = mean over [t_m, t_m+1] by 2-point Gauss–Legendre
    # quadrature (exact for cubics; O(Δt⁴) for the trigonometric kinematics).
    offsets = 0.5 * cfg.dt * (1.0 + _GL_NODES)
    half_w = 0.5 * _GL_WEIGHTS
    r = _lever(cfg.lever_arm_m)
    heading = (np.sin(sched.coefs[3, 3]), np.cos(sched.coefs[3, 3]))
    scratch = _SCRATCH
    n_values = 1 if vel is None else 2
    for a in range(0, n + 1, _BLOCK_POINTS):
        b = min(a + _BLOCK_POINTS, n + 1)
        out = _evaluate_block(sched, route, t_grid[a:b], n_values, r, cfg.g, heading, scratch)
        for c in range(3):
            pos[a:b, c] = out[c]
            if vel is not None and eul is not None:
                vel[a:b, c] = out[3 + c]
                eul[a:b, c] = out[6 + c]
    # Readings: both nodes of every sample, in time order (t_m + o₀ < t_m + o₁).
    step = _BLOCK_POINTS // 2
    for a in range(0, n, step):
        b = min(a + step, n)
        t = (t_grid[a:b, None] + offsets).ravel()
        out = _evaluate_block(sched, route, t, 3, r, cfg.g, heading, scratch)
        for row in range(6):  # ω then f
            mean = out[row, 0::2] * half_w[0]  # w₀h₀ + w₁h₁, the quadrature sum
            mean += out[row, 1::2] * half_w[1]
            # + 0: where the exact-zero shortcuts skipped a +0 term, a reading that
            # is exactly zero comes out as −0; the full formulas give +0.
            mean += 0.0
            (omega if row < 3 else f_b)[a:b, row % 3] = mean


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
        sched = _build_schedule(route)
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
        t_end = sched.breaks[-1]
        lo, hi = t_grid[:-1], t_grid[1:]
        starts, ends = sched.stance_start, sched.stance_end
        idx = np.searchsorted(starts, lo + 1e-12, side="right") - 1
        valid = idx >= 0
        inside = (
            valid
            & (lo >= starts[np.maximum(idx, 0)] - 1e-12)
            & (hi <= ends[np.maximum(idx, 0)] + 1e-12)
        )
        inside |= lo >= t_end - 1e-12
        stance[i] = inside
        gait_step[i] = np.maximum(idx, 0)
        if sched.span_start.size:
            s0, s1, labels = sched.span_start, sched.span_end, sched.span_gait
            j = np.searchsorted(s0, lo + 1e-12, side="right") - 1
            jj = np.maximum(j, 0)
            in_span = (j >= 0) & (lo < s1[jj] - 1e-12)
            gait[i] = np.where(in_span, labels[jj], int(Gait.STANDING))
        gait[i, inside] = int(Gait.STANDING)
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
