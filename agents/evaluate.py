"""Evaluate tuning policies on the same held-out episodes.

Every policy plays episodes with seeds S, S+1, …, S+N−1 (evaluation seeds,
below 1 000 000: disjoint from every training seed, see :mod:`pednav_env.seeds`).
The episodes are played in batches of at most ``lanes`` (one lane of the
native vector env per episode, lane i of a batch reset with its first seed + i)
through SB3's ``evaluate_policy`` on the :class:`pednav_env.sb3.NativeVecEnv`
adapter. SB3 returns episodes in the order they finish; here each is filed
under its lane, so results are in seed order and policies are paired episode
by episode. An episode's score is its time-averaged horizontal error in metres
(marker env: RMS marker error) = minus its return. Policies are compared with
the paper policy by a paired t-test over the same seeds.

A batch (one policy, up to ``lanes`` consecutive seeds) is the unit of work of
both backends (:mod:`agents.backends`): the serial one plays them in turn, the
Ray one as parallel tasks, with identical results.

The JSON object is described in docs/CONTRACTS.md ("pednav evaluate")::

    {"env": "pednav/FootZupt-v0", "episodes": 100, "seed": 5000,
     "policies": [{"name": "paper", "mean_error": .., "ci95": [lo, hi],
                   "final_error_pct": .., "divergence_rate": ..,
                   "divergence_ci95": [lo, hi],
                   "vs_paper": {"mean_diff": .., "p_value": ..},
                   "mean_error_non_diverged": .., "episode_errors": [.., ..],
                   "vs_tuned": {"mean_diff": .., "p_value": ..}}, ...]}

The tuned constant (``tuned``) is played whether named or not when one is shipped
for the env, as the paper policy is, for ``vs_tuned``.

Replay env (recordings): the episodes play the recordings in sequential order
(``trial_order="sequential"``, ``first_trial_seed`` = the first seed, unless the
env arguments say otherwise): the episode of seed s plays recording (s − S) mod n
of the n recordings sorted by name, the same for every policy, so N = n episodes
play each recording once and the paired tests pair the same recording. The JSON
adds ``episode_recordings``: the recording of each episode, in seed order (the
order of every policy's ``episode_errors``).

Foot envs (filter families, :mod:`agents.policies`): each policy plays on its
own family (``"filter"`` in its entry); ``vs_paper`` and ``vs_tuned`` compare it
with its family's action 0 (``paper`` or ``real-fixed``, played whether named
or not) and tuned constant. An env argument ``filter`` sets the family of the
names that take one (``tuned``, ``adaptive``, ``pretrained``).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import load_env_creator
from scipy import stats
from stable_baselines3.common.evaluation import evaluate_policy

import pednav_env  # noqa: F401  (registers the environments)
from agents.episode_result import EpisodeResult
from agents.evaluate_report import write_plots
from agents.policies import BUILTIN_POLICIES, FAMILY_ENVS, ZERO_ACTION, load_policy, split_name
from baselines import PaperPolicy, TunedFixedPolicy
from pednav_env.sb3 import NativeVecEnv
from pednav_env.seeds import check_evaluation_seeds

__all__ = [
    "BUILTIN_POLICIES",
    "MAX_LANES",
    "RECORDING_ENVS",
    "EpisodeBatch",
    "EpisodeResult",
    "evaluate",
    "load_policy",
    "play_batch",
    "refuse_privileged",
    "run_episodes",
    "summarize",
]

#: Lanes per batch when evaluating many episodes.
MAX_LANES = 128
#: Envs whose episodes are recordings (played in sequential order, module docstring).
RECORDING_ENVS = ("pednav/FootZuptReplay-v0",)


def refuse_privileged(env_id: str, name: str, policy: Any = None) -> None:
    """ValueError when policy ``name`` (or its loaded ``policy``) is privileged — it
    reads ``info["context"]``, like the oracle — and ``env_id`` plays recordings:
    there the context (speed band) is derived from the recording's truth track, so
    the score would be that of a policy that sees the truth."""
    if env_id not in RECORDING_ENVS:
        return
    if split_name(name)[0] == "oracle" or getattr(policy, "needs_context", False):
        raise ValueError(
            f"{env_id}: policy {name}: privileged (it reads the simulator's true context, "
            "info['context']); on recordings that context comes from the truth track, so it "
            "cannot be evaluated there"
        )


@dataclass(frozen=True)
class EpisodeBatch:
    """One unit of work: ``policy`` on seeds ``first_seed … first_seed+episodes−1``."""

    env_id: str
    policy: Any
    first_seed: int
    episodes: int
    env_kwargs: dict[str, Any]


def env_options(env_id: str) -> list[str] | None:
    """The keyword arguments the constructor of ``env_id`` takes (None when it does not
    say); ValueError naming ``env_id`` when it is not registered."""
    try:
        spec = gym.spec(env_id)
    except gym.error.Error:
        known = sorted(k for k in gym.registry if k.startswith("pednav/"))
        raise ValueError(f"unknown environment {env_id!r}; known: {', '.join(known)}") from None
    creator = spec.entry_point
    if isinstance(creator, str):
        creator = load_env_creator(creator)
    declared = getattr(creator, "arguments", None)  # the native envs list theirs
    if declared is not None:
        return sorted({"config", "render_mode", *declared})
    params = inspect.signature(creator).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return None
    return sorted(k for k in params if k != "self")


def check_env_kwargs(env_id: str, env_kwargs: dict[str, Any]) -> None:
    """ValueError naming the environment or option when ``env_id`` is not registered
    or its constructor does not take an option of ``env_kwargs``."""
    options = env_options(env_id)
    if options is None:
        return
    for key in env_kwargs:
        if key not in options:
            raise ValueError(f"{env_id} has no option {key!r}; its options: {', '.join(options)}")


class ContextFeed:
    """Hands a policy that declares ``needs_context`` the privileged context of
    the env's current episodes (``predict(..., context=vec.context)``); no other
    policy ever sees it."""

    def __init__(self, policy: Any, vec: NativeVecEnv, env_id: str) -> None:
        self.policy = policy
        self.vec = vec
        self.env_id = env_id

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        if self.vec.context is None:
            raise ValueError(f"{self.env_id} exposes no info['context'] for a privileged policy")
        return self.policy.predict(
            observation, state, episode_start, deterministic, context=self.vec.context
        )


def play_batch(
    batch: EpisodeBatch, on_episode: Callable[[int], None] | None = None
) -> list[EpisodeResult]:
    """Play one batch in a native vector env with a lane per episode; results in seed
    order. ``on_episode(1)`` is called as each episode ends. A policy with
    ``needs_context = True`` also gets the episodes' ``info["context"]``."""
    n = batch.episodes
    refuse_privileged(batch.env_id, str(getattr(batch.policy, "name", "")), batch.policy)
    venv = gym.make_vec(
        batch.env_id, num_envs=n, vectorization_mode="vector_entry_point", **batch.env_kwargs
    )
    vec = NativeVecEnv(venv, split="evaluation")
    vec.seed(batch.first_seed)
    policy = batch.policy
    if getattr(policy, "needs_context", False):
        policy = ContextFeed(policy, vec, batch.env_id)
    lane: dict[int, EpisodeResult] = {}
    traces: dict[int, list[float]] = {i: [] for i in range(n)}

    def record(local: dict[str, Any], _: dict[str, Any]) -> None:
        i = local["i"]
        if i in lane:
            return
        info = local["info"]
        traces[i].append(float(info["error"]))
        if local["done"]:
            lane[i] = EpisodeResult(
                seed=batch.first_seed + i,
                mean_error=-float(local["current_rewards"][i]),
                final_error=float(info["error"]),
                distance=float(info["distance"]),
                diverged=not bool(info["TimeLimit.truncated"]),
                error_trace=tuple(traces[i]),
                trial=str(info["trial"]) if "trial" in info else None,
            )
            if on_episode is not None:
                on_episode(1)

    evaluate_policy(policy, vec, n_eval_episodes=n, deterministic=True, warn=False, callback=record)
    vec.close()
    return [lane[i] for i in range(n)]


