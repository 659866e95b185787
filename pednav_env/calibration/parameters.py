"""The fitted values of the calibrated foot simulator and the walker population
they give (:func:`randomization`); the fit itself is :mod:`pednav_env.calibration.fit`.

The parameters (:data:`PARAMETERS`) are those of the distribution over
walkers :class:`pednav_env.gait.stance_motion.StanceRandomization`: the
mid-stance quiet amplitude (log10 mean and spread over walkers, speed
exponent), the edge amplitude (the same), the heel-strike and heel-off time
constants, the roll-over amplitude, the walker's foot-flat share of the
walking cycle (mean at 1 m/s, spread over walkers, change per unit ln speed),
the heel-off/heel-strike share, and the swing vigour (log10 mean and spread of
the scale of the swing's pitch knots). Optionally (:data:`SWING_SPEED`, a
16th value) the swing vigour's speed exponent,
:attr:`pednav_env.gait.stance_motion.StanceRandomization.swing_speed_exponent`,
which the shipped fit holds at 0. Optionally (:data:`PITCH_KNOTS`, one value
more, last) the stride length below which the swing's pitch knots shrink,
:attr:`pednav_env.gait.stance_motion.StanceRandomization.pitch_knot_stride_m`
(0, off, in the shipped fit). Model options that are not fitted (such as
``heel_rocker``, :attr:`pednav_env.gait.stance_motion.StanceRandomization.heel_rocker`,
or a walking cadence law regressed on the training recordings,
:mod:`pednav_env.calibration.cadence`) are held fixed by ``options``. The IMU
grade is the recordings' (``microstrain_gx5``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.gait.stance_motion import StanceRandomization

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Parameter:
    """One fitted value: its name, start point and box (the fit's units)."""

    name: str
    start: float
    lower: float
    upper: float


#: The fitted values in vector order. Start points: today's stance timing
#: (foot flat 0.34 of the cycle, heel-off and heel-strike 0.16 each, unscaled
#: swing) and round guesses for the stance dynamics, not a previous fit.
PARAMETERS = (
    Parameter("quiet_log10_mean", -2.5, -4.5, -1.2),
    Parameter("quiet_log10_std", 0.3, 0.02, 1.0),
    Parameter("quiet_speed_exponent", 0.5, -1.0, 3.0),
    Parameter("edge_log10_mean", -2.0, -5.0, -0.8),
    Parameter("edge_log10_std", 0.2, 0.02, 1.0),
    Parameter("edge_speed_exponent", 1.0, -1.0, 4.0),
    Parameter("log10_tau_hs_s", -1.4, -2.0, -0.7),
    Parameter("log10_tau_ho_s", -1.4, -2.0, -0.7),
    Parameter("log10_roll_rad", -2.0, -4.0, -0.8),
    Parameter("flat_fraction", 0.34, 0.15, 0.6),
    Parameter("flat_fraction_std", 0.03, 0.0, 0.15),
    Parameter("flat_speed_slope", 0.0, -0.3, 0.1),
    Parameter("heel_fraction", 0.16, 0.05, 0.2),
    Parameter("log10_swing_pitch_scale", 0.0, -0.15, 0.35),
    Parameter("swing_pitch_log10_std", 0.05, 0.0, 0.2),
)
NAMES = tuple(p.name for p in PARAMETERS)
START = np.array([p.start for p in PARAMETERS])
LOWER = np.array([p.lower for p in PARAMETERS])
UPPER = np.array([p.upper for p in PARAMETERS])
#: The optional 16th value: the swing vigour's speed exponent (k ∝ v^p), start 0
#: (the shipped model's speed-independent scale).
SWING_SPEED = Parameter("swing_speed_exponent", 0.0, -0.5, 1.5)
EXTENDED = (*PARAMETERS, SWING_SPEED)
#: The optional last value with ``knots``: the stride length (m) below which the
#: swing's pitch knots shrink (StanceRandomization.pitch_knot_stride_m), start 0
#: (off: today's knots at every length), box up to 1.2 m (about the route's
#: default stride at 1 m/s, 1.18 m).
PITCH_KNOTS = Parameter("pitch_knot_stride_m", 0.0, 0.0, 1.2)


#: Opt-in literature priors on the walker population's gait timing
#: (``calibrate_foot.py --gait-priors``, candidate v8 of docs/SIM_TO_REAL_CANDIDATES.md): a
#: narrower box for the values named, (lower, upper) in the fit's units; the other
#: values keep their box. In the model (:meth:`StanceMotion.cycle_fractions
#: <pednav_env.gait.stance_motion.StanceMotion.cycle_fractions>`) a walking cycle is
#: foot flat f (foot-flat to heel-off), heel strike h (heel contact to foot flat),
#: heel-off h (heel-off to toe-off) and swing 1 − f − 2h; f = f₁ + β ln v.
#:
#: - ``flat_fraction`` f₁ (at 1 m/s) in [0.15, 0.43]. Published event timings at
#:   comfortable speed (1.2–1.4 m/s) put foot flat (forefoot contact) to heel-off
#:   at 0.20 of the cycle (Perry & Burnfield, *Gait Analysis: Normal and
#:   Pathological Function*, 2nd ed. 2010: forefoot contact ends loading response
#:   at about 10 %, heel rise opens terminal stance at about 31 %, toe-off at about
#:   60 %) to 0.33 (the traditional events of Levangie & Norkin, *Joint Structure
#:   and Function*: foot flat about 7–8 %, heel-off about 40 %, toe-off about 60 %).
#:   At 1 m/s the share is larger, by at most 0.15 · ln 1.37 ≈ 0.05 (β below):
#:   0.20–0.38. Walkers differ: the stance share's SD over healthy adults is
#:   0.019–0.025 of the cycle (Kirtley's normative collection,
#:   clinicalgaitanalysis.com/data/stance.html: 61.9 ± 1.9 % and 61.8 ± 2.5 % in two
#:   groups under 45 years, 61.5 ± 1.9 % and 60.9 ± 2.5 % in students); no SD of the
#:   foot-flat share itself was found, so that of the stance share, 2 SD = 0.05 either
#:   side: 0.15–0.43.
#: - ``flat_speed_slope`` β in [−0.15, 0]. The stance share falls with walking
#:   speed: 64.2 % − 3.5 % per m/s (Kirtley, Whittle & Jefferson 1985, J Biomed Eng
#:   7:282, regression over walkers and speeds, r = 0.71), −0.035 · v per unit ln v,
#:   −0.05 on average from 1 to 2 m/s (the whole change put on foot flat, as the
#:   model does): never rising (β ≤ 0), and three times that at most.
#: - ``heel_fraction`` h in [0.12, 0.20]. The model's two moving stance phases
#:   2h are loading (heel contact to foot flat, 0.07–0.10 of the cycle) plus
#:   heel-off to toe-off (0.20 from heel-off at 40 %, 0.29–0.31 from heel rise at
#:   31 % to toe-off at 60–62 %; the same two sources): 2h in 0.27–0.41, h in
#:   0.135–0.205; 0.12 below, the shipped upper bound 0.20 above.
#:
#: ``flat_fraction_std`` (the spread over walkers) keeps its box [0, 0.15]: no
#: published between-walker spread of the foot-flat share was found to bound it.
GAIT_PRIORS: Mapping[str, tuple[float, float]] = {
    "flat_fraction": (0.15, 0.43),
    "flat_speed_slope": (-0.15, 0.0),
    "heel_fraction": (0.12, 0.20),
}


def parameter_set(size: int, knots: bool = False) -> tuple[Parameter, ...]:
    """The parameters of a vector of ``size`` values: :data:`PARAMETERS` (15) or
    :data:`EXTENDED` (16), followed by :data:`PITCH_KNOTS` when ``knots`` (one
    value more)."""
    base = size - 1 if knots else size
    extra = (PITCH_KNOTS,) if knots else ()
    if base == len(PARAMETERS):
        return (*PARAMETERS, *extra)
    if base == len(EXTENDED):
        return (*EXTENDED, *extra)
    raise ValueError(
        f"a parameter vector{' with the pitch knots' if knots else ''} has "
        f"{len(PARAMETERS) + len(extra)} or {len(EXTENDED) + len(extra)} values, got {size}"
    )


def box(size: int, knots: bool = False, priors: bool = False) -> tuple[Array, Array]:
    """Lower and upper bounds of a vector of ``size`` values (:func:`parameter_set`);
    with ``priors`` those of :data:`GAIT_PRIORS` narrowed to its ranges."""
    ps = parameter_set(size, knots)
    lower = np.array([p.lower for p in ps])
    upper = np.array([p.upper for p in ps])
    if priors:
        for i, p in enumerate(ps):
            if p.name in GAIT_PRIORS:
                lower[i], upper[i] = GAIT_PRIORS[p.name]
    return lower, upper


def randomization(
    x: Sequence[float],
    options: Mapping[str, float | bool] | None = None,
    knots: bool = False,
) -> StanceRandomization:
    """The parameter vector (:data:`NAMES` order, then optionally
    :data:`SWING_SPEED`, then with ``knots`` :data:`PITCH_KNOTS`; clipped to the
    box) as a StanceRandomization, with the fixed model ``options``
    (StanceRandomization fields, e.g. ``heel_rocker`` or the ``cadence_*`` law of
    :func:`pednav_env.calibration.cadence.fit_cadence_law`)."""
    x = np.asarray(x, dtype=float)
    lower, upper = box(x.size, knots)
    x = np.clip(x, lower, upper)
    v = dict(zip([p.name for p in parameter_set(x.size, knots)], x.tolist(), strict=True))
    if knots:
        options = {**(options or {}), "pitch_knot_stride_m": v["pitch_knot_stride_m"]}
    return StanceRandomization(
        quiet_log10_mean=v["quiet_log10_mean"],
        quiet_log10_std=v["quiet_log10_std"],
        quiet_speed_exponent=v["quiet_speed_exponent"],
        edge_log10_mean=v["edge_log10_mean"],
        edge_log10_std=v["edge_log10_std"],
        edge_speed_exponent=v["edge_speed_exponent"],
        tau_hs_s=10 ** v["log10_tau_hs_s"],
        tau_ho_s=10 ** v["log10_tau_ho_s"],
        roll_rad=10 ** v["log10_roll_rad"],
        flat_fraction=v["flat_fraction"],
        flat_fraction_std=v["flat_fraction_std"],
        flat_speed_slope=v["flat_speed_slope"],
        heel_fraction=v["heel_fraction"],
        swing_pitch_scale=10 ** v["log10_swing_pitch_scale"],
        swing_pitch_log10_std=v["swing_pitch_log10_std"],
        swing_speed_exponent=v.get("swing_speed_exponent", 0.0),
        **(options or {}),
    )
