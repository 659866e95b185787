"""Sensor record of a belt IMU and its INS along a waist walk (papers 000 and 004).

From the truth of a walk (:class:`pednav_env.gait.waist_walk.WaistWalk`) and
a sensor grade (:class:`pednav_env.sensors.waist_grades.WaistSensorGrade`):

- the accelerometer of the level waist IMU (paper 000): the interval-mean
  acceleration (delta velocity) of the hip in body axes rotated by the yaw,
  plus g on the vertical; heel-strike ringing of the belt on the vertical
  axis (:class:`BeltVibration`); a constant bias and white noise per axis.
  Recorded as |f̃| (paper 004's step detector reads |f̃| − g) and the
  vertical channel a_up = f̃_z − g;
- the INS velocity V^INS = V + δV, δV from the Schuler error model of papers
  000/004 (:mod:`pednav_env.sensors.ins_error`), one value per error segment
  (each step and each stand), held constant within it (paper 004 eq 1); the
  INS position is its integral;
- the INS yaw, error-free (paper 004 uses the known azimuth α(k));
- the step-to-step irregularity n of the pendulum step velocity, one draw
  per segment (paper 004: V̄^BM = V̄ + n).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.gait.waist_walk import WaistWalk
from pednav_env.sensors.ins_error import (
    SchulerErrorConfig,
    per_sample_velocity_error,
    simulate_schuler_errors,
)
from pednav_env.sensors.waist_grades import WaistSensorGrade

Array = NDArray[np.float64]


@dataclass(frozen=True)
class BeltVibration:
    """Heel-strike ringing of the belt IMU on the vertical axis.

    A exp(−τ/τ_d) sin(2π f τ) after each footfall (τ: time since it), with A
    multiplied by U(0.7, 1.3) per step. ``amplitude_mps2 = 0``: no ringing.
    """

    amplitude_mps2: float = 0.0  #: A (m/s²)
    frequency_hz: float = 1.0  #: f (Hz)
    decay_s: float = 1.0  #: τ_d (s)

    def __post_init__(self) -> None:
        for name in ("amplitude_mps2", "frequency_hz", "decay_s"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ValueError(f"BeltVibration.{name} must be a finite number ≥ 0, got {v!r}")
        if self.decay_s <= 0:
            raise ValueError(f"BeltVibration.decay_s must be > 0, got {self.decay_s!r}")


@dataclass
class WaistRecord:
    """What the filter sees along one walk, and the truth to score it.

    Per-sample arrays have length L (sample 0 is the start, t = 0).
    """

    f_norm: Array  #: |f̃| (m/s²)
    a_up: Array  #: f̃_z − g, vertical acceleration of the level waist IMU (m/s²)
    ins_pos: Array  #: (L, 2) INS horizontal position relative to the start (m)
    yaw: Array  #: INS heading ψ (rad, counter-clockwise from east)
    bm_noise: Array  #: n of the error segment containing each sample (m/s)
    pos_n: Array  #: (L, 2) true horizontal hip position relative to the start (m)
    distance_m: Array  #: (L,) horizontal distance walked (m)
    true_boundary: NDArray[np.bool_]  #: (L,) footfall / start / stop samples


def record_walk(
    walk: WaistWalk,
    grade: WaistSensorGrade,
    vibration: BeltVibration,
    ins_bias_mps2: float,
    rate_hz: float,
    g: float,
    earth_radius: float,
    rng: np.random.Generator,
) -> WaistRecord:
    """Sensor record of ``walk`` (fixed draw order: ringing, accelerometer bias and
    noise, INS errors, step-velocity irregularity).

    ``grade`` gives the episode's error statistics (σ_a and σ_n already
    scaled); ``ins_bias_mps2`` is paper 000's constant B in δV̇, drawn by the
    caller.
    """
    rate = float(rate_hz)
    dt = 1.0 / rate
    pos, vel, psi, seg = walk.pos_n, walk.vel_n, walk.yaw, walk.segment
    n = pos.shape[0]
    # Footfalls (step starts), walk starts and stops: where the error segment changes.
    boundary = np.zeros(n, dtype=bool)
    boundary[1:] = seg[1:] != seg[:-1]
    # IMU: interval-mean acceleration (delta-velocity), level body axes rotated by yaw.
    acc = np.zeros((n, 3))
    acc[1:] = np.diff(vel, axis=0) * rate
    c, s = np.cos(psi), np.sin(psi)
    f_b = np.empty((n, 3))
    f_b[:, 0] = c * acc[:, 0] + s * acc[:, 1]
    f_b[:, 1] = -s * acc[:, 0] + c * acc[:, 1]
    f_b[:, 2] = acc[:, 2] + g
    n_seg = int(walk.segment_duration_s.size)
    if vibration.amplitude_mps2 > 0:
        amp = vibration.amplitude_mps2 * rng.uniform(0.7, 1.3, n_seg)
        idx = np.arange(n)
        last = np.maximum.accumulate(np.where(boundary, idx, 0))
        tau = (idx - last) * dt
        ring = (
            amp[seg]
            * np.exp(-tau / vibration.decay_s)
            * np.sin(2.0 * math.pi * vibration.frequency_hz * tau)
        )
        f_b[:, 2] += np.where(last > 0, ring, 0.0)
    if grade.accel_bias_std > 0:
        f_b += rng.standard_normal(3) * grade.accel_bias_std
    if grade.accel_noise_std > 0:
        f_b += rng.standard_normal((n, 3)) * grade.accel_noise_std
    # INS velocity error per error segment (paper 004), constant within a segment.
    i0 = grade.ins_initial_std
    schuler = SchulerErrorConfig(
        accel_noise_std=grade.ins_accel_noise_std,
        drift_noise_std=grade.ins_drift_noise_std,
        initial_velocity_std=i0[0],
        initial_tilt_std=i0[1],
        initial_drift_std=i0[2],
        accel_bias=ins_bias_mps2,
        g=g,
        earth_radius=earth_radius,
    )
    x = simulate_schuler_errors(walk.segment_duration_s[None], schuler, [rng])
    dv = per_sample_velocity_error(x, seg[None])[0]  # (n, 2)
    bm_noise = rng.standard_normal(n_seg) * grade.bm_noise_std
    ins = np.zeros((n, 2))
    ins[1:] = np.cumsum(np.diff(pos[:, :2], axis=0) + dv[1:] * dt, axis=0)
    step_len = np.hypot(*np.diff(pos[:, :2], axis=0).T)
    return WaistRecord(
        f_norm=np.sqrt(np.sum(f_b * f_b, axis=-1)),
        a_up=f_b[:, 2] - g,
        ins_pos=ins,
        yaw=psi,
        bm_noise=bm_noise[seg],
        pos_n=pos[:, :2] - pos[0, :2],
        distance_m=np.concatenate(([0.0], np.cumsum(step_len))),
        true_boundary=boundary,
    )