def episode_batches(
    env_id: str,
    policy: Any,
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
    lanes: int = MAX_LANES,
) -> list[EpisodeBatch]:
    """Seeds ``seed … seed+episodes−1`` cut into batches of at most ``lanes``."""
    if episodes < 1:
        raise ValueError(f"episodes must be ≥ 1, got {episodes!r}")
    if lanes < 1:
        raise ValueError(f"lanes must be ≥ 1, got {lanes!r}")
    kwargs = dict(env_kwargs or {})
    return [
        EpisodeBatch(env_id, policy, seed + start, min(lanes, episodes - start), kwargs)
        for start in range(0, episodes, lanes)
    ]


def run_episodes(
    env_id: str,
    policy: Any,
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
    on_episode: Callable[[int], None] | None = None,
) -> list[EpisodeResult]:
    """Play ``episodes`` episodes (seeds ``seed`` …) with ``policy``, batch after batch."""
    out: list[EpisodeResult] = []
    for batch in episode_batches(env_id, policy, episodes, seed, env_kwargs):
        out.extend(play_batch(batch, on_episode))
    return out


def paired_test(err: np.ndarray, base: np.ndarray) -> dict[str, float]:
    """Mean difference ``err − base`` over paired episodes and the paired t-test's
    two-sided p-value (1 when nothing differs or there is one episode, 0 when
    every pair differs by the same amount)."""
    diff = err - base
    if len(diff) < 2 or not np.any(diff != 0):
        p = 1.0
    elif np.all(diff == diff[0]):
        p = 0.0  # every pair differs by the same amount: t is infinite
    else:
        p = float(stats.ttest_rel(err, base).pvalue)
    return {"mean_diff": float(diff.mean()), "p_value": p}


