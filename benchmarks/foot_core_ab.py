"""Paired A/B of the foot env's core: an older ``foot_core.py`` against this tree's, in one process.

    git show 62809c3:pednav_env/envs/foot_core.py > /tmp/old_foot_core.py
    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/foot_core_ab.py /tmp/old_foot_core.py \
        [ROUNDS] [CHUNK] [FAMILY ...]

Loads the given file as a module of its own (its imports resolve to this tree) and
builds two ``FootZupt-v0`` vector envs of N = 256 lanes on the bench's episodes
(``scenario="random"``, reset with seed 0, one warm-up step, action 0), one with
the old core and one with this tree's. Both play the same episodes and call the
same filter and walk generator, so what differs is the env's own work per step.
They are stepped alternately, CHUNK vector steps (default 10) at a time, ROUNDS
rounds (default 30), the order swapped every round, and the CPU time of every
chunk is kept: load that drifts hits both alike. Prints, per filter family
(default both), the CPU ms per vector step of each, the ratio of the totals and
the median and quartiles of the per-round ratios, and whether the two envs
returned the same outputs (observations, rewards, flags and every info entry,
bit for bit) at the end of every round. ``NUMBA_NUM_THREADS=1`` keeps the
kernel's threads out of the CPU time.
"""

from __future__ import annotations

import importlib.util
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_filters import FILTER_FAMILIES
from pednav_env.envs.foot_zupt import FootZuptVectorEnv

N = 256


def load_core(path: Path) -> type:
    """``FootZuptCore`` of the module at ``path``, imported as ``foot_core_under_test``."""
    spec = importlib.util.spec_from_file_location("foot_core_under_test", path)
    if spec is None or spec.loader is None:
        raise ValueError(f"{path}: not a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module.FootZuptCore


def same(a: Any, b: Any) -> bool:
    """Equal bit for bit, through dicts, tuples and object arrays."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, tuple | list) or (isinstance(a, np.ndarray) and a.dtype == object):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return np.array_equal(np.asarray(a), np.asarray(b))


def compare(old_core: type, family: str, rounds: int, chunk: int) -> None:
    cfg = FootZuptConfig(filter_family=family, scenario="random")

    class OldEnv(FootZuptVectorEnv):
        core_cls = old_core

    envs = {"old": OldEnv(num_envs=N, config=cfg), "new": FootZuptVectorEnv(num_envs=N, config=cfg)}
    zero = np.zeros((N, cfg.action_dim), np.float32)
    for env in envs.values():
        env.reset(seed=0)
        env.step(zero)
    cpu: dict[str, list[float]] = {"old": [], "new": []}
    equal = True
    for r in range(rounds):
        outputs = {}
        for name in ("old", "new") if r % 2 == 0 else ("new", "old"):
            t0 = time.process_time()
            for _ in range(chunk):
                outputs[name] = envs[name].step(zero)
            cpu[name].append(time.process_time() - t0)
        equal = equal and same(outputs["old"], outputs["new"])
    ratios = sorted(b / a for a, b in zip(cpu["old"], cpu["new"], strict=True))
    q = statistics.quantiles(ratios, n=4)
    old_ms, new_ms = (sum(cpu[k]) / (rounds * chunk) * 1e3 for k in ("old", "new"))
    print(
        f"{family}: {rounds} × {chunk} vector steps each; CPU per vector step old {old_ms:.2f} ms, "
        f"new {new_ms:.2f} ms; ratio of totals {new_ms / old_ms:.3f}, per round median "
        f"{q[1]:.3f} (quartiles {q[0]:.3f}–{q[2]:.3f}); outputs equal: {equal}",
        flush=True,
    )


if __name__ == "__main__":
    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    core = load_core(Path(args[0]))
    for fam in args[3:] or FILTER_FAMILIES:
        compare(
            core, fam, int(args[1]) if len(args) > 1 else 30, int(args[2]) if len(args) > 2 else 10
        )
