"""Walks of a belt-IMU walker on paper 000's inverted pendulum, one walker per call.

- Paper 004's test walk (:func:`paper_walk`): l = 0.7 m, φ_min = 60°,
  T = 0.5 s (0.7 m steps at 1.4 m/s), K = 10 128 steps (84.4 min, one
  Schuler period) on six equal legs (:func:`route_azimuths`).
- Randomised walks: :func:`walk_plan` draws bouts of steps in a gait style,
  with slopes, turns and stops, from ranges (:class:`WalkRanges`);
  :func:`assemble_walk` chains the pendulum steps
  (:func:`pednav_env.gait.pendulum.simulate_walk`) and splices the stands in,
  on one sample grid.

The result (:class:`WaistWalk`) is the truth a sensor model reads
(:mod:`pednav_env.sensors.waist_record`): hip position and velocity, yaw, and
the error segments (each step and each stand) with their durations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from pednav_env.gait.pendulum import PendulumSteps, simulate_walk

Array = NDArray[np.float64]

#: Paper 004's number of steps K (84.4 min at T = 0.5 s).
PAPER_STEPS = 10_128
#: Paper 004's test walker (paper 000's check): l (m), φ_min (rad), T (s).
PAPER_LEG_LENGTH = 0.7
PAPER_PHI_MIN = math.pi / 3
PAPER_STEP_PERIOD = 0.5


def route_azimuths(steps: int, legs: int = 6, first_deg: float = 30.0) -> np.ndarray:
    """Azimuth α(k) (rad, from north, clockwise) of each step k = 1 … K: ``legs`` equal
    legs turning by 360°/legs, starting at ``first_deg`` (paper 004: α = 30°)."""
    leg = np.minimum(np.arange(steps) * legs // steps, legs - 1)
    return np.radians(first_deg + leg * 360.0 / legs)


class WalkRanges(Protocol):
    """Ranges :func:`walk_plan` draws from (uniform unless said; SI units, degrees).

    Gait styles slow / normal / fast set, per bout, the step period T and the
    step length as a fraction of the leg length (L = 2 l cos φ_min, paper 000);
    each step then jitters both by ``step_jitter`` (relative std, clipped to
    ±20 %).
    """

    initial_stand_s: tuple[float, float]
    gait_weights: tuple[float, float, float]
    gait_step_period_s: tuple[tuple[float, float], ...]
    gait_step_ratio: tuple[tuple[float, float], ...]
    step_jitter: float
    bout_steps: tuple[int, int]
    stop_probability: float
    stop_duration_s: tuple[float, float]
    slope_probability: float
    slope_deg: tuple[float, float]
    turn_probability: float
    turn_deg: tuple[float, float]
    heading_wander_deg: float


@dataclass(frozen=True)
class WalkPlan:
    """Per-step parameters of one walk, arrays (K,), and its stands."""

    step_period_s: Array  #: T of each step (s)
    step_length_m: Array  #: L of each step (m)
    slope_rad: Array  #: surface slope α of each step (rad)
    heading_rad: Array  #: heading ψ of each step (rad, counter-clockwise from east)
    initial_stand_s: float  #: standing time before the first step (s)
    #: Stops as (index of the step after which the walker stops, duration s).
    stops: tuple[tuple[int, float], ...]


@dataclass(frozen=True)
class WaistWalk:
    """One walker's sampled truth, L samples from t = 0."""

    pos_n: Array  #: (L, 3) hip position relative to the start (m, ENU)
    vel_n: Array  #: (L, 3) hip velocity (m/s); 0 while standing
    yaw: Array  #: (L,) heading of the level waist IMU (rad, counter-clockwise from east)
    segment: NDArray[np.int64]  #: (L,) error segment of each sample (steps and stands, in order)
    segment_duration_s: Array  #: (S,) duration of each segment (s)


