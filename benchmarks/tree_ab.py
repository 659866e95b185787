"""Paired A/B of the foot env against an older commit's package, in one process.

    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/tree_ab.py REV walks [ROUNDS] [WALKS]
    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/tree_ab.py REV steps [ROUNDS] [CHUNK] \
        [FAMILY ...]

Extracts ``pednav_env`` of commit REV (``git archive``) into a folder of the
temporary directory named after the commit, renames the package there to
``pednav_env_ab_old`` (its imports with it) and imports it beside this tree's
``pednav_env``. Everything the two packages compute is then measured on the
same inputs, alternately, the order swapped every round, and the CPU time
(``process_time``) and the wall time of every part are kept, so that load that
drifts hits both alike; the outputs of the two are compared bit for bit.

- ``walks``: episode generation of the FootZupt env's random scenario (the
  bench's: route, IMU grade, walk, IMU errors; ``generate_episode``), ROUNDS
  rounds (default 10) of WALKS walks (default 40) from the seeds 21 200 + i,
  the same walks in every round. Prints the CPU and wall time per walk of
  each, the ratio of the totals and the median and quartiles of the per-round
  ratios, and whether every array of every episode was equal.
- ``steps``: two native vector envs of N = 256 lanes (``scenario="random"``,
  reset with seed 0, one warm-up step, action 0, autoresets included), one
  from each package, stepped CHUNK vector steps (default 10) at a time for
  ROUNDS rounds (default 30), per filter family (default both). Prints the
  CPU and wall time per vector step, the ratios as above and whether observations,
  rewards, flags and every info entry were equal at the end of every round.

``NUMBA_NUM_THREADS=1`` keeps the kernel's threads out of the CPU time.
"""

from __future__ import annotations

import importlib
import io
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

import pednav_env  # noqa: F401  (registers the envs before the old package is imported)
from pednav_env.envs import foot_core, foot_zupt

OLD = "pednav_env_ab_old"
N = 256
REPO = Path(__file__).resolve().parents[1]


def old_package(rev: str) -> ModuleType:
    """``pednav_env`` of commit ``rev``, imported as :data:`OLD`."""
    sha = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", rev], capture_output=True, text=True, check=False
    )
    if sha.returncode != 0:
        raise ValueError(f"REV: not a commit of {REPO}: {rev!r}")
    root = Path(tempfile.gettempdir()) / f"pednav_ab_{sha.stdout.strip()[:12]}"
    if not (root / OLD).is_dir():
        archive = subprocess.run(
            ["git", "-C", str(REPO), "archive", "--format=tar", rev, "pednav_env"],
            capture_output=True,
            check=True,
        ).stdout
        staging = Path(tempfile.mkdtemp(prefix="pednav_ab_"))
        with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
            tar.extractall(staging, filter="data")
        for path in (staging / "pednav_env").rglob("*.py"):
            path.write_text(path.read_text().replace("pednav_env", OLD))
        (staging / "pednav_env").rename(staging / OLD)
        staging.rename(root)
    sys.path.insert(0, str(root))
    return importlib.import_module(OLD)


