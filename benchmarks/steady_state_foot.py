"""Steady-state throughput of the FootZupt vector env, autoresets included.

`pednav bench foot` times episodes from reset (few autoresets). This script
warms up for WARMUP vector steps, so that lanes are spread over their episodes,
then times SECONDS of stepping with the paper policy.
"""

import sys
import time

import numpy as np

from pednav_env.envs.foot_zupt import FootZuptVectorEnv

N = int(sys.argv[1]) if len(sys.argv) > 1 else 256
WARMUP, SECONDS = 150, 45.0

if __name__ == "__main__":
    env = FootZuptVectorEnv(num_envs=N)
    env.reset(seed=0)
    zero = np.zeros((N, 4), np.float32)
    for _ in range(WARMUP):
        env.step(zero)
    steps, resets, t0 = 0, 0, time.perf_counter()
    while time.perf_counter() - t0 < SECONDS:
        _, _, term, trunc, _ = env.step(zero)
        steps += 1
        resets += int((term | trunc).sum())
    wall = time.perf_counter() - t0
    print(
        f"N={N}: {N * steps / wall:.0f} env steps/s over {steps} vector steps, "
        f"{resets} autoresets ({resets / steps:.2f} per vector step)"
    )
