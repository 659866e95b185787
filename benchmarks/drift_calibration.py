"""The per-gait-step drift and the gyro-bias calibration: a constant heading-rate error.

With the ``paper003`` grade (drift ν redrawn per gait cycle, σ = 0.02 rad/s
per axis) and ``ZuptUkfConfig(calibrate_gyro_bias=True)`` (the mean gyro
reading of the first ``alignment_s`` subtracted from every later sample), the
alignment window lies inside gait step 0, so the subtracted "bias" is ν₀ plus
noise, and every later sample carries ν_k − ν₀: a constant −ν₀ for the whole
walk on top of the per-step draws. This script measures it on the sensor
errors themselves (no filter): per walk, the mean residual vertical-axis rate
error after the alignment window, and the heading error it integrates to by
the end of the walk, with the calibration and without it (the per-step
random walk alone).

    PYTHONPATH=. .venv/bin/python benchmarks/drift_calibration.py
"""

from __future__ import annotations

import numpy as np

from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import random_route
from pednav_env.sensors.imu import IMU_GRADES, simulate_imu

WALKS = 64
RATE_HZ = 100.0
ALIGN_S = 1.0


def measure(grade: str) -> dict[str, float]:
    rngs = [np.random.default_rng([77, i]) for i in range(WALKS)]
    routes = [random_route(r) for r in rngs]
    truth = simulate_foot(routes, FootSimConfig(rate_hz=RATE_HZ), full_state=False)
    imu = simulate_imu(
        truth.omega_b, truth.f_b, RATE_HZ, IMU_GRADES[grade](), rngs, truth.gait_step
    )
    n_align = int(ALIGN_S * RATE_HZ)
    err = imu.omega_b[..., 2] - truth.omega_b[..., 2]  # (N, T) vertical-axis error
    bias_hat = err[:, :n_align].mean(axis=1, keepdims=True)
    residual = err - bias_hat
    means, heading, heading_steps = [], [], []
    for i in range(WALKS):
        end = int(round(truth.duration_s[i] * RATE_HZ))
        r = residual[i, n_align:end]
        means.append(r.mean())
        heading.append(r.sum() / RATE_HZ)
        heading_steps.append(err[i, n_align:end].sum() / RATE_HZ)
    duration = float(np.mean(truth.duration_s))
    return {
        "mean_rate_error_std_rad_s": float(np.std(means)),
        "final_heading_error_rms_rad": float(np.sqrt(np.mean(np.square(heading)))),
        "uncalibrated_rms_rad": float(np.sqrt(np.mean(np.square(heading_steps)))),
        "mean_duration_s": duration,
    }


def main() -> None:
    for grade in ("paper003", "microstrain_gx5"):
        m = measure(grade)
        print(
            f"{grade:16s} std over walks of the mean vertical rate error after calibration "
            f"{m['mean_rate_error_std_rad_s']:.4f} rad/s; heading error at the end "
            f"(mean walk {m['mean_duration_s']:.0f} s): RMS "
            f"{m['final_heading_error_rms_rad']:.2f} rad calibrated, "
            f"{m['uncalibrated_rms_rad']:.2f} rad uncalibrated"
        )


if __name__ == "__main__":
    main()
