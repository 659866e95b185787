"""A long episode runs with flat memory: nothing grows per step.

(The 84.4-minute episode (one Schuler period) runs in benchmarks/long_episode_memory.py;
this is a 5-minute one so that the suite stays fast.)
"""

import tracemalloc

import numpy as np

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_zupt import FootZuptEnv
from pednav_env.gait.foot_route import RouteRandomization


def test_five_minute_episode_memory_is_flat():
    # Walking only, one grade, no error bound: the walk runs to its end.
    config = FootZuptConfig(
        route=RouteRandomization(duration_s=(300.0, 300.0), gait_weights=(0.0, 1.0, 0.0, 0.0)),
        imu_grades=("adis16470",),
        imu_grade_weights=(1.0,),
        divergence_error_m=1e9,
    )
    env = FootZuptEnv(config=config)
    env.reset(seed=1)
    zero = np.zeros(4, np.float32)
    tracemalloc.start()
    try:
        steps, marks = 0, []
        while True:
            _, _, term, trunc, _ = env.step(zero)
            steps += 1
            if steps in (50, 500):
                marks.append(tracemalloc.get_traced_memory()[0])
            if term or trunc:
                break
        end = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert steps > 500
    # Per-step growth would show as ≥ steps × (a few hundred bytes); allow 200 kB of noise.
    assert end - marks[0] < 200_000
    assert marks[1] - marks[0] < 200_000
