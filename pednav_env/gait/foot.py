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
pieces; the whole walk is one ``scipy.interpolate.PPoly``. The paper scenario uses exactly its knots
(stance, mid-swing). The ``realistic`` routes add, beyond the paper:

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
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.gait.foot_route import Gait, Route
from pednav_env.gait.splines import clamped_cubic_coefficients
from pednav_env.rotations import (
    body_angular_acceleration_from_euler,
    body_rates_from_euler,
    euler_to_dcm,
)

Array = NDArray[np.float64]

#: Samples evaluated at once (bounds memory on long walks).
_CHUNK_SAMPLES = 50_000
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
    """

    rate_hz: float
    t: Array  # (T+1,)
    pos_n: Array  # (N, T+1, 3) IMU position (m)
    vel_n: Array  # (N, T+1, 3) IMU velocity (m/s)
    euler: Array  # (N, T+1, 3) ψ, θ, γ (rad), ψ unwrapped
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
        step = np.linalg.norm(np.diff(self.pos_n[..., :2], axis=1), axis=-1)
        return np.concatenate((np.zeros((self.num_walkers, 1)), np.cumsum(step, axis=1)), axis=1)


def _direction(psi: float) -> Array:
    return np.array([math.cos(psi), math.sin(psi), 0.0])


@dataclass
class _Schedule:
    pp: PPoly  # heel x, y, z, ψ, θ, γ
    stance_intervals: list[tuple[float, float, float, float]]  # (start, end, speed, T₀)
    strike_times: list[tuple[float, float, Array]]  # (t_hs, speed, forward dir)
    gait_spans: list[tuple[float, float, int]]  # (start, end, Gait) for moving phases


def _build_schedule(route: Route) -> _Schedule:
    """Piecewise polynomial of heel position and Euler angles for one walk."""
    breaks: list[float] = [0.0]
    pieces: list[Array | int] = []  # constant stance coefficients, or a swing index
    pos = np.zeros(3)
    psi = 0.0
    t = 0.0
    stances: list[tuple[float, float, float, float]] = []
    strikes: list[tuple[float, float, Array]] = []
    spans: list[tuple[float, float, int]] = []
    swing_t: list[list[float]] = []
    swing_y: list[list[Array]] = []

    def add_constant(until: float, value: Array) -> None:
        nonlocal t
        c = np.zeros((4, 1, 6))
        c[3, 0] = value
        pieces.append(c)
        breaks.append(until)
        t = until

    stand = route.initial_stand_s
    for stride in route.strides:
        sh = stride.shape
        pose = np.concatenate((pos, [psi, 0.0, 0.0]))
        stance_len = stand + stride.stop_s + sh.stance_s
        add_constant(t + stance_len, pose)
        stances.append((t - stance_len, t, sh.speed, sh.stance_s))
        stand = 0.0
        psi_next = psi + stride.heading_change
        pos_next = pos + sh.stride_length_m * _direction(psi_next)
        t0 = t
        t_mid = t0 + sh.heel_off_s + 0.5 * sh.swing_s
        t_end = t0 + sh.heel_off_s + sh.swing_s + sh.heel_strike_s
        mid = np.concatenate(
            (
                0.5 * (pos + pos_next) + np.array([0, 0, sh.swing_height_m]),
                [0.5 * (psi + psi_next), sh.mid_swing_pitch, sh.mid_swing_roll],
            )
        )
        end = np.concatenate((pos_next, [psi_next, 0.0, 0.0]))
        if sh.toe_off_pitch is None:
            knots_t = [t0, t_mid, t_end]
            knots_y = [pose, mid, end]
        else:
            a = sh.toe_off_pitch
            heel_off = pos + FOOT_LENGTH_M * (1 - math.cos(a)) * _direction(psi)
            heel_off[2] = FOOT_LENGTH_M * math.sin(a)
            toe_off = np.concatenate((heel_off, [psi, a, 0.0]))
            strike = np.concatenate((pos_next, [psi_next, sh.heel_strike_pitch, 0.0]))
            t_hs = t0 + sh.heel_off_s + sh.swing_s
            knots_t = [t0, t0 + sh.heel_off_s, t_mid, t_hs, t_end]
            knots_y = [pose, toe_off, mid, strike, end]
            strikes.append((t_hs, sh.speed, _direction(psi_next)))
        pieces.append(len(swing_t))
        swing_t.append(knots_t)
        swing_y.append(knots_y)
        breaks.extend(knots_t[1:])
        spans.append((t0, t_end, int(sh.gait)))
        t = t_end
        pos, psi = pos_next, psi_next
    final = np.concatenate((pos, [psi, 0.0, 0.0]))
    stance_len = stand + route.final_stand_s
    if stance_len > 0:
        add_constant(t + stance_len, final)
        stances.append((t - stance_len, t, 0.0, stance_len))
    coefs: list[Array] = []
    if swing_t:
        n_int = len(swing_t[0]) - 1
        swing_c = clamped_cubic_coefficients(np.asarray(swing_t), np.asarray(swing_y))
        for p in pieces:
            if isinstance(p, int):
                coefs.append(swing_c[:, p * n_int : (p + 1) * n_int])
            else:
                coefs.append(p)
    else:
        coefs = [p for p in pieces if not isinstance(p, int)]
    pp = PPoly(np.concatenate(coefs, axis=1), np.asarray(breaks), extrapolate=True)
    return _Schedule(pp, stances, strikes, spans)


def _sin2_window(t: Array, start: Array, end: Array) -> tuple[Array, Array, Array]:
    """w = sin²(πs), s = (t − start)/(end − start), and its first two time derivatives."""
    d = end - start
    s = np.clip((t - start) / d, 0.0, 1.0)
    inside = (t > start) & (t < end)
    w = np.where(inside, np.sin(np.pi * s) ** 2, 0.0)
    w1 = np.where(inside, np.pi / d * np.sin(2 * np.pi * s), 0.0)
    w2 = np.where(inside, 2 * np.pi**2 / d**2 * np.cos(2 * np.pi * s), 0.0)
    return w, w1, w2


def _add_realism(sched: _Schedule, route: Route, t: Array, y: list[Array]) -> None:
    """Add stance roll-over, micro-motion and heel-strike transients in place.

    ``y`` = [value, first derivative, second derivative], each (len(t), 6).
    Vectorised: every time is matched to its stance window and its latest
    heel strike with ``searchsorted`` (windows and transients never overlap).
    """
    phases = np.asarray(route.seed_phases or (0.0, 0.0, 0.0))
    freqs = 2 * np.pi * np.array([9.0, 11.0, 13.0])
    windows = np.array(
        [(max(s, e - nominal), e, v) for s, e, v, nominal in sched.stance_intervals if v > 0]
    )
    if windows.size:
        ws, we, speed = windows.T
        k = np.searchsorted(ws, t, side="right") - 1
        kk = np.maximum(k, 0)
        sel = np.flatnonzero((k >= 0) & (t > ws[kk]) & (t < we[kk]))
        k = kk[sel]
        ts = t[sel]
        w, w1, w2 = _sin2_window(ts, ws[k], we[k])
        amp = 0.011 * speed[k] ** 2  # roll-over pitch bump (rad)
        y[0][sel, 4] += amp * w
        y[1][sel, 4] += amp * w1
        y[2][sel, 4] += amp * w2
        a_mm = (2e-4 * speed[k] ** 2)[:, None]  # heel micro-motion (m)
        arg = ts[:, None] * freqs[None, :] + phases[None, :]
        sn, cs = np.sin(arg), np.cos(arg)
        w, w1, w2 = w[:, None], w1[:, None], w2[:, None]
        y[0][sel, :3] += a_mm * w * sn
        y[1][sel, :3] += a_mm * (w1 * sn + w * freqs * cs)
        y[2][sel, :3] += a_mm * (w2 * sn + 2 * w1 * freqs * cs - w * freqs**2 * sn)
    if sched.strike_times:
        ths = np.array([s[0] for s in sched.strike_times])
        speed = np.array([s[1] for s in sched.strike_times])
        forward = np.array([s[2] for s in sched.strike_times])
        k = np.searchsorted(ths, t, side="right") - 1
        kk = np.maximum(k, 0)
        sel = np.flatnonzero((k >= 0) & (t - ths[kk] < 12 * _HS_TAU))
        k = kk[sel]
        lam = _HS_LAMBDA
        s = (t[sel] - ths[k]) / _HS_TAU
        e = np.exp(lam * s)
        B = 10.0 * speed[k] ** 2 * _HS_TAU**2 / _HS_PEAK
        p = np.stack(
            (
                B * np.imag(s**2 * e),
                B / _HS_TAU * np.imag((2 * s + lam * s**2) * e),
                B / _HS_TAU**2 * np.imag((2 + 4 * lam * s + lam**2 * s**2) * e),
            )
        )
        direction = np.stack((0.5 * forward[k, 0], 0.5 * forward[k, 1], np.ones(len(k))), -1)
        for d in range(3):
            y[d][sel, :3] += p[d][:, None] * direction


def imu_kinematics(
    heel: list[Array], euler: list[Array], lever_arm_m: Array, g: float
) -> tuple[Array, Array, Array, Array, Array]:
    """IMU position, velocity, acceleration, body rate and specific force.

    ``heel`` = [r_CO, ṙ_CO, r̈_CO] and ``euler`` = [e, ė, ë] (each (..., 3));
    paper 003's lever-arm formulas (module docstring).
    """
    C_nb = euler_to_dcm(euler[0])
    omega = body_rates_from_euler(euler[0], euler[1])
    omega_dot = body_angular_acceleration_from_euler(euler[0], euler[1], euler[2])
    r = np.broadcast_to(lever_arm_m, omega.shape)
    w_x_r = np.cross(omega, r)
    rel_acc = np.cross(omega, w_x_r) + np.cross(omega_dot, r)
    pos = heel[0] + np.einsum("...ij,...j->...i", C_nb, r)
    vel = heel[1] + np.einsum("...ij,...j->...i", C_nb, w_x_r)
    acc = heel[2] + np.einsum("...ij,...j->...i", C_nb, rel_acc)
    a_minus_g = acc.copy()
    a_minus_g[..., 2] += g
    f_b = np.einsum("...ji,...j->...i", C_nb, a_minus_g)  # C_nbᵀ (a − g_vec)
    return pos, vel, acc, omega, f_b


def simulate_foot(
    routes: Route | Sequence[Route], config: FootSimConfig | None = None
) -> FootTrajectory:
    """Simulate the instrumented foot of N walkers.

    Walks shorter than the longest are padded by standing still at the end.
    """
    cfg = config or FootSimConfig()
    routes = [routes] if isinstance(routes, Route) else list(routes)
    if not routes:
        raise ValueError("routes is empty")
    dt = cfg.dt
    durations = np.array([r.duration_s for r in routes])
    n_samples = int(math.ceil(durations.max() * cfg.rate_hz - 1e-9))
    t_grid = np.arange(n_samples + 1) * dt
    # Sensor sample m = mean over [t_m, t_m+1] by 2-point Gauss–Legendre
    # quadrature (exact for cubics; O(Δt⁴) for the trigonometric kinematics).
    gl_nodes, gl_weights = np.polynomial.legendre.leggauss(2)
    t_gauss = (t_grid[:-1, None] + 0.5 * dt * (1.0 + gl_nodes[None, :])).ravel()
    lever = np.asarray(cfg.lever_arm_m, dtype=float)

    n = len(routes)
    pos = np.empty((n, n_samples + 1, 3))
    vel = np.empty_like(pos)
    eul = np.empty_like(pos)
    omega = np.empty((n, n_samples, 3))
    f_b = np.empty_like(omega)
    stance = np.zeros((n, n_samples), dtype=bool)
    gait_step = np.zeros((n, n_samples), dtype=np.int64)
    gait = np.zeros((n, n_samples), dtype=np.int8)
    for i, route in enumerate(routes):
        sched = _build_schedule(route)
        t_end = sched.pp.x[-1]
        # Evaluate in chunks of samples so that memory stays bounded on long walks.
        for a in range(0, n_samples, _CHUNK_SAMPLES):
            b = min(a + _CHUNK_SAMPLES, n_samples)
            g_hi = b + 1 if b == n_samples else b
            t_chunk = np.concatenate((t_grid[a:g_hi], t_gauss[2 * a : 2 * b]))
            t_eval = np.minimum(t_chunk, t_end)
            y = [sched.pp(t_eval, nu) for nu in range(3)]
            after = t_chunk > t_end  # past the end of the walk the foot stands still
            y[1][after] = 0.0
            y[2][after] = 0.0
            if route.realistic:
                _add_realism(sched, route, t_chunk, y)
            heel = [yy[:, :3] for yy in y]
            e = [yy[:, [3, 4, 5]] for yy in y]
            p, v, _, w, f = imu_kinematics(heel, e, lever, cfg.g)
            ng = g_hi - a
            pos[i, a:g_hi], vel[i, a:g_hi], eul[i, a:g_hi] = p[:ng], v[:ng], e[0][:ng]
            half_w = 0.5 * gl_weights
            omega[i, a:b] = np.einsum("tgc,g->tc", w[ng:].reshape(b - a, -1, 3), half_w)
            f_b[i, a:b] = np.einsum("tgc,g->tc", f[ng:].reshape(b - a, -1, 3), half_w)
        starts = np.array([iv[0] for iv in sched.stance_intervals])
        ends = np.array([iv[1] for iv in sched.stance_intervals])
        lo, hi = t_grid[:-1], t_grid[1:]
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
        if sched.gait_spans:
            s0, s1, labels = (np.array(col) for col in zip(*sched.gait_spans, strict=True))
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
