"""``pednav bench foot``: the native ``FootZupt-v0`` vector env against a filterpy loop.

Measures, for N = 1, 16, 64, 256, the env steps per second of the native vector
env (all N walks in one batched filter, paper policy, autoresets included) and,
in the same process, of N scalar environments stepped one after another, each
with its own ``filterpy.kalman.UnscentedKalmanFilter`` doing the same work
(:class:`pednav_env.testing.reference_foot.FilterpyFootReference`): the same
episodes, the same detector on the same samples, the same strapdown process
function (filterpy loops over the sigma points), the same Q, R and updates.

Both filter families (:mod:`pednav_env.envs.foot_filters`) on the same random
walks (``scenario="random"``, 100 Hz): the paper filter and the shoe family's
action 0 (``real-fixed``: SHOE, a ZUPT at every stance sample).

JSON: ``{"bench": "foot", "rows": [{"filter": "paper", "num_envs": 256,
"steps_per_s": .., "reference_steps_per_s": .., "ratio": ..}, ...]}`` (plus
``peak_rss_mb``).
"""

from __future__ import annotations

from functools import partial
from typing import Any

from agents.bench.timing import DEFAULT_SIZES, bench_native_vs_reference
from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_filters import FILTER_FAMILIES
from pednav_env.envs.foot_zupt import FootZuptVectorEnv
from pednav_env.testing.reference_foot import FilterpyFootReference


def bench_foot(
    sizes: tuple[int, ...] = DEFAULT_SIZES,
    min_seconds: float = 3.0,
    reference_seconds: float = 3.0,
    config: FootZuptConfig | None = None,
    families: tuple[str, ...] = FILTER_FAMILIES,
) -> dict[str, Any]:
    """Steps per second of the native vector env and of the filterpy reference, per
    filter family (``config``: one configuration instead, its own family)."""
    configs = (
        [config]
        if config is not None
        else [FootZuptConfig(filter_family=f, scenario="random") for f in families]
    )
    rows = []
    for cfg in configs:
        result = bench_native_vs_reference(
            "foot",
            partial(FootZuptVectorEnv, config=cfg),
            partial(FilterpyFootReference, cfg),
            cfg.action_dim,
            sizes,
            min_seconds,
            reference_seconds,
            # ≥ 3 rounds: the first interval after alignment is mostly standing (few
            # corrections), so one round alone would flatter the reference.
            reference_min_calls=3,
        )
        rows += [{"filter": cfg.filter_family, **row} for row in result["rows"]]
    return {**result, "rows": rows}
