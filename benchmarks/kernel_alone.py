"""The compiled ZUPT kernel alone, on captured inputs: CPU time and an output hash.

    # capture the kernel's inputs of vector steps 20-24 of the bench's env
    .venv/bin/python benchmarks/kernel_alone.py capture shoe /tmp/shoe_blocks.pkl
    # time them (least CPU time of R calls per block, summed) and hash the outputs
    .venv/bin/python benchmarks/kernel_alone.py time /tmp/shoe_blocks.pkl [R]
    # two code trees in one process, alternately (e.g. main's checkout against this one)
    .venv/bin/python benchmarks/kernel_alone.py pair /tmp/shoe_blocks.pkl /work/main . [R]
    # 1 thread against all of numba's threads, alternately: CPU and wall time, outputs
    .venv/bin/python benchmarks/kernel_alone.py threads /tmp/shoe_blocks.pkl [R]

``capture FAMILY FILE``: the native ``FootZupt-v0`` vector env of ``pednav bench foot``
(N = 256, ``scenario="random"``, filter family FAMILY, seeds 0-255, action 0) is stepped
25 times; the arguments of the last 5 calls of
:func:`pednav_env.nav.zupt_kernel.advance_block` are pickled as they were before the
call. ``time FILE [R]``: each block is run R times (default 15) on fresh copies of its
inputs; prints the least CPU time (``process_time``) per block summed over the blocks,
and a SHA-256 of every output (filter state, detector state, block output) so that two
code trees can be compared on the same inputs: run ``time`` with each tree on the
``PYTHONPATH``, alternately, to compare them under machine load (the least of many
calls is what load moves least). ``pair FILE TREE_A TREE_B [R]`` does that in one
process: each tree's ``pednav_env`` is copied to a temporary directory under its own
package name, and the two kernels run the same blocks alternately (the order swapped
every round), R rounds (default 10); it prints the least CPU time of each summed
over the blocks and their ratio. Run it with the same tree twice for the harness's
own spread (A/A). ``threads FILE [R]`` runs the blocks alternately with one numba
thread (the serial kernel) and with all of numba's threads (``NUMBA_NUM_THREADS``,
default all cores), R rounds (default 10), and prints for each the least wall time
(``perf_counter``) and the least CPU time (all threads) per block, summed, with the
output hashes, which must be equal.
"""

from __future__ import annotations

import copy
import hashlib
import importlib
import pickle
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np


def capture(family: str, path: str, n: int = 256, warmup: int = 20, keep: int = 5) -> None:
    """Pickle the inputs of ``keep`` kernel calls after ``warmup`` vector steps."""
    from pednav_env.envs.foot_core import FootZuptConfig
    from pednav_env.envs.foot_zupt import FootZuptVectorEnv
    from pednav_env.nav import zupt_ukf

    calls: list[tuple] = []
    kernel = zupt_ukf.advance_block

    def recording(*args):  # type: ignore[no-untyped-def]
        calls.append(copy.deepcopy(args))
        return kernel(*args)

    zupt_ukf.advance_block = recording
    cfg = FootZuptConfig(filter_family=family, scenario="random")
    env = FootZuptVectorEnv(num_envs=n, config=cfg)
    env.reset(seed=list(range(n)))
    zero = np.zeros((n, cfg.action_dim), np.float32)
    for _ in range(warmup + keep):
        env.step(zero)
    with open(path, "wb") as fh:
        pickle.dump(calls[-keep:], fh)
    print(f"{len(calls[-keep:])} blocks of {family} captured to {path}")


def time_blocks(path: str, reps: int = 15) -> None:
    """Least CPU time per captured block (summed) and a hash of the outputs."""
    from pednav_env.nav.zupt_kernel import advance_block

    with open(path, "rb") as fh:
        calls = pickle.load(fh)
    advance_block(*copy.deepcopy(calls[0]))  # compile / load the cache
    digest = hashlib.sha256()
    total = 0.0
    for args in calls:
        best = float("inf")
        for r in range(reps):
            fresh = copy.deepcopy(args)
            t0 = time.process_time()
            n_log = advance_block(*fresh)
            best = min(best, time.process_time() - t0)
            if r == 0:
                digest.update(np.int64(n_log).tobytes())
                for group in fresh[3:7]:  # filters, detector, output, log
                    for a in group:
                        digest.update(np.ascontiguousarray(a).tobytes())
        total += best
    outputs = digest.hexdigest()[:16]
    print(f"kernel {total * 1e3:.2f} ms CPU per {len(calls)} blocks; outputs {outputs}")


