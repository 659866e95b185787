"""Which observation feature of the foot env identifies the walking speed
(docs/RESULTS.md, "The gait-adaptive SHOE rule", "Which feature").

    PYTHONPATH=. .venv/bin/python benchmarks/gait_feature_correlation.py \
        [--walks 16] [--seed 1070000]

Plays ``--walks`` calibrated walks of ``pednav/FootZupt-v0`` (shoe family, one vector
env reset with a training seed) with the shipped shoe ``tuned`` constant, and pairs
each observation (the interval just played) with the truth speed of that interval
(``info["context"]``'s ``speed_mps`` returned before the step: it describes the
interval the step plays). Over the intervals in which the foot moves (speed > 0.2
m/s), prints the Pearson correlation of log10 of each observation feature with
log10 of the speed, largest magnitude first. Only each lane's first episode is used.
The speed is truth and is read for this analysis only; no policy sees it.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import pednav_env  # noqa: F401  (registers the envs)
from agents.policies import load_policy
from pednav_env.envs.foot_context import CONTEXT_FIELDS
from pednav_env.envs.foot_core import OBS_FEATURES

ENV_ID = "pednav/FootZupt-v0"
MOVING_MPS = 0.2


def collect(walks: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(features (K, F), speed (K,)) over the moving intervals of the first episodes."""
    env = gym.make_vec(ENV_ID, num_envs=walks, vectorization_mode="vector_entry_point")
    policy = load_policy("tuned", env.single_action_space, ENV_ID)
    speed_col = CONTEXT_FIELDS.index("speed_mps")
    obs, info = env.reset(seed=seed)
    alive = np.ones(walks, dtype=bool)
    feats, speeds = [], []
    n_feat = len(OBS_FEATURES)
    while alive.any():
        speed = np.asarray(info["context"])[:, speed_col].copy()
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        keep = alive & ~(terminated | truncated) & (speed > MOVING_MPS)
        feats.append(obs[keep, :n_feat])
        speeds.append(speed[keep])
        alive &= ~(terminated | truncated)
    env.close()
    return np.concatenate(feats), np.concatenate(speeds)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--walks", type=int, default=16)
    ap.add_argument("--seed", type=int, default=1_070_000)
    args = ap.parse_args()
    x, v = collect(args.walks, args.seed)
    log_v = np.log10(v)
    rows = []
    for j, feature in enumerate(OBS_FEATURES):
        values = x[:, j]
        ok = values > 0
        if ok.sum() < 10 or np.ptp(np.log10(values[ok])) == 0:
            continue
        r = float(np.corrcoef(np.log10(values[ok]), log_v[ok])[0, 1])
        rows.append((abs(r), r, feature.name, int(ok.sum())))
    print(f"{v.size} moving intervals of {args.walks} walks (reset seed {args.seed})")
    print("| feature | log-log Pearson r | intervals |\n|---|---|---|")
    for _, r, name, n in sorted(rows, reverse=True):
        print(f"| `{name}` | {r:+.3f} | {n} |")


if __name__ == "__main__":
    main()
