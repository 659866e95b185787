"""Evaluate tuning policies on the same held-out episodes.

Every policy plays episodes with seeds S, S+1, …, S+N−1 (evaluation seeds,
below 1 000 000: disjoint from every training seed, see baselines.seeds; one lane of the
native vector env per episode, lane i reset with seed S+i), through SB3's
``evaluate_policy`` on the :class:`agents.sb3_vec.NativeVecEnv` adapter.
An episode's score is its time-averaged horizontal error in metres (marker
env: RMS marker error) = minus its return. Policies are compared with the
paper policy episode by episode (paired t-test on the same seeds).

JSON (DESIGN.md, "Evaluation output")::

    {"env": "pednav/FootZupt-v0", "episodes": 100, "seed": 5000,
     "policies": [{"name": "paper", "mean_error": .., "ci95": [lo, hi],
                   "final_error_pct": .., "divergence_rate": ..,
                   "vs_paper": {"mean_diff": .., "p_value": ..}}, ...]}
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from scipy import stats
from stable_baselines3.common.evaluation import evaluate_policy

import pednav_env  # noqa: F401  (registers the environments)
from agents.policies import load_run, pretrained_dir
from agents.sb3_vec import NativeVecEnv
from baselines import InnovationAdaptivePolicy, PaperPolicy, TunedFixedPolicy
from baselines.seeds import check_evaluation_seeds

#: Policy names understood besides a path to a saved SB3 model (.zip).
BUILTIN_POLICIES = ("paper", "tuned", "adaptive", "pretrained")
#: Lanes per batch when evaluating many episodes.
MAX_LANES = 128


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of one evaluation episode."""

    seed: int
    mean_error: float  # time-averaged horizontal error (m) = −return
    final_error: float  # m
    distance: float  # m walked
    diverged: bool
    #: horizontal error (m) at the end of each decision interval
    error_trace: tuple[float, ...] = ()

    @property
    def final_error_pct(self) -> float:
        return 100.0 * self.final_error / self.distance if self.distance > 0 else math.nan


def load_policy(name: str, action_space: gym.spaces.Box, env_id: str = "") -> Any:
    """A policy by name or from a run directory / saved SB3 model (.zip).

    Names: ``paper`` (action 0), ``tuned`` (the shipped best constant action),
    ``adaptive`` (the innovation-based rule), ``pretrained`` (the shipped
    tuner under ``agents/pretrained/``).
    """
    if name == "paper":
        return PaperPolicy(action_space)
    if name == "tuned":
        return TunedFixedPolicy.for_env(env_id, action_space)
    if name == "adaptive":
        return InnovationAdaptivePolicy(action_space, env_id)
    if name == "pretrained":
        path = pretrained_dir(env_id)
        if not (path / "model.zip").exists():
            raise ValueError(f"no pretrained tuner shipped for {env_id!r} (looked in {path})")
        return load_run(path)
    path = Path(name)
    if path.suffix == ".zip" or path.exists():
        return load_run(path)
    raise ValueError(
        f"unknown policy {name!r}: use one of {', '.join(BUILTIN_POLICIES)} or a path to a "
        "run directory or saved SB3 model (.zip)"
    )


def run_episodes(
    env_id: str,
    policy: Any,
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
) -> list[EpisodeResult]:
    """Play ``episodes`` episodes (seeds ``seed`` …) with ``policy``, in batches."""
    if episodes < 1:
        raise ValueError(f"episodes must be ≥ 1, got {episodes!r}")
    env_kwargs = env_kwargs or {}
    results: list[EpisodeResult] = []
    for start in range(0, episodes, MAX_LANES):
        n = min(MAX_LANES, episodes - start)
        venv = gym.make_vec(
            env_id, num_envs=n, vectorization_mode="vector_entry_point", **env_kwargs
        )
        vec = NativeVecEnv(venv)
        vec.seed(seed + start)
        lane: dict[int, EpisodeResult] = {}
        traces: dict[int, list[float]] = {i: [] for i in range(n)}

        def record(
            local: dict[str, Any], _: dict[str, Any], lane=lane, traces=traces, base=seed + start
        ) -> None:
            i = local["i"]
            if i in lane:
                return
            info = local["info"]
            traces[i].append(float(info["error"]))
            if local["done"]:
                lane[i] = EpisodeResult(
                    seed=base + i,
                    mean_error=-float(local["current_rewards"][i]),
                    final_error=float(info["error"]),
                    distance=float(info["distance"]),
                    diverged=not bool(info["TimeLimit.truncated"]),
                    error_trace=tuple(traces[i]),
                )

        evaluate_policy(
            policy, vec, n_eval_episodes=n, deterministic=True, warn=False, callback=record
        )
        vec.close()
        results.extend(lane[i] for i in range(n))
    return results


