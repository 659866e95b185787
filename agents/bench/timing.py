"""The timing loop shared by the ``pednav bench`` benchmarks (foot, waist, marker).

Each bench steps the native vector env of N lanes (paper policy, autoresets
included) and, in the same process, N scalar reference environments (plain
filterpy filters, :mod:`pednav_env.testing`) one after another, and reports the
env steps per second of both.
"""

from __future__ import annotations

import resource
import time
from collections.abc import Callable
from functools import partial
from typing import Any, Protocol

import numpy as np

#: Numbers of environments benchmarked by default.
DEFAULT_SIZES = (1, 16, 64, 256)


class Reference(Protocol):
    """A scalar reference environment: one decision interval per :meth:`step`."""

    def step(self) -> object: ...


def timed_calls(step: Callable[[], Any], min_seconds: float, min_calls: int) -> tuple[int, float]:
    """Call ``step`` at least ``min_calls`` times and for at least ``min_seconds``;
    return (calls, wall seconds)."""
    calls, start = 0, time.perf_counter()
    while calls < min_calls or time.perf_counter() - start < min_seconds:
        step()
        calls += 1
    return calls, time.perf_counter() - start


def interleaved_calls(
    native: Callable[[], Any],
    reference: Callable[[], Any],
    min_seconds: float,
    reference_seconds: float,
    chunk_seconds: float = 0.25,
) -> tuple[int, float, int, float]:
    """Time both loops in alternating chunks until each has run its minimum time.

    On a shared machine the load drifts; alternating keeps the two measurements
    under the same conditions, so their ratio is stable. Returns (calls, seconds)
    of the native loop, then of the reference.
    """
    n_calls = r_calls = 0
    n_time = r_time = 0.0
    while n_time < min_seconds or r_time < reference_seconds or not (n_calls and r_calls):
        for fn, is_native in ((native, True), (reference, False)):
            start = time.perf_counter()
            calls = 0
            while calls == 0 or time.perf_counter() - start < chunk_seconds:
                fn()
                calls += 1
            elapsed = time.perf_counter() - start
            if is_native:
                n_calls, n_time = n_calls + calls, n_time + elapsed
            else:
                r_calls, r_time = r_calls + calls, r_time + elapsed
    return n_calls, n_time, r_calls, r_time


def bench_row(
    num_envs: int, calls: int, elapsed: float, ref_calls: int, ref_elapsed: float
) -> dict[str, float]:
    """One row of the bench JSON: env steps per second of both loops and their ratio."""
    native = num_envs * calls / elapsed
    reference = num_envs * ref_calls / ref_elapsed
    return {
        "num_envs": num_envs,
        "steps_per_s": native,
        "reference_steps_per_s": reference,
        "ratio": native / reference,
    }


def bench_result(name: str, rows: list[dict[str, float]]) -> dict[str, Any]:
    """The bench JSON object, with the process's peak RSS (MB)."""
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {"bench": name, "rows": rows, "peak_rss_mb": peak_mb}


def bench_native_vs_reference(
    name: str,
    make_vector_env: Callable[[int], Any],
    make_reference: Callable[[int], Reference],
    action_dim: int,
    sizes: tuple[int, ...],
    min_seconds: float,
    reference_seconds: float,
    *,
    reference_min_calls: int = 1,
    interleave: bool = False,
) -> dict[str, Any]:
    """Env steps per second of ``make_vector_env(n)`` and of ``n`` references
    ``make_reference(seed)`` (seeds 0 … n−1, the lanes' episodes), for each n in
    ``sizes``.

    The native env is reset with seed 0 and stepped once before timing (compilation
    and first allocations). Without ``interleave`` the native loop is timed for
    ``min_seconds`` (≥ 3 calls), then the references for ``reference_seconds``
    (≥ ``reference_min_calls`` rounds); with it, both in alternating chunks
    (:func:`interleaved_calls`).
    """
    rows = []
    for n in sizes:
        env = make_vector_env(n)
        env.reset(seed=0)
        native = partial(env.step, np.zeros((n, action_dim), np.float32))
        native()  # warm-up
        if interleave:
            reference = partial(_step_all, [make_reference(i) for i in range(n)])
            calls, elapsed, ref_calls, ref_elapsed = interleaved_calls(
                native, reference, min_seconds, reference_seconds
            )
            env.close()
        else:
            calls, elapsed = timed_calls(native, min_seconds, 3)
            env.close()
            reference = partial(_step_all, [make_reference(i) for i in range(n)])
            ref_calls, ref_elapsed = timed_calls(reference, reference_seconds, reference_min_calls)
        rows.append(bench_row(n, calls, elapsed, ref_calls, ref_elapsed))
    return bench_result(name, rows)


def _step_all(refs: list[Reference]) -> None:
    for r in refs:
        r.step()
