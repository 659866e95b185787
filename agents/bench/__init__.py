"""Throughput benchmarks: each native vector env against a filterpy reference.

``pednav bench foot|waist|marker [--json] [--sizes N ...] [--seconds S]``; one
module per env (:mod:`.foot`, :mod:`.waist`, :mod:`.marker`) over the shared
timing loop of :mod:`.timing`, whose references live in :mod:`pednav_env.testing`.

JSON: ``{"bench": NAME, "rows": [{"num_envs": 256, "steps_per_s": ..,
"reference_steps_per_s": .., "ratio": ..}, ...], "peak_rss_mb": ..}``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from agents.bench.foot import bench_foot
from agents.bench.marker import bench_marker
from agents.bench.waist import bench_waist

BENCHES: dict[str, Callable[..., dict[str, Any]]] = {
    "foot": bench_foot,
    "marker": bench_marker,
    "waist": bench_waist,
}

__all__ = ["BENCHES", "bench_foot", "bench_marker", "bench_waist", "format_table", "run"]


def run(name: str, **kwargs: Any) -> dict[str, Any]:
    """Run the benchmark ``name`` (foot, waist, marker)."""
    if name not in BENCHES:
        raise ValueError(f"bench {name!r} does not exist; known: {', '.join(sorted(BENCHES))}")
    return BENCHES[name](**kwargs)


def format_table(result: dict[str, Any]) -> str:
    """The bench result as a text table."""
    families = any("filter" in r for r in result["rows"])  # the foot bench's filter families
    lines = [
        f"bench {result['bench']} (peak RSS {result.get('peak_rss_mb', float('nan')):.0f} MB)",
        ("filter " if families else "")
        + f"{'num_envs':>8} {'steps/s':>12} {'filterpy steps/s':>17} {'ratio':>8}",
    ]
    for r in result["rows"]:
        lines.append(
            (f"{r.get('filter', ''):<6} " if families else "")
            + f"{r['num_envs']:>8} {r['steps_per_s']:>12.0f} "
            f"{r['reference_steps_per_s']:>17.1f} {r['ratio']:>8.1f}"
        )
    return "\n".join(lines)
