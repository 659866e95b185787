"""Routes for the foot simulator: what each stride of the instrumented foot does.

A route is a sequence of :class:`Stride` records; the simulator
(:mod:`pednav_env.gait.foot`) turns it into a trajectory. Two sources:

- :func:`square_route` — paper 003's square walk ("the model trajectory of
  the foot is a square"; side and cadence are not printed: see
  docs/REPRODUCTION.md);
- :func:`random_route` — domain randomisation for the environments: legs of
  random length, turns (heading changes spread over strides), stops
  (standing still for seconds) and gait changes from slow walking to running.

Routes whose strides keep to a speed band are in :mod:`pednav_env.gait.speed_route`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from enum import IntEnum

import numpy as np

from pednav_env.draws import choice_cdf, choice_index
from pednav_env.gait.stance_motion import StanceMotion


class Gait(IntEnum):
    """Gait class of a stride (stored per sample as an int label)."""

    STANDING = 0
    SLOW_WALK = 1
    WALK = 2
    FAST_WALK = 3
    RUN = 4


@dataclass(frozen=True)
class StrideShape:
    """Timing and shape of one gait cycle of the instrumented foot.

    Paper 003: a cycle is Γ₀ stance (T₀), Γ₁ heel-off (T₁), Γ₂ swing (T₂) and
    Γ₃ heel-strike (T₃); for symmetric walking T₁ = T₃ and T₀ = T₂.
    ``stride_length_m`` is the foot's displacement per cycle — what paper 003
    calls the step length (its Table 1: 0.5 m and 1 m).
    """

    stride_length_m: float = 1.0
    #: T₀, T₁, T₂, T₃ (s). Paper 003 prints none; 0.35/0.15/0.35/0.15 gives a 1 s cycle.
    stance_s: float = 0.35
    heel_off_s: float = 0.15
    swing_s: float = 0.35
    heel_strike_s: float = 0.15
    #: Heel height at mid-swing (m).
    swing_height_m: float = 0.10
    #: Pitch at mid-swing (rad, positive = toes down).
    mid_swing_pitch: float = 0.5
    #: Roll at mid-swing (rad).
    mid_swing_roll: float = 0.0
    #: Pitch at toe-off (end of Γ₁) and at heel-strike (start of Γ₃), rad.
    #: ``None`` = paper model: knots only at stance and mid-swing.
    toe_off_pitch: float | None = None
    heel_strike_pitch: float | None = None
    gait: Gait = Gait.WALK
    #: Leg length l (m), hip to ground. Bounds the stride: two steps whose legs
    #: swing at most ±60° from the vertical give at most 2·2l·sin 60° = 3.46 l.
    leg_length_m: float = 0.9

    def __post_init__(self) -> None:
        if not (math.isfinite(self.leg_length_m) and self.leg_length_m > 0):
            raise ValueError(f"StrideShape.leg_length_m must be > 0, got {self.leg_length_m!r}")
        max_stride = 4.0 * self.leg_length_m * math.sin(math.radians(60.0))
        if self.stride_length_m > max_stride:
            raise ValueError(
                f"StrideShape.stride_length_m={self.stride_length_m!r} is beyond the leg model: "
                f"at most {max_stride:.3f} m for leg_length_m={self.leg_length_m!r}"
            )
        if self.swing_height_m >= self.leg_length_m:
            raise ValueError(
                f"StrideShape.swing_height_m={self.swing_height_m!r} must be below "
                f"leg_length_m={self.leg_length_m!r}"
            )
        for name in ("stance_s", "heel_off_s", "swing_s", "heel_strike_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"StrideShape.{name} must be > 0, got {v!r}")
        if not (math.isfinite(self.stride_length_m) and self.stride_length_m >= 0):
            raise ValueError(
                f"StrideShape.stride_length_m must be ≥ 0, got {self.stride_length_m!r}"
            )
        if not (math.isfinite(self.swing_height_m) and self.swing_height_m >= 0):
            raise ValueError(f"StrideShape.swing_height_m must be ≥ 0, got {self.swing_height_m!r}")
        for name in ("mid_swing_pitch", "mid_swing_roll", "toe_off_pitch", "heel_strike_pitch"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and abs(v) < 1.4):
                raise ValueError(
                    f"StrideShape.{name} must be a finite angle below 1.4 rad, got {v!r}"
                )
        if (self.toe_off_pitch is None) != (self.heel_strike_pitch is None):
            raise ValueError("StrideShape.toe_off_pitch and heel_strike_pitch are set together")

    @classmethod
    def unchecked(cls, **values: float | Gait) -> StrideShape:
        """A shape from values inside the validated ranges by construction (the
        draws of :func:`random_route` and :func:`pednav_env.gait.speed_route.speed_route`),
        without ``__post_init__``'s checks: they were most of the time of drawing a route."""
        shape = object.__new__(cls)
        shape.__dict__.update(_SHAPE_DEFAULTS, **values)
        return shape

    @property
    def cycle_s(self) -> float:
        """Gait cycle T₀ + T₁ + T₂ + T₃ (s)."""
        return self.stance_s + self.heel_off_s + self.swing_s + self.heel_strike_s

    @property
    def speed(self) -> float:
        """Mean walking speed (m/s)."""
        return self.stride_length_m / self.cycle_s


