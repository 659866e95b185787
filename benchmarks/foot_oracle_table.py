"""A FootZupt speed-band oracle table from a run directory against the shipped one and
``tuned`` (shoe family, development seeds; docs/RESULTS.md).

``pednav evaluate --policy oracle`` plays the shipped table only; this plays the
table of ``pednav tune pednav/FootZupt-v0 --per-context --run-dir DIR`` (without
``--install``) beside it, the shipped ``tuned`` constant and ``real-fixed``, on the
first episodes of seeds S … S+N−1 of the calibrated scenario, and prints the mean,
divergence and the paired t-test and Wilcoxon test against ``tuned``. Command:

    PYTHONPATH=. .venv/bin/python benchmarks/foot_oracle_table.py DIR/oracle_actions.json \
        --episodes 200 --seed 20000
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
from oracle_gap import paired  # benchmarks/oracle_gap.py (the script directory is on sys.path)

import pednav_env  # noqa: F401  (registers the environments)
from agents.evaluate import run_episodes
from baselines import RealFixedPolicy, TunedFixedPolicy
from baselines.oracle import OraclePolicy, read_table
from pednav_env.seeds import check_evaluation_seeds

ENV_ID = "pednav/FootZupt-v0"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("table", help="an oracle_actions.json written by pednav tune --per-context")
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--seed", type=int, default=20_000)
    args = ap.parse_args()
    check_evaluation_seeds(args.seed, args.episodes)
    kwargs = {"filter": "shoe"}
    space = gym.make(ENV_ID, **kwargs).action_space
    table = read_table(Path(args.table))
    policies = {
        "real-fixed": RealFixedPolicy(space),
        "tuned": TunedFixedPolicy.for_env(ENV_ID, space, "shoe"),
        "oracle (privileged, shipped)": OraclePolicy.for_env(ENV_ID, space, "shoe"),
        f"oracle (privileged, {args.table})": OraclePolicy.from_table(
            table, ENV_ID, space, args.table, "shoe"
        ),
    }
    start = time.perf_counter()
    res = {
        n: run_episodes(ENV_ID, p, args.episodes, args.seed, kwargs) for n, p in policies.items()
    }
    err = {n: np.array([r.mean_error for r in rs]) for n, rs in res.items()}
    tuned = err["tuned"]
    print(
        f"{ENV_ID}, shoe family, calibrated scenario, {args.episodes} episodes from seed "
        f"{args.seed} ({time.perf_counter() - start:.0f} s)"
    )
    print("| policy | mean (m) | diverged | Δ vs tuned (m) | Δ vs tuned (%) | p t | p Wilcoxon |")
    print("|---|---|---|---|---|---|---|")
    for name, e in err.items():
        d = e - tuned
        _, p_t, p_w = paired(e, tuned)
        diverged = np.mean([r.diverged for r in res[name]])
        print(
            f"| {name} | {e.mean():.3f} | {100 * diverged:.1f} % | {d.mean():+.3f} "
            f"| {100 * d.mean() / tuned.mean():+.1f} % | {p_t:.2g} | {p_w:.2g} |"
        )


if __name__ == "__main__":
    main()
