"""The parametric heel–knee gait model of paper 001 (VR-tracking thesis, chapters 4–5).

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

This module holds what the walker and the filter share: the nominal values p⁰
(:class:`HeelKneeNominal`) and the law of the deviations
(:class:`HeelKneeModel`, :func:`process_model`). The truth simulator
(:mod:`pednav_env.gait.heel_knee`) draws walks from one instance of it; the
marker EKF (:mod:`pednav_env.nav.marker_model`) assumes another and adds the
measurement model h, H of eqs 4.10, 4.12 and 5.3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.checks import require_finite, require_nonnegative, require_positive

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
            require_finite(f"HeelKneeNominal.{name}", getattr(self, name))
        require_finite("HeelKneeNominal.shank_angle_amplitude", self.shank_angle_amplitude)
        if abs(self.shank_angle_amplitude) >= math.pi / 2:
            raise ValueError(
                "HeelKneeNominal.shank_angle_amplitude must be in (−π/2, π/2) rad, "
                f"got {self.shank_angle_amplitude!r}"
            )
        require_positive("HeelKneeNominal.stride_period", self.stride_period)
        require_positive("HeelKneeNominal.shank_length", self.shank_length)

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
    require_finite("inertia", float(inertia))
    if not 0.0 < inertia < 1.0:
        raise ValueError(f"inertia must be in (0, 1), got {inertia!r}")
    require_nonnegative("var_ratio", float(var_ratio))
    p0 = np.asarray(nominal, dtype=float)
    if p0.shape != (6,) or not np.all(np.isfinite(p0)):
        raise ValueError(f"nominal must be 6 finite numbers, got {nominal!r}")
    d = np.full(6, float(inertia))
    stationary = var_ratio * p0**2
    Q = (1.0 + d) / (1.0 - d) * stationary
    return ProcessModel(F=d, Gamma=1.0 - d, Q=Q, P0=(1.0 - d) / (1.0 + d) * Q)


@dataclass(frozen=True)
class HeelKneeModel:
    """The heel–knee model: nominal parameters and the law of their deviations.

    Shared by the truth simulator's settings
    (:class:`~pednav_env.gait.heel_knee.HeelKneeConfig`) and the filter's
    assumed model (:class:`~pednav_env.nav.marker_model.MarkerEkfConfig`),
    which subclass it.

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
    """

    nominal: HeelKneeNominal = field(default_factory=HeelKneeNominal)
    sample_period: float = 0.1  # ours: 10 Hz DecaWave TWR location rate
    param_var_ratio: float = 0.03  # thesis eq 5.4
    # Ours (not in the thesis): long enough that eq 4.10's kT-amplified jitter adds
    # ≤ ~10 % of c_x⁰ to the heel speed after 10 s; docs/REPRODUCTION.md (paper 001).
    param_corr_time: float = 1e4

    def __post_init__(self) -> None:
        name = type(self).__name__
        if not isinstance(self.nominal, HeelKneeNominal):
            raise ValueError(f"{name}.nominal must be a HeelKneeNominal, got {self.nominal!r}")
        require_positive(f"{name}.sample_period", self.sample_period)
        require_nonnegative(f"{name}.param_var_ratio", self.param_var_ratio)
        require_positive(f"{name}.param_corr_time", self.param_corr_time)

    @property
    def inertia(self) -> float:
        """d = exp(−T/τ), the one-step correlation of the deviations (eq 5.1)."""
        return math.exp(-self.sample_period / self.param_corr_time)

    @property
    def process(self) -> ProcessModel:
        """F, Γ, Q, P0 of eqs 5.1, 5.2, 5.4, 5.8 for this model."""
        return process_model(self.inertia, self.param_var_ratio, self.nominal.vector)
