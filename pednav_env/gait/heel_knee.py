"""Heel–knee marker gait model of paper 001 (VR-tracking thesis, chapters 4–5).

Two UWB markers on one leg, in the sagittal plane (x forward along the walk,
z up): M3 on the heel and M4 on the knee, joined by the rigid shank of length
M. The thesis models each heel coordinate as a trend plus the fundamental
gait harmonic, and the shank as a pendulum whose angle β from the vertical is
harmonic at the same frequency (eqs 4.1, 4.2, 4.5–4.7, 4.10)::

    x₁ = (c_x⁰ + Δc_x) kT + (A_x⁰ + ΔA_x) sin((ω₀ + Δω) kT)
    z₁ = (c_z⁰ + Δc_z)    + (A_z⁰ + ΔA_z) sin((ω₀ + Δω) kT)
    β  = (A⁰ + ΔA) sin((ω₀ + Δω) kT)
    x₂ = x₁ + M sin β,    z₂ = z₁ + M cos β

with ω₀ = 2π/τ₀ (eq 4.8). The deviations L = [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω]
(eq 4.9; the order used everywhere in this package) are independent
exponentially correlated processes (eqs 4.11, 5.1, 5.2, 5.4)::

    L(k) = F L(k−1) + Γ κ(k),   F = d I,   Γ = (1 − d) I,
    κ ~ N(0, Q),   Q = (1 + d)/(1 − d) · 0.03 · diag(p⁰²)

so that each deviation has the stationary variance 0.03 · (its nominal)²
(see :func:`process_model` for how the garbled print of (5.2), (5.4) and (5.8)
is read). The thesis gives neither the sample period T nor the inertia d;
here d = exp(−T/τ) with a correlation time τ in seconds, so the statistics do
not depend on the sample rate.

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
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter

Array = NDArray[np.float64]

#: Names of the model parameters p = p⁰ + L, in the state order of eq 4.9.
PARAM_NAMES: tuple[str, ...] = ("A_x", "A_z", "c_x", "c_z", "A", "omega")
#: Units of the parameters (and of the deviations L).
PARAM_UNITS: tuple[str, ...] = ("m", "m", "m/s", "m", "rad", "rad/s")
I_AX, I_AZ, I_CX, I_CZ, I_A, I_OMEGA = range(6)
#: Marker indices of the ``(..., 2, 2)`` position arrays: marker, then (x, z).
HEEL, KNEE = 0, 1

#: Thesis §4.2 (nominal values before eq 4.8): heel amplitudes and trend.
_PAPER_A_X = 0.4
_PAPER_SHANK = 0.5
#: A⁰ for a straight leg of length 2M (thigh ≈ shank) swinging about the hip:
#: the heel's forward excursion A_x⁰ = 2M sin θ puts the shank at θ behind the
#: vertical when the heel is ahead, so A⁰ = −asin(A_x⁰ / 2M) ≈ −0.4115 rad.
SHANK_ANGLE_AMPLITUDE_GEOMETRIC = -math.asin(_PAPER_A_X / (2.0 * _PAPER_SHANK))


def _require_finite(name: str, value: float) -> None:
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")


def _require_positive(name: str, value: float) -> None:
    _require_finite(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")


@dataclass(frozen=True)
class HeelKneeNominal:
    """Nominal parameters p⁰ of the heel–knee model (thesis §4.2).

    Attributes
    ----------
    heel_x_amplitude : float
        A_x⁰ (m), amplitude of the heel's forward oscillation.
    heel_z_amplitude : float
        A_z⁰ (m), amplitude of the heel's vertical oscillation.
    heel_x_speed : float
        c_x⁰ (m/s), trend speed of the heel.
    heel_z_offset : float
        c_z⁰ (m), mean heel height.
    shank_angle_amplitude : float
        A⁰ (rad), amplitude of the shank angle β from the vertical (eq 4.5).
    stride_period : float
        τ₀ (s), period of the gait harmonic (eq 4.8).
    shank_length : float
        M (m), heel-to-knee distance (eqs 4.6–4.7).
    """

    heel_x_amplitude: float = _PAPER_A_X  # thesis §4.2: A_x⁰ = 0.4 m
    heel_z_amplitude: float = 0.1  # thesis §4.2: A_z⁰ = 0.1 m
    # Thesis §4.2 and (5.6): c_x⁰ = 3 m/s as printed. Kept: with A_x⁰ ω₀ = 3.59 m/s
    # the harmonic heel nearly stops once per cycle only if c_x⁰ ≈ A_x⁰ ω₀.
    heel_x_speed: float = 3.0
    heel_z_offset: float = 0.1  # thesis §4.2: c_z⁰ = 0.1 m
    # Thesis §4.2 prints A⁰ = 0 (then ΔA ≡ 0 and the knee is the heel shifted by
    # M, which contradicts the thesis's own low-pass table); ours: straight-leg
    # geometry, see SHANK_ANGLE_AMPLITUDE_GEOMETRIC.
    shank_angle_amplitude: float = SHANK_ANGLE_AMPLITUDE_GEOMETRIC
    stride_period: float = 0.7  # thesis §4.2: τ₀ = 0.7 s, eq 4.8 → ω₀ = 8.976 rad/s
    shank_length: float = _PAPER_SHANK  # thesis §4.2: M = 0.5 m

    def __post_init__(self) -> None:
        for name in ("heel_x_amplitude", "heel_z_amplitude", "heel_x_speed", "heel_z_offset"):
            _require_finite(f"HeelKneeNominal.{name}", getattr(self, name))
        _require_finite("HeelKneeNominal.shank_angle_amplitude", self.shank_angle_amplitude)
        if abs(self.shank_angle_amplitude) >= math.pi / 2:
            raise ValueError(
                "HeelKneeNominal.shank_angle_amplitude must be in (−π/2, π/2) rad, "
                f"got {self.shank_angle_amplitude!r}"
            )
        _require_positive("HeelKneeNominal.stride_period", self.stride_period)
        _require_positive("HeelKneeNominal.shank_length", self.shank_length)

    @property
    def omega(self) -> float:
        """ω₀ = 2π/τ₀ (rad/s), thesis eq 4.8."""
        return 2.0 * math.pi / self.stride_period

    @property
    def vector(self) -> Array:
        """p⁰ in the order of :data:`PARAM_NAMES`, shape ``(6,)``."""
        return np.array(
            [
                self.heel_x_amplitude,
                self.heel_z_amplitude,
                self.heel_x_speed,
                self.heel_z_offset,
                self.shank_angle_amplitude,
                self.omega,
            ]
        )


@dataclass(frozen=True)
class ProcessModel:
    """Discrete exponentially correlated model of the deviations (eq 4.11).

    ``L(k) = F L(k−1) + Γ κ(k)`` with diagonal ``F``, ``Γ`` and ``Q = cov κ``;
    ``P0`` is the thesis's initial covariance (5.8). All arrays ``(6,)`` hold
    diagonals.
    """

    F: Array
    Gamma: Array
    Q: Array
    P0: Array

    @property
    def process_noise(self) -> Array:
        """Diagonal of Γ Q Γᵀ, the covariance added per step (units² of L)."""
        return self.Gamma**2 * self.Q


def process_model(inertia: float, var_ratio: float, nominal: ArrayLike) -> ProcessModel:
    """F, Γ, Q and P0 of thesis eqs 5.1, 5.2, 5.4 and 5.8 (diagonals).

    The printed equations lost their signs and radicals; we read them as::

        F = diag(d)                                  (5.1)
        Γ = diag(1 − d)                              (5.2)
        Q = (1 + d)/(1 − d) · var_ratio · diag(p⁰²)  (5.4)
        P0 = (1 − d)/(1 + d) · Q = var_ratio · diag(p⁰²)   (5.8)

    the only reading in which the stray "1", "d" fragments of (5.4) and (5.8)
    form a consistent whole: the stationary variance of each deviation,
    Γ²Q/(1 − d²), equals var_ratio · p⁰², and P0 is that stationary variance.

    Parameters
    ----------
    inertia : float
        d in (0, 1), the one-step correlation of every deviation.
    var_ratio : float
        The thesis's 0.03: stationary variance relative to the squared nominal.
    nominal : array_like, shape (6,)
        p⁰ (units of :data:`PARAM_UNITS`).
    """
    _require_finite("inertia", float(inertia))
    if not 0.0 < inertia < 1.0:
        raise ValueError(f"inertia must be in (0, 1), got {inertia!r}")
    _require_finite("var_ratio", float(var_ratio))
    if var_ratio < 0:
        raise ValueError(f"var_ratio must be >= 0, got {var_ratio!r}")
    p0 = np.asarray(nominal, dtype=float)
    if p0.shape != (6,) or not np.all(np.isfinite(p0)):
        raise ValueError(f"nominal must be 6 finite numbers, got {nominal!r}")
    d = np.full(6, float(inertia))
    stationary = var_ratio * p0**2
    Q = (1.0 + d) / (1.0 - d) * stationary
    return ProcessModel(F=d, Gamma=1.0 - d, Q=Q, P0=(1.0 - d) / (1.0 + d) * Q)


@dataclass(frozen=True)
class HeelKneeConfig:
    """Truth simulator settings; defaults give the paper scenario.

    Attributes
    ----------
    nominal : HeelKneeNominal
        p⁰, thesis §4.2.
    sample_period : float
        T (s). Not in the thesis; 0.1 s is the 10 Hz location rate of
        DecaWave's two-way-ranging RTLS firmware (DWM1001 PANS maximum).
    param_var_ratio : float
        Stationary variance of each deviation over its squared nominal, the
        0.03 of thesis eq 5.4.
    param_corr_time : float
        τ (s), correlation time of every deviation, d = exp(−T/τ). Not in the
        thesis (it only says the parameters "change weakly in time").
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

    nominal: HeelKneeNominal = field(default_factory=HeelKneeNominal)
    sample_period: float = 0.1  # ours: 10 Hz DecaWave TWR location rate
    param_var_ratio: float = 0.03  # thesis eq 5.4
    # Ours (not in the thesis): long enough that eq 4.10's kT-amplified jitter adds
    # ≤ ~10 % of c_x⁰ to the heel speed after 10 s; docs/REPRODUCTION.md (paper 001).
    param_corr_time: float = 1e4
    kinematics: Literal["paper", "integrated"] = "paper"  # thesis eq 4.10
    initial_deviation: Literal["zero", "stationary"] = "zero"  # thesis eq 5.6
    gait_change_rate_hz: float = 0.0  # thesis: one steady gait
    cadence_factor_range: tuple[float, float] = (1.0, 1.0)  # thesis: one steady gait
    stride_factor_range: tuple[float, float] = (1.0, 1.0)  # thesis: one steady gait
    gait_transition_time: float = 1.0  # ours: about 1.5 strides

    def __post_init__(self) -> None:
        if not isinstance(self.nominal, HeelKneeNominal):
            raise ValueError(
                f"HeelKneeConfig.nominal must be a HeelKneeNominal, got {self.nominal!r}"
            )
        _require_positive("HeelKneeConfig.sample_period", self.sample_period)
        _require_finite("HeelKneeConfig.param_var_ratio", self.param_var_ratio)
        if self.param_var_ratio < 0:
            raise ValueError(
                f"HeelKneeConfig.param_var_ratio must be >= 0, got {self.param_var_ratio!r}"
            )
        _require_positive("HeelKneeConfig.param_corr_time", self.param_corr_time)
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
        _require_finite("HeelKneeConfig.gait_change_rate_hz", self.gait_change_rate_hz)
        if self.gait_change_rate_hz < 0:
            raise ValueError(
                f"HeelKneeConfig.gait_change_rate_hz must be >= 0, got {self.gait_change_rate_hz!r}"
            )
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
        _require_positive("HeelKneeConfig.gait_transition_time", self.gait_transition_time)
        if self.gait_change_rate_hz > 0 and self.kinematics != "integrated":
            raise ValueError(
                "HeelKneeConfig.gait_change_rate_hz > 0 needs kinematics='integrated' "
                f"(the literal eq 4.10 would jump by Δc·kT), got kinematics={self.kinematics!r}"
            )

    @property
    def inertia(self) -> float:
        """d = exp(−T/τ), the one-step correlation of the deviations (eq 5.1)."""
        return math.exp(-self.sample_period / self.param_corr_time)

    @property
    def process(self) -> ProcessModel:
        """F, Γ, Q, P0 of eqs 5.1, 5.2, 5.4, 5.8 for this config."""
        return process_model(self.inertia, self.param_var_ratio, self.nominal.vector)

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


