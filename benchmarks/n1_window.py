"""The FootZupt vector env at N = 1 in one timed window, for comparing trees.

    NUMBA_NUM_THREADS=1 PYTHONPATH=TREE .venv/bin/python benchmarks/n1_window.py \
        [FAMILY] [STEPS | SECONDSs] [profile]

Imports ``pednav_env`` from wherever ``PYTHONPATH`` points (this tree or an older
one: only ``FootZuptVectorEnv(num_envs=1, config=FootZuptConfig(...))`` is used,
and ``filter_family`` only for a family other than ``paper``), builds the vector env
of one lane (``scenario="random"``), resets it with seed 0, takes one warm-up step
with action 0 and then times, as ``pednav bench foot`` does at N = 1, either STEPS
vector steps (default 8000) or as many as fit in SECONDS (``3s``: the bench's
window). Prints the steps per wall second and per CPU second, the resets in the
window and a hash of the window's observations, rewards and flags (equal hashes:
the two trees stepped through the same episodes bit for bit).

With ``profile`` the window runs under :mod:`cProfile` and the 25 functions with
the largest own time are printed (the timing figures then include the profiler).
"""

from __future__ import annotations

import cProfile
import hashlib
import pstats
import sys
import time

import numpy as np

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_zupt import FootZuptVectorEnv


def window(env: FootZuptVectorEnv, steps: int, seconds: float) -> tuple[int, int, str]:
    """Step ``env`` with action 0 for ``steps`` steps or, if ``seconds`` > 0, as
    many as fit in that many seconds; return (steps, resets, hash of outputs)."""
    zero = np.zeros((1, env.config.action_dim), np.float32)
    digest = hashlib.sha256()
    done = resets = 0
    start = time.perf_counter()
    while (done < steps) if seconds <= 0 else (time.perf_counter() - start < seconds):
        obs, reward, term, trunc, _ = env.step(zero)
        digest.update(np.asarray(obs, np.float64).tobytes())
        digest.update(np.asarray([reward, term, trunc], np.float64).tobytes())
        resets += int(term[0] or trunc[0])
        done += 1
    return done, resets, digest.hexdigest()[:16]


def main(args: list[str]) -> None:
    family = args[0] if args else "paper"
    amount = args[1] if len(args) > 1 else "8000"
    seconds = float(amount[:-1]) if amount.endswith("s") else 0.0
    steps = 0 if seconds > 0 else int(amount)
    config = (
        FootZuptConfig(scenario="random")
        if family == "paper"
        else FootZuptConfig(filter_family=family, scenario="random")
    )
    env = FootZuptVectorEnv(num_envs=1, config=config)
    env.reset(seed=0)
    env.step(np.zeros((1, config.action_dim), np.float32))  # warm-up
    profiler = cProfile.Profile() if "profile" in args[2:] else None
    c0, w0 = time.process_time(), time.perf_counter()
    if profiler is not None:
        profiler.enable()
    done, resets, digest = window(env, steps, seconds)
    if profiler is not None:
        profiler.disable()
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    print(
        f"{family}: {done} steps, {resets} resets, {done / wall:.0f} steps/s wall, "
        f"{done / cpu:.0f} per CPU s, outputs {digest}",
        flush=True,
    )
    if profiler is not None:
        pstats.Stats(profiler).sort_stats("tottime").print_stats(25)


if __name__ == "__main__":
    main(sys.argv[1:])
