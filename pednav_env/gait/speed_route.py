"""Routes whose every stride keeps to a speed band, the gait following from the speed.

:func:`speed_route` draws the walks of the sim-to-real comparison
(:mod:`pednav_env.calibration.compare`) and of ``pednav simulate``
(:mod:`pednav_env.replay.simulate`): legs at one drawn speed separated by turns and
stops, each stride's shape drawn as :func:`pednav_env.gait.foot_route.random_route`
draws it but with the cycle set by the speed, and optionally a walker's calibrated
stance timing (:class:`pednav_env.gait.stance_motion.StanceMotion`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pednav_env.gait.foot_route import RUN_DRAWS, WALK_DRAWS, Gait, Route, Stride, StrideShape
from pednav_env.gait.stance_motion import StanceMotion


@dataclass(frozen=True)
class SpeedRouteConfig:
    """Ranges for :func:`speed_route`: walks whose every stride's speed lies in
    ``speed_mps`` (m/s), the gait following from the speed.

    Gait by speed: slow walk below 0.75 m/s, walk below 1.25, fast walk below
    ``run_from_mps``, run from there. Walking cycle T = 1 / (0.55 + 0.3 v) s
    (±7 %), i.e. 1.43 s at 0.5 m/s, 1.18 s at 1 m/s and 0.87 s at 2 m/s, unless
    the ``stance_motion`` walker has its own cadence law
    (:meth:`pednav_env.gait.stance_motion.StanceMotion.stride_frequency_hz`);
    running cycles 0.65–0.8 s as in
    :class:`pednav_env.gait.foot_route.RouteRandomization`. Each leg draws
    one speed and each stride varies it by ±``speed_jitter`` (relative).

    Each leg starts with a turn spread over its first strides (at most
    ``max_turn_per_stride`` each) and walks straight on, unless
    ``turn_per_stride_rad`` (lo, hi) is given: then every stride of a leg turns by
    the leg's own heading change, drawn in [lo, hi] rad with a random sign (a leg
    on a circle: the PyShoe VICON trials walk circles of about 1 m radius, about
    1 rad per stride; docs/SIM_TO_REAL.md, "The swing in three axes"). Without it
    the draws are those of a route without the option.
    """

    speed_mps: tuple[float, float] = (0.8, 1.3)
    duration_s: tuple[float, float] = (30.0, 60.0)
    leg_strides: tuple[int, int] = (4, 16)
    max_turn_per_stride: float = math.radians(60.0)
    stop_probability: float = 0.15
    stop_s: tuple[float, float] = (1.0, 5.0)
    speed_jitter: float = 0.05
    run_from_mps: float = 2.0
    stance_motion: StanceMotion | None = None
    turn_per_stride_rad: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        lo, hi = self.speed_mps
        if not (0.1 <= lo <= hi <= 4.0):
            raise ValueError(
                "SpeedRouteConfig.speed_mps must satisfy 0.1 ≤ lo ≤ hi ≤ 4 m/s, "
                f"got {self.speed_mps}"
            )
        if not (0 < self.duration_s[0] <= self.duration_s[1] and math.isfinite(self.duration_s[1])):
            raise ValueError(f"SpeedRouteConfig.duration_s invalid: {self.duration_s}")
        if not (1 <= self.leg_strides[0] <= self.leg_strides[1]):
            raise ValueError(f"SpeedRouteConfig.leg_strides invalid: {self.leg_strides}")
        if not (0 <= self.stop_probability <= 1):
            raise ValueError(
                f"SpeedRouteConfig.stop_probability must be in [0, 1], got {self.stop_probability}"
            )
        if not (0 <= self.stop_s[0] <= self.stop_s[1]):
            raise ValueError(f"SpeedRouteConfig.stop_s invalid: {self.stop_s}")
        if not (0 <= self.speed_jitter < 0.5):
            raise ValueError(
                f"SpeedRouteConfig.speed_jitter must be in [0, 0.5), got {self.speed_jitter}"
            )
        if self.turn_per_stride_rad is not None:
            lo, hi = (float(v) for v in self.turn_per_stride_rad)
            if not (0.0 <= lo <= hi <= math.pi / 2):
                raise ValueError(
                    "SpeedRouteConfig.turn_per_stride_rad must satisfy 0 ≤ lo ≤ hi ≤ π/2 rad, "
                    f"got {self.turn_per_stride_rad}"
                )


def gait_for_speed(speed_mps: float, run_from_mps: float = 2.0) -> Gait:
    """The gait class of a stride at ``speed_mps`` (:class:`SpeedRouteConfig`)."""
    if speed_mps < 0.75:
        return Gait.SLOW_WALK
    if speed_mps < 1.25:
        return Gait.WALK
    return Gait.FAST_WALK if speed_mps < run_from_mps else Gait.RUN


#: Bounds of the draws of :func:`speed_stride_shape`: running without the length
#: (the speed gives it), walking a cycle jitter then the shape noise.
_RUN_BOUNDS = (np.array(RUN_DRAWS)[1:, 0], np.array(RUN_DRAWS)[1:, 1])
_WALK_BOUNDS = (
    np.array((0.93, *np.array(WALK_DRAWS)[6:, 0])),
    np.array((1.07, *np.array(WALK_DRAWS)[6:, 1])),
)
#: The longest stride of the leg model at the default leg length (m; StrideShape).
_MAX_STRIDE_M = 4.0 * StrideShape.leg_length_m * math.sin(math.radians(60.0))
#: Middle of the walking stance share's range (0.30–0.38).
_MID_STANCE_SHARE = 0.34
#: Mean of the walking mid-swing pitch draw (rad; WALK_DRAWS' (−0.1, 0.2)).
_MID_PITCH_DRAW_MEAN = 0.05
#: Largest swing pitch knot (rad) a walker's ``swing_pitch_scale`` reaches
#: (StrideShape accepts angles below 1.4 rad).
MAX_SWING_PITCH_RAD = 1.35


def speed_stride_shape(
    rng: np.random.Generator, speed: float, gait: Gait, walker: StanceMotion | None = None
) -> StrideShape:
    """A realistic stride at ``speed`` m/s: cycle from the speed (SpeedRouteConfig),
    the other shape values drawn as in
    :func:`pednav_env.gait.foot_route.random_stride_shape`.

    A ``walker`` with a ``cadence_intercept_hz`` sets the walking cycle's law
    (:meth:`StanceMotion.stride_frequency_hz`, ±7 % jitter as the default's) and
    the stride's geometry (swing height, toe-off and heel-strike pitch) follows its
    length: it is the default stride's of the same nominal length
    (:meth:`StanceMotion.shape_speed`). A
    ``walker`` with a ``flat_fraction`` sets the shares of a walking cycle
    (:meth:`StanceMotion.cycle_fractions`; the drawn stance share less its mid-range
    0.34 is the stride's jitter) and scales the swing's pitch knots by its
    swing scale k(v) (:meth:`StanceMotion.swing_scale`; at most
    :data:`MAX_SWING_PITCH_RAD`). A ``walker`` with a ``pitch_knot_stride_m`` L_k
    then multiplies the toe-off, mid-swing and heel-strike pitch knots by
    min(1, L / L_k), L the stride's length
    (:meth:`StanceMotion.pitch_knot_factor`). A ``walker`` with ``mid_pitch_midpoint``
    puts a walking stride's mid-swing pitch knot at the midpoint of its toe-off and
    heel-strike knots, with the drawn jitter about it (before the swing scale). A
    ``walker`` with ``swing_roll_rad`` adds it to every stride's mid-swing roll knot. The
    draws from ``rng`` are the same with or without a walker."""
    if gait is Gait.RUN:
        cycle, stance_frac, height, toe_off, heel_strike, pitch, roll = rng.uniform(
            *_RUN_BOUNDS
        ).tolist()
        # Above about 3.9 m/s a drawn cycle would stretch the stride beyond the leg
        # model (StrideShape: 4 l sin 60°, 3.118 m); the runner then takes quicker strides.
        cycle = min(cycle, _MAX_STRIDE_M / speed)
        t0, t1 = stance_frac * cycle, 0.10 * cycle
        t2, t3 = cycle - t0 - 2 * t1, t1
        heel_strike = -heel_strike
    else:
        jitter, a, d_height, d_toe_off, pitch, roll = rng.uniform(*_WALK_BOUNDS).tolist()
        shape_speed = speed
        if walker is None or walker.cadence_intercept_hz is None:
            cycle = jitter / (0.55 + 0.3 * speed)
        else:
            cycle = jitter / walker.stride_frequency_hz(speed)
            shape_speed = walker.shape_speed(speed)
        if walker is None or walker.flat_fraction is None:
            t0, t1, t2, t3 = a * cycle, (0.5 - a) * cycle, a * cycle, (0.5 - a) * cycle
        else:
            flat, heel, swing = walker.cycle_fractions(speed, a - _MID_STANCE_SHARE)
            strike = heel * walker.heel_strike_scale
            t0, t1, t2, t3 = flat * cycle, heel * cycle, swing * cycle, strike * cycle
        height = 0.06 + 0.04 * shape_speed + d_height
        toe_off, heel_strike = 0.4 + 0.3 * shape_speed + d_toe_off, -(0.2 + 0.1 * shape_speed)
        if walker is not None and walker.mid_pitch_midpoint:
            pitch = 0.5 * (toe_off + heel_strike) + (pitch - _MID_PITCH_DRAW_MEAN)
    k = 1.0 if walker is None else walker.swing_scale(speed)
    if k != 1.0:
        top = MAX_SWING_PITCH_RAD
        toe_off, heel_strike = min(k * toe_off, top), max(k * heel_strike, -top)
        pitch = min(max(k * pitch, -top), top)
    if walker is not None and walker.swing_roll_rad:
        roll = walker.swing_roll_rad + roll
    length = speed * cycle
    g = 1.0 if walker is None else walker.pitch_knot_factor(length)
    if g != 1.0:
        toe_off, heel_strike, pitch = g * toe_off, g * heel_strike, g * pitch
    return StrideShape.unchecked(
        stride_length_m=length,
        stance_s=t0,
        heel_off_s=t1,
        swing_s=t2,
        heel_strike_s=t3,
        swing_height_m=height,
        mid_swing_pitch=pitch,
        mid_swing_roll=roll,
        toe_off_pitch=toe_off,
        heel_strike_pitch=heel_strike,
        gait=gait,
    )


def speed_route(rng: np.random.Generator, config: SpeedRouteConfig | None = None) -> Route:
    """A random walk whose strides' speeds lie in ``config.speed_mps``: legs
    separated by turns and stops (:class:`SpeedRouteConfig`).

    Draws only from ``rng``; the route starts at the origin heading east, with
    a 2 s stand (the alignment window) and a 1 s stand at the end.
    """
    cfg = config or SpeedRouteConfig()
    lo, hi = cfg.speed_mps
    target = rng.uniform(*cfg.duration_s)
    initial, final = 2.0, 1.0
    strides: list[Stride] = []
    elapsed = initial + final
    while True:
        leg_speed = rng.uniform(lo, hi)
        n_leg = int(rng.integers(cfg.leg_strides[0], cfg.leg_strides[1] + 1))
        turn_total = rng.uniform(-math.pi, math.pi)
        n_turn = max(1, math.ceil(abs(turn_total) / cfg.max_turn_per_stride))
        stop = rng.uniform(*cfg.stop_s) if rng.uniform() < cfg.stop_probability else 0.0
        curve = None
        if cfg.turn_per_stride_rad is not None:
            curve = rng.uniform(*cfg.turn_per_stride_rad) * (1.0 if rng.uniform() < 0.5 else -1.0)
        for i in range(n_leg):
            v = leg_speed * (1.0 + cfg.speed_jitter * rng.uniform(-1.0, 1.0))
            v = min(max(v, lo), hi)
            gait = gait_for_speed(v, cfg.run_from_mps)
            shape = speed_stride_shape(rng, v, gait, cfg.stance_motion)
            if curve is None:
                turn = turn_total / n_turn if i < n_turn else 0.0
            else:
                turn = curve
            s = Stride(shape, heading_change=turn, stop_s=stop if i == 0 else 0.0)
            if elapsed + shape.cycle_s + s.stop_s > target and strides:
                phases = tuple(rng.uniform(0, 2 * math.pi, 3))
                return Route(
                    tuple(strides),
                    initial,
                    final,
                    realistic=True,
                    seed_phases=phases,
                    stance_motion=cfg.stance_motion,
                )
            strides.append(s)
            elapsed += shape.cycle_s + s.stop_s


#: Stride speeds :func:`footfall_route` walks (m/s): the walk generator's limits.
FOOTFALL_SPEED_MPS = (0.1, 3.8)


def footfall_route(
    rng: np.random.Generator,
    speed_mps: Sequence[float],
    turn_rad: Sequence[float],
    stop_s: Sequence[float],
    walker: StanceMotion | None = None,
    run_from_mps: float = 2.0,
) -> Route:
    """A route that walks a given stride sequence: stride i at ``speed_mps[i]`` (clipped
    to :data:`FOOTFALL_SPEED_MPS`; the gait following from the speed, the shape drawn as
    :func:`speed_stride_shape` draws it, with ``walker``), turning by ``turn_rad[i]``
    (|turn| ≤ π) after a stand of ``stop_s[i]`` s (≥ 0). Starts with a stand of 2 s
    (the alignment window) or ``stop_s[0]`` if longer (the first stride then starts
    without another), ends with a 1 s stand. A simulated twin of a recorded walk
    (docs/SIM_TO_REAL.md, "Matched twins")."""
    n = len(speed_mps)
    if not (n == len(turn_rad) == len(stop_s)) or n < 1:
        raise ValueError(
            "footfall_route: speed_mps, turn_rad and stop_s must have one entry per stride "
            f"(≥ 1), got {len(speed_mps)}, {len(turn_rad)}, {len(stop_s)}"
        )
    if not all(math.isfinite(t) and t >= 0 for t in stop_s):
        raise ValueError(f"footfall_route: every stop_s must be a finite ≥ 0 s, got {list(stop_s)}")
    strides = []
    initial = max(2.0, float(stop_s[0]))
    stops = [0.0, *stop_s[1:]]
    for v, turn, stop in zip(speed_mps, turn_rad, stops, strict=True):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"footfall_route: every speed must be > 0, got {v!r}")
        v = min(max(float(v), FOOTFALL_SPEED_MPS[0]), FOOTFALL_SPEED_MPS[1])
        shape = speed_stride_shape(rng, v, gait_for_speed(v, run_from_mps), walker)
        strides.append(Stride(shape, heading_change=float(turn), stop_s=float(stop)))
    phases = tuple(rng.uniform(0, 2 * math.pi, 3))
    return Route(
        tuple(strides), initial, 1.0, realistic=True, seed_phases=phases, stance_motion=walker
    )
