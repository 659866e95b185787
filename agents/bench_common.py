"""Pieces shared by the ``pednav bench`` benchmarks (foot, waist, marker)."""

from __future__ import annotations

import resource
import time
from collections.abc import Callable
from typing import Any

#: Numbers of environments benchmarked by default (DESIGN.md).
DEFAULT_SIZES = (1, 16, 64, 256)


def timed_calls(step: Callable[[], Any], min_seconds: float, min_calls: int) -> tuple[int, float]:
    """Call ``step`` at least ``min_calls`` times and for at least ``min_seconds``;
    return (calls, wall seconds)."""
    calls, start = 0, time.perf_counter()
    while calls < min_calls or time.perf_counter() - start < min_seconds:
        step()
        calls += 1
    return calls, time.perf_counter() - start


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
