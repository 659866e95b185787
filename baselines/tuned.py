"""Tuned-fixed baseline: the best constant action, found by CMA-ES on training seeds.

This is the honest bar for a learned tuner: a tuner that only matches it has
learned nothing adaptive. The search (:func:`search`) minimises the mean
time-averaged error of a constant action over a fixed set of training
episodes (common random numbers for all candidates) with CMA-ES (``cma``),
bounds [-1, 1]; every generation runs as one batched vector env with a lane
per (candidate, episode). The result is shipped in ``tuned_actions.json``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from baselines.rollout import first_episode_errors
from baselines.seeds import SEARCH_SEED

RESULTS_FILE = Path(__file__).parent / "tuned_actions.json"


class TunedFixedPolicy:
    """A constant action (SB3 ``predict`` signature)."""

    name = "tuned"

    def __init__(self, action: np.ndarray, action_space: spaces.Box) -> None:
        a = np.asarray(action, dtype=np.float32)
        if a.shape != action_space.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"action {a.tolist()} does not fit {action_space}")
        self.action = np.clip(a, action_space.low, action_space.high)
        self.action_space = action_space

    @classmethod
    def for_env(cls, env_id: str, action_space: spaces.Box) -> TunedFixedPolicy:
        """The shipped search result for ``env_id``."""
        table = json.loads(RESULTS_FILE.read_text()) if RESULTS_FILE.exists() else {}
        if env_id not in table:
            raise ValueError(
                f"no tuned-fixed action for {env_id!r} yet: run `pednav tune {env_id}`"
            )
        return cls(np.array(table[env_id]["action"]), action_space)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        batch = np.asarray(observation).shape[:-1]
        return np.broadcast_to(self.action, batch + self.action.shape).copy(), state


def search(
    env_id: str,
    action_dim: int,
    episodes: int = 16,
    generations: int = 8,
    popsize: int = 8,
    sigma0: float = 0.4,
    seed: int = 1,
    env_kwargs: dict[str, Any] | None = None,
    save: bool = True,
) -> dict[str, Any]:
    """CMA-ES over constant actions; returns (and by default ships) the result."""
    import cma

    if episodes < 1 or generations < 1 or popsize < 2:
        raise ValueError("episodes, generations ≥ 1 and popsize ≥ 2 are required")
    ep_seeds = [SEARCH_SEED + i for i in range(episodes)]
    es = cma.CMAEvolutionStrategy(
        np.zeros(action_dim),
        sigma0,
        {"bounds": [-1.0, 1.0], "popsize": popsize, "seed": seed, "verbose": -9},
    )
    history = []
    start = time.perf_counter()
    for _ in range(generations):
        cands = np.asarray(es.ask())
        lanes = np.repeat(cands, episodes, axis=0)  # candidate-major
        err = first_episode_errors(
            env_id, lambda obs, a=lanes: a.astype(np.float32), ep_seeds * len(cands), env_kwargs
        )
        scores = err.reshape(len(cands), episodes).mean(axis=1)
        es.tell(list(cands), scores.tolist())
        history.append(float(scores.min()))
    paper = first_episode_errors(
        env_id, lambda obs: np.zeros((len(obs), action_dim), np.float32), ep_seeds, env_kwargs
    )
    best = np.clip(np.asarray(es.result.xbest), -1, 1)
    result = {
        "action": best.tolist(),
        "objective_m": float(es.result.fbest),
        "paper_objective_m": float(paper.mean()),
        "evaluations": int(es.result.evaluations),
        "episodes": episodes,
        "episode_seeds": [ep_seeds[0], ep_seeds[-1]],
        "generations": generations,
        "popsize": popsize,
        "best_per_generation_m": history,
        "seconds": round(time.perf_counter() - start, 1),
        "env_kwargs": {k: repr(v) for k, v in (env_kwargs or {}).items()},
    }
    if save:
        table = json.loads(RESULTS_FILE.read_text()) if RESULTS_FILE.exists() else {}
        table[env_id] = result
        RESULTS_FILE.write_text(json.dumps(table, indent=2) + "\n")
    return result