_SHAPE_DEFAULTS = {f.name: f.default for f in fields(StrideShape)}


@dataclass(frozen=True)
class Stride:
    """One cycle: stand ``stance_s + stop_s``, then move to the next footfall.

    The next stance heel position is the current one plus
    ``shape.stride_length_m`` along the new heading ψ + ``heading_change``
    (turns happen in the air, between stances).
    """

    shape: StrideShape
    heading_change: float = 0.0
    stop_s: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.stop_s) and self.stop_s >= 0):
            raise ValueError(f"Stride.stop_s must be ≥ 0, got {self.stop_s!r}")
        if not (math.isfinite(self.heading_change) and abs(self.heading_change) <= math.pi):
            raise ValueError(
                f"Stride.heading_change must be in [−π, π], got {self.heading_change!r}"
            )

    @classmethod
    def unchecked(cls, shape: StrideShape, heading_change: float, stop_s: float) -> Stride:
        """A stride from values inside the validated ranges by construction (the
        draws of :func:`random_route`), without ``__post_init__``'s checks."""
        stride = object.__new__(cls)
        stride.__dict__.update(shape=shape, heading_change=heading_change, stop_s=stop_s)
        return stride


@dataclass(frozen=True)
class Route:
    """Initial standing time, the strides, and final standing time (s)."""

    strides: tuple[Stride, ...]
    initial_stand_s: float = 2.0
    final_stand_s: float = 1.0
    #: Stance micro-motion, roll-over and heel-strike transients (beyond the paper).
    realistic: bool = False
    #: Per-route random phases for micro-motion (filled by random_route).
    seed_phases: tuple[float, ...] = field(default=())
    #: Calibrated stance dynamics (:mod:`pednav_env.gait.stance_motion`) in place of
    #: the realistic roll-over and micro-motion; None keeps those.
    stance_motion: StanceMotion | None = None

    def __post_init__(self) -> None:
        for name in ("initial_stand_s", "final_stand_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"Route.{name} must be ≥ 0, got {v!r}")

    @property
    def duration_s(self) -> float:
        """Total duration (s)."""
        return (
            self.initial_stand_s
            + sum(s.shape.cycle_s + s.stop_s for s in self.strides)
            + self.final_stand_s
        )


def square_route(
    side_m: float = 5.0,
    shape: StrideShape | None = None,
    laps: int = 1,
    initial_stand_s: float = 1.0,
    final_stand_s: float = 1.0,
) -> Route:
    """Paper 003's square: ``laps`` laps of a ``side_m`` square, turning left 90°.

    The side must hold a whole number of strides. The walker stands
    ``initial_stand_s`` first (the alignment window) and ``final_stand_s`` at
    the end.
    """
    shape = shape or StrideShape()
    if not side_m > 0:
        raise ValueError(f"side_m must be > 0, got {side_m!r}")
    if shape.stride_length_m <= 0:
        raise ValueError(f"stride_length_m must be > 0, got {shape.stride_length_m!r}")
    per_side = side_m / shape.stride_length_m
    if abs(per_side - round(per_side)) > 1e-9:
        raise ValueError(
            f"side_m={side_m} is not a whole number of strides of {shape.stride_length_m} m"
        )
    n = int(round(per_side))
    strides = []
    for lap in range(laps):
        for side in range(4):
            for i in range(n):
                turn = math.pi / 2 if (i == 0 and (side > 0 or lap > 0)) else 0.0
                strides.append(Stride(shape, heading_change=turn))
    return Route(tuple(strides), initial_stand_s, final_stand_s)


@dataclass(frozen=True)
class RouteRandomization:
    """Ranges for :func:`random_route` (domain randomisation, beyond the papers).

    Gait classes and their ranges: slow walk 0.4–0.8 m strides in 1.2–1.5 s
    cycles, walk 0.8–1.2 m in 1.0–1.2 s, fast walk 1.2–1.4 m in 0.85–1.0 s
    (the issue's 0.4–1.4 m walking range), run 1.6–2.4 m in 0.65–0.8 s with a
    short flat stance (8–12 % of the cycle), heel-off and heel-strike of 10 %
    each, and a long swing (flight phase).
    """

    duration_s: tuple[float, float] = (60.0, 180.0)
    leg_strides: tuple[int, int] = (4, 20)
    max_turn_per_stride: float = math.radians(60.0)
    stop_probability: float = 0.15
    stop_s: tuple[float, float] = (1.0, 8.0)
    gait_weights: tuple[float, float, float, float] = (0.2, 0.4, 0.25, 0.15)

    def __post_init__(self) -> None:
        lo, hi = self.duration_s
        if not (0 < lo <= hi and math.isfinite(hi)):
            raise ValueError(
                f"RouteRandomization.duration_s must satisfy 0 < lo ≤ hi, got {self.duration_s}"
            )
        if not (1 <= self.leg_strides[0] <= self.leg_strides[1]):
            raise ValueError(f"RouteRandomization.leg_strides invalid: {self.leg_strides}")
        if not (0 <= self.stop_probability <= 1):
            raise ValueError(
                "RouteRandomization.stop_probability must be in [0, 1], "
                f"got {self.stop_probability}"
            )
        if not (0 <= self.stop_s[0] <= self.stop_s[1]):
            raise ValueError(f"RouteRandomization.stop_s invalid: {self.stop_s}")
        w = np.asarray(self.gait_weights, dtype=float)
        if w.shape != (4,) or np.any(w < 0) or w.sum() <= 0:
            raise ValueError(f"RouteRandomization.gait_weights invalid: {self.gait_weights}")


#: Draws of one stride shape, in order: (low, high) of each ``rng.uniform``.
#: Walking gaits draw the (length, cycle) ranges of all three walking classes
#: and keep their own pair, then the stance fraction a and the noise of the
#: swing height, toe-off pitch, mid-swing pitch and roll.
WALK_DRAWS = (
    (0.4, 0.8),
    (1.2, 1.5),
    (0.8, 1.2),
    (1.0, 1.2),
    (1.2, 1.4),
    (0.85, 1.0),
    (0.30, 0.38),
    (-0.01, 0.01),
    (-0.05, 0.05),
    (-0.1, 0.2),
    (-0.05, 0.05),
)
_WALK_COLUMNS = {Gait.SLOW_WALK: 0, Gait.WALK: 2, Gait.FAST_WALK: 4}
#: Running: length, cycle, stance fraction, swing height, toe-off and
#: heel-strike pitch, mid-swing pitch and roll.
RUN_DRAWS = (
    (1.6, 2.4),
    (0.65, 0.8),
    (0.08, 0.12),
    (0.2, 0.3),
    (0.6, 0.8),
    (0.15, 0.3),
    (-0.1, 0.2),
    (-0.05, 0.05),
)


def _bounds(draws: tuple[tuple[float, float], ...]) -> tuple[np.ndarray, np.ndarray]:
    """Lower bounds and widths high − low of ``rng.uniform`` draws, as it computes them."""
    table = np.array(draws)
    return table[:, 0].copy(), table[:, 1] - table[:, 0]


_WALK_BOUNDS, _RUN_BOUNDS = _bounds(WALK_DRAWS), _bounds(RUN_DRAWS)


def _random_stride_shapes(
    rng: np.random.Generator, gait: Gait, n: int
) -> tuple[list[StrideShape], list[float]]:
    """Draw ``n`` realistic stride shapes for ``gait`` (ranges in RouteRandomization)
    and their cycles (:attr:`StrideShape.cycle_s`, the same sum).

    The same draws, in the same order, as ``n`` calls of
    :func:`random_stride_shape`: one ``rng.uniform(low, high, size=(n, k))``,
    written out as numpy computes it (low + (high − low) · u, u from
    ``rng.random``, element by element), which gives the same numbers
    without its argument handling.
    """
    low, width = _RUN_BOUNDS if gait is Gait.RUN else _WALK_BOUNDS
    u = (low + width * rng.random((n, low.size))).tolist()
    shapes, cycles = [], []
    for row in u:
        if gait is Gait.RUN:
            length, cycle, stance_frac, height, toe_off, heel_strike, pitch, roll = row
            heel_frac = 0.10
            t0, t1 = stance_frac * cycle, heel_frac * cycle
            t2 = cycle - t0 - 2 * t1
            heel_strike = -heel_strike
        else:
            j = _WALK_COLUMNS[gait]
            length, cycle = row[j], row[j + 1]
            a, d_height, d_toe_off, pitch, roll = row[6:]
            # T0 = T2 = a·cycle, T1 = T3 = (0.5 − a)·cycle (paper 003 symmetry)
            t0, t1, t2 = a * cycle, (0.5 - a) * cycle, a * cycle
            speed = length / cycle
            height = 0.06 + 0.04 * speed + d_height
            toe_off, heel_strike = 0.4 + 0.3 * speed + d_toe_off, -(0.2 + 0.1 * speed)
        shapes.append(
            StrideShape.unchecked(
                stride_length_m=length,
                stance_s=t0,
                heel_off_s=t1,
                swing_s=t2,
                heel_strike_s=t1,
                swing_height_m=height,
                mid_swing_pitch=pitch,
                mid_swing_roll=roll,
                toe_off_pitch=toe_off,
                heel_strike_pitch=heel_strike,
                gait=gait,
            )
        )
        cycles.append(((t0 + t1) + t2) + t1)  # cycle_s: T₀ + T₁ + T₂ + T₃, T₃ = T₁
    return shapes, cycles


def random_stride_shape(rng: np.random.Generator, gait: Gait) -> StrideShape:
    """Draw a realistic stride shape for ``gait`` (ranges in RouteRandomization)."""
    return _random_stride_shapes(rng, gait, 1)[0][0]


def random_route(rng: np.random.Generator, config: RouteRandomization | None = None) -> Route:
    """A random walk: legs of one gait class separated by turns and stops.

    Draws only from ``rng``; the route starts at the origin heading east. Per
    leg, in order: the gait class (``rng.choice(4, p=weights)``), the number
    of strides, the turn, whether to stop and for how long, the stride
    shapes; at the end the micro-motion phases. The gait class is drawn by
    :func:`pednav_env.draws.choice_index`, the same number as ``rng.choice``
    without its argument handling. The strides are built without their
    checks: every value is inside the validated ranges by construction.
    """
    cfg = config or RouteRandomization()
    target = rng.uniform(*cfg.duration_s)
    weights = np.asarray(cfg.gait_weights, dtype=float)
    cdf = choice_cdf(weights / weights.sum())
    gaits = [Gait.SLOW_WALK, Gait.WALK, Gait.FAST_WALK, Gait.RUN]
    initial, final = 2.0, 1.0
    strides: list[Stride] = []
    elapsed = initial + final
    while True:
        gait = gaits[choice_index(rng, cdf)]
        n_leg = int(rng.integers(cfg.leg_strides[0], cfg.leg_strides[1] + 1))
        turn_total = rng.uniform(-math.pi, math.pi)
        n_turn = max(1, math.ceil(abs(turn_total) / cfg.max_turn_per_stride))
        stop = rng.uniform(*cfg.stop_s) if rng.uniform() < cfg.stop_probability else 0.0
        shapes, cycles = _random_stride_shapes(rng, gait, n_leg)
        turn = turn_total / n_turn
        for i, (shape, cycle) in enumerate(zip(shapes, cycles, strict=True)):
            stop_i = stop if i == 0 else 0.0
            if elapsed + cycle + stop_i > target and strides:
                phases = tuple(rng.uniform(0, 2 * math.pi, 3))
                return Route(tuple(strides), initial, final, realistic=True, seed_phases=phases)
            strides.append(Stride.unchecked(shape, turn if i < n_turn else 0.0, stop_i))
            elapsed += cycle + stop_i


def paper_stride_shape(stride_length_m: float) -> StrideShape:
    """Paper 003 scenario stride: the paper's knots only (stance and mid-swing)."""
    return replace(StrideShape(), stride_length_m=stride_length_m)