def same(a: Any, b: Any) -> bool:
    """Equal bit for bit, through dicts, tuples, lists and object arrays."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, tuple | list) or (isinstance(a, np.ndarray) and a.dtype == object):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, str):
        return a == b
    x, y = np.asarray(a), np.asarray(b)
    return x.shape == y.shape and x.dtype == y.dtype and x.tobytes() == y.tobytes()


def paired(label: str, runs: dict[str, Callable[[], Any]], rounds: int, per_round: int) -> bool:
    """Run ``runs["old"]`` and ``runs["new"]`` alternately; print CPU per unit and ratios.
    Returns whether their results were equal in every round."""
    cpu: dict[str, list[float]] = {"old": [], "new": []}
    wall: dict[str, list[float]] = {"old": [], "new": []}
    equal = True
    for r in range(rounds):
        results = {}
        for name in ("old", "new") if r % 2 == 0 else ("new", "old"):
            t0, w0 = time.process_time(), time.perf_counter()
            results[name] = runs[name]()
            cpu[name].append(time.process_time() - t0)
            wall[name].append(time.perf_counter() - w0)
        equal = equal and same(results["old"], results["new"])
    for kind, spent in (("CPU", cpu), ("wall", wall)):
        ratios = sorted(b / a for a, b in zip(spent["old"], spent["new"], strict=True))
        q = statistics.quantiles(ratios, n=4)
        old_ms, new_ms = (sum(spent[k]) / (rounds * per_round) * 1e3 for k in ("old", "new"))
        print(
            f"{label}: {rounds} rounds × {per_round}; {kind} old {old_ms:.3f} ms, new "
            f"{new_ms:.3f} ms; ratio of totals {new_ms / old_ms:.3f}, per round median "
            f"{q[1]:.3f} (quartiles {q[0]:.3f}–{q[2]:.3f})",
            flush=True,
        )
    print(f"{label}: outputs equal in every round: {equal}", flush=True)
    return equal


def walks(old: ModuleType, rounds: int, count: int) -> None:
    """Episode generation, old against new (module docstring)."""
    old_core = importlib.import_module(f"{OLD}.envs.foot_core")
    configs = {
        "old": old_core.FootZuptConfig(scenario="random"),
        "new": foot_core.FootZuptConfig(scenario="random"),
    }
    modules = {"old": old_core, "new": foot_core}

    def run(name: str) -> Callable[[], list[tuple]]:
        def walk_all() -> list[tuple]:
            out = []
            for i in range(count):
                ep = modules[name].generate_episode(configs[name], np.random.default_rng(21200 + i))
                out.append((ep.omega_b, ep.f_b, ep.pos_n, ep.stance, ep.distance_m, ep.imu_grade))
            return out

        return walk_all

    runs = {name: run(name) for name in ("old", "new")}
    for fn in runs.values():
        fn()  # compile and warm
    paired("episode generation per walk", runs, rounds, count)


def steps(old: ModuleType, rounds: int, chunk: int, families: list[str]) -> None:
    """Vector steps of the two packages' envs (module docstring)."""
    old_zupt = importlib.import_module(f"{OLD}.envs.foot_zupt")
    old_core = importlib.import_module(f"{OLD}.envs.foot_core")
    for family in families:
        envs = {
            "old": old_zupt.FootZuptVectorEnv(
                num_envs=N, config=old_core.FootZuptConfig(filter_family=family, scenario="random")
            ),
            "new": foot_zupt.FootZuptVectorEnv(
                num_envs=N, config=foot_core.FootZuptConfig(filter_family=family, scenario="random")
            ),
        }
        zero = np.zeros((N, envs["new"].config.action_dim), np.float32)
        for env in envs.values():
            env.reset(seed=0)
            env.step(zero)

        runs = {name: stepper(env, zero, chunk) for name, env in envs.items()}
        paired(f"{family} vector step", runs, rounds, chunk)


def stepper(env: Any, action: np.ndarray, chunk: int) -> Callable[[], Any]:
    """``chunk`` steps of ``env`` with ``action``, returning the last step's outputs."""

    def step_chunk() -> Any:
        out = None
        for _ in range(chunk):
            out = env.step(action)
        return out

    return step_chunk


def main(args: list[str]) -> None:
    if len(args) < 2 or args[1] not in ("walks", "steps"):
        sys.exit(__doc__)
    old = old_package(args[0])
    if args[1] == "walks":
        walks(old, int(args[2]) if len(args) > 2 else 10, int(args[3]) if len(args) > 3 else 40)
    else:
        rounds = int(args[2]) if len(args) > 2 else 30
        chunk = int(args[3]) if len(args) > 3 else 10
        steps(old, rounds, chunk, args[4:] or ["paper", "shoe"])


if __name__ == "__main__":
    main(sys.argv[1:])
