"""``pednav bench waist``: the native ``WaistStep-v0`` vector env against filterpy.

Measures, for N = 1, 16, 64, 256, the env steps per second of the native vector
env (all N walks through one batched detector and step-fusion filter, paper
policy, autoresets included) and, in the same process, of N scalar environments
stepped one after another, each streaming its samples through the step detector
and running two ``filterpy.kalman.KalmanFilter`` objects
(:class:`pednav_env.testing.reference_waist.FilterpyWaistReference`).

JSON: ``{"bench": "waist", "rows": [{"num_envs": 256, "steps_per_s": ..,
"reference_steps_per_s": .., "ratio": ..}, ...]}`` (plus ``peak_rss_mb``).
"""

from __future__ import annotations

from functools import partial
from typing import Any

from agents.bench.timing import DEFAULT_SIZES, bench_native_vs_reference
from pednav_env.envs.waist_config import WaistStepConfig
from pednav_env.envs.waist_step import WaistStepVectorEnv
from pednav_env.testing.reference_waist import FilterpyWaistReference


def bench_waist(
    sizes: tuple[int, ...] = DEFAULT_SIZES,
    min_seconds: float = 3.0,
    reference_seconds: float = 3.0,
    config: WaistStepConfig | None = None,
) -> dict[str, Any]:
    """Steps per second of the native vector env and of the filterpy reference."""
    config = config or WaistStepConfig()
    return bench_native_vs_reference(
        "waist",
        partial(WaistStepVectorEnv, config=config),
        partial(FilterpyWaistReference, config),
        config.action_dim,
        sizes,
        min_seconds,
        reference_seconds,
    )
