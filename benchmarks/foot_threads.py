"""The native foot env's steps/s with one numba thread and with all, alternately.

    .venv/bin/python benchmarks/foot_threads.py [N] [SECONDS] [ROUNDS] [FAMILY ...]

The native loop of ``pednav bench foot`` (``agents.bench.timing``): the
``FootZupt-v0`` vector env of N lanes (default 256, ``scenario="random"``, filter
family FAMILY, default both), reset with seed 0 and stepped once, then stepped with
action 0 for at least SECONDS of wall time (default 3), autoresets included. Each
round times this once with one numba thread (the serial kernel) and once with all
of numba's threads (``NUMBA_NUM_THREADS``, default all cores), in alternating order,
in one process, so both see the same machine; ROUNDS rounds (default 3). Prints
every window's env steps/s and CPU time per vector step (all threads), the median
per thread count and their ratio, and the load average before and after. Both
thread counts play the same steps: the kernel's outputs do not depend on them
(tests/nav/test_kernel_threads.py).
"""

from __future__ import annotations

import os
import statistics
import sys
import time

import numba
import numpy as np

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_filters import FILTER_FAMILIES
from pednav_env.envs.foot_zupt import FootZuptVectorEnv


def window(family: str, n: int, seconds: float) -> tuple[float, float]:
    """(env steps/s, CPU ms per vector step) of one timed window from reset."""
    cfg = FootZuptConfig(filter_family=family, scenario="random")
    env = FootZuptVectorEnv(num_envs=n, config=cfg)
    env.reset(seed=0)
    zero = np.zeros((n, cfg.action_dim), np.float32)
    env.step(zero)  # warm-up, as the bench
    calls, w0, c0 = 0, time.perf_counter(), time.process_time()
    while calls < 3 or time.perf_counter() - w0 < seconds:
        env.step(zero)
        calls += 1
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    env.close()
    return n * calls / wall, cpu / calls * 1e3


def main(n: int, seconds: float, rounds: int, families: list[str]) -> None:
    counts = (1, numba.config.NUMBA_NUM_THREADS)
    print(f"load average {os.getloadavg()}; thread counts {counts}")
    for family in families:
        rates: dict[int, list[float]] = {t: [] for t in counts}
        for r in range(rounds):
            for t in counts if r % 2 == 0 else counts[::-1]:
                numba.set_num_threads(t)
                rate, cpu_ms = window(family, n, seconds)
                rates[t].append(rate)
                print(f"{family} N={n} threads={t}: {rate:.0f} steps/s, {cpu_ms:.1f} ms CPU/step")
        med = {t: statistics.median(v) for t, v in rates.items()}
        print(
            f"{family}: median {med[counts[0]]:.0f} (1 thread) / {med[counts[1]]:.0f} "
            f"({counts[1]} threads) steps/s, ratio {med[counts[1]] / med[counts[0]]:.2f}"
        )
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    args = sys.argv[1:]
    main(
        int(args[0]) if len(args) > 0 else 256,
        float(args[1]) if len(args) > 1 else 3.0,
        int(args[2]) if len(args) > 2 else 3,
        args[3:] or list(FILTER_FAMILIES),
    )