def divergence_interval(diverged: np.ndarray) -> tuple[float, float]:
    """The exact (Clopper–Pearson) 95 % interval of the divergence rate from
    per-episode flags: where the rate lies for episodes of the same kind."""
    ci = stats.binomtest(int(np.count_nonzero(diverged)), diverged.size).proportion_ci(
        0.95, method="exact"
    )
    return float(ci.low), float(ci.high)


def summarize(
    name: str,
    res: list[EpisodeResult],
    paper: list[EpisodeResult],
    tuned: list[EpisodeResult] | None = None,
    paper_name: str = "paper",
) -> dict[str, Any]:
    """Mean, 95 % CI (Student t), final error %, divergence rate and its exact 95 %
    interval, the mean over the episodes that did not diverge, the per-episode
    errors (seed order) and paired tests against the paper policy (``paper_name``:
    the action 0 it stands for) and (when played) the tuned constant."""
    err = np.array([r.mean_error for r in res])
    diverged = np.array([r.diverged for r in res])
    n = len(err)
    mean = float(err.mean())
    if n > 1:
        half = float(stats.t.ppf(0.975, n - 1) * err.std(ddof=1) / math.sqrt(n))
    else:
        half = 0.0
    if name == paper_name:
        vs_paper: dict[str, Any] = {"mean_diff": 0.0, "p_value": None}
    else:
        vs_paper = paired_test(err, np.array([r.mean_error for r in paper]))
    if tuned is None:
        vs_tuned: dict[str, Any] | None = None
    elif name == "tuned":
        vs_tuned = {"mean_diff": 0.0, "p_value": None}
    else:
        vs_tuned = paired_test(err, np.array([r.mean_error for r in tuned]))
    return {
        "name": name,
        "mean_error": mean,
        "ci95": [mean - half, mean + half],
        "final_error_pct": float(np.nanmean([r.final_error_pct for r in res])),
        "divergence_rate": float(diverged.mean()),
        "divergence_ci95": [float(v) for v in divergence_interval(diverged)],
        "vs_paper": vs_paper,
        "mean_error_non_diverged": float(err[~diverged].mean()) if (~diverged).any() else None,
        "episode_errors": err.tolist(),
        "vs_tuned": vs_tuned,
    }


def decision_interval_s(env: gym.Env) -> float | None:
    """Seconds of data per env step, when the env's configuration says."""
    config = getattr(env.unwrapped, "config", None)
    value = getattr(config, "decision_interval_s", None)
    return float(value) if value is not None else None


def evaluate(
    env_id: str,
    policy_names: list[str],
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
    plot_dir: str | Path | None = None,
    backend: Any = None,
    on_episode: Callable[[int], None] | None = None,
    lanes: int = MAX_LANES,
) -> dict[str, Any]:
    """Evaluate every named policy on the same episodes; returns the JSON object.

    ``backend``: ``None`` (or the serial backend) plays the batches in this process;
    an :mod:`agents.backends` Ray backend runs them as parallel tasks. ``lanes``:
    episodes per batch (learned policies' outputs can differ in the last bit
    between batch sizes, so compare runs made with the same ``lanes``).
    ``on_episode(n)``: progress, n more episodes done. With ``plot_dir``, also
    saves ``error_over_time.png`` and ``per_episode.png``.
    """
    if not policy_names:
        raise ValueError("no policy named")
    env_kwargs = dict(env_kwargs or {})
    check_evaluation_seeds(seed, episodes)
    if plot_dir is not None and Path(plot_dir).exists() and not Path(plot_dir).is_dir():
        raise ValueError(f"plot directory {str(plot_dir)!r} is a file")
    for name in policy_names:  # before the recordings are read
        refuse_privileged(env_id, name)
    if env_id in RECORDING_ENVS:
        env_kwargs.setdefault("trial_order", "sequential")
        env_kwargs.setdefault("first_trial_seed", seed)
    check_env_kwargs(env_id, env_kwargs)
    probe = gym.make(env_id, **env_kwargs)
    action_space = probe.action_space
    interval_s = decision_interval_s(probe)
    probe.close()
    if env_id in FAMILY_ENVS:
        return evaluate_families(
            env_id, policy_names, episodes, seed, env_kwargs, plot_dir, backend, on_episode, lanes
        )
    policies = {name: load_policy(name, action_space, env_id) for name in policy_names}
    for name, pol in policies.items():
        refuse_privileged(env_id, name, pol)
    if "paper" not in policies:
        policies = {"paper": PaperPolicy(action_space), **policies}
    if "tuned" not in policies:
        try:  # the comparison every tuner must win, when a constant is shipped
            policies["tuned"] = TunedFixedPolicy.for_env(env_id, action_space)
        except ValueError:
            pass
    plan = [
        (name, batch)
        for name, pol in policies.items()
        for batch in episode_batches(env_id, pol, episodes, seed, env_kwargs, lanes)
    ]
    outcomes = play_plan(plan, backend, on_episode)
    if plot_dir is not None:
        write_plots(env_id, outcomes, Path(plot_dir), interval_s)
    return {
        "env": env_id,
        "episodes": episodes,
        "seed": seed,
        "policies": [
            summarize(name, outcomes[name], outcomes["paper"], outcomes.get("tuned"))
            for name in policy_names
        ],
        **recordings_played(outcomes),
    }


