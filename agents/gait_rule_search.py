"""CMA-ES search of the gait-rule parameters (:mod:`agents.gait_rule`) on training walks.

Same protocol as the tuned-constant search (:func:`baselines.tuned.search`):
the candidates are scored by the mean time-averaged error on a fixed set of
training episodes of ``pednav/FootZupt-v0`` with the shoe filter family
(calibrated scenario; the seeds of search episode set ``episode_set``,
:func:`pednav_env.seeds.search_seeds`, set 0 starting at
:data:`pednav_env.seeds.SEARCH_SEED`; common random numbers for all
candidates), one batched vector env per generation with a lane per (candidate,
episode) (:func:`baselines.rollout.first_episode_errors`). The search runs in
x ∈ [−1, 1]⁵ with c = (x0, SLOPE_SCALE · x1, x2, x3, x4), started from the
shipped shoe ``tuned`` constant with c1 = 0. The chosen parameters and that
start (the tuned constant) are then played on fresh training episodes
(:data:`pednav_env.seeds.REEVALUATION_SEED`, the same whatever the episode set
and CMA-ES seed, so searches are compared paired): the honest figure,
``reevaluation``. The start is scored on the search episodes too
(``start_objective_m``) and returned when no candidate beats it (``kept_start``):
CMA-ES never evaluates its own mean.

    python -m agents.gait_rule_search --out runs/gait-rule [--episodes 16
        --generations 8 --popsize 8 --reevaluate 64 --seed 1 --episode-set 0]

writes ``gait_rule.json`` in ``--out`` (a file :class:`agents.gait_rule.GaitRulePolicy`
reads; ``pednav evaluate --policy PATH/gait_rule.json`` plays it). ``--seed``
seeds CMA-ES only; ``--episode-set k`` chooses the training episodes, so
independent searches take a different set and seed each (e.g. ``--seed k
--episode-set k``).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from agents.gait_rule import ENV_ID, FAMILY, N_PARAMS, GaitRuleParams, rule_actions, write_params
from baselines.rollout import first_episode_errors
from baselines.tuned import TunedFixedPolicy, best_of_start_and_search
from pednav_env.seeds import REEVALUATION_SEED, search_seeds

#: c1 = SLOPE_SCALE · x1: a change of 1 in a0 (two decades of γ) per decade of the
#: feature at x1 = 0.5.
SLOPE_SCALE = 2.0
ENV_KWARGS = {"filter": FAMILY}
OUT_NAME = "gait_rule.json"


def to_params(x: np.ndarray) -> np.ndarray:
    """Rule parameters c of search points x (…, 5)."""
    c = np.array(x, dtype=np.float64)
    c[..., 1] *= SLOPE_SCALE
    return c


def rule_errors(cs: np.ndarray, seeds: list[int], base: GaitRuleParams) -> np.ndarray:
    """Time-averaged error of the rule with each parameter row of ``cs`` (m, 5) on
    each seed: (m, len(seeds)); lanes candidate-major."""
    cs = np.atleast_2d(cs)
    lanes = np.repeat(cs, len(seeds), axis=0)
    err = first_episode_errors(
        ENV_ID, lambda obs: rule_actions(obs, lanes, base), seeds * len(cs), ENV_KWARGS
    )
    return err.reshape(len(cs), len(seeds))


def tuned_start() -> np.ndarray:
    """The shipped shoe tuned constant as a search point (x1 = 0)."""
    box = spaces.Box(-1.0, 1.0, (4,), np.float32)
    a = TunedFixedPolicy.for_env(ENV_ID, box, FAMILY).action.astype(np.float64)
    return np.array([a[0], 0.0, a[1], a[2], a[3]])


def search(
    episodes: int = 16,
    generations: int = 8,
    popsize: int = 8,
    sigma0: float = 0.25,
    seed: int = 1,
    reevaluate_episodes: int = 64,
    base: GaitRuleParams | None = None,
    episode_set: int = 0,
) -> tuple[GaitRuleParams, dict[str, Any]]:
    """CMA-ES over the rule's parameters on the training episodes of
    ``episode_set`` (CMA-ES seeded with ``seed``); returns them and the search's
    record."""
    import cma

    if episodes < 1 or generations < 1 or popsize < 2 or reevaluate_episodes < 0:
        raise ValueError(
            "episodes, generations ≥ 1, popsize ≥ 2 and reevaluate_episodes ≥ 0 are required"
        )
    base = base or GaitRuleParams(c=(0.0,) * N_PARAMS)
    seeds = search_seeds(episode_set, episodes)
    x0 = tuned_start()
    es = cma.CMAEvolutionStrategy(
        x0, sigma0, {"bounds": [-1.0, 1.0], "popsize": popsize, "seed": seed, "verbose": -9}
    )
    history, start = [], time.perf_counter()
    for g in range(generations):
        xs = np.asarray(es.ask())
        scores = rule_errors(to_params(xs), seeds, base).mean(axis=1)
        es.tell(list(xs), scores.tolist())
        history.append(float(scores.min()))
        print(f"generation {g + 1}/{generations}: best {scores.min():.3f} m", file=sys.stderr)
    start_objective = float(rule_errors(to_params(x0[None, :]), seeds, base).mean())
    best, objective, kept_start = best_of_start_and_search(es, x0, start_objective)
    c = to_params(best)
    params = replace(base, c=tuple(float(v) for v in c))
    reevaluation = None
    if reevaluate_episodes:
        fresh = [REEVALUATION_SEED + i for i in range(reevaluate_episodes)]
        both = rule_errors(np.stack([c, to_params(x0)]), fresh, base)
        reevaluation = {
            "episodes": reevaluate_episodes,
            "episode_seeds": [fresh[0], fresh[-1]],
            "mean_m": float(both[0].mean()),
            "tuned_mean_m": float(both[1].mean()),
            "episode_errors_m": both[0].round(4).tolist(),
            "tuned_episode_errors_m": both[1].round(4).tolist(),
        }
    record = {
        "objective_m": objective,
        "start_objective_m": start_objective,
        "kept_start": kept_start,
        "evaluations": int(es.result.evaluations),
        "episodes": episodes,
        "episode_set": episode_set,
        "episode_seeds": [seeds[0], seeds[-1]],
        "generations": generations,
        "popsize": popsize,
        "sigma0": sigma0,
        "cma_seed": seed,
        "initial_c": to_params(x0).tolist(),
        "best_per_generation_m": history,
        "seconds": round(time.perf_counter() - start, 1),
        "reevaluation": reevaluation,
    }
    return params, record


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="directory for gait_rule.json")
    ap.add_argument("--episodes", type=int, default=16)
    ap.add_argument("--generations", type=int, default=8)
    ap.add_argument("--popsize", type=int, default=8)
    ap.add_argument("--reevaluate", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1, help="CMA-ES seed")
    ap.add_argument(
        "--episode-set",
        type=int,
        default=0,
        help="training episode set k: seeds SEARCH_SEED + k·SEARCH_SET_STRIDE + i "
        "(pednav_env.seeds.search_seeds; 0 = the shipped search's episodes)",
    )
    args = ap.parse_args(argv)
    try:
        out = Path(args.out)
        if out.exists() and not out.is_dir():
            raise ValueError(f"--out {out}: not a directory")
        params, record = search(
            args.episodes,
            args.generations,
            args.popsize,
            0.25,
            args.seed,
            args.reevaluate,
            episode_set=args.episode_set,
        )
        path = write_params(params, out / OUT_NAME, record)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path}; c = {[round(v, 4) for v in params.c]}")
    if record["reevaluation"]:
        r = record["reevaluation"]
        print(
            f"re-evaluation on {r['episodes']} fresh training episodes: {r['mean_m']:.3f} m "
            f"(tuned constant {r['tuned_mean_m']:.3f} m)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
