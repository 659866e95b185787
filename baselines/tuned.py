"""Tuned-fixed baseline: the best constant action, found by CMA-ES on training seeds.

This is the honest bar for a learned tuner: a tuner that only matches it has
learned nothing adaptive. The search (:func:`search`) minimises the mean
time-averaged error of a constant action over a fixed set of training
episodes (common random numbers for all candidates) with CMA-ES (``cma``),
bounds [-1, 1]. Every generation runs as batched vector envs with a lane per
(candidate, episode); ``map_fn``/``n_tasks`` spread a generation's candidates
over several workers (lanes are independent, so the split changes no result).

Results are tables ``{key: result}`` in JSON files (:func:`save_result`); the key
is the env id, with ``:shoe`` appended for the foot envs' shoe filter family
(:func:`result_key`; the paper family keeps the bare env id).
The shipped table is ``tuned_actions.json`` beside this module
(:data:`RESULTS_FILE`); ``TunedFixedPolicy.for_env`` reads it and
``TunedFixedPolicy.from_file`` reads any other.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from baselines.rollout import first_episode_errors
from pednav_env.files import writing
from pednav_env.seeds import REEVALUATION_SEED, SEARCH_SEED

#: The shipped search results (one entry per env id).
RESULTS_FILE = Path(__file__).parent / "tuned_actions.json"
#: File name of a search result in a run directory.
RESULT_NAME = "tuned_actions.json"

#: ``map_fn(fn, items) -> list`` in item order (the builtin ``map`` by default).
MapFn = Callable[[Callable[[Any], Any], Sequence[Any]], Sequence[Any]]


def result_key(env_id: str, filter_family: str | None = None) -> str:
    """Key of a search result: ``env_id``, plus ``:family`` for a filter family other
    than the paper's."""
    return env_id if filter_family in (None, "paper") else f"{env_id}:{filter_family}"


class TunedFixedPolicy:
    """A constant action (SB3 ``predict`` signature) of one filter family (None:
    an env without families)."""

    name = "tuned"

    def __init__(
        self, action: np.ndarray, action_space: spaces.Box, filter_family: str | None = None
    ) -> None:
        self.filter_family = filter_family
        a = np.asarray(action, dtype=np.float32)
        if a.shape != action_space.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"action {a.tolist()} does not fit {action_space}")
        self.action = np.clip(a, action_space.low, action_space.high)
        self.action_space = action_space

    @classmethod
    def for_env(
        cls, env_id: str, action_space: spaces.Box, filter_family: str | None = None
    ) -> TunedFixedPolicy:
        """The shipped search result for ``env_id`` (and filter family)."""
        table = read_results(RESULTS_FILE) if RESULTS_FILE.exists() else {}
        key = result_key(env_id, filter_family)
        if key not in table:
            flag = f" --filter {filter_family}" if filter_family else ""
            raise ValueError(
                f"no tuned-fixed action for {key!r} yet: run `pednav tune {env_id}{flag}`"
            )
        return cls(np.array(table[key]["action"]), action_space, filter_family)

    @classmethod
    def from_file(
        cls,
        path: str | Path,
        env_id: str,
        action_space: spaces.Box,
        filter_family: str | None = None,
    ) -> TunedFixedPolicy:
        """The result for ``env_id`` (and filter family) in a results file written by
        ``pednav tune``. ``filter_family`` None on an env with families: the file's
        only family for ``env_id``."""
        table = read_results(Path(path))
        key = result_key(env_id, filter_family)
        if filter_family is None and key not in table:
            own = [k for k in table if k.partition(":")[0] == env_id]
            if len(own) == 1:
                key, filter_family = own[0], own[0].partition(":")[2] or "paper"
        if key not in table:
            raise ValueError(f"{path}: no tuned-fixed action for {key!r} (it has {sorted(table)})")
        return cls(np.array(table[key]["action"]), action_space, filter_family)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        batch = np.asarray(observation).shape[:-1]
        return np.broadcast_to(self.action, batch + self.action.shape).copy(), state


def read_results(path: Path) -> dict[str, Any]:
    """A results table ``{env_id: {"action": [...], ...}}``; ValueError naming the file
    when it is not one."""
    try:
        table = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a readable tuned-actions JSON file ({exc})") from None
    if not isinstance(table, dict) or not all(
        isinstance(v, dict) and "action" in v for v in table.values()
    ):
        raise ValueError(f"{path}: expected {{env_id: {{'action': [...], ...}}}}")
    return table


def save_result(env_id: str, result: dict[str, Any], path: Path) -> Path:
    """Write ``result`` as the entry ``env_id`` (a :func:`result_key`) in the table
    at ``path`` (other entries kept); returns ``path``."""
    table = read_results(path) if path.exists() else {}
    table[env_id] = result
    path.parent.mkdir(parents=True, exist_ok=True)
    with writing(path):
        path.write_text(json.dumps(table, indent=2) + "\n")
    return path


def constant_action_errors(
    env_id: str,
    actions: np.ndarray,
    episode_seeds: Sequence[int],
    env_kwargs: dict[str, Any] | None = None,
) -> np.ndarray:
    """Time-averaged error of each constant action (rows of ``actions``) on each
    episode seed: shape (len(actions), len(episode_seeds)); one vector env with a
    lane per (action, episode), action-major."""
    actions = np.asarray(actions, dtype=np.float32)
    lanes = np.repeat(actions, len(episode_seeds), axis=0)
    err = first_episode_errors(
        env_id, lambda obs: lanes, list(episode_seeds) * len(actions), env_kwargs
    )
    return err.reshape(len(actions), len(episode_seeds))


