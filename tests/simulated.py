"""Simulated walks with their sensor records, shared by the filter tests."""

from __future__ import annotations

import numpy as np

from pednav_env.gait.foot import FootTrajectory
from pednav_env.gait.heel_knee import HeelKneeConfig, HeelKneeWalk, simulate_heel_knee
from pednav_env.sensors.imu import ImuMeasurements, ImuSpec, simulate_imu
from pednav_env.sensors.uwb import UwbMeasurements, UwbSpec, measure_uwb

#: Sample rate of the foot walks the filter tests simulate (Hz).
FOOT_RATE_HZ = 100.0


def foot_imu(
    walk: FootTrajectory, n: int, seed: int = 0, spec: ImuSpec | None = None
) -> ImuMeasurements:
    """``n`` noisy IMU records of the same foot walk (``spec`` default: paper 003's grade),
    one generator per walker spawned from ``seed``."""
    gens = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]
    return simulate_imu(
        np.repeat(walk.omega_b, n, 0),
        np.repeat(walk.f_b, n, 0),
        FOOT_RATE_HZ,
        ImuSpec.paper003() if spec is None else spec,
        gens,
        gait_step_index=np.repeat(walk.gait_step, n, 0),
    )


def marker_walker_rngs(seed: int, n: int) -> tuple[list, list]:
    """Per walker, one generator for the gait and one for the UWB noise."""
    kids = [s.spawn(2) for s in np.random.SeedSequence(seed).spawn(n)]
    return [np.random.default_rng(k[0]) for k in kids], [np.random.default_rng(k[1]) for k in kids]


def marker_walks(
    seed: int, n: int, k: int, gait: HeelKneeConfig, uwb: UwbSpec
) -> tuple[HeelKneeWalk, UwbMeasurements]:
    """``n`` heel–knee walks of ``k`` samples and their UWB measurements."""
    g_rngs, u_rngs = marker_walker_rngs(seed, n)
    walk = simulate_heel_knee(gait, k, g_rngs)
    return walk, measure_uwb(uwb, walk.markers, u_rngs)