def summarize(name: str, res: list[EpisodeResult], paper: list[EpisodeResult]) -> dict[str, Any]:
    """Mean, 95 % CI (Student t), final error %, divergence rate, paired test vs paper."""
    err = np.array([r.mean_error for r in res])
    n = len(err)
    mean = float(err.mean())
    if n > 1:
        half = float(stats.t.ppf(0.975, n - 1) * err.std(ddof=1) / math.sqrt(n))
    else:
        half = 0.0
    if name == "paper":
        vs = {"mean_diff": 0.0, "p_value": None}
    else:
        base = np.array([r.mean_error for r in paper])
        diff = err - base
        if n > 1 and np.any(diff != 0):
            p = float(stats.ttest_rel(err, base).pvalue)
        else:
            p = 1.0
        vs = {"mean_diff": float(diff.mean()), "p_value": p}
    return {
        "name": name,
        "mean_error": mean,
        "ci95": [mean - half, mean + half],
        "final_error_pct": float(np.nanmean([r.final_error_pct for r in res])),
        "divergence_rate": float(np.mean([r.diverged for r in res])),
        "vs_paper": vs,
    }


def evaluate(
    env_id: str,
    policy_names: list[str],
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
    plot_dir: str | Path | None = None,
) -> dict[str, Any]:
    """Evaluate every named policy on the same episodes; returns the JSON object.

    With ``plot_dir``, also saves ``error_over_time.png`` and ``per_episode.png``.
    """
    if not policy_names:
        raise ValueError("no policy named")
    check_evaluation_seeds(seed, episodes)
    probe = gym.make(env_id, **(env_kwargs or {}))
    action_space = probe.action_space
    probe.close()
    policies = {name: load_policy(name, action_space, env_id) for name in policy_names}
    if "paper" not in policies:
        policies = {"paper": PaperPolicy(action_space), **policies}
    outcomes = {
        name: run_episodes(env_id, pol, episodes, seed, env_kwargs)
        for name, pol in policies.items()
    }
    if plot_dir is not None:
        write_plots(env_id, outcomes, Path(plot_dir))
    return {
        "env": env_id,
        "episodes": episodes,
        "seed": seed,
        "policies": [summarize(name, outcomes[name], outcomes["paper"]) for name in policy_names],
    }


def format_table(result: dict[str, Any]) -> str:
    """Plain-text table of an evaluation result."""
    head = (
        f"{'policy':<24} {'mean error (m)':>14} {'95 % CI':>19} {'final % dist':>12} "
        f"{'diverged':>8} {'Δ vs paper':>10} {'p':>8}"
    )
    lines = [
        f"{result['env']}: {result['episodes']} episodes, seeds {result['seed']}…"
        f"{result['seed'] + result['episodes'] - 1}",
        head,
        "-" * len(head),
    ]
    for p in result["policies"]:
        lo, hi = p["ci95"]
        pv = p["vs_paper"]["p_value"]
        lines.append(
            f"{p['name']:<24} {p['mean_error']:>14.3f} {f'[{lo:.3f}, {hi:.3f}]':>19} "
            f"{p['final_error_pct']:>12.2f} {p['divergence_rate']:>8.2f} "
            f"{p['vs_paper']['mean_diff']:>+10.3f} {'—' if pv is None else f'{pv:.2g}':>8}"
        )
    return "\n".join(lines)


def write_plots(env_id: str, outcomes: dict[str, list[EpisodeResult]], out: Path) -> list[Path]:
    """Error over time (mean and quartiles over episodes, per policy) and a per-episode
    comparison against the paper policy."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for name, res in outcomes.items():
        longest = max(len(r.error_trace) for r in res)
        grid = np.full((len(res), longest), np.nan)
        for j, r in enumerate(res):
            grid[j, : len(r.error_trace)] = r.error_trace
        step = np.arange(1, longest + 1)
        line = ax.plot(step, np.nanmedian(grid, axis=0), label=name)[0]
        q1, q3 = np.nanpercentile(grid, [25, 75], axis=0)
        ax.fill_between(step, q1, q3, color=line.get_color(), alpha=0.15)
    ax.set_xlabel("decision step")
    ax.set_ylabel("error (m): median, 25–75 % band")
    ax.set_title(f"{env_id}: error over time ({len(next(iter(outcomes.values())))} episodes)")
    ax.set_yscale("log")
    ax.legend()
    fig.tight_layout()
    files = [out / "error_over_time.png"]
    fig.savefig(files[0], dpi=110)
    plt.close(fig)

    paper = np.array([r.mean_error for r in outcomes["paper"]])
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    for name, res in outcomes.items():
        if name == "paper":
            continue
        ax.scatter(paper, [r.mean_error for r in res], s=12, label=name, alpha=0.7)
    lim = [min(paper.min(), 1e-3), paper.max() * 1.1]
    ax.plot(lim, lim, "k:", lw=1, label="equal to paper")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("paper policy: time-averaged error (m)")
    ax.set_ylabel("policy: time-averaged error (m)")
    ax.set_title(f"{env_id}: per episode (below the line = better)")
    ax.legend(fontsize="small")
    fig.tight_layout()
    files.append(out / "per_episode.png")
    fig.savefig(files[1], dpi=110)
    plt.close(fig)
    return files
