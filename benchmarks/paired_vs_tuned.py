"""Paired comparison of a learned tuner with the tuned-fixed action, and what it does.

.venv/bin/python benchmarks/paired_vs_tuned.py [RUN_DIR_OR_NAME] [--env ENV_ID] [--episodes N]
[--seed S] (default: the shipped tuner of pednav/FootZupt-v0, 100 episodes from seed 5000).
"""

import argparse

import gymnasium as gym
import numpy as np
from scipy import stats

from agents.evaluate import load_policy, run_episodes

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policy", nargs="?", default="pretrained")
    ap.add_argument("--env", default="pednav/FootZupt-v0")
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--seed", type=int, default=5000)
    args = ap.parse_args()
    ENV_ID = args.env
    space = gym.make(ENV_ID).action_space
    tuned_pol = load_policy("tuned", space, ENV_ID)
    learned_pol = load_policy(args.policy, space, ENV_ID)
    tuned = np.array(
        [r.mean_error for r in run_episodes(ENV_ID, tuned_pol, args.episodes, args.seed)]
    )
    learned = np.array(
        [r.mean_error for r in run_episodes(ENV_ID, learned_pol, args.episodes, args.seed)]
    )
    diff = learned - tuned
    print(
        f"{args.policy} − tuned: mean diff {diff.mean():+.3f} m, paired t p = "
        f"{stats.ttest_rel(learned, tuned).pvalue:.3g}, Wilcoxon p = "
        f"{stats.wilcoxon(learned, tuned).pvalue:.3g}; better in {np.mean(diff < 0):.0%}"
    )
    venv = gym.make_vec(ENV_ID, num_envs=8, vectorization_mode="vector_entry_point")
    obs, _ = venv.reset(seed=[args.seed + i for i in range(8)])
    acts = []
    for _ in range(200):
        a, _ = learned_pol.predict(obs)
        acts.append(a)
        obs, *_ = venv.step(a)
    acts = np.array(acts)
    print(
        "learned action: mean per knob",
        acts.mean(axis=(0, 1)).round(2),
        "| std over time",
        acts.std(axis=0).mean(axis=0).round(2),
    )
    print("tuned action:", np.round(tuned_pol.action, 2))