def _run_block(args: tuple, digest: Any) -> tuple[float, float]:
    """Wall and CPU seconds of one kernel call on a fresh copy of ``args``; the
    outputs go into ``digest`` when one is given."""
    from pednav_env.nav.zupt_kernel import advance_block

    fresh = copy.deepcopy(args)
    w0, c0 = time.perf_counter(), time.process_time()
    n_log = advance_block(*fresh)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    if digest is not None:
        digest.update(np.int64(n_log).tobytes())
        for group in fresh[3:7]:  # filters, detector, output, log
            for a in group:
                digest.update(np.ascontiguousarray(a).tobytes())
    return wall, cpu


def threads(path: str, reps: int = 10) -> None:
    """Least wall and CPU time per block (summed) with 1 thread and with all."""
    import numba

    with open(path, "rb") as fh:
        calls = pickle.load(fh)
    counts = (1, numba.config.NUMBA_NUM_THREADS)
    best = {t: np.full((2, len(calls)), np.inf) for t in counts}
    digests = {t: hashlib.sha256() for t in counts}
    for t in counts:  # compile / load the cache of both paths
        numba.set_num_threads(t)
        _run_block(calls[0], None)
    for r in range(reps):
        for t in counts if r % 2 == 0 else counts[::-1]:
            numba.set_num_threads(t)
            for b, args in enumerate(calls):
                wall, cpu = _run_block(args, digests[t] if r == 0 else None)
                best[t][:, b] = np.minimum(best[t][:, b], (wall, cpu))
    for t in counts:
        wall, cpu = best[t].sum(axis=1) * 1e3
        print(
            f"{t} thread(s): wall {wall:.2f} ms, CPU {cpu:.2f} ms per {len(calls)} blocks "
            f"(least of {reps}); outputs {digests[t].hexdigest()[:16]}"
        )
    one, many = (best[t].sum(axis=1) for t in counts)
    print(f"wall {counts[1]} / 1 thread: {many[0] / one[0]:.3f}; CPU {many[1] / one[1]:.3f}")


def _renamed_copy(tree: str, name: str, root: Path) -> str:
    """``tree``/pednav_env copied to ``root``/``name`` with its imports renamed."""
    dest = root / name
    shutil.copytree(Path(tree) / "pednav_env", dest, ignore=shutil.ignore_patterns("__pycache__"))
    for py in dest.rglob("*.py"):
        text = re.sub(r"\bpednav_env(?=[. ])", name, py.read_text())
        py.write_text(text)
    return name


def pair(path: str, tree_a: str, tree_b: str, reps: int = 10) -> None:
    """Least CPU time of the kernels of two trees on the same blocks, alternately."""
    with open(path, "rb") as fh:
        calls = pickle.load(fh)
    root = Path(tempfile.mkdtemp(prefix="kernel_pair_"))
    sys.path.insert(0, str(root))
    kernels = {}
    for label, tree in (("A", tree_a), ("B", tree_b)):
        kernels[label] = importlib.import_module(
            _renamed_copy(tree, f"pednav_env_{label.lower()}", root) + ".nav.zupt_kernel"
        )

    def inputs(mod, args):  # the blocks' NamedTuples rebuilt with the tree's own classes
        # (a tree whose class has fewer fields, e.g. an older KernelSettings, takes the first ones)
        out = []
        for a in copy.deepcopy(args):
            cls = getattr(mod, type(a).__name__)
            out.append(cls(*a[: len(cls._fields)]))
        return tuple(out)

    for mod in kernels.values():
        mod.advance_block(*inputs(mod, calls[0]))  # compile
    best = {label: [float("inf")] * len(calls) for label in kernels}
    for r in range(reps):
        order = ("A", "B") if r % 2 == 0 else ("B", "A")
        for b, args in enumerate(calls):
            for label in order:
                fresh = inputs(kernels[label], args)
                t0 = time.process_time()
                kernels[label].advance_block(*fresh)
                best[label][b] = min(best[label][b], time.process_time() - t0)
    shutil.rmtree(root)
    ta, tb = sum(best["A"]) * 1e3, sum(best["B"]) * 1e3
    print(
        f"A {tree_a}: {ta:.2f} ms, B {tree_b}: {tb:.2f} ms CPU per {len(calls)} blocks "
        f"(least of {reps}, alternating); B/A {tb / ta:.3f}"
    )


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "capture":
        capture(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 5 and sys.argv[1] == "pair":
        pair(sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]) if len(sys.argv) > 5 else 10)
    elif len(sys.argv) >= 3 and sys.argv[1] == "threads":
        threads(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 10)
    elif len(sys.argv) >= 3 and sys.argv[1] == "time":
        time_blocks(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 15)
    else:
        sys.exit(__doc__)
