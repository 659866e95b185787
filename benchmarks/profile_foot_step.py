"""Where a FootZupt vector step spends its time (the split in docs/PERFORMANCE.md).

    .venv/bin/python benchmarks/profile_foot_step.py [N] [STEPS] [FAMILY]

Steps the native vector env's core (no autoresets) with action 0 of filter family
FAMILY (default ``paper``; ``shoe`` on the random scenario, as ``pednav bench foot``
times it) for STEPS vector steps after 3 warm-up steps, and prints CPU time per vector step:
in total, in the compiled ZUPT-UKF kernel (detector, strapdown preintegrals,
ZUPT updates and sigma-point redraws of all walkers), in the rest of
``ZuptUkf.advance`` (argument packing, divergence freezes) and in the env's
feature computation, plus the ZUPTs per vector step. Then it times 20 lane
resets (episode generation and filter initialisation). CPU time
(``process_time``) keeps the figures meaningful when other work shares the
machine; it adds up the kernel's threads (``NUMBA_NUM_THREADS=1`` for one core), so
the wall time of the stepping loop is printed too.
"""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from pednav_env.envs import foot_core
from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_zupt import FootZuptVectorEnv
from pednav_env.nav import zupt_ukf

N = int(sys.argv[1]) if len(sys.argv) > 1 else 256
STEPS = int(sys.argv[2]) if len(sys.argv) > 2 else 30
FAMILY = sys.argv[3] if len(sys.argv) > 3 else "paper"

spent: dict[str, float] = {}


def timed(owner: Any, name: str, label: str) -> None:
    """Wrap ``owner.name`` so that its CPU time adds to ``spent[label]``."""
    fn: Callable[..., Any] = getattr(owner, name)

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[label] = spent.get(label, 0.0) + time.process_time() - t0

    setattr(owner, name, wrapper)


if __name__ == "__main__":
    timed(zupt_ukf, "advance_block", "compiled kernel (advance_block)")
    timed(zupt_ukf.ZuptUkf, "advance", "ZuptUkf.advance (kernel included)")
    timed(foot_core.FootZuptCore, "_features", "observation features")
    timed(foot_core, "generate_episode", "episode generation")
    timed(foot_core.ShoeStatistic, "interval", "SHOE statistic (shoe family)")

    config = None if FAMILY == "paper" else FootZuptConfig(filter_family=FAMILY, scenario="random")
    env = FootZuptVectorEnv(num_envs=N, config=config)
    env.reset(seed=0)
    core = env.core
    zero = np.zeros((N, core.config.action_dim), np.float32)
    for _ in range(3):
        core.step(zero)
    spent.clear()
    zupts0 = core.engine.updates.sum() + core.engine.rejected.sum()
    t0, w0 = time.process_time(), time.perf_counter()
    for _ in range(STEPS):
        core.step(zero)
    total, wall = time.process_time() - t0, time.perf_counter() - w0
    zupts = core.engine.updates.sum() + core.engine.rejected.sum() - zupts0
    print(f"N = {N}: core.step {total / STEPS * 1e3:.2f} ms CPU per vector step (no resets),")
    print(f"  {wall / STEPS * 1e3:.2f} ms wall (the kernel's threads: CPU of all of them)")
    print(f"  ≈ {N * STEPS / total:.0f} env steps/s per CPU second without resets")
    for label, t in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"  {label:45s} {t / STEPS * 1e3:6.2f} ms")
    print(f"  ZUPTs per vector step: {zupts / STEPS:.0f}")

    spent.clear()
    t0 = time.process_time()
    for i in range(20):
        core.reset_lanes(np.array([i % N]), [np.random.default_rng(100 + i)])
    reset = (time.process_time() - t0) / 20
    gen = spent.get("episode generation", 0.0) / 20
    print(f"lane reset {reset * 1e3:.1f} ms CPU, of which episode generation {gen * 1e3:.1f} ms")