def recordings_played(outcomes: dict[Any, list[EpisodeResult]]) -> dict[str, Any]:
    """``{"episode_recordings": [...]}`` (seed order) when the episodes played
    recordings, else ``{}``; every policy must have played the same recording
    on the same seed (the pairing), a RuntimeError otherwise."""
    orders = {tuple(r.trial for r in res) for res in outcomes.values()}
    if len(orders) != 1:
        raise RuntimeError("policies played different recordings on the same seeds")
    order = orders.pop()
    if not order or order[0] is None:
        return {}
    return {"episode_recordings": list(order)}


def play_plan(
    plan: list[tuple[Any, EpisodeBatch]],
    backend: Any,
    on_episode: Callable[[int], None] | None,
) -> dict[Any, list[EpisodeResult]]:
    """Play every (key, batch) of ``plan``; the results of each key in seed order."""
    if backend is None or backend.name == "serial":
        played = [play_batch(batch, on_episode) for _, batch in plan]
    else:

        def done(i: int) -> None:
            if on_episode is not None:
                on_episode(plan[i][1].episodes)

        played = backend.map(play_batch, [batch for _, batch in plan], on_done=done)
    outcomes: dict[Any, list[EpisodeResult]] = {key: [] for key, _ in plan}
    for (key, _), results in zip(plan, played, strict=True):
        outcomes[key].extend(results)
    return outcomes


def evaluate_families(
    env_id: str,
    policy_names: list[str],
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any],
    plot_dir: str | Path | None,
    backend: Any,
    on_episode: Callable[[int], None] | None,
    lanes: int,
) -> dict[str, Any]:
    """:func:`evaluate` on an env with filter families: each policy on its own family,
    compared with that family's action 0 and tuned constant (module docstring)."""
    forced = env_kwargs.pop("filter", None)
    probe = gym.make(env_id, **env_kwargs)
    action_space, interval_s = probe.action_space, decision_interval_s(probe)
    probe.close()
    named = [
        (name, load_policy(name, action_space, env_id, filter_family=forced))
        for name in policy_names
    ]
    for name, pol in named:
        refuse_privileged(env_id, name, pol)
    policies: dict[tuple[str, str], Any] = {}
    for name, pol in named:
        family = pol.filter_family or "paper"
        zero = ZERO_ACTION[family]
        if (family, zero) not in policies:
            policies[(family, zero)] = load_policy(zero, action_space, env_id)
        policies[(family, name)] = pol
        if (family, "tuned") not in policies:
            try:  # the comparison every tuner must win, when a constant is shipped
                tuned = load_policy("tuned", action_space, env_id, filter_family=family)
                policies[(family, "tuned")] = tuned
            except ValueError:
                pass
    plan = [
        (key, batch)
        for key, pol in policies.items()
        for batch in episode_batches(
            env_id, pol, episodes, seed, {**env_kwargs, "filter": key[0]}, lanes
        )
    ]
    outcomes = play_plan(plan, backend, on_episode)
    if plot_dir is not None:
        by_name = {
            name if fam == "paper" else f"{name}:{fam}": res
            for (fam, name), res in outcomes.items()
        }
        write_plots(env_id, by_name, Path(plot_dir), interval_s)
    entries = []
    for name, pol in named:
        family = pol.filter_family or "paper"
        zero = ZERO_ACTION[family]
        entry = summarize(
            name,
            outcomes[(family, name)],
            outcomes[(family, zero)],
            outcomes.get((family, "tuned")),
            paper_name=zero,
        )
        entries.append({**entry, "filter": family})
    return {
        "env": env_id,
        "episodes": episodes,
        "seed": seed,
        "policies": entries,
        **recordings_played(outcomes),
    }
