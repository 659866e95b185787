"""Calibrated stance dynamics of the foot: quiet mid-stance, loud edges, roll-over.

An alternative to the ``realistic`` stance terms of :mod:`pednav_env.gait.foot`
(whose micro-motion, A_mm sin²(πs), is loudest at mid-stance, where recorded
feet are quietest; docs/SIM_TO_REAL.md). Over each moving stance
[t_s, t_e] (d = t_e − t_s), on the foot's pitch θ and roll γ:

- micro-motion ``env(t) sin(ω (t − t_s))`` with ω = 2π·(7, 10 Hz) for pitch
  and roll and the envelope

      env(t) = Q + E (exp(−(t − t_s)/τ_hs) + exp(−(t_e − t)/τ_ho)),

  a floor Q (mid-stance quietness) and two edges: the settling after heel
  strike (τ_hs) and the loading before heel-off (τ_ho). The oscillation
  starts at zero at t_s (the strike excites it); at t_e it leaves an offset
  of at most env·1 rad (a few mrad), which the swing spline does not see;
- roll-over into heel-off: a pitch bump A_r sin²(π u) over the last fraction
  ρ of the stance, u = (t − (t_e − ρ d))/(ρ d).

Amplitudes scale with the stride speed v (m/s): Q = Q₁ v^p_q, E = E₁ v^p_e,
A_r = A₁ v^p_r. One :class:`StanceMotion` per walk (the walker's values;
:class:`StanceRandomization` is the distribution over walkers); each stance
multiplies Q and E by 10^(σ_s ξ), ξ standard normal drawn from ``seed``
(stance-to-stance variation).

A walker also has a gait timing and a swing vigour, used by
:func:`pednav_env.gait.speed_route.speed_route` when ``flat_fraction`` is set
(:meth:`StanceMotion.cycle_fractions`): the walking cycle is split into foot
flat f = f₁ + β ln v (plus the stride's jitter), heel-off and heel strike h
each, and swing 1 − f − 2h; the swing's pitch knots are scaled by
k(v) = ``swing_pitch_scale`` · v^``swing_speed_exponent``
(:meth:`StanceMotion.swing_scale`; exponent 0, a speed-independent scale,
unless set). Without ``flat_fraction`` the route keeps its own timing
(paper 003's symmetric T₀ = T₂, T₁ = T₃). Optionally a walker has its own
walking cadence law, stride frequency f = a + b·v
(:meth:`StanceMotion.stride_frequency_hz`; ``cadence_intercept_hz`` None, the
default, keeps the route's 0.55 + 0.3 v); :class:`StanceRandomization` scales
a and b by 10^(σ_c ξ) per walker (``cadence_log10_std``). With a law, a
stride's swing height and pitch knots are those of the default stride of the
same length (:meth:`StanceMotion.shape_speed`): a walker who walks slowly with
short quick strides swings its foot through smaller angles.

``pitch_knot_stride_m`` L_k (0, the default, off) makes a stride's swing pitch
knots (toe-off, mid-swing, heel strike) follow its length L all the way down:
they are multiplied by min(1, L / L_k) (:meth:`StanceMotion.pitch_knot_factor`),
today's knots for strides of at least L_k and a foot that hardly pitches in a
shuffle (docs/SIM_TO_REAL_CANDIDATES.md, "Pitch knots that follow the stride length").

``heel_rocker`` (off by default) changes the heel strike of the walker's
realistic strides: the heel comes to rest at its footfall at the heel-strike
knot and stays there while the foot rotates down about it
(:func:`pednav_env.gait.foot.build_schedule`); off, the heel runs on past the
footfall and slides back (docs/SIM_TO_REAL_CANDIDATES.md, "The heel that ran past
its footfall").

``heel_strike_scale`` (1 by default) sets the heel-strike phase's share of a walking
cycle to heel-off's × the scale, the swing taking the difference (the recorded foot
rolls down after heel strike for less of the cycle than the simulated one;
docs/SIM_TO_REAL.md, "The error level and where it comes from").

``mid_pitch_midpoint`` (off by default) puts a walking stride's mid-swing pitch knot at
the midpoint of its toe-off and heel-strike knots instead of near level
(:func:`pednav_env.gait.speed_route.speed_stride_shape`), so that the swing's forward
rotation is spread evenly about mid-swing.

``swing_roll_rad`` (0 by default) adds a roll of that many radians to every stride's
mid-swing roll knot: the foot inverts during the swing and comes back by heel strike,
turning about a second axis as recorded feet do (docs/SIM_TO_REAL.md, "The error level
and where it comes from").

``monotone_pitch`` (off by default) makes the swing's pitch monotone between its knots
(stance, toe-off, mid-swing, heel strike, next stance;
:func:`pednav_env.gait.splines.monotone_clamped_cubic_coefficients`, Fritsch & Carlson
1980): the foot's pitch then turns back only at a knot instead of overshooting the
toe-off or heel-strike knot while the foot still moves (docs/SIM_TO_REAL.md, "The error
level and where it comes from"). The other angles and the heel keep their splines.

These functions are compiled into :mod:`pednav_env.gait.foot_kernels`, whose
numba cache checks that module's file only: after editing this one, delete
``pednav_env/gait/__pycache__/foot_kernels.*.nb[ic]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from pednav_env.gait.walker_checks import (
    CADENCE_CHECK_SPEEDS,
    CADENCE_HZ_RANGE,
    DEFAULT_CADENCE,
    check_walker_fields,
)

Array = NDArray[np.float64]

#: Micro-motion angular frequencies 2π·(7, 10 Hz) of pitch and roll.
MICRO_W = (2 * math.pi * 7.0, 2 * math.pi * 10.0)
#: Columns of the per-stance parameter table (:func:`stance_table`).
COLUMNS = ("quiet_rad", "edge_rad", "tau_hs_s", "tau_ho_s", "roll_rad", "roll_fraction")
#: Bounds of a walking cycle's shares (:meth:`StanceMotion.cycle_fractions`).
MIN_FLAT = 0.05
MIN_SWING = 0.2


@dataclass(frozen=True)
class StanceMotion:
    """One walker's stance dynamics (module docstring); angles in rad at 1 m/s."""

    quiet_rad: float = 1e-3
    quiet_speed_exponent: float = 0.5
    edge_rad: float = 1e-2
    edge_speed_exponent: float = 1.0
    tau_hs_s: float = 0.04
    tau_ho_s: float = 0.04
    roll_rad: float = 0.01
    roll_speed_exponent: float = 2.0
    roll_fraction: float = 0.3
    stance_spread_log10: float = 0.2
    seed: int = 0
    flat_fraction: float | None = None
    flat_speed_slope: float = 0.0
    heel_fraction: float = 0.16
    swing_pitch_scale: float = 1.0
    swing_speed_exponent: float = 0.0
    heel_rocker: bool = False
    cadence_intercept_hz: float | None = None
    cadence_slope_hz_per_mps: float = DEFAULT_CADENCE[1]
    pitch_knot_stride_m: float = 0.0
    monotone_pitch: bool = False
    heel_strike_scale: float = 1.0
    mid_pitch_midpoint: bool = False
    swing_roll_rad: float = 0.0

    def __post_init__(self) -> None:
        check_walker_fields("StanceMotion", self)
        for name in ("quiet_rad", "edge_rad", "roll_rad", "stance_spread_log10"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v < 1.0):
                raise ValueError(f"StanceMotion.{name} must be in [0, 1), got {v!r}")
        for name in ("tau_hs_s", "tau_ho_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 < v <= 1.0):
                raise ValueError(f"StanceMotion.{name} must be in (0, 1] s, got {v!r}")
        if not (0 < self.roll_fraction <= 1):
            raise ValueError(
                f"StanceMotion.roll_fraction must be in (0, 1], got {self.roll_fraction!r}"
            )
        for name in ("quiet_speed_exponent", "edge_speed_exponent", "roll_speed_exponent"):
            v = getattr(self, name)
            if not (math.isfinite(v) and -4 <= v <= 4):
                raise ValueError(f"StanceMotion.{name} must be in [−4, 4], got {v!r}")
        if self.flat_fraction is not None and not (
            math.isfinite(self.flat_fraction) and 0.05 <= self.flat_fraction <= 0.7
        ):
            raise ValueError(
                f"StanceMotion.flat_fraction must be in [0.05, 0.7] or None, "
                f"got {self.flat_fraction!r}"
            )
        if not (math.isfinite(self.flat_speed_slope) and abs(self.flat_speed_slope) <= 0.5):
            raise ValueError(
                f"StanceMotion.flat_speed_slope must be in [−0.5, 0.5], "
                f"got {self.flat_speed_slope!r}"
            )
        if not (0.03 <= self.heel_fraction <= 0.25):
            raise ValueError(
                f"StanceMotion.heel_fraction must be in [0.03, 0.25], got {self.heel_fraction!r}"
            )
        if not (math.isfinite(self.swing_pitch_scale) and 0.25 <= self.swing_pitch_scale <= 4):
            raise ValueError(
                f"StanceMotion.swing_pitch_scale must be in [0.25, 4], "
                f"got {self.swing_pitch_scale!r}"
            )
        if not (math.isfinite(self.swing_speed_exponent) and -2 <= self.swing_speed_exponent <= 2):
            raise ValueError(
                f"StanceMotion.swing_speed_exponent must be in [−2, 2], "
                f"got {self.swing_speed_exponent!r}"
            )

    def stride_frequency_hz(self, speed_mps: float) -> float:
        """The walker's walking stride frequency f = a + b·v (Hz) at ``speed_mps``:
        ``cadence_intercept_hz`` + ``cadence_slope_hz_per_mps`` · v, or the route's
        default 0.55 + 0.3 v when ``cadence_intercept_hz`` is None."""
        if self.cadence_intercept_hz is None:
            return DEFAULT_CADENCE[0] + DEFAULT_CADENCE[1] * speed_mps
        return self.cadence_intercept_hz + self.cadence_slope_hz_per_mps * speed_mps

    def shape_speed(self, speed_mps: float) -> float:
        """The speed (m/s) whose stride under the default law 0.55 + 0.3 v has the
        nominal length L = v / f(v) of this walker's stride at ``speed_mps``:
        v' = 0.55 L / (1 − 0.3 L), at most 4 m/s. The route draws a stride's swing
        height and pitch knots at v' (the foot's pitch at toe-off and heel strike
        follows the step's geometry, its length, not the time taken; with the
        default law v' = v). Without a cadence law: ``speed_mps`` itself."""
        if self.cadence_intercept_hz is None:
            return speed_mps
        a, b = DEFAULT_CADENCE
        length = speed_mps / self.stride_frequency_hz(speed_mps)
        return a * length / max(1.0 - b * length, a * length / 4.0)

    def pitch_knot_factor(self, stride_length_m: float) -> float:
        """The factor min(1, L / L_k) on the swing pitch knots of a stride of length
        L = ``stride_length_m`` (m), L_k = ``pitch_knot_stride_m``; 1 (today's knots)
        when L_k is 0, the default."""
        if self.pitch_knot_stride_m == 0.0:
            return 1.0
        return min(1.0, max(stride_length_m, 0.0) / self.pitch_knot_stride_m)

    def swing_scale(self, speed_mps: float) -> float:
        """The factor k(v) = ``swing_pitch_scale`` · v^``swing_speed_exponent`` on the
        swing's pitch knots of a stride at ``speed_mps`` (m/s): the swing's vigour
        grows with speed faster (exponent > 0) than the route's knots (toe-off
        0.4 + 0.3 v) alone. Exponent 0 (the default) returns ``swing_pitch_scale``
        itself, for every speed."""
        if self.swing_speed_exponent == 0.0:
            return self.swing_pitch_scale
        return self.swing_pitch_scale * max(speed_mps, 1e-3) ** self.swing_speed_exponent

    def cycle_fractions(self, speed_mps: float, jitter: float = 0.0) -> tuple[float, float, float]:
        """Shares of a walking cycle at ``speed_mps`` (m/s): (foot flat, heel-off,
        swing); heel strike takes heel-off's share × ``heel_strike_scale`` (1: the two
        are equal). Foot flat is ``flat_fraction + flat_speed_slope · ln v + jitter``,
        kept in [:data:`MIN_FLAT`, 1 − heel-off − heel strike − :data:`MIN_SWING`];
        swing is the rest. Requires ``flat_fraction``."""
        if self.flat_fraction is None:
            raise ValueError("StanceMotion.cycle_fractions needs flat_fraction")
        heel = self.heel_fraction
        both = heel * (1.0 + self.heel_strike_scale)
        flat = self.flat_fraction + self.flat_speed_slope * math.log(max(speed_mps, 1e-3))
        flat = min(max(flat + jitter, MIN_FLAT), 1.0 - both - MIN_SWING)
        return flat, heel, 1.0 - flat - both


def stance_table(motion: StanceMotion, speed_mps: Array) -> Array:
    """Per-stance parameters (K, 6) in :data:`COLUMNS` order for stances walked at
    ``speed_mps`` (K,)."""
    v = np.maximum(np.asarray(speed_mps, dtype=float), 1e-3)
    jitter = 10.0 ** (
        motion.stance_spread_log10 * np.random.default_rng(motion.seed).standard_normal(v.size)
    )
    table = np.empty((v.size, len(COLUMNS)))
    table[:, 0] = motion.quiet_rad * v**motion.quiet_speed_exponent * jitter
    table[:, 1] = motion.edge_rad * v**motion.edge_speed_exponent * jitter
    table[:, 2] = motion.tau_hs_s
    table[:, 3] = motion.tau_ho_s
    table[:, 4] = motion.roll_rad * v**motion.roll_speed_exponent
    table[:, 5] = motion.roll_fraction
    return table


@njit(cache=True)
def _oscillation(
    n_values: int, w: float, x: float, env: float, env1: float, env2: float
) -> tuple[float, float, float]:
    """env(t) sin(w x), x = t − t_s, and its first two time derivatives."""
    sn, cs = math.sin(w * x), math.cos(w * x)
    v = a = 0.0
    if n_values > 1:
        v = env1 * sn + env * w * cs
    if n_values > 2:
        a = env2 * sn + 2.0 * env1 * w * cs - env * w * w * sn
    return env * sn, v, a


@njit(cache=True)
def stance_motion(
    n_values: int, t: float, start: float, end: float, par: NDArray[np.float64]
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Pitch and roll offsets at ``t`` in the stance [start, end) and their first two
    time derivatives (0 beyond ``n_values``), parameters ``par`` (:data:`COLUMNS`)."""
    quiet, edge, tau1, tau2, roll, frac = par[0], par[1], par[2], par[3], par[4], par[5]
    e1 = math.exp(-(t - start) / tau1)
    e2 = math.exp(-(end - t) / tau2)
    env = quiet + edge * (e1 + e2)
    env1 = edge * (e2 / tau2 - e1 / tau1)
    env2 = edge * (e1 / (tau1 * tau1) + e2 / (tau2 * tau2))
    x = t - start
    p0, p1, p2 = _oscillation(n_values, MICRO_W[0], x, env, env1, env2)
    roll_motion = _oscillation(n_values, MICRO_W[1], x, env, env1, env2)
    width = frac * (end - start)
    u = (t - (end - width)) / width
    if u > 0.0:
        s1 = math.sin(math.pi * u)
        p0 += roll * s1 * s1
        p1 += roll * math.pi / width * math.sin(2 * math.pi * u)
        p2 += roll * 2 * math.pi * math.pi / (width * width) * math.cos(2 * math.pi * u)
    return (p0, p1, p2), roll_motion


@dataclass(frozen=True)
class StanceRandomization:
    """Walker-to-walker and day-to-day variability of :class:`StanceMotion`
    (domain randomisation): log10 of the quiet and edge amplitudes normal
    with the given means and standard deviations, the other values fixed.

    The defaults are today's guess; :meth:`calibrated` holds the values fitted
    to recorded walks (docs/SIM_TO_REAL.md, ``benchmarks/calibrate_foot.py``).
    ``swing_speed_exponent`` (every walker's, :meth:`StanceMotion.swing_scale`)
    needs ``flat_fraction`` (the walker's gait timing); 0 keeps the swing scale
    independent of speed, as in :meth:`calibrated`. ``heel_rocker`` (every
    walker's, :class:`StanceMotion`) lands the heel at rest on its footfall; off
    in :meth:`calibrated`. ``cadence_intercept_hz``,
    ``cadence_slope_hz_per_mps`` and ``cadence_log10_std`` set every walker's
    cadence law (module docstring; None, the default and :meth:`calibrated`'s,
    keeps the route's law and draws nothing more from the generator).
    ``pitch_knot_stride_m`` (every walker's; 0, off, in :meth:`calibrated`) shrinks
    the swing pitch knots of strides shorter than it (module docstring).
    """

    quiet_log10_mean: float = -3.0
    quiet_log10_std: float = 0.3
    quiet_speed_exponent: float = 0.5
    edge_log10_mean: float = -2.0
    edge_log10_std: float = 0.2
    edge_speed_exponent: float = 1.0
    tau_hs_s: float = 0.04
    tau_ho_s: float = 0.04
    roll_rad: float = 0.01
    roll_speed_exponent: float = 1.0
    roll_fraction: float = 0.3
    stance_spread_log10: float = 0.2
    flat_fraction: float | None = None
    flat_fraction_std: float = 0.0
    flat_speed_slope: float = 0.0
    heel_fraction: float = 0.16
    swing_pitch_scale: float = 1.0
    swing_pitch_log10_std: float = 0.0
    swing_speed_exponent: float = 0.0
    heel_rocker: bool = False
    cadence_intercept_hz: float | None = None
    cadence_slope_hz_per_mps: float = DEFAULT_CADENCE[1]
    cadence_log10_std: float = 0.0
    pitch_knot_stride_m: float = 0.0
    monotone_pitch: bool = False
    heel_strike_scale: float = 1.0
    mid_pitch_midpoint: bool = False
    swing_roll_rad: float = 0.0

    def __post_init__(self) -> None:
        check_walker_fields("StanceRandomization", self)
        if not (math.isfinite(self.cadence_log10_std) and 0 <= self.cadence_log10_std <= 0.3):
            raise ValueError(
                "StanceRandomization.cadence_log10_std must be in [0, 0.3], "
                f"got {self.cadence_log10_std!r}"
            )
        if self.cadence_log10_std != 0.0 and self.cadence_intercept_hz is None:
            raise ValueError(
                "StanceRandomization.cadence_log10_std needs cadence_intercept_hz "
                "(the cadence law), got cadence_intercept_hz=None"
            )
        for name in ("quiet_log10_std", "edge_log10_std", "swing_pitch_log10_std"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v <= 2):
                raise ValueError(f"StanceRandomization.{name} must be in [0, 2], got {v!r}")
        if not (math.isfinite(self.flat_fraction_std) and 0 <= self.flat_fraction_std <= 0.3):
            raise ValueError(
                "StanceRandomization.flat_fraction_std must be in [0, 0.3], "
                f"got {self.flat_fraction_std!r}"
            )
        for name in ("quiet_log10_mean", "edge_log10_mean"):
            v = getattr(self, name)
            if not (math.isfinite(v) and -7 <= v <= -0.5):
                raise ValueError(f"StanceRandomization.{name} must be in [−7, −0.5], got {v!r}")
        if self.swing_speed_exponent != 0.0 and self.flat_fraction is None:
            raise ValueError(
                "StanceRandomization.swing_speed_exponent needs flat_fraction "
                "(the walker's gait timing), got flat_fraction=None"
            )
        # the remaining values are checked by StanceMotion at each draw
        self.draw(np.random.default_rng(0))

    @classmethod
    def calibrated(cls) -> StanceRandomization:
        """The values fitted to the 31 development recordings
        (``benchmarks/calibrate_foot.py``; docs/SIM_TO_REAL.md), rounded to 3
        digits: the second fit, whose distance adds the per-stride quietness by
        stride speed and the coverage of each recording (CMA-ES, 31 generations
        of 12 warm-started from the first fit's values)."""
        return cls(
            quiet_log10_mean=-2.34,
            quiet_log10_std=0.235,
            quiet_speed_exponent=0.79,
            edge_log10_mean=-3.49,
            edge_log10_std=0.366,
            edge_speed_exponent=3.76,
            tau_hs_s=0.19,
            tau_ho_s=0.0321,
            roll_rad=0.000623,
            roll_speed_exponent=1.0,
            roll_fraction=0.3,
            stance_spread_log10=0.2,
            flat_fraction=0.296,
            flat_fraction_std=0.047,
            flat_speed_slope=-0.0718,
            heel_fraction=0.188,
            swing_pitch_scale=1.37,
            swing_pitch_log10_std=0.0805,
        )

    def draw(self, rng: np.random.Generator) -> StanceMotion:
        """One walker's stance dynamics: two normal draws and a seed from ``rng``."""
        z_quiet, z_edge = rng.standard_normal(2)
        quiet = self.quiet_log10_mean + self.quiet_log10_std * z_quiet
        edge = self.edge_log10_mean + self.edge_log10_std * z_edge
        return StanceMotion(
            quiet_rad=float(min(10.0**quiet, 0.5)),
            quiet_speed_exponent=self.quiet_speed_exponent,
            edge_rad=float(min(10.0**edge, 0.5)),
            edge_speed_exponent=self.edge_speed_exponent,
            tau_hs_s=self.tau_hs_s,
            tau_ho_s=self.tau_ho_s,
            roll_rad=self.roll_rad,
            roll_speed_exponent=self.roll_speed_exponent,
            roll_fraction=self.roll_fraction,
            stance_spread_log10=self.stance_spread_log10,
            seed=int(rng.integers(2**31)),
            heel_rocker=self.heel_rocker,
            pitch_knot_stride_m=self.pitch_knot_stride_m,
            monotone_pitch=self.monotone_pitch,
            heel_strike_scale=self.heel_strike_scale,
            mid_pitch_midpoint=self.mid_pitch_midpoint,
            swing_roll_rad=self.swing_roll_rad,
            **self._draw_gait(rng),
            **self._draw_cadence(rng),
        )

    def _draw_cadence(self, rng: np.random.Generator) -> dict[str, float | None]:
        """The walker's cadence law: the law a + b·v scaled by 10^(σ_c ξ), ξ one more
        normal draw from ``rng`` only when ``cadence_intercept_hz`` is set (else the
        route's default law and no draw). The scale is clipped so that the walker's
        law stays valid (:func:`pednav_env.gait.walker_checks.check_cadence_law`)."""
        if self.cadence_intercept_hz is None:
            return {}
        a, b = self.cadence_intercept_hz, self.cadence_slope_hz_per_mps
        scale = 10.0 ** (self.cadence_log10_std * float(rng.standard_normal()))
        ends = [a + b * v for v in CADENCE_CHECK_SPEEDS]
        lo, hi = CADENCE_HZ_RANGE
        scale = min(max(scale, lo / min(ends)), hi / max(ends))
        return {"cadence_intercept_hz": scale * a, "cadence_slope_hz_per_mps": scale * b}

    def _draw_gait(self, rng: np.random.Generator) -> dict[str, float | None]:
        """The walker's gait timing and swing vigour; two more normal draws from
        ``rng`` only when ``flat_fraction`` is set (else the route's own timing)."""
        if self.flat_fraction is None:
            return {}
        z_flat, z_swing = rng.standard_normal(2)
        flat = self.flat_fraction + self.flat_fraction_std * z_flat
        scale = self.swing_pitch_scale * 10.0 ** (self.swing_pitch_log10_std * z_swing)
        return {
            "flat_fraction": float(min(max(flat, MIN_FLAT), 0.7)),
            "flat_speed_slope": self.flat_speed_slope,
            "heel_fraction": self.heel_fraction,
            "swing_pitch_scale": float(min(max(scale, 0.25), 4.0)),
            "swing_speed_exponent": self.swing_speed_exponent,
        }
