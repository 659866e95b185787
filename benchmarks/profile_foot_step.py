"""Where a FootZupt vector step spends its time (the split in docs/PERFORMANCE.md).

    .venv/bin/python benchmarks/profile_foot_step.py [N] [STEPS]

Steps the native vector env's core (no autoresets) with the paper policy for
STEPS vector steps after 3 warm-up steps, and prints CPU time per vector step:
in total and in the ZUPT-UKF's parts (update rounds, moving sigma points,
per-sample increments, preintegration, detector passes, divergence checks),
plus the number of update rounds per step. Then it times 20 lane resets
(episode generation and filter initialisation). CPU time (``process_time``)
keeps the figures meaningful when other work shares the machine.
"""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from pednav_env.envs import foot_core
from pednav_env.envs.foot_zupt import FootZuptVectorEnv
from pednav_env.nav import detectors, zupt_ukf

N = int(sys.argv[1]) if len(sys.argv) > 1 else 256
STEPS = int(sys.argv[2]) if len(sys.argv) > 2 else 30

spent: dict[str, float] = {}
calls: dict[str, int] = {}


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
            calls[label] = calls.get(label, 0) + 1

    setattr(owner, name, wrapper)


rounds: list[tuple[int, float]] = []  # (walkers in the round, CPU s)


def record_round_sizes() -> None:
    """Wrap ``ZuptUkf._update`` to record each round's size and CPU time."""
    fn = zupt_ukf.ZuptUkf._update

    @functools.wraps(fn)
    def wrapper(self: Any, idx: Any, *args: Any, **kwargs: Any) -> Any:
        t0 = time.process_time()
        try:
            return fn(self, idx, *args, **kwargs)
        finally:
            rounds.append((len(idx), time.process_time() - t0))

    zupt_ukf.ZuptUkf._update = wrapper  # type: ignore[method-assign]


if __name__ == "__main__":
    record_round_sizes()
    timed(zupt_ukf.ZuptUkf, "_update", "ZUPT update rounds")
    timed(zupt_ukf.ZuptUkf, "_sigmas_at", "moving sigma points")
    timed(zupt_ukf.ZuptUkf, "increments", "per-sample increments")
    timed(zupt_ukf, "preintegrate", "preintegration")
    timed(detectors.OnlineStanceDetector, "evaluate_threshold", "detector passes")
    timed(zupt_ukf, "_diverging", "divergence checks")
    timed(zupt_ukf.ZuptUkf, "_central_track", "divergence checks")
    timed(zupt_ukf.ZuptUkf, "advance", "ZuptUkf.advance (all of the above and more)")
    timed(foot_core, "generate_episode", "episode generation")

    env = FootZuptVectorEnv(num_envs=N)
    env.reset(seed=0)
    core = env.core
    zero = np.zeros((N, core.config.action_dim), np.float32)
    for _ in range(3):
        core.step(zero)
    spent.clear()
    calls.clear()
    rounds.clear()
    t0 = time.process_time()
    for _ in range(STEPS):
        core.step(zero)
    total = time.process_time() - t0
    print(f"N = {N}: core.step {total / STEPS * 1e3:.1f} ms CPU per vector step (no resets),")
    print(f"  ≈ {N * STEPS / total:.0f} env steps/s without resets")
    rounds_per_step = calls.get("ZUPT update rounds", 0) / STEPS
    for label, t in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"  {label:45s} {t / STEPS * 1e3:6.2f} ms")
    print(f"  update rounds per vector step: {rounds_per_step:.1f}")
    sizes = np.array(rounds)
    for lo, hi in ((1, 20), (20, 60), (60, 120), (120, N + 1)):
        sel = (sizes[:, 0] >= lo) & (sizes[:, 0] < hi)
        print(
            f"    rounds of {lo:3d}–{hi - 1:3d} walkers: {sel.sum() / STEPS:4.1f} per step, "
            f"{sizes[sel, 1].sum() / STEPS * 1e3:5.2f} ms"
        )

    spent.clear()
    t0 = time.process_time()
    for i in range(20):
        core.reset_lanes(np.array([i % N]), [np.random.default_rng(100 + i)])
    reset = (time.process_time() - t0) / 20
    gen = spent.get("episode generation", 0.0) / 20
    print(f"lane reset {reset * 1e3:.1f} ms CPU, of which episode generation {gen * 1e3:.1f} ms")
