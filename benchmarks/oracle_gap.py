"""How much of the tuned → oracle gap each policy closes, from a saved evaluation.

.venv/bin/python benchmarks/oracle_gap.py RESULT.json [--markdown]

RESULT.json is the output of ``pednav evaluate ENV --policy paper tuned oracle ... --json``
(every policy on the same seeds, ``episode_errors`` in seed order). Nothing is
replayed. Per policy: mean error, divergence rate, the paired difference against
``tuned`` and against ``oracle`` (paired t-test and Wilcoxon signed-rank), the share
of episodes it beats tuned, and the share of the gap it closes,
(tuned − policy) / (tuned − oracle), printed "n/a (reason)" where it is not defined:
no oracle in the result, an oracle not shown better than tuned (paired t-test,
p < 0.05; the reason gives its ceiling and p), or a policy worse than tuned. Run
directories named ``.../seedN`` are also summarised together (mean and spread over
training seeds). Works for every env
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


def ceiling(tuned: np.ndarray, oracle: np.ndarray | None) -> tuple[float, str | None]:
    """The tuned → oracle gap (m) and why it cannot be closed, or None when it can.

    The gap is tuned − oracle (means over the same episodes). It counts only when the
    oracle beats tuned (gap > 0, paired t-test p < 0.05); otherwise the reason is the
    text printed in the "gap closed" column: there is no oracle in the result, or its
    ceiling is not positive or not shown (the ceiling in % of tuned and its p).
    """
    if oracle is None:
        return float("nan"), "n/a (no oracle)"
    gap = float(tuned.mean() - oracle.mean())
    _, p, _ = paired(oracle, tuned)
    if gap > 0 and p < 0.05:
        return gap, None
    return gap, f"n/a (ceiling {100 * gap / tuned.mean():.1f} %, p = {p:.2g})"


def gap_closed(tuned_mean: float, mean: float, gap: float, reason: str | None) -> str:
    """The "gap closed" cell: (tuned − policy) / (tuned − oracle) in %, or ``reason``
    when there is no gap to close, or "n/a (worse than tuned)" for a policy above
    tuned (a share of the gap is not defined there; its Δ vs tuned says how much)."""
    if reason is not None:
        return reason
    if mean > tuned_mean:
        return "n/a (worse than tuned)"
    return f"{100 * (tuned_mean - mean) / gap:.0f} %"


def seeds_line(rows: list[tuple[str, float, float]], tuned_mean: float, reason: str | None) -> str:
    """Training runs ``.../seedN`` (name, mean error, gap) summarised together."""
    means = np.array([m for _, m, _ in rows])
    text = (
        f"training seeds ({len(means)}): mean error {means.mean():.4f} "
        f"± {means.std(ddof=1):.4f} (std), range [{means.min():.4f}, {means.max():.4f}]; "
    )
    if reason is not None:
        return text + f"gap closed {reason}"
    worse = means > tuned_mean
    closes = np.array([(tuned_mean - m) / gap for _, m, gap in rows])[~worse]
    if not closes.size:
        return text + "gap closed n/a (every seed worse than tuned)"
    text += (
        f"gap closed {100 * closes.mean():.0f} % "
        f"(range {100 * closes.min():.0f}–{100 * closes.max():.0f} %)"
    )
    if worse.any():
        text += f"; {worse.sum()} of {len(means)} seeds worse than tuned (n/a, left out)"
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args()
    result = json.loads(Path(args.result).read_text())
    pol = {p["name"]: p for p in result["policies"]}
    err = {n: np.array(p["episode_errors"]) for n, p in pol.items()}
    if "tuned" not in err:
        raise SystemExit(f"{args.result}: no 'tuned' policy (evaluate with --policy ... tuned)")
    tuned, oracle = err["tuned"], err.get("oracle")
    gap, reason = ceiling(tuned, oracle)
    head_line = (
        f"{result['env']}: {result['episodes']} episodes from seed {result['seed']}; "
        f"tuned {tuned.mean():.4f}, "
    )
    if oracle is None:
        print(head_line + "no oracle in this result (gap closed: n/a)")
    else:
        _, p_gap, _ = paired(oracle, tuned)
        tail = "" if reason is None else "; no gap to close"
        print(
            head_line + f"oracle {oracle.mean():.4f}, ceiling {100 * gap / tuned.mean():.1f} % "
            f"of tuned (paired t p = {p_gap:.2g}){tail}"
        )
    head = (
        "| policy | mean (m) | diverged | Δ vs tuned (m) | p t | p Wilcoxon | better than tuned "
        "| Δ vs oracle (m) | p t | gap closed |"
    )
    print(head if args.markdown else head.replace("|", " "))
    if args.markdown:
        print("|" + "---|" * (head.count("|") - 1))
    seeds = []
    for name, e in err.items():
        vs_tuned = ["—"] * 4
        if name != "tuned":
            dt, pt, wt = paired(e, tuned)
            vs_tuned = [f"{dt:+.4f}", f"{pt:.2g}", f"{wt:.2g}", f"{100 * np.mean(e < tuned):.0f} %"]
        vs_oracle = ["—"] * 2
        if oracle is not None and name != "oracle":
            do, po, _ = paired(e, oracle)
            vs_oracle = [f"{do:+.4f}", f"{po:.2g}"]
        if re.search(r"seed\d+$", name):
            seeds.append((name, float(e.mean()), gap))
        row = [
            label(name),
            f"{e.mean():.4f}",
            f"{100 * pol[name]['divergence_rate']:.1f} %",
            *vs_tuned,
            *vs_oracle,
            gap_closed(float(tuned.mean()), float(e.mean()), gap, reason),
        ]
        print("| " + " | ".join(row) + " |" if args.markdown else "  ".join(row))
    if len(seeds) > 1:
        print(seeds_line(seeds, float(tuned.mean()), reason))


if __name__ == "__main__":
    main()
