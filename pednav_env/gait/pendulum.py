"""Paper 000's inverted-pendulum waist model, batched over walkers.

Yarmolich, "Test model of pedestrian motion" (paper 000): two rigid legs
AO = OC = l joined at the hip O; during one step the stance foot C stays put
and the hip swings over it. With the leg-opening angle φ running from φ_min
to π − φ_min at the constant rate ω_φ = (π − 2φ_min)/T (the symmetric case
T_I-III = T_III-V, eqs 12–13), in the sagittal plane of the walker (x* along
the walking surface, y* normal to it, origin at the stance foot)::

    x*(t) = −l cos(φ_min + ω_φ t),   y*(t) = l sin(φ_min + ω_φ t)    (12, 13)

and on a surface inclined by α the level-frame coordinates are the rotation
(18, 19); velocities and accelerations are the analytic derivatives (14–17,
20, 21), e.g. ẍ = ω_φ² l cos(φ_min + ω_φ t − α).

Step chaining (the paper's "add the start and end times of each step"):
step k has its own l_k, φ_min,k, T_k, slope α_k and heading ψ_k; its stance
foot is placed so that the hip *position* is continuous. The hip *velocity*
is not: at every double-support instant the vertical velocity reverses
(paper 000: y'(0) = −y'(T) on level ground) and the horizontal acceleration
jumps. When l sin φ_min changes between steps, keeping the hip continuous
moves the new stance foot off the previous ground line by the difference
(the model has no transition phase); with constant parameters all feet lie
on the slope line.

Embedding in 3-D (the frames of docs/CONVENTIONS.md, east-north-up): the hip moves along the
horizontal direction ψ_k (yaw, counter-clockwise from east) during step k;
the waist IMU is level (pitch = roll = 0) and its yaw turns from ψ_{k−1} to
ψ_k during step k along ψ_{k−1} + Δψ (1 − cos πτ)/2, τ = (t − t_k)/T_k, so
that body rates stay finite. After its last step a walker stands still.

Two accelerations are returned. ``acc_n`` is the closed form sampled at the
sample instants (what paper 000 integrates, eqs 20–21). ``acc_n_mean`` is the
mean acceleration over the preceding sample interval, (v_i − v_{i−1})/Δt, the
delta-velocity an IMU integrates; unlike point samples it contains the
double-support velocity reversal (a one-sample spike), so that integrating it
reproduces the hip velocity exactly across steps. Feed either to
:func:`pednav_env.sensors.imu.ideal_specific_force`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def _as_batch(name: str, value: ArrayLike, shape: tuple[int, int] | None = None) -> Array:
    arr = np.asarray(value, dtype=float)
    if shape is not None:
        try:
            arr = np.broadcast_to(arr, shape).copy()
        except ValueError:
            raise ValueError(
                f"{name} has shape {arr.shape}, not broadcastable to {shape}"
            ) from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    return arr


@dataclass(frozen=True)
class PendulumSteps:
    """Per-step parameters of N walkers taking K steps each, arrays ``(N, K)``.

    Scalars and ``(N, 1)`` / ``(K,)`` arrays broadcast to the shape of
    ``leg_length`` (or of the first parameter that is 2-D).

    Attributes
    ----------
    leg_length : (N, K) m
        l = AO = OC. Paper 000's check: 0.7 m.
    phi_min : (N, K) rad
        Leg-opening angle at double support, 0 < φ_min < π/2. Paper 000: π/3.
    step_period : (N, K) s
        Step duration T. Paper 000: 0.5 s.
    slope : (N, K) rad
        Surface inclination α (eqs 18–21), |α| < φ_min so that the hip moves
        forward during the whole step. Default 0.
    heading : (N, K) rad
        Walking direction ψ (yaw, counter-clockwise from east). Default 0.
    """

    leg_length: Array
    phi_min: Array
    step_period: Array
    slope: Array = 0.0  # type: ignore[assignment]
    heading: Array = 0.0  # type: ignore[assignment]

    def __post_init__(self) -> None:
        names = ("leg_length", "phi_min", "step_period", "slope", "heading")
        raw = {n: np.asarray(getattr(self, n), dtype=float) for n in names}
        two_d = [a.shape for a in raw.values() if a.ndim == 2]
        if not two_d:
            raise ValueError(
                "PendulumSteps needs at least one (N, K) parameter array; got shapes "
                + ", ".join(f"{n}={raw[n].shape}" for n in names)
            )
        shape = two_d[0]
        for n in names:
            object.__setattr__(self, n, _as_batch(f"PendulumSteps.{n}", raw[n], shape))
        if shape[1] < 1:
            raise ValueError(f"PendulumSteps needs at least one step, got shape {shape}")
        if np.any(self.leg_length <= 0):
            raise ValueError(f"PendulumSteps.leg_length must be > 0, min {self.leg_length.min()!r}")
        if np.any((self.phi_min <= 0) | (self.phi_min >= 0.5 * math.pi)):
            raise ValueError(
                "PendulumSteps.phi_min must lie in (0, π/2), got range "
                f"[{self.phi_min.min()!r}, {self.phi_min.max()!r}]"
            )
        if np.any(self.step_period <= 0):
            raise ValueError(
                f"PendulumSteps.step_period must be > 0, min {self.step_period.min()!r}"
            )
        if np.any(np.abs(self.slope) >= self.phi_min):
            raise ValueError(
                "PendulumSteps.slope must satisfy |α| < φ_min (hip moving forward), got "
                f"max |α| = {np.abs(self.slope).max()!r}"
            )

    @classmethod
    def from_step_length(
        cls,
        step_length: ArrayLike,
        leg_length: ArrayLike,
        step_period: ArrayLike,
        slope: ArrayLike = 0.0,
        heading: ArrayLike = 0.0,
    ) -> PendulumSteps:
        """Steps given their length L = 2 l cos φ_min along the surface (paper 000, eq 1
        with h = l(1 − sin φ_min)); needs L < 2l."""
        L = np.asarray(step_length, dtype=float)
        l_ = np.asarray(leg_length, dtype=float)
        if not (np.all(np.isfinite(L)) and np.all(np.isfinite(l_))):
            raise ValueError("step_length and leg_length must be finite")
        if np.any(L <= 0):
            raise ValueError(f"step_length must be > 0, min {L.min()!r}")
        if np.any(l_ <= 0.5 * L):
            raise ValueError(
                "leg_length must exceed half the step length (L = 2 l cos φ_min < 2 l); got "
                f"leg_length={l_!r} for step_length={L!r}"
            )
        phi = np.arccos(L / (2.0 * l_))
        shape = np.broadcast_shapes(L.shape, l_.shape, np.shape(step_period), (1, 1))
        return cls(
            leg_length=np.broadcast_to(l_, shape),
            phi_min=np.broadcast_to(phi, shape),
            step_period=np.broadcast_to(np.asarray(step_period, dtype=float), shape),
            slope=np.broadcast_to(np.asarray(slope, dtype=float), shape),
            heading=np.broadcast_to(np.asarray(heading, dtype=float), shape),
        )

    @property
    def shape(self) -> tuple[int, int]:
        """(N, K)."""
        return self.leg_length.shape  # type: ignore[return-value]

    @property
    def omega_phi(self) -> Array:
        """ω_φ = (π − 2φ_min)/T (rad/s), paper 000 eq (12)."""
        return (math.pi - 2.0 * self.phi_min) / self.step_period

    @property
    def step_length(self) -> Array:
        """Step length along the surface, 2 l cos φ_min (m)."""
        return 2.0 * self.leg_length * np.cos(self.phi_min)

    @property
    def mean_velocity(self) -> Array:
        """Mean horizontal hip speed per step, V̄_x = 2 l cos φ_min cos α / T (m/s),
        paper 000 (V̄^ИСТ and its slope projection)."""
        return self.step_length * np.cos(self.slope) / self.step_period

    @property
    def step_start(self) -> Array:
        """Start times of the steps and the end of the last one, ``(N, K+1)`` (s)."""
        n = self.shape[0]
        return np.concatenate((np.zeros((n, 1)), np.cumsum(self.step_period, axis=1)), axis=1)


def step_kinematics(
    t: ArrayLike,
    leg_length: ArrayLike,
    phi_min: ArrayLike,
    step_period: ArrayLike,
    slope: ArrayLike = 0.0,
) -> tuple[Array, Array, Array, Array, Array, Array]:
    """Hip position, velocity and acceleration within one step, relative to the stance foot.

    Paper 000 eqs (12)–(21): with θ = φ_min + ω_φ t, ω_φ = (π − 2φ_min)/T and
    the level frame rotated by the slope α (x forward-horizontal, y up)::

        x = −l cos(θ − α),        y = l sin(θ − α)
        ẋ = ω_φ l sin(θ − α),     ẏ = ω_φ l cos(θ − α)
        ẍ = ω_φ² l cos(θ − α),    ÿ = −ω_φ² l sin(θ − α)

    (eqs 18–19 applied to 12–13 give x = x* cos α − y* sin α = −l cos(θ − α)).

    Parameters
    ----------
    t : array, s
        Time since the step's start, 0 ≤ t ≤ T (broadcasts with the rest).
    leg_length, phi_min, step_period, slope : arrays
        l (m), φ_min (rad), T (s), α (rad).

    Returns
    -------
    x, y, vx, vy, ax, ay : arrays (m, m/s, m/s²)
    """
    t = np.asarray(t, dtype=float)
    l_ = np.asarray(leg_length, dtype=float)
    phi = np.asarray(phi_min, dtype=float)
    w = (math.pi - 2.0 * phi) / np.asarray(step_period, dtype=float)
    arg = phi + w * t - np.asarray(slope, dtype=float)
    c, s = np.cos(arg), np.sin(arg)
    return -l_ * c, l_ * s, w * l_ * s, w * l_ * c, w * w * l_ * c, -w * w * l_ * s


def hip_rise(leg_length: ArrayLike, phi_min: ArrayLike) -> Array:
    """Maximum hip rise during a level step, h = l (1 − sin φ_min) (m) (paper 000, Fig. 2)."""
    return np.asarray(leg_length, dtype=float) * (1.0 - np.sin(np.asarray(phi_min, dtype=float)))


def step_length_from_rise(hip_rise_m: ArrayLike, leg_length: ArrayLike) -> Array:
    """Step length L = 2 sqrt(2 l h − h²) (m), paper 000 eq (1); needs 0 ≤ h ≤ l."""
    h = np.asarray(hip_rise_m, dtype=float)
    l_ = np.asarray(leg_length, dtype=float)
    if np.any(h < 0) or np.any(h > l_) or not np.all(np.isfinite(h)):
        raise ValueError(f"hip_rise_m must lie in [0, leg_length], got {h!r}")
    return 2.0 * np.sqrt(2.0 * l_ * h - h * h)


@dataclass(frozen=True)
class PendulumWalk:
    """Sampled hip trajectory of N walkers on a common time grid of T samples.

    Attributes
    ----------
    t : (T,) s
        Sample times i/rate_hz.
    pos_n, vel_n : (N, T, 3)
        Hip position (m) and velocity (m/s), east-north-up.
    acc_n : (N, T, 3)
        Closed-form acceleration at the sample instants (paper 000 eqs 20–21).
    acc_n_mean : (N, T, 3)
        Mean acceleration over (t_{i−1}, t_i], (v_i − v_{i−1})·rate_hz; sample 0
        holds ``acc_n[:, 0]``. Contains the double-support velocity reversal.
    euler, euler_rate : (N, T, 3)
        IMU attitude [ψ, θ, γ] (rad) and its rate (rad/s); θ = γ = 0.
    step_index : (N, T) int
        Step number of each sample; K after the last step (standing).
    step_start : (N, K+1) s
        Step boundary times.
    foot_pos_n : (N, K, 3)
        Stance-foot position of each step (m).
    rate_hz : float
    """

    t: Array
    pos_n: Array
    vel_n: Array
    acc_n: Array
    acc_n_mean: Array
    euler: Array
    euler_rate: Array
    step_index: NDArray[np.int64]
    step_start: Array
    foot_pos_n: Array
    rate_hz: float

    @property
    def walking(self) -> NDArray[np.bool_]:
        """(N, T) True while the walker is within one of its steps."""
        return self.step_index < self.step_start.shape[1] - 1


def simulate_walk(
    steps: PendulumSteps,
    rate_hz: float,
    n_samples: int | None = None,
    origin: ArrayLike = (0.0, 0.0, 0.0),
) -> PendulumWalk:
    """Sample the chained pendulum walk of every walker on one time grid.

    Parameters
    ----------
    steps : PendulumSteps
        Per-step parameters, ``(N, K)``.
    rate_hz : float
        Sample rate (Hz), > 0. Paper 000: 100 Hz.
    n_samples : int, optional
        Number of samples; default covers the longest walk, ``floor(t_end·rate) + 1``.
    origin : (3,) or (N, 3)
        Position of the rear foot A at t = 0 (paper 000: x_C(0) = 2 l cos φ_min,
        y_C(0) = 0, i.e. A at the origin and the first stance foot one step ahead).

    Returns
    -------
    PendulumWalk
    """
    if not (isinstance(rate_hz, int | float) and math.isfinite(rate_hz) and rate_hz > 0):
        raise ValueError(f"rate_hz must be a finite number > 0, got {rate_hz!r}")
    n, k = steps.shape
    starts = steps.step_start
    t_end = starts[:, -1]
    if n_samples is None:
        n_samples = int(math.floor(float(t_end.max()) * rate_hz + 1e-9)) + 1
    if not isinstance(n_samples, int | np.integer) or n_samples < 1:
        raise ValueError(f"n_samples must be a positive integer, got {n_samples!r}")
    origin = np.broadcast_to(np.asarray(origin, dtype=float), (n, 3))
    if not np.all(np.isfinite(origin)):
        raise ValueError("origin contains NaN or inf")

    t = np.arange(n_samples) / float(rate_hz)
    l_, phi, T, alpha, psi = (
        steps.leg_length,
        steps.phi_min,
        steps.step_period,
        steps.slope,
        steps.heading,
    )
    # Hip position relative to the stance foot at the start and end of each step.
    x0, y0, *_ = step_kinematics(0.0, l_, phi, T, alpha)
    x1, y1, *_ = step_kinematics(T, l_, phi, T, alpha)
    cpsi, spsi = np.cos(psi), np.sin(psi)

    def to_nav(x: Array, y: Array) -> Array:
        return np.stack((x * cpsi, x * spsi, y), axis=-1)

    rel0, rel1 = to_nav(x0, y0), to_nav(x1, y1)  # (N, K, 3)
    # Foot of step 0: one step (2 l cos φ_min along the surface) ahead of A.
    L0 = steps.step_length[:, 0]
    foot0 = origin + np.stack(
        (
            L0 * np.cos(alpha[:, 0]) * cpsi[:, 0],
            L0 * np.cos(alpha[:, 0]) * spsi[:, 0],
            L0 * np.sin(alpha[:, 0]),
        ),
        axis=-1,
    )
    # Continuity of the hip: hip_end(k−1) = foot_{k−1} + rel1_{k−1} = foot_k + rel0_k.
    feet = foot0[:, None, :] + np.concatenate(
        (np.zeros((n, 1, 3)), np.cumsum(rel1[:, :-1] - rel0[:, 1:], axis=1)), axis=1
    )

    # Step index of every sample: sample j belongs to step k when t_k ≤ t_j < t_{k+1}.
    # First sample of each step, ceil(t_k·rate) (a boundary within 1e-9 of a sample
    # snaps onto it); counting boundaries with a cumulative sum keeps every walker's
    # result independent of the batch.
    first = np.ceil(starts[:, 1:] * float(rate_hz) - 1e-9).astype(np.int64)
    marks = np.zeros((n, n_samples + 1), dtype=np.int64)
    np.add.at(marks, (np.repeat(np.arange(n), k), np.minimum(first, n_samples).ravel()), 1)
    step_index = np.cumsum(marks[:, :-1], axis=1)
    walking = step_index < k
    ki = np.minimum(step_index, k - 1)

    def take(a: Array) -> Array:
        return np.take_along_axis(a, ki, axis=1)

    tau = np.where(walking, t[None, :] - take(starts[:, :-1]), take(T))
    x, y, vx, vy, ax, ay = step_kinematics(tau, take(l_), take(phi), take(T), take(alpha))
    c, s = take(cpsi), take(spsi)
    foot = np.take_along_axis(feet, ki[..., None], axis=1)
    pos = foot + np.stack((x * c, x * s, y), axis=-1)
    stand = ~walking
    vel = np.stack((vx * c, vx * s, vy), axis=-1)
    acc = np.stack((ax * c, ax * s, ay), axis=-1)
    vel[stand] = 0.0
    acc[stand] = 0.0

    # Yaw: from the previous heading to this step's heading during the step.
    psi_prev = np.concatenate((psi[:, :1], psi[:, :-1]), axis=1)
    dpsi = (psi - psi_prev + math.pi) % (2.0 * math.pi) - math.pi
    frac = np.clip(tau / take(T), 0.0, 1.0)
    d = take(dpsi)
    yaw = take(psi_prev) + d * 0.5 * (1.0 - np.cos(math.pi * frac))
    yaw_rate = np.where(walking, d * 0.5 * math.pi / take(T) * np.sin(math.pi * frac), 0.0)
    euler = np.zeros((n, n_samples, 3))
    euler[..., 0] = yaw
    euler_rate = np.zeros((n, n_samples, 3))
    euler_rate[..., 0] = yaw_rate

    acc_mean = np.empty_like(acc)
    acc_mean[:, 0] = acc[:, 0]
    acc_mean[:, 1:] = np.diff(vel, axis=1) * float(rate_hz)
    return PendulumWalk(
        t=t,
        pos_n=pos,
        vel_n=vel,
        acc_n=acc,
        acc_n_mean=acc_mean,
        euler=euler,
        euler_rate=euler_rate,
        step_index=step_index,
        step_start=starts,
        foot_pos_n=feet,
        rate_hz=float(rate_hz),
    )
