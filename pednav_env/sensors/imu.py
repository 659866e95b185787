"""IMU measurement model: ideal readings from truth, then the sensor errors.

The split follows pyins: :class:`ImuSpec` is the *true* error model used to
synthesise measurements; a navigation filter carries its own *assumed* model
(which may differ — that mismatch is what an agent tunes).

Measured rate and specific force (paper 003 eq 2, extended)::

    ω' = sat(quant(K_ω ω + b_ω + b_ω,rw(t) + ν_step + δω))
    f' = sat(quant(K_f f + b_f + b_f,rw(t) + δf))

with K = (I + diag(scale)) (I + [misalignment]) , turn-on biases b, bias random
walks b_rw, paper 003's gyro drift ν ("constant within a step", two readings,
see :class:`DriftModel`), white noise δω, δf, quantisation to one LSB and range
saturation (the paper's gyro saturated at 6 rad/s).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from enum import StrEnum

import numpy as np
from numba import njit
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.rotations import body_rates_from_euler, euler_to_dcm

Array = NDArray[np.float64]


class DriftModel(StrEnum):
    """Two readings of paper 003's "gyro drift ν constant within a step".

    ``PER_GAIT_STEP``: one draw of ν per gait cycle of the instrumented foot
    (held from one stance start to the next) — "шаг" as the paper uses it for
    the walker's step. ``PER_SAMPLE``: one draw per integration step Δt, i.e.
    extra white noise.
    """

    PER_GAIT_STEP = "per_gait_step"
    PER_SAMPLE = "per_sample"


@dataclass(frozen=True)
class ImuSpec:
    """True error model of a 6-axis IMU (rad, m, s).

    Noise is given as densities so that one spec serves any sample rate:
    the per-sample standard deviation is ``density · sqrt(rate_hz)``.
    """

    #: Gyro white noise density (rad/s/√Hz). Paper 003: σ[δω] = 0.05 rad/s at 100 Hz.
    gyro_noise_density: float = 0.005
    #: Accelerometer white noise density (m/s²/√Hz). Paper 003: σ[δf] = 0.1 m/s² at 100 Hz.
    accel_noise_density: float = 0.01
    #: Gyro drift ν, std per axis (rad/s). Paper 003: σ[ν] = 0.02 rad/s.
    gyro_step_drift_std: float = 0.02
    #: How ν is redrawn (paper 003 is ambiguous; see :class:`DriftModel`).
    drift_model: DriftModel = DriftModel.PER_GAIT_STEP
    #: Turn-on (residual after calibration) bias std per axis.
    gyro_bias_std: float = 0.0
    accel_bias_std: float = 0.0
    #: Bias random-walk densities (rad/s/√s, m/s²/√s).
    gyro_bias_rw_density: float = 0.0
    accel_bias_rw_density: float = 0.0
    #: Scale-factor error std per axis (fraction).
    gyro_scale_std: float = 0.0
    accel_scale_std: float = 0.0
    #: Axis misalignment std (rad), small-angle off-diagonal terms.
    gyro_misalignment_std: float = 0.0
    accel_misalignment_std: float = 0.0
    #: Quantisation step, one LSB (rad/s, m/s²); 0 = none.
    gyro_lsb: float = 0.0
    accel_lsb: float = 0.0
    #: Measurement range (rad/s, m/s²); readings beyond are clipped and flagged.
    gyro_range: float = math.inf
    accel_range: float = math.inf

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name == "drift_model":
                object.__setattr__(self, "drift_model", DriftModel(self.drift_model))
                continue
            value = getattr(self, f.name)
            if not isinstance(value, int | float) or math.isnan(value) or value < 0:
                raise ValueError(f"ImuSpec.{f.name} must be a number ≥ 0, got {value!r}")
            if f.name.endswith("range") and value == 0:
                raise ValueError(f"ImuSpec.{f.name} must be > 0, got {value!r}")
            if not f.name.endswith("range") and math.isinf(value):
                raise ValueError(f"ImuSpec.{f.name} must be finite, got {value!r}")

    def gyro_noise_std(self, rate_hz: float) -> float:
        """Per-sample gyro white-noise std (rad/s) at ``rate_hz``."""
        return self.gyro_noise_density * math.sqrt(rate_hz)

    def accel_noise_std(self, rate_hz: float) -> float:
        """Per-sample accelerometer white-noise std (m/s²) at ``rate_hz``."""
        return self.accel_noise_density * math.sqrt(rate_hz)

    # ------------------------------------------------------------------ grades
    @classmethod
    def paper003(
        cls,
        gyro_noise_std: float = 0.05,
        accel_noise_std: float = 0.1,
        gyro_step_drift_std: float = 0.02,
        rate_hz: float = 100.0,
        drift_model: DriftModel | str = DriftModel.PER_GAIT_STEP,
    ) -> ImuSpec:
        """Paper 003's simulation: σ[δω] = 0.05 rad/s, σ[ν] = 0.02 rad/s,
        σ[δf] = 0.1 m/s² per sample at Δt = 0.01 s; ideal otherwise."""
        if rate_hz <= 0:
            raise ValueError(f"rate_hz must be > 0, got {rate_hz!r}")
        root = math.sqrt(rate_hz)
        return cls(
            gyro_noise_density=gyro_noise_std / root,
            accel_noise_density=accel_noise_std / root,
            gyro_step_drift_std=gyro_step_drift_std,
            drift_model=DriftModel(drift_model),
        )

    @classmethod
    def adis16405(cls) -> ImuSpec:
        """ADIS16405-like tactical-MEMS grade (paper 003's real IMU), datasheet
        orders of magnitude after a bias calibration like the paper's: gyro
        noise 0.05 °/s/√Hz, accel 0.5 mg/√Hz, residual biases 0.2 °/s and
        5 mg, 0.3 % scale, 0.05° misalignment, 0.05 °/s and 3.33 mg LSB, gyro
        range 6 rad/s (the paper's saturation), accel ±18 g."""
        deg = math.pi / 180.0
        mg = 1e-3 * STANDARD_GRAVITY
        return cls(
            gyro_noise_density=0.05 * deg,
            accel_noise_density=0.5 * mg,
            gyro_step_drift_std=0.0,
            gyro_bias_std=0.2 * deg,
            accel_bias_std=5.0 * mg,
            gyro_bias_rw_density=0.002 * deg,
            accel_bias_rw_density=0.05 * mg,
            gyro_scale_std=0.003,
            accel_scale_std=0.003,
            gyro_misalignment_std=0.05 * deg,
            accel_misalignment_std=0.05 * deg,
            gyro_lsb=0.05 * deg,
            accel_lsb=3.33 * mg,
            gyro_range=6.0,
            accel_range=18.0 * STANDARD_GRAVITY,
        )

    @classmethod
    def adis16470(cls) -> ImuSpec:
        """Modern industrial MEMS grade, ADIS16470 class, with a ±2000 °/s gyro
        that does not saturate in running: gyro noise 0.008 °/s/√Hz, accel
        0.1 mg/√Hz, residual biases 0.05 °/s and 2 mg, 0.1 % scale, 0.05°
        misalignment, 0.1 °/s and 1.25 mg LSB, ±40 g."""
        deg = math.pi / 180.0
        mg = 1e-3 * STANDARD_GRAVITY
        return cls(
            gyro_noise_density=0.008 * deg,
            accel_noise_density=0.1 * mg,
            gyro_step_drift_std=0.0,
            gyro_bias_std=0.05 * deg,
            accel_bias_std=2.0 * mg,
            gyro_bias_rw_density=0.001 * deg,
            accel_bias_rw_density=0.02 * mg,
            gyro_scale_std=0.001,
            accel_scale_std=0.001,
            gyro_misalignment_std=0.05 * deg,
            accel_misalignment_std=0.05 * deg,
            gyro_lsb=0.1 * deg,
            accel_lsb=1.25 * mg,
            gyro_range=2000.0 * deg,
            accel_range=40.0 * STANDARD_GRAVITY,
        )

    @classmethod
    def consumer(cls) -> ImuSpec:
        """Consumer (phone/wearable) MEMS grade, MPU-6050/BMI160 class: gyro
        noise 0.015 °/s/√Hz, accel 0.3 mg/√Hz, residual biases 0.5 °/s and
        20 mg, 1 % scale, 0.5° misalignment, 16-bit over ±2000 °/s and ±16 g."""
        deg = math.pi / 180.0
        mg = 1e-3 * STANDARD_GRAVITY
        return cls(
            gyro_noise_density=0.015 * deg,
            accel_noise_density=0.3 * mg,
            gyro_step_drift_std=0.0,
            gyro_bias_std=0.5 * deg,
            accel_bias_std=20.0 * mg,
            gyro_bias_rw_density=0.01 * deg,
            accel_bias_rw_density=0.2 * mg,
            gyro_scale_std=0.01,
            accel_scale_std=0.01,
            gyro_misalignment_std=0.5 * deg,
            accel_misalignment_std=0.5 * deg,
            gyro_lsb=2000.0 / 32768.0 * deg,
            accel_lsb=16.0 * STANDARD_GRAVITY / 32768.0,
            gyro_range=2000.0 * deg,
            accel_range=16.0 * STANDARD_GRAVITY,
        )

    @classmethod
    def microstrain_gx5(cls) -> ImuSpec:
        """MicroStrain 3DM-GX5-25, the IMU of the PyShoe VICON trials and the
        hallway walks (docs/SIM_TO_REAL.md). Datasheet (8400-0093): gyro noise
        density 0.005 °/s/√Hz, in-run bias instability 8 °/h; accelerometer
        noise density 100 µg/√Hz, bias instability 0.04 mg (PyShoe's SHOE
        σ_ω = 8.7266e-5 rad/s and σ_a = 0.00098 m/s² are these densities).
        Bias instability as a random walk reaching it in 100 s (8 °/h /
        √(100 s), 0.04 mg / √(100 s)). Ranges: the recorded walks reach
        9.2 rad/s and 13.9 g, beyond the standard ±300 °/s and ±8 g, so the
        ±900 °/s and ±20 g options. Not in the datasheet, assumed: residual
        turn-on biases 0.05 °/s and 2 mg, 0.1 % scale, 0.05° misalignment,
        no quantisation (the unit outputs floats). No per-gait-step drift."""
        deg = math.pi / 180.0
        mg = 1e-3 * STANDARD_GRAVITY
        return cls(
            gyro_noise_density=0.005 * deg,
            accel_noise_density=0.1 * mg,
            gyro_step_drift_std=0.0,
            gyro_bias_std=0.05 * deg,
            accel_bias_std=2.0 * mg,
            gyro_bias_rw_density=8.0 / 3600.0 * deg / 10.0,
            accel_bias_rw_density=0.04 * mg / 10.0,
            gyro_scale_std=0.001,
            accel_scale_std=0.001,
            gyro_misalignment_std=0.05 * deg,
            accel_misalignment_std=0.05 * deg,
            gyro_range=900.0 * deg,
            accel_range=20.0 * STANDARD_GRAVITY,
        )

    @classmethod
    def ideal(cls) -> ImuSpec:
        """No errors at all (for kinematics and strapdown tests)."""
        return cls(gyro_noise_density=0.0, accel_noise_density=0.0, gyro_step_drift_std=0.0)


#: Named grades for configuration files and the CLI.
IMU_GRADES = {
    "paper003": ImuSpec.paper003,
    "adis16405": ImuSpec.adis16405,
    "adis16470": ImuSpec.adis16470,
    "consumer": ImuSpec.consumer,
    "microstrain_gx5": ImuSpec.microstrain_gx5,
    "ideal": ImuSpec.ideal,
}


@functools.cache
def grade_spec(grade: str) -> ImuSpec:
    """The spec of the named grade of :data:`IMU_GRADES`, built once (specs are
    frozen, so one instance serves every episode)."""
    if grade not in IMU_GRADES:
        raise ValueError(f"grade: unknown IMU grade {grade!r}; known: {sorted(IMU_GRADES)}")
    return IMU_GRADES[grade]()


@dataclass(frozen=True)
class ImuMeasurements:
    """Simulated IMU output, arrays ``(N, T, 3)`` plus saturation flags ``(N, T)``."""

    omega_b: Array
    f_b: Array
    rate_hz: float
    gyro_saturated: NDArray[np.bool_]
    accel_saturated: NDArray[np.bool_]


def ideal_specific_force(acc_n: Array, euler: Array, g: float = STANDARD_GRAVITY) -> Array:
    """Specific force in body axes, f_b = C_nbᵀ (a − g_vec), g_vec = (0, 0, −g).

    Paper 003: f_z = a_z − g_z with a_z = B_zx a_x. At rest and level this is (0, 0, +g).
    """
    C_nb = euler_to_dcm(euler)
    a_minus_g = np.asarray(acc_n, dtype=float).copy()
    a_minus_g[..., 2] += g
    return np.einsum("...ji,...j->...i", C_nb, a_minus_g)


def ideal_imu(
    euler: Array, euler_rate: Array, acc_n: Array, g: float = STANDARD_GRAVITY
) -> tuple[Array, Array]:
    """Ideal body rate and specific force of a sampled motion, each (..., 3).

    ω_b = body rates of the true Euler angles and their rates (paper 002 eq 9,
    :func:`pednav_env.rotations.body_rates_from_euler`); f_b =
    :func:`ideal_specific_force` of the acceleration ``acc_n`` (paper 002
    eq 12). For :class:`pednav_env.gait.robot.RobotWalk` and
    :class:`pednav_env.gait.pendulum.PendulumWalk` pass ``acc_n_mean``, the
    mean acceleration over each sample interval (paper 002 eq 10), which is
    what an IMU's delta velocities measure.
    """
    return body_rates_from_euler(euler, euler_rate), ideal_specific_force(acc_n, euler, g)


def _as_list(value, n: int, name: str) -> list:
    if isinstance(value, Sequence) and not isinstance(value, str | bytes):
        if len(value) != n:
            raise ValueError(f"{name} has {len(value)} entries for {n} walkers")
        return list(value)
    return [value] * n


def _error_matrix(rng: np.random.Generator, scale_std: float, misalignment_std: float) -> Array:
    """(I + diag(s)) (I + m) with small-angle off-diagonal misalignment."""
    scale = rng.standard_normal(3) * scale_std
    mis = rng.standard_normal(6) * misalignment_std
    M = np.eye(3)
    M[0, 1], M[0, 2], M[1, 0], M[1, 2], M[2, 0], M[2, 1] = mis
    return (np.eye(3) + np.diag(scale)) @ M


@njit(cache=True)
def _add_bias_and_random_walk(
    rng: np.random.Generator, x: Array, bias: Array, step_std: float
) -> None:
    """x ← (x + b) + b_rw for every row of ``x`` (T, 3): the turn-on bias ``bias`` and
    the bias random walk b_rw(t_k) = Σ_{j≤k} σ ξ_j (ξ_j standard normal, summed in
    order as ``np.cumsum``).

    The T × 3 draws are always made, row by row (as ``standard_normal((T, 3))``):
    the stream of later errors must not depend on the densities. With
    ``step_std == 0`` the walk is exactly zero and is not added.
    """
    s0 = s1 = s2 = 0.0
    for k in range(x.shape[0]):
        xi0, xi1, xi2 = rng.standard_normal(), rng.standard_normal(), rng.standard_normal()
        if k == 0:
            s0, s1, s2 = xi0, xi1, xi2
        else:
            s0, s1, s2 = s0 + xi0, s1 + xi1, s2 + xi2
        x0, x1, x2 = x[k, 0] + bias[0], x[k, 1] + bias[1], x[k, 2] + bias[2]
        if step_std != 0:
            x0, x1, x2 = x0 + s0 * step_std, x1 + s1 * step_std, x2 + s2 * step_std
        x[k, 0], x[k, 1], x[k, 2] = x0, x1, x2


@njit(cache=True)
def _add_white_noise(rng: np.random.Generator, std: float, x: Array) -> None:
    """x += σ ξ, one standard normal ξ per element of ``x`` (T, 3), drawn row by row."""
    for k in range(x.shape[0]):
        for j in range(3):
            x[k, j] += rng.standard_normal() * std


@njit(cache=True)
def _add_random_errors(
    rng: np.random.Generator,
    w: Array,
    f: Array,
    b_w: Array,
    b_f: Array,
    nu: Array,
    steps: NDArray[np.integer],
    walk_std: tuple[float, float],
    noise_std: tuple[float, float],
) -> None:
    """ω' = (((K ω + b) + b_rw) + ν) + δω into ``w`` and f' = ((K f + b) + b_rw) + δf
    into ``f`` (T, 3), which hold K ω and K f: the terms added in this order as they
    are drawn (b_rw, b_rw, δω, δf; per-step and noise σ of gyro and accelerometer in
    ``walk_std`` and ``noise_std``). The drift of sample k is ``nu[steps[k]]``."""
    _add_bias_and_random_walk(rng, w, b_w, walk_std[0])
    for k in range(w.shape[0]):
        for j in range(3):
            w[k, j] += nu[steps[k], j]
    _add_bias_and_random_walk(rng, f, b_f, walk_std[1])
    _add_white_noise(rng, noise_std[0], w)
    _add_white_noise(rng, noise_std[1], f)


def _apply_error_matrix(x: Array, K: Array) -> Array:
    """K x for every row of ``x`` (T, 3); x itself when K is exactly the identity."""
    if np.array_equal(K, np.eye(3)):
        return x
    return x @ K.T


@njit(cache=True)
def _quantise(x: Array, lsb: float) -> None:
    """x ← round(x / lsb) · lsb in place for a C-contiguous ``x``, halves to even as
    ``np.round`` (nothing for lsb = 0)."""
    if lsb > 0:
        flat = x.reshape(-1)  # (contiguous: one loop, vectorised)
        for i in range(flat.size):
            flat[i] = np.rint(flat[i] / lsb) * lsb


def _saturate(x: Array, limit: float, flags: NDArray[np.bool_]) -> None:
    """Clip ``x`` (T, 3) to ±limit in place; flag the samples with a component beyond."""
    if math.isfinite(limit) and not (-limit <= x.min() and x.max() <= limit):
        np.any(np.abs(x) > limit, axis=-1, out=flags)
        np.clip(x, -limit, limit, out=x)


def simulate_imu(
    omega_b: Array,
    f_b: Array,
    rate_hz: float,
    spec: ImuSpec | Sequence[ImuSpec],
    rngs: np.random.Generator | Sequence[np.random.Generator],
    gait_step_index: NDArray[np.integer] | None = None,
) -> ImuMeasurements:
    """Add the errors of ``spec`` to ideal readings.

    Parameters
    ----------
    omega_b, f_b : (N, T, 3)
        Ideal body angular rate (rad/s) and specific force (m/s²).
    rate_hz : float
        Sample rate (Hz).
    spec : ImuSpec or sequence of N ImuSpec
        True error model (one per walker allowed).
    rngs : Generator or sequence of N Generators
        Walker i draws only from ``rngs[i]``, so walker i's errors do not
        depend on the batch it is simulated in.
    gait_step_index : (N, T) int, optional
        Gait-cycle number of each sample (for ``DriftModel.PER_GAIT_STEP``);
        without it the whole record is one step.
    """
    omega_b = np.asarray(omega_b, dtype=float)
    f_b = np.asarray(f_b, dtype=float)
    if omega_b.ndim != 3 or omega_b.shape[-1] != 3 or omega_b.shape != f_b.shape:
        raise ValueError(
            f"omega_b and f_b must both be (N, T, 3); got {omega_b.shape} and {f_b.shape}"
        )
    if not (np.all(np.isfinite(omega_b)) and np.all(np.isfinite(f_b))):
        raise ValueError("omega_b/f_b contain NaN or inf")
    if not rate_hz > 0 or not math.isfinite(rate_hz):
        raise ValueError(f"rate_hz must be a finite number > 0, got {rate_hz!r}")
    n, t, _ = omega_b.shape
    specs = _as_list(spec, n, "spec")
    gens = _as_list(rngs, n, "rngs") if n > 0 else []
    if n > 1 and isinstance(rngs, np.random.Generator):
        raise ValueError("pass one Generator per walker (rngs) when N > 1")
    if gait_step_index is None:
        gait_step_index = np.zeros((n, t), dtype=int)
    gait_step_index = np.asarray(gait_step_index)
    if gait_step_index.shape != (n, t):
        raise ValueError(f"gait_step_index must be ({n}, {t}), got {gait_step_index.shape}")

    dt = 1.0 / rate_hz
    omega_out = np.empty_like(omega_b)
    f_out = np.empty_like(f_b)
    gyro_sat = np.zeros((n, t), dtype=bool)
    accel_sat = np.zeros((n, t), dtype=bool)
    for i, (s, rng) in enumerate(zip(specs, gens, strict=True)):
        # Fixed draw order per walker: errors constant over the record first.
        K_w = _error_matrix(rng, s.gyro_scale_std, s.gyro_misalignment_std)
        K_f = _error_matrix(rng, s.accel_scale_std, s.accel_misalignment_std)
        b_w = rng.standard_normal(3) * s.gyro_bias_std
        b_f = rng.standard_normal(3) * s.accel_bias_std
        if s.drift_model is DriftModel.PER_GAIT_STEP:
            steps = gait_step_index[i] - gait_step_index[i].min()
            nu = rng.standard_normal((int(steps.max()) + 1, 3)) * s.gyro_step_drift_std
        else:
            nu = rng.standard_normal((t, 3))
            nu *= s.gyro_step_drift_std
            steps = np.arange(t)
        w, f = omega_out[i], f_out[i]
        w[:] = _apply_error_matrix(omega_b[i], K_w)
        f[:] = _apply_error_matrix(f_b[i], K_f)
        walk_std = (s.gyro_bias_rw_density * dt**0.5, s.accel_bias_rw_density * dt**0.5)
        noise_std = (s.gyro_noise_std(rate_hz), s.accel_noise_std(rate_hz))
        _add_random_errors(rng, w, f, b_w, b_f, nu, steps, walk_std, noise_std)
        _quantise(w, s.gyro_lsb)
        _quantise(f, s.accel_lsb)
        _saturate(w, s.gyro_range, gyro_sat[i])
        _saturate(f, s.accel_range, accel_sat[i])
    return ImuMeasurements(omega_out, f_out, rate_hz, gyro_sat, accel_sat)
