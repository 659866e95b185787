"""An 84.4-minute FootZupt episode (one Schuler period): memory must stay flat.

Walking gaits and the ADIS16470-like grade with no error bound, so that the
walk runs to its end. Prints steps, wall time, peak RSS and the traced Python
memory at 10 % and at the end of the episode.

    .venv/bin/python benchmarks/long_episode_memory.py [FAMILY]

FAMILY: the filter family, ``paper`` (default) or ``shoe`` (random scenario).
"""

import resource
import sys
import time
import tracemalloc

import numpy as np

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_zupt import FootZuptEnv
from pednav_env.gait.foot_route import RouteRandomization

DURATION_S = 84.4 * 60

if __name__ == "__main__":
    config = FootZuptConfig(
        route=RouteRandomization(
            duration_s=(DURATION_S, DURATION_S), gait_weights=(0.3, 0.7, 0.0, 0.0)
        ),
        imu_grades=("adis16470",),
        imu_grade_weights=(1.0,),
        divergence_error_m=1e9,
        filter_family=sys.argv[1] if len(sys.argv) > 1 else "paper",
        scenario="random",
    )
    env = FootZuptEnv(config=config)
    t0 = time.perf_counter()
    env.reset(seed=0)
    reset_s = time.perf_counter() - t0
    rss_after_reset = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    tracemalloc.start()
    zero = np.zeros(4, np.float32)
    steps, mark = 0, None
    expected = int(DURATION_S / config.decision_interval_s)
    t0 = time.perf_counter()
    while True:
        _, _, term, trunc, info = env.step(zero)
        steps += 1
        if steps == expected // 10:
            mark = tracemalloc.get_traced_memory()[0]
        if term or trunc:
            break
    wall = time.perf_counter() - t0
    end, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"episode: {steps} steps ({steps * config.decision_interval_s / 60:.1f} min), "
        f"terminated={term}, final error {info['error']:.1f} m over {info['distance']:.0f} m"
    )
    print(
        f"reset (walk + IMU generation): {reset_s:.2f} s; stepping: {wall:.1f} s "
        f"({steps / wall:.0f} steps/s, under tracemalloc)"
    )
    print(f"peak RSS: {rss_after_reset:.0f} MB after reset, {rss:.0f} MB at the end")
    print(
        f"traced memory: {mark / 1e6:.3f} MB at 10 %, {end / 1e6:.3f} MB at the end, "
        f"growth {(end - mark) / 1e3:.1f} kB over {steps - expected // 10} steps"
    )