def _errors_task(job: tuple[str, np.ndarray, list[int], dict[str, Any] | None]) -> np.ndarray:
    return constant_action_errors(*job)


def best_of_start_and_search(
    es: Any, start: np.ndarray, start_objective: float
) -> tuple[np.ndarray, float, bool]:
    """The better of a CMA-ES search's start (scored on the same episodes as its
    candidates: CMA-ES never evaluates its own mean) and its best candidate, in
    [−1, 1]: ``(point, objective, kept_start)``; the start on a tie."""
    if not float(es.result.fbest) < start_objective:
        return np.array(start, dtype=float), float(start_objective), True
    return np.clip(np.asarray(es.result.xbest), -1, 1), float(es.result.fbest), False


def search(
    env_id: str,
    action_dim: int,
    episodes: int = 16,
    generations: int = 8,
    popsize: int = 8,
    sigma0: float = 0.4,
    seed: int = 1,
    env_kwargs: dict[str, Any] | None = None,
    map_fn: MapFn = lambda fn, items: list(map(fn, items)),
    n_tasks: int = 1,
    on_generation: Callable[[int], None] | None = None,
    reevaluate_episodes: int = 0,
    x0: Sequence[float] | None = None,
) -> dict[str, Any]:
    """CMA-ES over constant actions; returns the result (``save_result`` writes it).

    Each generation's candidates are split into ``n_tasks`` groups run through
    ``map_fn`` (e.g. a Ray backend's ``map``); ``on_generation(1)`` is called after
    each generation and after the final paper-action evaluation.

    ``objective_m`` is the best candidate's mean on the search episodes: the best
    of many noisy draws, so biased low. With ``reevaluate_episodes`` > 0 the
    chosen action and the paper action are also played on that many fresh
    training episodes (seeds from :data:`REEVALUATION_SEED`), reported as
    ``reevaluation`` (the honest figure). ``x0``: the initial mean (default
    action 0, the paper's filter).

    The start (``x0``) is scored on the search episodes too
    (``start_objective_m``; for action 0 that is ``paper_objective_m``) and
    returned when no candidate beats it (``kept_start``): CMA-ES never
    evaluates its own mean, so a warm-started search could otherwise end above
    its start.
    """
    import cma

    if episodes < 1 or generations < 1 or popsize < 2:
        raise ValueError("episodes, generations ≥ 1 and popsize ≥ 2 are required")
    if n_tasks < 1:
        raise ValueError(f"n_tasks must be ≥ 1, got {n_tasks}")
    if reevaluate_episodes < 0:
        raise ValueError(f"reevaluate_episodes must be ≥ 0, got {reevaluate_episodes}")
    ep_seeds = [SEARCH_SEED + i for i in range(episodes)]
    start_mean = np.zeros(action_dim) if x0 is None else np.asarray(x0, dtype=float)
    if start_mean.shape != (action_dim,) or np.any(np.abs(start_mean) > 1):
        raise ValueError(f"x0 must be {action_dim} values in [-1, 1], got {x0!r}")
    es = cma.CMAEvolutionStrategy(
        start_mean,
        sigma0,
        {"bounds": [-1.0, 1.0], "popsize": popsize, "seed": seed, "verbose": -9},
    )
    history = []
    start = time.perf_counter()
    for _ in range(generations):
        cands = np.asarray(es.ask())
        groups = [g for g in np.array_split(cands, min(n_tasks, len(cands))) if len(g)]
        parts = map_fn(_errors_task, [(env_id, g, ep_seeds, env_kwargs) for g in groups])
        scores = np.concatenate(list(parts)).mean(axis=1)
        es.tell(list(cands), scores.tolist())
        history.append(float(scores.min()))
        if on_generation is not None:
            on_generation(1)
    paper = constant_action_errors(env_id, np.zeros((1, action_dim)), ep_seeds, env_kwargs)
    if on_generation is not None:
        on_generation(1)
    if x0 is None:
        start_objective = float(paper.mean())  # the start is action 0, the paper's
    else:
        start_objective = float(
            constant_action_errors(env_id, start_mean[None, :], ep_seeds, env_kwargs).mean()
        )
    best, objective, kept_start = best_of_start_and_search(es, start_mean, start_objective)
    reevaluation = None
    if reevaluate_episodes:
        seeds = [REEVALUATION_SEED + i for i in range(reevaluate_episodes)]
        both = constant_action_errors(
            env_id, np.stack([best, np.zeros(action_dim)]), seeds, env_kwargs
        )
        reevaluation = {
            "episodes": reevaluate_episodes,
            "episode_seeds": [seeds[0], seeds[-1]],
            "mean_m": float(both[0].mean()),
            "paper_mean_m": float(both[1].mean()),
        }
    return {
        "action": best.tolist(),
        "objective_m": objective,
        "paper_objective_m": float(paper.mean()),
        "start_objective_m": start_objective,
        "kept_start": kept_start,
        "evaluations": int(es.result.evaluations),
        "episodes": episodes,
        "episode_seeds": [ep_seeds[0], ep_seeds[-1]],
        "generations": generations,
        "popsize": popsize,
        "initial_mean": start_mean.tolist(),
        "sigma0": sigma0,
        "best_per_generation_m": history,
        "seconds": round(time.perf_counter() - start, 1),
        "env_kwargs": {k: repr(v) for k, v in (env_kwargs or {}).items()},
        "reevaluation": reevaluation,
    }
