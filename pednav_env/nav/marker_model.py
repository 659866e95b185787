"""The marker EKF's assumed model (paper 001, thesis chapters 4–5).

What the filter of :mod:`pednav_env.nav.marker_ekf` believes about the walker
and the sensor:

- the parametric gait model and the law of its deviations L (eqs 4.9–4.11,
  5.1, 5.2, 5.4, 5.8), an instance of
  :class:`~pednav_env.gait.heel_knee_model.HeelKneeModel` with its own values
  (:class:`MarkerEkfConfig`; the truth simulator may use others);
- the measurement function h(L) of eq 4.12: the raw UWB positions
  r = [x₁, z₁, x₂, z₂] of heel and knee given by eq 4.10
  (:func:`heel_knee_positions`, :func:`marker_measurement`), its Jacobian H of
  eq 5.3 (:func:`marker_jacobian`) and the noise R = σ² I of eq 5.5.

Our column order of H puts ∂/∂ΔA fifth and ∂/∂Δω sixth (the state order of
eq 4.9); the thesis's printed (5.3) and (5.6) list ω before A, i.e. its H15,
H25, H35, H45 are our column 6 and its H36, H46 our column 5.
:func:`marker_measurement` and :func:`marker_jacobian` are h and H as plain
functions (the filterpy oracle and the benchmark's reference use them); the
engine evaluates the same expressions for all lanes at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.checks import require_positive
from pednav_env.gait.heel_knee_model import I_A, I_AX, I_AZ, I_CX, I_CZ, I_OMEGA, HeelKneeModel
from pednav_env.sensors.uwb import UwbSpec

Array = NDArray[np.float64]

#: Size of the state L (eq 4.9) and of one UWB sample r (eq 4.12).
DIM_X = 6
DIM_Z = 4


@dataclass(frozen=True)
class MarkerEkfConfig(HeelKneeModel):
    """The filter's assumed model (thesis chapter 5).

    The gait fields (``nominal``: p⁰ the filter linearises around;
    ``sample_period``: T between UWB samples, 10 Hz as
    :class:`~pednav_env.sensors.uwb.UwbSpec`; ``param_var_ratio``: the 0.03 of
    eq 5.4; ``param_corr_time``: τ of d = exp(−T/τ) in eq 5.1) are those of
    :class:`~pednav_env.gait.heel_knee_model.HeelKneeModel`.

    Attributes
    ----------
    meas_std : float
        σ (m) of R = σ² I, eq 5.5 (0.1 m).
    eig_floor : float
        Relative eigenvalue floor of the covariance repair.
    """

    meas_std: float = 0.1  # thesis eq 5.5: R = 0.01 I
    eig_floor: float = 1e-12  # ours: numerical floor, relative to the largest eigenvalue

    def __post_init__(self) -> None:
        super().__post_init__()
        require_positive("MarkerEkfConfig.meas_std", self.meas_std)
        if (
            not (isinstance(self.eig_floor, (int, float)) and math.isfinite(self.eig_floor))
            or not 0 < self.eig_floor < 1
        ):
            raise ValueError(f"MarkerEkfConfig.eig_floor must be in (0, 1), got {self.eig_floor!r}")

    @property
    def R(self) -> Array:
        """Measurement covariance σ² I, eq 5.5, shape ``(4, 4)``."""
        return self.meas_std**2 * np.eye(DIM_Z)

    @classmethod
    def matched(cls, gait: HeelKneeModel, uwb: UwbSpec) -> MarkerEkfConfig:
        """The thesis filter for a simulator: the walker's p⁰, T, 0.03 and τ, the sensor's σ."""
        if not math.isclose(gait.sample_period, uwb.sample_period, rel_tol=1e-12):
            raise ValueError(
                f"gait.sample_period={gait.sample_period} differs from the UWB period "
                f"{uwb.sample_period}"
            )
        model = {f.name: getattr(gait, f.name) for f in fields(HeelKneeModel)}
        return cls(**model, meas_std=uwb.noise_std)


def heel_knee_positions(params: ArrayLike, t: ArrayLike, shank_length: float) -> Array:
    """Heel and knee positions of thesis eq 4.10 (the measurement function h).

    Parameters
    ----------
    params : array_like, shape (..., 6)
        p = p⁰ + L in the order of :data:`~pednav_env.gait.heel_knee_model.PARAM_NAMES`.
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
    s = np.sin(p[..., I_OMEGA] * tt)
    x1 = p[..., I_CX] * tt + p[..., I_AX] * s
    z1 = p[..., I_CZ] + p[..., I_AZ] * s
    beta = p[..., I_A] * s  # eq 4.5
    x2 = x1 + shank_length * np.sin(beta)  # eq 4.6
    z2 = z1 + shank_length * np.cos(beta)  # eq 4.7
    return np.stack((np.stack((x1, z1), axis=-1), np.stack((x2, z2), axis=-1)), axis=-2)


def marker_measurement(params: ArrayLike, t: ArrayLike, shank_length: float) -> Array:
    """h(L) of thesis eq 4.12: :func:`heel_knee_positions` as [x₁, z₁, x₂, z₂].

    Same arguments; returns shape ``(..., 4)``: heel x, heel z, knee x, knee z (m).
    """
    pos = heel_knee_positions(params, t, shank_length)
    return pos.reshape((*pos.shape[:-2], DIM_Z))


def marker_jacobian(params: ArrayLike, t: ArrayLike, shank_length: float) -> Array:
    """H = ∂h/∂L of thesis eq 5.3 (our column order, module docstring).

    The arguments are those of :func:`marker_measurement`, ``params`` being
    the linearisation point. Returns shape ``(..., 4, 6)``: rows x₁, z₁, x₂,
    z₂; columns ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω.
    """
    p = np.asarray(params, dtype=float)
    tt = np.broadcast_to(np.asarray(t, dtype=float), p.shape[:-1])
    M = shank_length
    phase = p[..., I_OMEGA] * tt
    s, c = np.sin(phase), np.cos(phase)
    beta = p[..., I_A] * s
    cb, sb = np.cos(beta), np.sin(beta)
    dbeta_dw = p[..., I_A] * c * tt
    H = np.zeros((*p.shape[:-1], DIM_Z, DIM_X))
    H[..., 0, I_AX] = s  # H11
    H[..., 0, I_CX] = tt  # H13 = kT
    H[..., 0, I_OMEGA] = p[..., I_AX] * c * tt  # thesis H15
    H[..., 1, I_AZ] = s  # H22
    H[..., 1, I_CZ] = 1.0  # H24
    H[..., 1, I_OMEGA] = p[..., I_AZ] * c * tt  # thesis H25
    H[..., 2, I_AX] = s  # H31
    H[..., 2, I_CX] = tt  # H33
    H[..., 2, I_A] = M * cb * s  # thesis H36
    H[..., 2, I_OMEGA] = H[..., 0, I_OMEGA] + M * cb * dbeta_dw  # thesis H35
    H[..., 3, I_AZ] = s  # H42
    H[..., 3, I_CZ] = 1.0  # H44
    H[..., 3, I_A] = -M * sb * s  # thesis H46
    H[..., 3, I_OMEGA] = H[..., 1, I_OMEGA] - M * sb * dbeta_dw  # thesis H45
    return H
