"""Spread of the recordings-plus-simulation gait-rule fit over CMA-ES seeds.

    .venv/bin/python benchmarks/gait_rule_real_seeds.py [--seeds 2 3] [--shared DIR] [--json FILE]

Repeats the shipped fit (all 31 development recordings + 16 simulated walks,
benchmarks/gait_rule_real_cv.py's settings) with other CMA-ES seeds and prints
each fit's parameters, in-sample objective, PyShoe ratio and hallway mean beside the
shipped fit (seed 1, from benchmarks/results/gait_rule_real_cv_sim16.json).
In-sample figures only: the held-out ones are the cross-validation's.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from gait_rule_real_cv import FIT

from agents.gait_rule_real import ARMSE_KEY, fit, load_fit_recordings

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "benchmarks/results/gait_rule_real_cv_sim16.json"


def figures(errors: dict, recs, refs: dict) -> dict:
    p = [r.name for r in recs if r.metric == ARMSE_KEY]
    h = [r.name for r in recs if r.metric != ARMSE_KEY]
    ratio = np.mean([errors[n] for n in p]) / np.mean([refs[n] for n in p])
    return {"pyshoe_ratio": float(ratio), "hallway_mean_m": float(np.mean([errors[n] for n in h]))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[2, 3])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--json", default=str(ROOT / "benchmarks/results/gait_rule_real_seeds.json"))
    args = ap.parse_args()
    shared = Path(args.shared)
    hallway = sorted((shared / "hallway-gcp-dev").glob("*_LLIO.mat"))
    recs = load_fit_recordings([shared / "pyshoe-vicon-dev", *hallway])
    shipped = json.loads(SHIPPED.read_text())
    refs = shipped["references"]
    rows = [
        {
            "cma_seed": 1,
            "c": shipped["all_sim16"]["c"],
            "objective_log10_m": shipped["all_sim16"]["objective_log10_m"],
            **figures(shipped["all_sim16"]["errors_m"], recs, refs),
        }
    ]
    for seed in args.seeds:
        print(f"CMA-ES seed {seed}", file=sys.stderr, flush=True)
        params, record = fit(recs, **{**FIT, "seed": seed}, simulated_episodes=16)
        rows.append(
            {
                "cma_seed": seed,
                "c": list(params.c),
                "objective_log10_m": record["objective_log10_m"],
                **figures(record["errors_m"], recs, refs),
            }
        )
        Path(args.json).write_text(json.dumps({"fits": rows}, indent=1) + "\n")
    print("| CMA-ES seed | c | objective (log10 m) | PyShoe ratio | hallway mean (m) |")
    print("|---|---|---|---|---|")
    for r in rows:
        c = ", ".join(f"{v:.3f}" for v in r["c"])
        print(
            f"| {r['cma_seed']} | ({c}) | {r['objective_log10_m']:.4f} | "
            f"{r['pyshoe_ratio']:.2f}× | {r['hallway_mean_m']:.2f} |"
        )


if __name__ == "__main__":
    main()
