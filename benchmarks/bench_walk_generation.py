"""CPU time per simulated foot walk: today's stance model against the calibrated one.

Three generators, each on the same 64 routes per speed band (100 Hz, as the
FootZupt env; route drawing, the walk kernel and the IMU errors timed
together, one walk per call as an env reset does):

- ``today``: :func:`pednav_env.gait.speed_route.speed_route` with the realistic
  stance terms, ADIS16470 grade;
- ``calibrated``: the same routes with the calibrated stance dynamics
  (:meth:`StanceRandomization.calibrated`), MicroStrain 3DM-GX5-25 grade;
- ``env``: the FootZupt env's own walks (:func:`random_route`, ADIS16470), for
  scale.

Prints ms of CPU per walk and per simulated minute, and the ratio
calibrated / today (figures in docs/PERFORMANCE.md).
"""

from __future__ import annotations

import time

import numpy as np

from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import random_route
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.sensors.imu import ImuSpec, simulate_imu

BANDS = ((0.3, 0.8), (0.8, 1.3), (1.3, 1.8), (1.8, 2.6), (2.6, 3.8))
WALKS = 64
SIM = FootSimConfig(rate_hz=100.0)


def one_walk(seed: int, band: tuple[float, float] | None, calibrated: bool) -> float:
    """Simulate one walk; return its duration (s)."""
    rng = np.random.default_rng(seed)
    if band is None:
        route, spec = random_route(rng), ImuSpec.adis16470()
    else:
        motion = StanceRandomization.calibrated().draw(rng) if calibrated else None
        cfg = SpeedRouteConfig(speed_mps=band, duration_s=(60.0, 180.0), stance_motion=motion)
        route = speed_route(rng, cfg)
        spec = ImuSpec.microstrain_gx5() if calibrated else ImuSpec.adis16470()
    truth = simulate_foot(route, SIM, full_state=False)
    simulate_imu(truth.omega_b, truth.f_b, SIM.rate_hz, spec, [rng], truth.gait_step)
    return float(truth.duration_s[0])


def timed(label: str, band: tuple[float, float] | None, calibrated: bool) -> tuple[float, float]:
    one_walk(0, band, calibrated)  # compile and warm caches
    t0 = time.process_time()
    seconds = sum(one_walk(1000 + i, band, calibrated) for i in range(WALKS))
    cpu = time.process_time() - t0
    per_walk, per_min = 1e3 * cpu / WALKS, 1e3 * cpu / (seconds / 60.0)
    print(f"{label:28s} {per_walk:6.2f} ms/walk  {per_min:6.2f} ms per simulated minute")
    return per_walk, per_min


def main() -> None:
    ratios = []
    for band in BANDS:
        _, today = timed(f"today {band}", band, False)
        _, calib = timed(f"calibrated {band}", band, True)
        ratios.append(calib / today)
        print(f"  calibrated / today: {calib / today:.2f}")
    timed("env random_route (today)", None, False)
    print(
        f"calibrated / today, per simulated minute, over bands: {np.mean(ratios):.2f} "
        f"(min {min(ratios):.2f}, max {max(ratios):.2f})"
    )


if __name__ == "__main__":
    main()
