"""Episodes of ``pednav/WaistStep-v0``: the scenario's draws, then the walk and its record.

:func:`generate_episode` draws one lane's episode from its generator in a
fixed order — the walk (:mod:`pednav_env.gait.waist_walk`), the sensor grade
and its scaling, the filter's leg-length calibration error, the belt ringing,
the INS bias — and records it (:func:`pednav_env.sensors.waist_record.record_walk`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from pednav_env.envs.waist_config import WaistStepConfig
from pednav_env.gait.waist_walk import PAPER_LEG_LENGTH, assemble_walk, paper_walk, walk_plan
from pednav_env.sensors.waist_grades import WAIST_GRADES
from pednav_env.sensors.waist_record import BeltVibration, WaistRecord, record_walk


@dataclass
class Episode(WaistRecord):
    """One lane's walk: the sensor record and truth, and the walker."""

    leg_length: float  #: true l (m)
    leg_length_assumed: float  #: the filter's l (m)
    sensor_grade: str
    accel_noise_scale: float = 1.0  #: factor on the grade's σ_a (1)
    bm_noise_scale: float = 1.0  #: factor on the grade's σ_n (1)
    vibration_amplitude_mps2: float = 0.0  #: belt ringing amplitude A (m/s²)


def generate_episode(config: WaistStepConfig, rng: np.random.Generator) -> Episode:
    """Draw one episode from ``rng`` (fixed draw order: walk, grade, sensor errors)."""
    rate = float(config.rate_hz)
    if config.scenario == "paper":
        leg = leg_assumed = PAPER_LEG_LENGTH
        walk = paper_walk(int(config.paper_steps), rate, config.max_samples)
        grade_name = "paper004"
        grade = WAIST_GRADES[grade_name]
        vibration = BeltVibration()
        ins_bias = 0.0
        accel_scale = bm_scale = 1.0
    else:
        r = config.randomization
        duration = rng.uniform(*r.duration_s)
        n_total = int(round(duration * rate)) + 1
        leg = rng.uniform(*r.leg_length_m)
        walk = assemble_walk(leg, walk_plan(rng, r, duration, leg), rate, n_total)
        w = np.asarray(config.sensor_grade_weights, dtype=float)
        grade_name = config.sensor_grades[int(rng.choice(len(w), p=w / w.sum()))]
        base = WAIST_GRADES[grade_name]
        lo, hi = np.log(r.grade_scale)
        accel_scale = math.exp(rng.uniform(lo, hi))
        bm_scale = math.exp(rng.uniform(lo, hi))
        sigma_a = base.ins_accel_noise_std * accel_scale
        sigma_n = base.bm_noise_std * bm_scale
        grade = replace(base, ins_accel_noise_std=sigma_a, bm_noise_std=sigma_n)
        err = float(np.clip(rng.standard_normal() * r.leg_length_error, -0.06, 0.06))
        leg_assumed = leg * (1.0 + err)
        a_lo, a_hi = r.vibration_amplitude
        vib_amp = math.exp(rng.uniform(math.log(a_lo), math.log(a_hi))) if a_hi > 0 else 0.0
        vib_f = rng.uniform(*r.vibration_frequency_hz)
        vib_tau = rng.uniform(*r.vibration_decay_s)
        vibration = BeltVibration(vib_amp, vib_f, vib_tau)
        ins_bias = rng.standard_normal() * base.ins_bias_std
    record = record_walk(
        walk, grade, vibration, ins_bias, rate, config.g, config.filter.earth_radius, rng
    )
    return Episode(
        **vars(record),
        leg_length=float(leg),
        leg_length_assumed=float(leg_assumed),
        sensor_grade=grade_name,
        accel_noise_scale=accel_scale,
        bm_noise_scale=bm_scale,
        vibration_amplitude_mps2=vibration.amplitude_mps2,
    )