def walk_plan(
    rng: np.random.Generator, ranges: WalkRanges, duration_s: float, leg_length_m: float
) -> WalkPlan:
    """Draw a walk of at least ``duration_s`` from ``ranges`` (fixed draw order).

    Bouts until the duration is covered: gait style, bout length, T and step
    ratio of the style, the bout's slope (± with ``slope_probability``), then
    per step the jitter of T and L, a turn (``turn_probability``) and the
    heading wander; after the bout a stop with ``stop_probability``.
    """
    r = ranges
    T_parts, L_parts, a_parts, h_parts = [], [], [], []
    stops: list[tuple[int, float]] = []
    heading = rng.uniform(-math.pi, math.pi)
    initial_stand = rng.uniform(*r.initial_stand_s)
    t = initial_stand
    steps = 0
    w = np.asarray(r.gait_weights, dtype=float)
    w = w / w.sum()
    while t < duration_s:
        gait = int(rng.choice(3, p=w))
        n = int(rng.integers(r.bout_steps[0], r.bout_steps[1] + 1))
        T0 = rng.uniform(*r.gait_step_period_s[gait])
        ratio = rng.uniform(*r.gait_step_ratio[gait])
        slope = 0.0
        if rng.random() < r.slope_probability:
            slope = math.radians(rng.uniform(*r.slope_deg)) * (1.0 if rng.random() < 0.5 else -1.0)
        jit = np.minimum(np.maximum(1.0 + rng.standard_normal((2, n)) * r.step_jitter, 0.8), 1.2)
        turn = rng.random(n) < r.turn_probability
        turn_deg = rng.uniform(*r.turn_deg, n) * np.where(rng.random(n) < 0.5, 1.0, -1.0)
        wander = rng.standard_normal(n) * r.heading_wander_deg
        dpsi = np.radians(wander + np.where(turn, turn_deg, 0.0))
        T_parts.append(T0 * jit[0])
        L_parts.append(ratio * leg_length_m * jit[1])
        a_parts.append(np.full(n, slope))
        h_parts.append(heading + np.cumsum(dpsi))
        heading = float(h_parts[-1][-1])
        t += float(T_parts[-1].sum())
        steps += n
        if rng.random() < r.stop_probability:
            stop_s = rng.uniform(*r.stop_duration_s)
            stops.append((steps - 1, stop_s))
            t += stop_s
    return WalkPlan(
        step_period_s=np.concatenate(T_parts),
        step_length_m=np.concatenate(L_parts),
        slope_rad=np.concatenate(a_parts),
        heading_rad=np.concatenate(h_parts),
        initial_stand_s=initial_stand,
        stops=tuple(stops),
    )


def assemble_walk(leg_length_m: float, plan: WalkPlan, rate_hz: float, n_samples: int) -> WaistWalk:
    """One pendulum chain (paper 000) with stands spliced in, on one sample grid.

    The chain is simulated without stops; a stand of duration D after step k
    begins at the first sample after that footfall, holds that hip position
    (velocity 0) for round(D·rate) samples, and the chain then resumes (the
    velocity jump at resumption is the start footfall). Segments: step k → 2k,
    a stand before step k → 2k − 1, standing after the last step → 2K, numbered
    in time order.
    """
    T, leg, rate = plan.step_period_s, leg_length_m, rate_hz
    steps = PendulumSteps.from_step_length(
        plan.step_length_m[None], leg, T[None], plan.slope_rad[None], plan.heading_rad[None]
    )
    bounds = steps.step_start[0]
    src_parts: list[NDArray[np.int64]] = []
    stand_parts: list[NDArray[np.bool_]] = []
    m0 = int(round(plan.initial_stand_s * rate))
    src_parts.append(np.zeros(m0, dtype=np.int64))
    stand_parts.append(np.ones(m0, dtype=bool))
    have, orig = m0, 0
    for k, dur in plan.stops:
        if have >= n_samples:
            break
        j = int(math.ceil(bounds[k + 1] * rate - 1e-9))  # first sample after the footfall
        src_parts += [np.arange(orig, j), np.full(int(round(dur * rate)), j)]
        stand_parts += [np.zeros(j - orig, dtype=bool), np.ones(int(round(dur * rate)), dtype=bool)]
        have += j - orig + int(round(dur * rate))
        orig = j
    rest = max(n_samples - have, 0)
    src_parts.append(np.arange(orig, orig + rest))
    stand_parts.append(np.zeros(rest, dtype=bool))
    src = np.concatenate(src_parts)[:n_samples]
    stand = np.concatenate(stand_parts)[:n_samples]
    walk = simulate_walk(steps, rate, n_samples=int(src.max()) + 1)
    pos = walk.pos_n[0, src]
    pos -= pos[0]
    vel = np.where(stand[:, None], 0.0, walk.vel_n[0, src])
    step_idx = walk.step_index[0, src]
    key = 2 * step_idx - stand.astype(np.int64)
    key[stand & (step_idx == T.size)] = 2 * T.size
    change = np.flatnonzero(key[1:] != key[:-1]) + 1  # keys never decrease
    seg = np.zeros(key.size, dtype=np.int64)
    seg[change] = 1
    np.cumsum(seg, out=seg)
    keys = key[np.concatenate(([0], change))]
    counts = np.diff(np.concatenate(([0], change, [key.size])))
    is_step = (keys % 2 == 0) & (keys < 2 * T.size)
    periods = np.where(is_step, T[np.minimum(keys // 2, T.size - 1)], counts / rate)
    return WaistWalk(
        pos_n=pos, vel_n=vel, yaw=walk.euler[0, src, 0], segment=seg, segment_duration_s=periods
    )


def paper_walk(steps: int, rate_hz: float, n_samples: int) -> WaistWalk:
    """Paper 004's test walk of ``steps`` steps (level, no stands), ``n_samples`` samples."""
    leg = PAPER_LEG_LENGTH
    az = route_azimuths(steps)  # from north, clockwise → yaw from east, counter-clockwise
    plan = WalkPlan(
        step_period_s=np.full(steps, PAPER_STEP_PERIOD),
        step_length_m=np.full(steps, 2.0 * leg * math.cos(PAPER_PHI_MIN)),
        slope_rad=np.zeros(steps),
        heading_rad=0.5 * math.pi - az,
        initial_stand_s=0.0,
        stops=(),
    )
    return assemble_walk(leg, plan, rate_hz, n_samples)
