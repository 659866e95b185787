"""Sensor grades of the belt IMU and its INS (papers 000 and 004).

A :class:`WaistSensorGrade` is the *true* error model of one class of sensor
(the filter does not know it): accelerometer noise and bias, the Schuler
error model of the INS velocity (papers 000/004,
:mod:`pednav_env.sensors.ins_error`) and the step-to-step irregularity σ_n of
the pendulum step velocity (paper 004: V̄^BM = V̄ + n). :data:`WAIST_GRADES`
names them; only ``paper004`` comes from a paper.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class WaistSensorGrade:
    """True sensor errors of one grade (the filter does not know them).

    Attributes
    ----------
    accel_noise_std : float
        White noise of each accelerometer axis per sample (m/s²).
    accel_bias_std : float
        Std of the constant accelerometer bias per axis, drawn per episode (m/s²).
    ins_accel_noise_std : float
        σ_a of the Schuler error model, std of the δV increment per step (m/s);
        paper 004: 0.1, 0.5, 1.
    ins_drift_noise_std : float
        σ_ε, std of the drift increment per step (rad/s); paper 004: 1e-6.
    ins_initial_std : tuple
        Std of the initial δV (m/s), β (rad), ε (rad/s); paper 004 prints none,
        our reading (0.3 m/s, 1 mrad, 0.1 °/h) as in :class:`SchulerErrorConfig`.
    ins_bias_std : float
        Std of paper 000's constant B (m/s²) in δV̇, drawn per episode.
    bm_noise_std : float
        Std of the step-to-step irregularity n of the pendulum step velocity
        (paper 004: V̄^BM = V̄ + n, σ_n = 0.5 m/s).
    """

    accel_noise_std: float
    accel_bias_std: float
    ins_accel_noise_std: float
    ins_drift_noise_std: float
    ins_initial_std: tuple[float, float, float]
    ins_bias_std: float
    bm_noise_std: float

    def __post_init__(self) -> None:
        for name in (
            "accel_noise_std",
            "accel_bias_std",
            "ins_accel_noise_std",
            "ins_drift_noise_std",
            "ins_bias_std",
            "bm_noise_std",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ValueError(f"WaistSensorGrade.{name} must be a finite number ≥ 0, got {v!r}")
        s = self.ins_initial_std
        if len(s) != 3 or not all(math.isfinite(x) and x >= 0 for x in s):
            raise ValueError(f"WaistSensorGrade.ins_initial_std needs 3 values ≥ 0, got {s!r}")


_DRIFT_DPH = math.radians(1.0) / 3600.0  # 1 °/h in rad/s

#: Named grades. ``paper004``: paper 004's simulation (ideal accelerometer, its
#: INS error model with σ_a = 0.5 m/s, σ_n = 0.5 m/s). The others are
#: illustrative belt-IMU/INS classes (our choice, not from a paper).
WAIST_GRADES: dict[str, WaistSensorGrade] = {
    "paper004": WaistSensorGrade(0.0, 0.0, 0.5, 1e-6, (0.3, 1e-3, 0.1 * _DRIFT_DPH), 0.0, 0.5),
    "tactical": WaistSensorGrade(
        0.005, 0.002, 0.05, 1e-7, (0.05, 2e-4, 0.01 * _DRIFT_DPH), 0.002, 0.08
    ),
    "industrial": WaistSensorGrade(
        0.02, 0.01, 0.2, 1e-6, (0.2, 1e-3, 0.1 * _DRIFT_DPH), 0.01, 0.15
    ),
    "consumer": WaistSensorGrade(0.08, 0.05, 0.8, 1e-5, (0.3, 3e-3, 1.0 * _DRIFT_DPH), 0.05, 0.3),
}
