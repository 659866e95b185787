"""``pednav bench marker``: the native ``MarkerTrack-v0`` vector env against filterpy.

Measures, for N = 1, 16, 64, 256, the env steps per second of the native vector
env (all N walks in one batched filter, paper policy, autoresets included) and,
in the same process, of N scalar environments stepped one after another, each
the env's own episode core with one ``filterpy.kalman.ExtendedKalmanFilter``
as its filter (:class:`pednav_env.testing.reference_marker.ReferenceMarkerEnv`).

The two loops are timed in alternating chunks of 0.25 s until each has run
``min_seconds`` / ``reference_seconds`` (3 s), so that both see the same load
on a shared machine.

JSON: ``{"bench": "marker", "rows": [{"num_envs": 256, "steps_per_s": ..,
"reference_steps_per_s": .., "ratio": ..}, ...]}`` (plus ``peak_rss_mb``).
"""

from __future__ import annotations

from functools import partial
from typing import Any

from agents.bench.timing import DEFAULT_SIZES, bench_native_vs_reference
from pednav_env.envs.marker_config import MarkerTrackConfig
from pednav_env.envs.marker_track import MarkerTrackVectorEnv
from pednav_env.testing.reference_marker import ReferenceMarkerEnv


def bench_marker(
    sizes: tuple[int, ...] = DEFAULT_SIZES,
    min_seconds: float = 3.0,
    reference_seconds: float = 3.0,
    config: MarkerTrackConfig | None = None,
) -> dict[str, Any]:
    """Steps per second of the native vector env and of the filterpy reference."""
    config = config or MarkerTrackConfig()
    return bench_native_vs_reference(
        "marker",
        partial(MarkerTrackVectorEnv, config=config),
        partial(ReferenceMarkerEnv, config),
        config.action_dim,
        sizes,
        min_seconds,
        reference_seconds,
        interleave=True,
    )
