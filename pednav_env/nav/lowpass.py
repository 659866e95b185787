"""Low-pass baseline of paper 001: the thesis's "simplest low-pass filter".

The thesis compares its marker EKF (:mod:`pednav_env.nav.marker_ekf`) with
"the simplest low-pass filter" (chapter 6): here a causal first-order
Butterworth (RC) filter of each raw coordinate (:func:`lowpass_filter`).
:func:`lowpass_cutoff_for_gait` chooses its cut-off from what the EKF is given
(the nominal gait p⁰ and σ), so that the baseline is the best such filter for
the scenario.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar
from scipy.signal import butter, sosfilt, sosfilt_zi, sosfiltfilt

from pednav_env.checks import require_positive
from pednav_env.gait.heel_knee_model import HeelKneeNominal
from pednav_env.nav.marker_model import heel_knee_positions
from pednav_env.sensors.uwb import hold_last_valid

Array = NDArray[np.float64]


def lowpass_filter(
    z: ArrayLike,
    cutoff_hz: float,
    rate_hz: float,
    valid: ArrayLike | None = None,
    order: int = 1,
    zero_phase: bool = False,
) -> Array:
    """Butterworth low-pass of raw positions (the thesis's "simplest LPF").

    Causal by default (``scipy.signal.sosfilt``), starting in steady state at
    the first sample (``sosfilt_zi``) so no start-up transient from zero is
    added. ``zero_phase=True`` runs it forwards and backwards
    (``sosfiltfilt``), which is not causal and is offered only to analyse
    the reproduction. Dropped samples are replaced by the last valid one
    before filtering.

    Parameters
    ----------
    z : array_like, shape (N, K, ...)
        Raw positions (m), time on axis 1.
    cutoff_hz : float
        −3 dB cut-off (Hz) of one pass, below the Nyquist frequency.
    rate_hz : float
        Sample rate (Hz).
    valid : array_like of bool, shape (N, K, 2), optional
        Per-marker validity of ``z`` shaped ``(N, K, 2, 2)``.
    order : int
        Filter order (1: RC filter, the thesis's simplest LPF).
    zero_phase : bool
        Forward-backward filtering instead of the causal filter.

    Returns
    -------
    ndarray, same shape as ``z``
    """
    require_positive("rate_hz", rate_hz)
    require_positive("cutoff_hz", cutoff_hz)
    if cutoff_hz >= rate_hz / 2:
        raise ValueError(f"cutoff_hz must be below rate_hz/2 = {rate_hz / 2}, got {cutoff_hz!r}")
    if not isinstance(order, (int, np.integer)) or order < 1:
        raise ValueError(f"order must be an integer >= 1, got {order!r}")
    zz = np.asarray(z, dtype=float)
    if zz.ndim < 2 or zz.shape[1] < 1:
        raise ValueError(f"z must have shape (N, K, ...) with K >= 1, got {zz.shape}")
    if valid is not None:
        v = np.asarray(valid)
        if zz.shape[2:] != (2, 2) or v.shape != zz.shape[:3] or v.dtype != np.bool_:
            raise ValueError(
                f"valid must be boolean (N, K, 2) for z of shape (N, K, 2, 2), got {v.shape}"
            )
        zz = hold_last_valid(zz, v)
    if not np.all(np.isfinite(zz)):
        raise ValueError("z must be finite (found NaN or inf)")
    sos = butter(order, cutoff_hz, btype="low", fs=rate_hz, output="sos")
    if zero_phase:
        return sosfiltfilt(sos, zz, axis=1)
    zi_unit = sosfilt_zi(sos)  # (sections, 2): steady state for a unit input
    # sosfilt wants zi shaped (sections, N, 2, ...): the state axis replaces time.
    zi = zi_unit.reshape((zi_unit.shape[0], 1, 2) + (1,) * (zz.ndim - 2)) * zz[None, :, 0:1]
    y, _ = sosfilt(sos, zz, axis=1, zi=zi)
    return y


def lowpass_noise_gain(
    cutoff_hz: float, rate_hz: float, order: int = 1, zero_phase: bool = False
) -> float:
    """Output variance of :func:`lowpass_filter` per unit white-noise input variance.

    Σ g_k² of the filter's impulse response g, computed numerically (for the
    causal first-order filter it equals (1 − a)/2, a the pole).
    """
    # 40 time constants of the slowest pole (order ≤ a few): the tail is < e⁻⁴⁰.
    n = int(40 * order * rate_hz / (2 * math.pi * cutoff_hz)) + 64
    impulse = np.zeros((1, 2 * n + 1))
    impulse[0, n] = 1.0
    response = lowpass_filter(impulse, cutoff_hz, rate_hz, order=order, zero_phase=zero_phase)
    return float(np.sum(response**2))


def lowpass_cutoff_for_gait(
    nominal: HeelKneeNominal,
    rate_hz: float,
    noise_std: float,
    duration: float,
    zero_phase: bool = False,
) -> float:
    """Cut-off (Hz) of the first-order LPF that is best for the nominal gait.

    Minimises, over the cut-off, the predicted mean squared error summed over
    the four coordinates x₁, z₁, x₂, z₂: the error of the filter on the
    noise-free nominal trajectory over ``duration`` (lag on the trend,
    attenuation and phase lag of the gait harmonic) plus its white-noise
    output variance (:func:`lowpass_noise_gain`). It uses only the
    information the EKF is given (p⁰, σ), no truth and no random draw, so the
    baseline is the best "simplest LPF" for the scenario rather than a straw
    man.

    Parameters
    ----------
    nominal : HeelKneeNominal
        p⁰ of the gait.
    rate_hz : float
        Sample rate (Hz).
    noise_std : float
        σ (m) of the raw positions.
    duration : float
        Length (s) of the walks the filter is scored on.
    zero_phase : bool
        Optimise the forward-backward variant instead.

    Returns
    -------
    float
        Cut-off (Hz) in (0.01, 0.99) × Nyquist.
    """
    require_positive("rate_hz", rate_hz)
    require_positive("noise_std", noise_std)
    require_positive("duration", duration)
    k = max(2, round(duration * rate_hz))
    t = np.arange(k) / rate_hz
    truth = heel_knee_positions(nominal.vector, t, nominal.shank_length)[None]  # (1, K, 2, 2)
    nyq = rate_hz / 2

    def cost(log_fc: float) -> float:
        fc = math.exp(log_fc)
        out = lowpass_filter(truth, fc, rate_hz, zero_phase=zero_phase)
        bias_mse = np.mean((out - truth) ** 2)
        gain = lowpass_noise_gain(fc, rate_hz, zero_phase=zero_phase)
        return float(bias_mse + noise_std**2 * gain)

    res = minimize_scalar(
        cost, bounds=(math.log(0.01 * nyq), math.log(0.99 * nyq)), method="bounded"
    )
    return float(math.exp(res.x))
