"""The checks a walker's stance-motion fields share: ``StanceMotion`` and
``StanceRandomization`` (:mod:`pednav_env.gait.stance_motion`) run the same ones on the
same fields, the walking cadence law, the pitch-knot stride length, the heel-strike
share and the swing roll. Each raises a ValueError naming its owner and field.
"""

from __future__ import annotations

import math
from typing import Protocol

#: The route's walking cadence law f = 0.55 + 0.3 v (Hz, v in m/s;
#: :class:`pednav_env.gait.speed_route.SpeedRouteConfig`): intercept and slope.
DEFAULT_CADENCE = (0.55, 0.3)
#: Walking speeds (m/s) over which a cadence law must give a stride frequency
#: within CADENCE_HZ_RANGE (the walking speeds of speed_route).
CADENCE_CHECK_SPEEDS = (0.1, 2.0)
CADENCE_HZ_RANGE = (0.3, 2.5)


#: Largest stride length (m) ``pitch_knot_stride_m`` may take.
MAX_PITCH_KNOT_STRIDE_M = 3.0


def check_pitch_knot_stride(owner: str, value: float) -> None:
    """Raise ValueError naming ``owner``'s ``pitch_knot_stride_m`` unless it is a
    number in [0, :data:`MAX_PITCH_KNOT_STRIDE_M`] m (0: off)."""
    if isinstance(value, bool) or not (
        isinstance(value, int | float)
        and math.isfinite(value)
        and 0.0 <= value <= MAX_PITCH_KNOT_STRIDE_M
    ):
        raise ValueError(
            f"{owner}.pitch_knot_stride_m must be in [0, {MAX_PITCH_KNOT_STRIDE_M:g}] m "
            f"(0: off), got {value!r}"
        )


def check_cadence_law(owner: str, intercept_hz: float | None, slope_hz_per_mps: float) -> None:
    """Raise ValueError naming ``owner``'s field unless the law a + b·v gives a
    stride frequency in :data:`CADENCE_HZ_RANGE` at both ends of
    :data:`CADENCE_CHECK_SPEEDS` (``intercept_hz`` None: the default law, and the
    slope must be the default's)."""
    if not math.isfinite(slope_hz_per_mps):
        raise ValueError(
            f"{owner}.cadence_slope_hz_per_mps must be finite, got {slope_hz_per_mps!r}"
        )
    if intercept_hz is None:
        if slope_hz_per_mps != DEFAULT_CADENCE[1]:
            raise ValueError(
                f"{owner}.cadence_slope_hz_per_mps needs cadence_intercept_hz (the law "
                f"a + b·v), got cadence_intercept_hz=None and slope {slope_hz_per_mps!r}"
            )
        return
    if not math.isfinite(intercept_hz):
        raise ValueError(f"{owner}.cadence_intercept_hz must be finite, got {intercept_hz!r}")
    lo, hi = CADENCE_HZ_RANGE
    for v in CADENCE_CHECK_SPEEDS:
        f = intercept_hz + slope_hz_per_mps * v
        if not lo <= f <= hi:
            raise ValueError(
                f"{owner}.cadence_intercept_hz, cadence_slope_hz_per_mps = {intercept_hz!r}, "
                f"{slope_hz_per_mps!r} give {f:.3g} Hz at {v:g} m/s; the stride frequency "
                f"must lie in [{lo:g}, {hi:g}] Hz over {CADENCE_CHECK_SPEEDS[0]:g}–"
                f"{CADENCE_CHECK_SPEEDS[1]:g} m/s"
            )


def check_heel_strike_scale(owner: str, scale: float) -> None:
    """ValueError unless the heel-strike share's factor is in [0.25, 2]."""
    if not (isinstance(scale, int | float) and math.isfinite(scale) and 0.25 <= scale <= 2.0):
        raise ValueError(f"{owner}.heel_strike_scale must be in [0.25, 2], got {scale!r}")


def check_swing_roll(owner: str, roll_rad: float) -> None:
    """ValueError unless the added mid-swing roll is a number in [−0.5, 0.5] rad (the
    stride's roll knot must stay below 1.4 rad in magnitude; 0: off)."""
    if isinstance(roll_rad, bool) or not (
        isinstance(roll_rad, int | float) and math.isfinite(roll_rad) and abs(roll_rad) <= 0.5
    ):
        raise ValueError(f"{owner}.swing_roll_rad must be in [−0.5, 0.5] rad, got {roll_rad!r}")


#: The on/off model options of a walker (``True`` or ``False``).
WALKER_FLAGS = ("heel_rocker", "monotone_pitch", "mid_pitch_midpoint")


class WalkerFields(Protocol):
    """The fields ``StanceMotion`` and ``StanceRandomization`` share and check alike."""

    heel_strike_scale: float
    swing_roll_rad: float
    pitch_knot_stride_m: float
    cadence_intercept_hz: float | None
    cadence_slope_hz_per_mps: float


def check_walker_fields(owner: str, walker: WalkerFields) -> None:
    """The checks every walker (``StanceMotion``, ``StanceRandomization``) runs on the
    fields they share: the flags of :data:`WALKER_FLAGS`, the heel-strike share, the
    swing roll, the pitch-knot stride length and the cadence law."""
    for flag in WALKER_FLAGS:
        value = getattr(walker, flag)
        if not isinstance(value, bool):
            raise ValueError(f"{owner}.{flag} must be True or False, got {value!r}")
    check_heel_strike_scale(owner, walker.heel_strike_scale)
    check_swing_roll(owner, walker.swing_roll_rad)
    check_pitch_knot_stride(owner, walker.pitch_knot_stride_m)
    check_cadence_law(owner, walker.cadence_intercept_hz, walker.cadence_slope_hz_per_mps)
