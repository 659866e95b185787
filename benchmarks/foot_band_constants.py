"""Each FootZupt speed band's oracle constant against the shipped ``tuned`` on walks of
that band (shoe family; docs/RESULTS.md).

For every searched band of the shipped oracle table (``baselines/oracle_actions.json``,
key ``pednav/FootZupt-v0:shoe``), the band's constant and the shipped tuned constant
play the same 64 fresh training walks of the band (seeds from
:data:`pednav_env.seeds.REEVALUATION_SEED`, the band restriction of
``CONTEXTS[...].restrict``); prints both means and the paired t-test. Training-side
episodes only. Command:

    PYTHONPATH=. .venv/bin/python benchmarks/foot_band_constants.py
"""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np
from scipy import stats

from baselines.oracle import CONTEXTS, OraclePolicy
from baselines.tuned import TunedFixedPolicy, constant_action_errors
from pednav_env.seeds import REEVALUATION_SEED

ENV_ID = "pednav/FootZupt-v0"


def main() -> None:
    split = CONTEXTS["pednav/FootZupt-v0:shoe"]
    space = gym.make(ENV_ID, filter="shoe").action_space
    tuned = TunedFixedPolicy.for_env(ENV_ID, space, "shoe").action
    oracle = OraclePolicy.for_env(ENV_ID, space, "shoe")
    seeds = [REEVALUATION_SEED + i for i in range(64)]
    for label in split.searched:
        start = time.perf_counter()
        band = oracle.actions[split.labels.index(label)]
        errors = constant_action_errors(
            ENV_ID, np.stack([band, tuned]), seeds, split.restrict(label)
        )
        p = stats.ttest_rel(errors[0], errors[1]).pvalue
        print(
            f"{label}: band constant {errors[0].mean():.3f} m, tuned {errors[1].mean():.3f} m, "
            f"difference {(errors[0] - errors[1]).mean():+.3f} m (paired t p {p:.2g}); "
            f"{time.perf_counter() - start:.0f} s",
            flush=True,
        )


if __name__ == "__main__":
    main()
