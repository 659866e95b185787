"""Truth simulator of the heel–knee marker gait (paper 001, thesis chapters 4–5).

Walks of the parametric model of :mod:`pednav_env.gait.heel_knee_model`
(eqs 4.1–4.11): the deviations L of the gait parameters from their nominal
values p⁰ follow the exponentially correlated law of eq 4.11, and the heel and
knee markers follow eq 4.10 (or its integrated form below).

Two kinematics are offered:

``"paper"``
    Eq 4.10 literally: the trend is (c_x⁰ + Δc_x(k))·kT and the phase
    (ω₀ + Δω(k))·kT. Exact for constant parameters; when the parameters vary,
    the elapsed time kT multiplies their sample-to-sample jitter, so the
    positions become rough late in a long walk. Used by the paper scenario
    (the thesis simulated its own model).
``"integrated"``
    The trend and phase are integrals of the speed and frequency (trapezoid
    rule), so speed and cadence changes move the markers smoothly. Required
    for gait changes within a walk.

Gait changes (``"integrated"`` only) switch, at Poisson times, to a new gait
with cadence factor f_c and stride factor f_s (uniform in their ranges), with
a linear transition: ω⁰ → f_c ω⁰, A_x⁰ → f_s A_x⁰, A⁰ → f_s A⁰ and the speed
c_x⁰ → f_c f_s c_x⁰ (speed = stride length × cadence).

All outputs are batched over walkers, ``(N, K, ...)``; walker i draws only
from its own generator ``rngs[i]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from pednav_env.checks import require_nonnegative, require_positive
from pednav_env.gait.heel_knee_model import (
    HEEL,
    I_A,
    I_AX,
    I_AZ,
    I_CX,
    I_CZ,
    I_OMEGA,
    KNEE,
    HeelKneeModel,
)

Array = NDArray[np.float64]


@dataclass(frozen=True)
class HeelKneeConfig(HeelKneeModel):
    """Truth simulator settings; defaults give the paper scenario.

    The model fields (``nominal``, ``sample_period``, ``param_var_ratio``,
    ``param_corr_time``) are those of :class:`HeelKneeModel`.

    Attributes
    ----------
    kinematics : {"paper", "integrated"}
        Eq 4.10 literally, or integrated trend and phase (module docstring).
    initial_deviation : {"zero", "stationary"}
        L(0) = 0, i.e. the walk starts at the nominal values (thesis eq 5.6),
        or L(0) drawn from the stationary law N(0, P0).
    gait_change_rate_hz : float
        Mean number of gait changes per second (Poisson); 0 in the thesis.
    cadence_factor_range, stride_factor_range : tuple of float
        Ranges of the uniform factors f_c, f_s of a new gait.
    gait_transition_time : float
        Duration (s) of the linear transition to a new gait.
    """

    kinematics: Literal["paper", "integrated"] = "paper"  # thesis eq 4.10
    initial_deviation: Literal["zero", "stationary"] = "zero"  # thesis eq 5.6
    gait_change_rate_hz: float = 0.0  # thesis: one steady gait
    cadence_factor_range: tuple[float, float] = (1.0, 1.0)  # thesis: one steady gait
    stride_factor_range: tuple[float, float] = (1.0, 1.0)  # thesis: one steady gait
    gait_transition_time: float = 1.0  # ours: about 1.5 strides

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.kinematics not in ("paper", "integrated"):
            raise ValueError(
                "HeelKneeConfig.kinematics must be 'paper' or 'integrated', "
                f"got {self.kinematics!r}"
            )
        if self.initial_deviation not in ("zero", "stationary"):
            raise ValueError(
                "HeelKneeConfig.initial_deviation must be 'zero' or 'stationary', "
                f"got {self.initial_deviation!r}"
            )
        require_nonnegative("HeelKneeConfig.gait_change_rate_hz", self.gait_change_rate_hz)
        for name in ("cadence_factor_range", "stride_factor_range"):
            lo_hi = getattr(self, name)
            if (
                len(lo_hi) != 2
                or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in lo_hi)
                or not 0 < lo_hi[0] <= lo_hi[1]
            ):
                raise ValueError(
                    f"HeelKneeConfig.{name} must be (lo, hi) with 0 < lo <= hi, got {lo_hi!r}"
                )
        require_positive("HeelKneeConfig.gait_transition_time", self.gait_transition_time)
        if self.gait_change_rate_hz > 0 and self.kinematics != "integrated":
            raise ValueError(
                "HeelKneeConfig.gait_change_rate_hz > 0 needs kinematics='integrated' "
                f"(the literal eq 4.10 would jump by Δc·kT), got kinematics={self.kinematics!r}"
            )

    @classmethod
    def paper(cls) -> HeelKneeConfig:
        """The thesis setup (every default; see docs/REPRODUCTION.md (paper 001))."""
        return cls()


@dataclass(frozen=True)
class HeelKneeWalk:
    """Truth of a batch of walks, sampled at t_k = kT, k = 0 … K−1.

    Attributes
    ----------
    t : ndarray, shape (K,)
        Sample times (s).
    nominal : ndarray, shape (N, K, 6)
        Nominal parameters p⁰(k) (constant unless the gait changes).
    deviation : ndarray, shape (N, K, 6)
        L(k), the exponentially correlated deviations (eq 4.11).
    phase : ndarray, shape (N, K)
        Phase of the gait harmonic (rad).
    markers : ndarray, shape (N, K, 2, 2)
        Positions (m): marker (heel, knee), then (x forward, z up).
    """

    t: Array
    nominal: Array
    deviation: Array
    phase: Array
    markers: Array

    @property
    def params(self) -> Array:
        """p(k) = p⁰(k) + L(k), shape ``(N, K, 6)``."""
        return self.nominal + self.deviation

    @property
    def heel(self) -> Array:
        """Heel (x, z), shape ``(N, K, 2)`` (m)."""
        return self.markers[:, :, HEEL]

    @property
    def knee(self) -> Array:
        """Knee (x, z), shape ``(N, K, 2)`` (m)."""
        return self.markers[:, :, KNEE]

    @property
    def num_walkers(self) -> int:
        return self.markers.shape[0]


def _check_rngs(rngs: Sequence[np.random.Generator]) -> None:
    if isinstance(rngs, np.random.Generator) or len(rngs) == 0:
        raise ValueError(
            f"rngs must be a non-empty sequence of numpy Generators (one per walker), got {rngs!r}"
        )
    for i, rng in enumerate(rngs):
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rngs[{i}] must be a numpy.random.Generator, got {rng!r}")


def _gait_factors_into(
    config: HeelKneeConfig, t: Array, rng: np.random.Generator, out: Array
) -> bool:
    """Write f_c(t), f_s(t) of one walker into ``out`` (2, K), which holds ones.

    Draws, in order: the Poisson change times (exponential gaps until the walk's
    end), then per change its cadence and stride factors. Change i rules the
    samples from its time up to the next change (t is ascending) with a linear
    transition from the previous gait. Returns whether the walk changes gait
    (else ``out`` is left at 1).
    """
    if config.gait_change_rate_hz == 0.0 or t.size == 0:
        return False
    t_end = t[-1]
    times: list[float] = []
    now = 0.0
    while True:
        now += rng.exponential(1.0 / config.gait_change_rate_hz)
        if now >= t_end:
            break
        times.append(now)
    if not times:
        return False
    m = len(times)
    (lo_c, hi_c), (lo_s, hi_s) = config.cadence_factor_range, config.stride_factor_range
    # one uniform per factor in the order (c, s) of each change: the same numbers
    # as m pairs of scalar rng.uniform(lo, hi) calls (low + (high − low) · U each)
    new = rng.uniform(np.array([lo_c, lo_s] * m), np.array([hi_c, hi_s] * m))
    # per change: its time, the factor steps new − old and the old factors
    table = np.empty((5, m))
    table[0] = times
    table[3:5, 0] = 1.0
    table[3:5, 1:] = new[: 2 * m - 2].reshape(m - 1, 2).T
    np.subtract(new.reshape(m, 2).T, table[3:5], out=table[1:3])
    bounds = np.empty(m + 1, dtype=np.intp)
    bounds[:m] = np.searchsorted(t, times, side="left")
    bounds[m] = t.size
    first = int(bounds[0])
    # the change ruling each sample from the first change on (an empty segment,
    # two changes between the same samples, rules no sample)
    rule = np.repeat(table, bounds[1:] - bounds[:-1], axis=1)
    w = t[first:] - rule[0]
    w /= config.gait_transition_time
    np.clip(w, 0.0, 1.0, out=w)
    np.multiply(rule[1:3], w, out=out[:, first:])
    out[:, first:] += rule[3:5]  # old + (new − old) w
    return True


@dataclass(frozen=True)
class _SimConstants:
    """What :func:`simulate_heel_knee` derives from its config (read only)."""

    inertia: float  # d of eq 5.1
    initial_std: Array  # (6,) √P0
    step_std: Array  # (6, 1) std of Γκ per step
    nominal: Array  # (6, 1) p⁰


_SIM_CONSTANTS: dict[HeelKneeConfig, _SimConstants] = {}


def _sim_constants(config: HeelKneeConfig) -> _SimConstants:
    """:class:`_SimConstants` of ``config``, built once per config."""
    const = _SIM_CONSTANTS.get(config)
    if const is None:
        if len(_SIM_CONSTANTS) > 64:
            _SIM_CONSTANTS.clear()
        proc = config.process
        const = _SIM_CONSTANTS[config] = _SimConstants(
            inertia=float(proc.F[0]),
            initial_std=np.sqrt(proc.P0),
            step_std=np.sqrt(proc.process_noise)[:, None],
            nominal=config.nominal.vector[:, None],
        )
    return const


def simulate_heel_knee(
    config: HeelKneeConfig, num_samples: int, rngs: Sequence[np.random.Generator]
) -> HeelKneeWalk:
    """Simulate N walks of K samples (thesis eqs 4.10, 4.11).

    Parameters
    ----------
    config : HeelKneeConfig
        Simulator settings.
    num_samples : int
        K ≥ 1, samples per walk at t_k = kT.
    rngs : sequence of numpy.random.Generator, length N
        One generator per walker; walker i's walk depends only on ``rngs[i]``.
        Each draws, in order: L(0) (only if ``initial_deviation`` is
        "stationary"), the K−1 innovations, then the gait changes.

    Returns
    -------
    HeelKneeWalk
        Arrays shaped ``(N, K, ...)`` (``nominal`` and ``deviation`` are views
        of parameter-major arrays).
    """
    if not isinstance(num_samples, (int, np.integer)) or num_samples < 1:
        raise ValueError(f"num_samples must be an integer >= 1, got {num_samples!r}")
    _check_rngs(rngs)
    n_walkers, k_samples = len(rngs), int(num_samples)
    T = config.sample_period
    t = np.arange(k_samples) * T
    const = _sim_constants(config)
    stationary = config.initial_deviation == "stationary"

    drive = np.empty((n_walkers, k_samples, 6))  # the draws, filled in place
    factors = np.ones((n_walkers, 2, k_samples))  # f_c, f_s
    changes = False
    for i, rng in enumerate(rngs):
        if stationary:
            rng.standard_normal(out=drive[i, 0])
        else:
            drive[i, 0] = 0.0  # eq 5.6: the walk starts at the nominal values
        rng.standard_normal(out=drive[i, 1:])
        changes |= _gait_factors_into(config, t, rng, factors[i])
    # From here on parameter-major (N, 6, K): every series is contiguous in time.
    drive = np.ascontiguousarray(drive.transpose(0, 2, 1))
    if stationary:
        drive[..., 0] *= const.initial_std
    drive[..., 1:] *= const.step_std  # std of Γκ per step
    # L(k) = d L(k−1) + Γκ(k): a first-order recursion along time (eq 4.11).
    deviation = lfilter([1.0], [1.0, -const.inertia], drive, axis=2)

    nominal = np.empty((n_walkers, 6, k_samples))
    nominal[...] = const.nominal
    if changes:  # (× 1 elsewhere would change nothing)
        f_c, f_s = factors[:, 0], factors[:, 1]
        nominal[:, I_OMEGA] *= f_c
        nominal[:, I_AX] *= f_s
        nominal[:, I_A] *= f_s
        nominal[:, I_CX] *= f_c * f_s
    params = nominal + deviation

    if config.kinematics == "paper":
        trend_x = params[:, I_CX] * t
        phase = params[:, I_OMEGA] * t
    else:  # ∫₀^{kT} rate dt with the trapezoid rule, starting at 0
        rates = params[:, I_CX :: I_OMEGA - I_CX]  # c_x and ω rows (a view)
        step = rates[..., 1:] + rates[..., :-1]
        step *= 0.5 * T
        integral = np.empty(rates.shape)
        integral[..., 0] = 0.0
        np.cumsum(step, axis=2, out=integral[..., 1:])
        trend_x, phase = integral[:, 0], integral[:, 1]
    markers = np.empty((n_walkers, k_samples, 2, 2))
    _markers_into(markers, trend_x, params, phase, config.nominal.shank_length)
    return HeelKneeWalk(
        t=t,
        nominal=nominal.transpose(0, 2, 1),
        deviation=deviation.transpose(0, 2, 1),
        phase=phase,
        markers=markers,
    )


def _markers_into(
    out: Array, trend_x: Array, params: Array, phase: Array, shank_length: float
) -> None:
    """Heel and knee positions (eqs 4.5–4.7, 4.10) from the trend ``trend_x``
    (N, K), parameter-major ``params`` (N, 6, K) and ``phase`` (N, K), into
    ``out`` (N, K, 2, 2): computed on contiguous rows, then interleaved."""
    s = np.sin(phase)
    rows = np.empty((4, *s.shape))  # x₁, z₁, x₂, z₂
    np.multiply(params[:, I_AX], s, out=rows[0])
    rows[0] += trend_x  # trend_x + A_x s
    np.multiply(params[:, I_AZ], s, out=rows[1])
    rows[1] += params[:, I_CZ]  # c_z + A_z s
    beta = params[:, I_A] * s  # eq 4.5
    np.sin(beta, out=rows[2])
    rows[2] *= shank_length
    rows[2] += rows[0]  # eq 4.6
    np.cos(beta, out=rows[3])
    rows[3] *= shank_length
    rows[3] += rows[1]  # eq 4.7
    flat = out.reshape(*s.shape, 4)
    for c in range(4):
        flat[..., c] = rows[c]
