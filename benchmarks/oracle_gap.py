"""How much of the tuned → oracle gap each policy closes, from a saved evaluation.

.venv/bin/python benchmarks/oracle_gap.py RESULT.json [--markdown]

RESULT.json is the output of ``pednav evaluate ENV --policy paper tuned oracle ... --json``
(every policy on the same seeds, ``episode_errors`` in seed order). Nothing is
replayed. Per policy: mean error, divergence rate, the paired difference against
``tuned`` and against ``oracle`` (paired t-test and Wilcoxon signed-rank), the share
of episodes it beats tuned, and the share of the gap it closes,
(tuned − policy) / (tuned − oracle), undefined (—) unless the oracle beats tuned
(paired t-test, p < 0.05). Run directories named ``.../seedN`` are also
summarised together (mean and spread over training seeds). Works for every env
with an oracle (for FootZupt the policies of the shoe family: ``real-fixed``,
``tuned``, ``oracle``).
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
from scipy import stats


def paired(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """Mean of a − b, paired t-test p and Wilcoxon p (1 when a equals b)."""
    d = a - b
    if not np.any(d != 0):
        return 0.0, 1.0, 1.0
    return float(d.mean()), float(stats.ttest_rel(a, b).pvalue), float(stats.wilcoxon(a, b).pvalue)


def label(name: str) -> str:
    if name == "oracle":
        return "oracle (privileged)"
    return "/".join(Path(name).parts[-2:]) if "/" in name else name


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args()
    result = json.loads(Path(args.result).read_text())
    pol = {p["name"]: p for p in result["policies"]}
    err = {n: np.array(p["episode_errors"]) for n, p in pol.items()}
    tuned, oracle = err["tuned"], err.get("oracle")
    oracle_mean = float(oracle.mean()) if oracle is not None else float("nan")
    gap = float(tuned.mean()) - oracle_mean
    _, p_gap, _ = paired(oracle, tuned) if oracle is not None else (0.0, 1.0, 1.0)
    print(
        f"{result['env']}: {result['episodes']} episodes from seed {result['seed']}; "
        f"tuned {tuned.mean():.4f}, oracle {oracle_mean:.4f}, "
        f"ceiling {100 * gap / tuned.mean():.1f} % of tuned (paired t p = {p_gap:.2g})"
    )
    if not (gap > 0 and p_gap < 0.05):
        gap = float("nan")  # no gap to close
    head = (
        "| policy | mean (m) | diverged | Δ vs tuned (m) | p t | p Wilcoxon | better than tuned "
        "| Δ vs oracle (m) | p t | gap closed |"
    )
    print(head if args.markdown else head.replace("|", " "))
    if args.markdown:
        print("|" + "---|" * (head.count("|") - 1))
    closed_by_seed = []
    for name, e in err.items():
        dt, pt, wt = paired(e, tuned)
        do, po, _ = paired(e, oracle) if oracle is not None else (float("nan"),) * 3
        # undefined when the oracle is not shown better than tuned (no gap to close)
        closed = (tuned.mean() - e.mean()) / gap
        if re.search(r"seed\d+$", name):
            closed_by_seed.append((name, e.mean(), closed, dt, pt))
        row = [
            label(name),
            f"{e.mean():.4f}",
            f"{100 * pol[name]['divergence_rate']:.1f} %",
            f"{dt:+.4f}",
            f"{pt:.2g}",
            f"{wt:.2g}",
            f"{100 * np.mean(e < tuned):.0f} %",
            f"{do:+.4f}",
            f"{po:.2g}",
            "—" if np.isnan(closed) else f"{100 * closed:.0f} %",
        ]
        print("| " + " | ".join(row) + " |" if args.markdown else "  ".join(row))
    if len(closed_by_seed) > 1:
        means = np.array([m for _, m, _, _, _ in closed_by_seed])
        closes = np.array([c for _, _, c, _, _ in closed_by_seed])
        closed_text = (
            "gap closed — (no gap)"
            if np.isnan(closes).any()
            else f"gap closed {100 * closes.mean():.0f} % "
            f"(range {100 * closes.min():.0f}–{100 * closes.max():.0f} %)"
        )
        print(
            f"training seeds ({len(means)}): mean error {means.mean():.4f} "
            f"± {means.std(ddof=1):.4f} (std), range [{means.min():.4f}, {means.max():.4f}]; "
            + closed_text
        )


if __name__ == "__main__":
    main()