def _markers(trend_x: Array, params: Array, phase: Array, shank_length: float) -> Array:
    """Marker positions from trend, parameters and phase (eqs 4.6, 4.7, 4.10)."""
    s = np.sin(phase)
    x1 = trend_x + params[..., I_AX] * s
    z1 = params[..., I_CZ] + params[..., I_AZ] * s
    beta = params[..., I_A] * s  # eq 4.5
    x2 = x1 + shank_length * np.sin(beta)  # eq 4.6
    z2 = z1 + shank_length * np.cos(beta)  # eq 4.7
    return np.stack((np.stack((x1, z1), axis=-1), np.stack((x2, z2), axis=-1)), axis=-2)


def heel_knee_positions(params: ArrayLike, t: ArrayLike, shank_length: float) -> Array:
    """Heel and knee positions of thesis eq 4.10 (the measurement function h).

    Parameters
    ----------
    params : array_like, shape (..., 6)
        p = p⁰ + L in the order of :data:`PARAM_NAMES`.
    t : array_like, shape (...)
        kT (s), broadcast against ``params[..., 0]``.
    shank_length : float
        M (m).

    Returns
    -------
    ndarray, shape (..., 2, 2)
        (heel, knee) × (x, z) in metres; ``reshape(..., 4)`` gives
        [x₁, z₁, x₂, z₂], the observation order of eqs 4.12 and 5.3.
    """
    p = np.asarray(params, dtype=float)
    tt = np.asarray(t, dtype=float)
    return _markers(p[..., I_CX] * tt, p, p[..., I_OMEGA] * tt, shank_length)


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
    """:func:`_markers` of parameter-major ``params`` (N, 6, K) into ``out``
    (N, K, 2, 2): the same operations, on contiguous rows, then interleaved."""
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
