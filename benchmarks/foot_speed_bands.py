"""The calibrated scenario of pednav/FootZupt-v0 per speed band: how the episodes
are spread over the bands, and how action 0 of each filter family (paper 003's
filter, ``real-fixed``) or other named policies fare in each (docs/ENV_FOOT.md).

Each policy plays the first episode of seeds S … S+N−1 (development evaluation
seeds) in one vector env of its own filter family: by default action 0 of each
family (``paper``, ``real-fixed``); ``--policies`` names others as ``pednav
evaluate`` does (``tuned``, ``oracle``, ``gait-rule``, ...; stateless policies
only; the privileged oracle gets ``info["context"]``). Every decision interval is filed
under the speed band of its privileged context (``info["context"]``, the truth
walking speed over the interval). Per band: the share of the intervals, the
horizontal error growth over the band's intervals per metre walked in them
(%; not for standing), and the divergences that happened in an interval of
that band (share of all episodes). The shares are those of the first policy's
intervals (until each episode's end or divergence). Command:

    PYTHONPATH=. .venv/bin/python benchmarks/foot_speed_bands.py --episodes 200 --seed 20000
    PYTHONPATH=. .venv/bin/python benchmarks/foot_speed_bands.py --episodes 200 --seed 20800 \
        --policies real-fixed tuned oracle gait-rule
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import gymnasium as gym
import numpy as np

import pednav_env  # noqa: F401  (registers the environments)
from agents.policies import load_policy
from pednav_env.envs.foot_context import SPEED_BANDS
from pednav_env.seeds import check_evaluation_seeds

ENV_ID = "pednav/FootZupt-v0"
DEFAULT_POLICIES = ("paper", "real-fixed")


def band_label(band: tuple[float, float]) -> str:
    lo, hi = band
    return f"≥ {lo:g}" if np.isinf(hi) else f"{lo:g}–{hi:g}"


def play(policy: Any, episodes: int, seed: int) -> dict[str, np.ndarray]:
    """Per band: intervals, error growth (m), distance (m), divergences; plus the
    episodes' durations (s) and mean errors (m). ``policy`` plays on its own
    filter family (``policy.filter_family``)."""
    family = policy.filter_family
    venv = gym.make_vec(
        ENV_ID,
        num_envs=episodes,
        vectorization_mode="vector_entry_point",
        filter=family,
        scenario="calibrated",
    )
    obs, info = venv.reset(seed=seed)
    nb = len(SPEED_BANDS)
    out = {k: np.zeros(nb) for k in ("intervals", "growth_m", "distance_m", "diverged")}
    live = np.ones(episodes, dtype=bool)
    steps = np.zeros(episodes)
    returns = np.zeros(episodes)
    context = info["context"].copy()
    last_err = np.zeros(episodes)
    last_dist = np.zeros(episodes)
    privileged = getattr(policy, "needs_context", False)
    dt = venv.unwrapped.config.decision_interval_s
    while live.any():
        extra = {"context": context} if privileged else {}
        action, _ = policy.predict(obs, deterministic=True, **extra)
        obs, reward, term, trunc, info = venv.step(np.asarray(action, np.float32))
        final = info.get("final_info")
        err = np.array(
            [
                final[i]["error"] if term[i] or trunc[i] else info["error"][i]
                for i in range(episodes)
            ]
        )
        dist = np.array(
            [
                final[i]["distance"] if term[i] or trunc[i] else info["distance"][i]
                for i in range(episodes)
            ]
        )
        band = context[:, 0].astype(int)
        for i in np.flatnonzero(live):
            out["intervals"][band[i]] += 1
            steps[i] += 1
            returns[i] += reward[i]
            if term[i]:
                out["diverged"][band[i]] += 1
            else:
                out["growth_m"][band[i]] += err[i] - last_err[i]
                out["distance_m"][band[i]] += dist[i] - last_dist[i]
        last_err, last_dist = err, dist
        live &= ~(term | trunc)
        context = info["context"].copy()
    venv.close()
    out["duration_s"] = steps * dt
    out["mean_error_m"] = -returns
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--seed", type=int, default=20_000)
    ap.add_argument("--json", action="store_true", help="print the figures as JSON too")
    ap.add_argument(
        "--policies",
        nargs="+",
        default=list(DEFAULT_POLICIES),
        help="policies as pednav evaluate names them (default: action 0 of each family)",
    )
    args = ap.parse_args()
    check_evaluation_seeds(args.seed, args.episodes)
    space = gym.make(ENV_ID, filter="shoe").action_space
    policies = {name: load_policy(name, space, ENV_ID) for name in args.policies}
    results = {name: play(pol, args.episodes, args.seed) for name, pol in policies.items()}
    first = next(iter(results.values()))
    share = first["intervals"] / first["intervals"].sum()
    print(
        f"{ENV_ID}, scenario calibrated, {args.episodes} episodes, seeds {args.seed}…"
        f"{args.seed + args.episodes - 1}, policies {', '.join(policies)}"
    )
    head = f"{'speed band (m/s)':<17} {'share':>6}"
    for name in results:
        head += f" {name + ' growth %':>20} {name + ' div.':>16}"
    print(head)
    print("-" * len(head))
    table = []
    for b, band in enumerate(SPEED_BANDS):
        row = f"{band_label(band):<17} {100 * share[b]:>5.1f}%"
        entry = {"band": list(band), "share": float(share[b])}
        for name, r in results.items():
            d = r["distance_m"][b]
            # standing: the foot hardly moves, a growth per metre means nothing
            growth = 100 * r["growth_m"][b] / d if b > 0 and d > 1.0 else float("nan")
            div = r["diverged"][b] / args.episodes
            row += f" {growth:>20.1f} {100 * div:>15.1f}%"
            entry[name] = {"growth_pct": growth, "diverged_share": float(div)}
        print(row)
        table.append(entry)
    for name, r in results.items():
        print(
            f"{name}: mean time-averaged error {r['mean_error_m'].mean():.2f} m, "
            f"diverged {100 * r['diverged'].sum() / args.episodes:.1f} % of episodes"
        )
    print(
        f"episode length {np.mean(first['duration_s']):.0f} s mean "
        f"(until the end or a divergence of {next(iter(results))})"
    )
    if args.json:
        print(json.dumps(table, default=float))


if __name__ == "__main__":
    main()
