"""Paper 002's walking robot with a waist IMU, batched over walkers.

Kuporosova (paper 002) models a person with a belt IMU as a "robot" walking
a closed rectangle O₀ABC (sides 5, 3, 5, 3 m) at V* = 0.93 m/s, stopping at
each corner and turning 90° left in Δt = 1 s at constant rate, while the IMU
performs harmonic motions at the gait frequency ω = 4.86 rad/s (a two-step
period of 1.29 s):

- vertical, eqs (1)–(2): h(t) = |y_m cos ωt|, ḣ = ∓y_m ω sin ωt (y_m = 0.06 m);
- pitch, eq (3): ϑ = ϑ_m − ϑ_m cos 2ωt (forward tilt 2ϑ_m at each footfall);
- roll and yaw, eq (4): γ = γ_m sin ωt, Δψ = Δψ_m sin ωt; heading ψ = ψ* + Δψ (6);
- forward speed, eq (7): V* + ΔV cos 2ωt (ΔV = 0.3 m/s);
- lateral speed, eq (8): −Δẋ_m cos ωt (Δẋ_m = 0.15 m/s).

Frames. The paper's O₀x₀y₀z₀ has y₀ up and the robot leaving O₀ along z₀;
its IMU axes a_x (lateral, to the left), a_y (up), a_z (forward), and its
Euler sequence is yaw ψ about a_y, pitch ϑ about a_x, roll γ about a_z with
the rate relation (9). This module uses the project's frames (docs/CONVENTIONS.md) instead —
east-north-up, body x forward / y left / z up, [ψ, θ, γ] of
:mod:`pednav_env.rotations` — through the proper rotations

    paper (x₀, y₀, z₀) = (west, up, north),   paper (a_x, a_y, a_z) = body (y, z, x),
    ψ_ours = π/2 + ψ_paper,  θ_ours = ϑ,  γ_ours = γ,

under which the paper's eq (9) becomes :func:`pednav_env.rotations.body_rates_from_euler`
and its matrix B(ψ, ϑ, γ) becomes C_nbᵀ (verified in ``tests/gait/test_robot.py``).
The robot therefore starts heading north and turns left (west, south, east).

Choices where the paper is silent (docs/REPRODUCTION.md (papers 000/002/004)):
the corner turn is exactly π/2 in ``turn_duration`` (the paper's 1.57 s⁻¹ is
π/2 rounded); the path direction is ψ* (yaw oscillation Δψ sways the body,
not the path); the lateral speed is along the body's left axis of the path
frame; the oscillations run on the global clock t during stops as written
(``oscillate_when_stopped=True``) or freeze while the robot stands
(``False``: a gait clock τ that only advances while walking); forward and
lateral speeds are zero while turning and after the end.

The robot's ideal IMU readings (eqs 9, 10, 12) are
:func:`pednav_env.sensors.imu.ideal_imu` of its Euler angles, rates and
``acc_n_mean``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class RobotConfig:
    """One robot walk (SI units, radians). Defaults are paper 002's values.

    Attributes
    ----------
    side_lengths : tuple of float
        Route legs O₀A, AB, BC, CO₀ (m): 5, 3, 5, 3 (S = 16 m). Any number ≥ 1 of
        legs; the robot turns after every leg but the last.
    speed : float
        V* (m/s): 0.93.
    turn_duration : float
        Stop-and-turn time at a corner (s): 1.
    turn_angle : float
        Turn at each corner (rad, + = left): π/2.
    omega : float
        ω (rad/s): 4.86 (= ½ · 2π · 1.55 Hz).
    vertical_amplitude : float
        y_m (m): 0.06 as printed (its formula l − sqrt(l² − 0.25 L₁²) with
        l = 1 m, L₁ = 0.6 m gives 0.046 m).
    pitch_amplitude, roll_amplitude, yaw_amplitude : float
        ϑ_m, γ_m, Δψ_m (rad). Experiment: ϑ_m = 0.69°, γ_m = 1.13°; Δψ_m not
        printed (default 0).
    speed_oscillation : float
        ΔV (m/s): 0.3.
    lateral_speed_amplitude : float
        Δẋ_m (m/s): 0.15.
    initial_heading : float
        ψ* at t = 0 (rad, from east counter-clockwise): π/2 (north = paper's z₀).
    oscillate_when_stopped : bool
        See the module docstring. Default True (the paper's functions of t).
    """

    side_lengths: tuple[float, ...] = (5.0, 3.0, 5.0, 3.0)
    speed: float = 0.93
    turn_duration: float = 1.0
    turn_angle: float = 0.5 * math.pi
    omega: float = 4.86
    vertical_amplitude: float = 0.06
    pitch_amplitude: float = math.radians(0.69)
    roll_amplitude: float = math.radians(1.13)
    yaw_amplitude: float = 0.0
    speed_oscillation: float = 0.3
    lateral_speed_amplitude: float = 0.15
    initial_heading: float = 0.5 * math.pi
    oscillate_when_stopped: bool = True

    def __post_init__(self) -> None:
        sides = tuple(float(s) for s in self.side_lengths)
        if not sides or any(not math.isfinite(s) or s <= 0 for s in sides):
            raise ValueError(f"RobotConfig.side_lengths must be finite and > 0, got {sides!r}")
        object.__setattr__(self, "side_lengths", sides)
        for f in fields(self):
            if f.name in ("side_lengths", "oscillate_when_stopped"):
                continue
            v = getattr(self, f.name)
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"RobotConfig.{f.name} must be a finite number, got {v!r}")
        for name in ("speed", "turn_duration", "omega"):
            if getattr(self, name) <= 0:
                raise ValueError(f"RobotConfig.{name} must be > 0, got {getattr(self, name)!r}")
        for name in (
            "vertical_amplitude",
            "pitch_amplitude",
            "roll_amplitude",
            "yaw_amplitude",
            "speed_oscillation",
            "lateral_speed_amplitude",
        ):
            if getattr(self, name) < 0:
                raise ValueError(f"RobotConfig.{name} must be ≥ 0, got {getattr(self, name)!r}")
        if self.speed_oscillation >= self.speed:
            raise ValueError(
                f"RobotConfig.speed_oscillation must be < speed (no walking backwards), got "
                f"{self.speed_oscillation!r} ≥ {self.speed!r}"
            )
        if 2.0 * self.pitch_amplitude >= 0.5 * math.pi:
            raise ValueError(
                f"RobotConfig.pitch_amplitude must be < π/4, got {self.pitch_amplitude!r}"
            )

    @classmethod
    def no_oscillation(cls, **kw: object) -> RobotConfig:
        """Paper 002's ideal case: no angular and no linear oscillations (Fig. 6)."""
        base = dict(
            vertical_amplitude=0.0,
            pitch_amplitude=0.0,
            roll_amplitude=0.0,
            yaw_amplitude=0.0,
            speed_oscillation=0.0,
            lateral_speed_amplitude=0.0,
        )
        base.update(kw)
        return cls(**base)  # type: ignore[arg-type]

    def with_(self, **kw: object) -> RobotConfig:
        """A copy with some fields replaced (validated)."""
        return replace(self, **kw)  # type: ignore[arg-type]

    @property
    def walk_durations(self) -> tuple[float, ...]:
        """Duration of each leg, L / V* (s)."""
        return tuple(s / self.speed for s in self.side_lengths)

    @property
    def route_duration(self) -> float:
        """Time from O₀ back to the end point (s): 20.2 s for the defaults."""
        return sum(self.walk_durations) + self.turn_duration * (len(self.side_lengths) - 1)

    @property
    def route_length(self) -> float:
        """S (m): 16 m for the defaults."""
        return float(sum(self.side_lengths))


def vertical_amplitude_from_leg(leg_length: float, step_length: float) -> float:
    """y_m = l − sqrt(l² − 0.25 L₁²) (m), paper 002 after eq (2)."""
    if not (math.isfinite(leg_length) and math.isfinite(step_length)) or step_length <= 0:
        raise ValueError(f"step_length must be finite and > 0, got {step_length!r}")
    if leg_length <= 0.5 * step_length:
        raise ValueError(
            f"leg_length must exceed half the step length, got leg_length={leg_length!r} for "
            f"step_length={step_length!r}"
        )
    return leg_length - math.sqrt(leg_length**2 - 0.25 * step_length**2)


def paper_kinematic_matrix(pitch: Array, roll: Array) -> Array:
    """Paper 002's eq (9) matrix in its own axes, (..., 3, 3).

    (ω_x, ω_y, ω_z)_paper = M (ψ̇, ϑ̇, γ̇) with M = [[cos ϑ sin γ, cos γ, 0],
    [cos ϑ cos γ, −sin γ, 0], [−sin ϑ, 0, 1]] (a_x lateral-left, a_y up, a_z forward).
    """
    th = np.asarray(pitch, dtype=float)
    ga = np.asarray(roll, dtype=float)
    M = np.zeros((*np.broadcast(th, ga).shape, 3, 3))
    M[..., 0, 0] = np.cos(th) * np.sin(ga)
    M[..., 0, 1] = np.cos(ga)
    M[..., 1, 0] = np.cos(th) * np.cos(ga)
    M[..., 1, 1] = -np.sin(ga)
    M[..., 2, 0] = -np.sin(th)
    M[..., 2, 2] = 1.0
    return M


def paper_dcm(yaw: Array, pitch: Array, roll: Array) -> Array:
    """Paper 002's B(ψ, ϑ, γ) (navigation → IMU, its own axes), (..., 3, 3).

    Three frame rotations from the aligned position: ψ about a_y, then ϑ about
    a_x, then γ about a_z (the sequence its eq (9) differentiates):
    B = R_z(γ) R_x(ϑ) R_y(ψ) with R the passive (frame) rotations.
    """

    def rot(axis: int, a: Array) -> Array:
        a = np.asarray(a, dtype=float)
        c, s = np.cos(a), np.sin(a)
        R = np.zeros((*a.shape, 3, 3))
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        R[..., axis, axis] = 1.0
        R[..., i, i] = c
        R[..., j, j] = c
        R[..., i, j] = s
        R[..., j, i] = -s
        return R

    return rot(2, roll) @ rot(0, pitch) @ rot(1, yaw)


#: Paper 002 navigation axes (x₀, y₀, z₀) in ENU columns, and IMU axes (a_x, a_y, a_z)
#: in our body axes: paper = P · ours.
PAPER_NAV_FROM_ENU = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
PAPER_BODY_FROM_OURS = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


@dataclass(frozen=True)
class RobotWalk:
    """Sampled robot motion, N walkers on one grid of T samples.

    Attributes
    ----------
    t : (T,) s
    pos_n, vel_n : (N, T, 3)
        IMU position (m; up = h(t) above H_min) and velocity (m/s), ENU.
    acc_n_mean : (N, T, 3)
        Eq (10): (V(i) − V(i−1))/Δt, the mean acceleration over (t_{i−1}, t_i];
        sample 0 is 0 (the scheme starts at i = 1).
    euler, euler_rate : (N, T, 3)
        True [ψ, θ, γ] (rad) and rates (rad/s).
    walking : (N, T) bool
    route_end : (N,) s
    end_index : (N,) int
        First sample at or after the route's end.
    dt : float
    """

    t: Array
    pos_n: Array
    vel_n: Array
    acc_n_mean: Array
    euler: Array
    euler_rate: Array
    walking: NDArray[np.bool_]
    route_end: Array
    end_index: NDArray[np.int64]
    dt: float


def _arrays(configs: Sequence[RobotConfig], name: str) -> Array:
    return np.array([getattr(c, name) for c in configs], dtype=float)[:, None]


def simulate_robot(
    config: RobotConfig | Sequence[RobotConfig],
    dt: float = 0.025,
    n_samples: int | None = None,
    align_to_grid: bool = False,
) -> RobotWalk:
    """Sample the robot's true motion at t_i = i·dt.

    Parameters
    ----------
    config : RobotConfig or sequence of N configs (same number of legs)
    dt : float
        Sample period (s), > 0. Paper 002: T = 0.025 s.
    n_samples : int, optional
        Default: up to the first sample at or after the latest route end.
    align_to_grid : bool
        Round every walk and turn duration to a whole number of samples, so
        that stops, turns and starts happen exactly at sample instants (the
        legs shorten or lengthen by less than V*·dt/2). A hypothesis about the
        paper's discrete-time simulation; off by default (continuous time).

    Returns
    -------
    RobotWalk
    """
    configs = [config] if isinstance(config, RobotConfig) else list(config)
    if not configs:
        raise ValueError("config: need at least one RobotConfig")
    if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a finite number > 0, got {dt!r}")
    n_legs = len(configs[0].side_lengths)
    if any(len(c.side_lengths) != n_legs for c in configs):
        raise ValueError("config: all walkers need the same number of route legs")
    n = len(configs)

    V = _arrays(configs, "speed")
    dV = _arrays(configs, "speed_oscillation")
    dxm = _arrays(configs, "lateral_speed_amplitude")
    w = _arrays(configs, "omega")
    ym = _arrays(configs, "vertical_amplitude")
    th_m = _arrays(configs, "pitch_amplitude")
    ga_m = _arrays(configs, "roll_amplitude")
    ps_m = _arrays(configs, "yaw_amplitude")
    turn_T = _arrays(configs, "turn_duration")
    turn_a = _arrays(configs, "turn_angle")
    psi0 = _arrays(configs, "initial_heading")
    always = np.array([c.oscillate_when_stopped for c in configs])[:, None]

    # Segment boundaries: leg 0, turn 0, leg 1, …, leg n−1 → 2 n_legs − 1 segments.
    durations = []
    for j in range(n_legs):
        durations.append(np.array([c.walk_durations[j] for c in configs]))
        if j < n_legs - 1:
            durations.append(turn_T[:, 0].copy())
    if align_to_grid:
        durations = [np.maximum(np.round(d / dt), 1.0) * dt for d in durations]
        turn_T = durations[1][:, None] if n_legs > 1 else turn_T
    route_end = np.sum(durations, axis=0)
    end_index = np.ceil(route_end / dt - 1e-9).astype(np.int64)
    if n_samples is None:
        n_samples = int(end_index.max()) + 1
    if not isinstance(n_samples, int | np.integer) or n_samples < 1:
        raise ValueError(f"n_samples must be a positive integer, got {n_samples!r}")
    t = np.arange(n_samples) * float(dt)
    bounds = np.concatenate((np.zeros((n, 1)), np.cumsum(np.stack(durations, 1), 1)), 1)
    seg = np.sum(t[None, :, None] >= bounds[:, None, 1:], axis=2)  # (N, T), 2 n_legs − 1 = end
    n_seg = 2 * n_legs - 1
    seg_c = np.minimum(seg, n_seg - 1)
    seg_start = np.take_along_axis(bounds, seg_c, axis=1)
    walking = (seg % 2 == 0) & (seg < n_seg)
    turning = (seg % 2 == 1) & (seg < n_seg)
    leg = np.minimum(seg // 2, n_legs - 1)  # leg index (during a turn: the leg just ended)

    # Gait clock τ: t, or time spent walking (oscillations frozen while standing).
    walk_dur = np.where(np.arange(n_seg) % 2 == 0, np.diff(bounds, axis=1), 0.0)
    walked_before = np.concatenate((np.zeros((n, 1)), np.cumsum(walk_dur, axis=1)), axis=1)
    tau_walk = np.take_along_axis(walked_before, np.minimum(seg, n_seg), axis=1) + np.where(
        walking, t[None, :] - seg_start, 0.0
    )
    tau = np.where(always, t[None, :], tau_walk)
    dtau = np.where(always | walking, 1.0, 0.0)

    # Heading ψ* of the path.
    turn_frac = np.where(turning, (t[None, :] - seg_start) / turn_T, 0.0)
    psi_star = psi0 + turn_a * (leg + turn_frac)
    psi_star_rate = np.where(turning, turn_a / turn_T, 0.0)

    # Attitude, eqs (3), (4), (6), and rates, eq (5).
    s1, c1 = np.sin(w * tau), np.cos(w * tau)
    s2, c2 = np.sin(2 * w * tau), np.cos(2 * w * tau)
    euler = np.stack(
        (psi_star + ps_m * s1, th_m - th_m * c2, ga_m * s1),
        axis=-1,
    )
    euler_rate = np.stack(
        (
            psi_star_rate + ps_m * w * c1 * dtau,
            2.0 * th_m * w * s2 * dtau,
            ga_m * w * c1 * dtau,
        ),
        axis=-1,
    )

    # Velocities, eqs (2), (7), (8): path frame (forward, left) rotated by ψ* of the leg.
    psi_leg = psi0 + turn_a * leg
    cf, sf = np.cos(psi_leg), np.sin(psi_leg)
    u = np.where(walking, V + dV * c2, 0.0)
    lat = np.where(walking, -dxm * c1, 0.0)
    vel = np.stack(
        (u * cf - lat * sf, u * sf + lat * cf, -ym * w * s1 * np.sign(c1) * dtau),
        axis=-1,
    )

    # Positions: closed-form integrals of the velocities, leg by leg.
    tau_leg0 = np.take_along_axis(walked_before, np.arange(0, n_seg, 2)[None, :].repeat(n, 0), 1)
    t_leg0 = bounds[:, 0:n_seg:2]
    t_leg1 = bounds[:, 1 : n_seg + 1 : 2]
    tau_c0 = np.where(always, t_leg0, tau_leg0)
    tau_c1 = tau_c0 + (t_leg1 - t_leg0)
    psi_legs = psi0 + turn_a * np.arange(n_legs)[None, :]

    def disp(tau_a: Array, tau_b: Array) -> tuple[Array, Array]:
        fwd = V * (tau_b - tau_a) + dV / (2 * w) * (np.sin(2 * w * tau_b) - np.sin(2 * w * tau_a))
        left = -dxm / w * (np.sin(w * tau_b) - np.sin(w * tau_a))
        return fwd, left

    fwd_l, left_l = disp(tau_c0, tau_c1)
    leg_disp = np.stack(
        (
            fwd_l * np.cos(psi_legs) - left_l * np.sin(psi_legs),
            fwd_l * np.sin(psi_legs) + left_l * np.cos(psi_legs),
        ),
        axis=-1,
    )  # (N, n_legs, 2)
    leg_start = np.concatenate((np.zeros((n, 1, 2)), np.cumsum(leg_disp, axis=1)), axis=1)
    start = np.take_along_axis(leg_start, leg[..., None], axis=1)
    tau_a = np.take_along_axis(tau_c0, leg, axis=1)
    tau_now = np.where(walking, tau_a + (t[None, :] - np.take_along_axis(t_leg0, leg, 1)), 0.0)
    fwd, left = disp(tau_a, tau_now)
    fwd = np.where(walking, fwd, 0.0)
    left = np.where(walking, left, 0.0)
    done = ~walking  # standing after leg `leg` (turn) or after the route
    end_of_leg = np.take_along_axis(leg_start, (leg + 1)[..., None], axis=1)
    horiz = np.where(
        done[..., None],
        end_of_leg,
        start + np.stack((fwd * cf - left * sf, fwd * sf + left * cf), axis=-1),
    )
    pos = np.concatenate((horiz, (ym * np.abs(c1))[..., None]), axis=-1)

    acc_mean = np.zeros_like(vel)
    acc_mean[:, 1:] = np.diff(vel, axis=1) / dt
    return RobotWalk(
        t=t,
        pos_n=pos,
        vel_n=vel,
        acc_n_mean=acc_mean,
        euler=euler,
        euler_rate=euler_rate,
        walking=walking,
        route_end=route_end,
        end_index=end_index,
        dt=float(dt),
    )
