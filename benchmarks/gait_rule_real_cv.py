"""The gait rule fitted on recordings, cross-validated (docs/REAL_DATA.md).

    .venv/bin/python benchmarks/gait_rule_real_cv.py [--shared DIR] [--stages cv lodo all]
        [--json FILE] [--out DIR]

Recordings: the PyShoe development trials (``pyshoe-vicon-dev``, scored by
PyShoe's ARMSE) and the hallway walks (``hallway-gcp-dev/*_LLIO.mat``, scored by
the mean footprint error; the vendor CSVs hold the same walks and are not
used), two groups of equal weight (:mod:`agents.gait_rule_real`).

Stages (each adds to the JSON file, so they can run separately):

- ``cv``: 4 folds; fold k holds out the k-th contiguous block of each group
  (sorted by name) and fits on the rest. Every recording gets one held-out error:
  the headline figures.
- ``lodo``: leave one data set out (fit on the PyShoe trials, score the
  hallway walks; and the other way round): transfer to another walker, place
  and speed range.
- ``all``: the fit on every recording, written as a rule file in ``--out``
  (what would be shipped), with its in-sample errors.
- ``table`` (always): the same recordings under ``real-fixed``, the simulated
  ``tuned`` constant and the simulated ``gait-rule``, PyShoe's per-trial
  optimised SHOE errors and the LSTM tracks of the hallway files, then the
  summary: PyShoe ratio (mean ARMSE / mean per-trial SHOE error) and mean
  footprint error, each with a 95 % bootstrap interval over the recordings
  (``scipy.stats.bootstrap``, 10 000 resamples, seed 0).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from hallway_table import pyshoe_lstm
from scipy import stats
from transfer_by_regime import paired_ratio_ci

from agents.gait_rule import write_params
from agents.gait_rule_real import (
    ARMSE_KEY,
    cross_validate,
    fit,
    folds,
    load_fit_recordings,
)
from agents.run_recording import run_named, summarize

ROOT = Path(__file__).resolve().parents[1]
FIT = {"generations": 12, "popsize": 10, "sigma0": 0.3, "seed": 1}
BASELINES = ("real-fixed", "tuned", "gait-rule")


def _progress(gen: int, best: float) -> None:
    print(f"  generation {gen}: best objective {best:.4f} (log10 m)", file=sys.stderr, flush=True)


def baseline_error(fr, policy: str) -> float:
    return float(summarize(fr.recording, run_named(fr.recording, policy))[fr.metric])


def ci_ratio(err: np.ndarray, ref: np.ndarray) -> list[float]:
    """Paired percentile interval of mean(err) / mean(ref) (this protocol's method)."""
    return paired_ratio_ci(err, ref, ("percentile",))["ci95"]


def ci_mean(err: np.ndarray) -> list[float]:
    res = stats.bootstrap((err,), np.mean, n_resamples=10_000, random_state=0, method="percentile")
    return [float(res.confidence_interval.low), float(res.confidence_interval.high)]


def summary(out: dict, recs) -> dict:
    names = [r.name for r in recs]
    armse = np.array([r.metric == ARMSE_KEY for r in recs])
    cols = {}
    sims = {"_" + k.split("_", 1)[1] for k in out if k.split("_")[0] in ("cv", "lodo", "all")}
    for suffix in ("", *sorted(s for s in sims if s.startswith(("_sim", "_const")))):
        for k in ("cv", "lodo"):
            if k + suffix in out:
                cols[k + suffix] = out[k + suffix]["held_out_errors_m"]
        if "all" + suffix in out:
            cols[f"all{suffix} (in-sample)"] = out["all" + suffix]["errors_m"]
    cols.update({b: out["baselines"][b] for b in BASELINES})
    shoe = np.array([out["references"][n] for n, a in zip(names, armse, strict=True) if a])
    lstm = np.array([out["references"][n] for n, a in zip(names, armse, strict=True) if not a])
    res: dict = {
        "pyshoe_shoe_mean_m": float(shoe.mean()),
        "lstm_footprint_mean_m": float(lstm.mean()),
    }
    for key, errs in cols.items():
        e = np.array([errs[n] for n in names])
        p, h = e[armse], e[~armse]
        res[key] = {
            "pyshoe_ratio": float(p.mean() / shoe.mean()),
            "pyshoe_ratio_ci95": ci_ratio(p, shoe),
            "pyshoe_armse_mean_m": float(p.mean()),
            "hallway_mean_m": float(h.mean()),
            "hallway_mean_ci95": ci_mean(h),
            "hallway_median_m": float(np.median(h)),
        }
    return res


def rule_vs_constant(out: dict, recs) -> dict:
    """Held-out errors of the rule against the constant fitted the same way (each
    ``cv*`` stage with a ``*_const`` twin), per data set: ratio of means and its
    paired 95 % bootstrap interval over recordings."""
    res: dict = {}
    for key in sorted(k for k in out if k.startswith("cv") and not k.endswith("_const")):
        if key + "_const" not in out:
            continue
        rule, const = out[key]["held_out_errors_m"], out[key + "_const"]["held_out_errors_m"]
        for metric, label in ((ARMSE_KEY, "PyShoe ARMSE"), ("footprint_mean_error_m", "hallway")):
            names = [r.name for r in recs if r.metric == metric]
            a = np.array([rule[n] for n in names])
            b = np.array([const[n] for n in names])
            res[f"{key} {label}"] = {
                "ratio": float(a.mean() / b.mean()),
                "ratio_ci95": ci_ratio(a, b),
                "rule_mean_m": float(a.mean()),
                "constant_mean_m": float(b.mean()),
                "rule_lower": int(np.sum(a < b)),
                "recordings": len(names),
            }
    return res


def print_summary(res: dict) -> None:
    print(
        f"PyShoe per-trial-optimised SHOE: {res['pyshoe_shoe_mean_m']:.4f} m; "
        f"hallway LSTM: {res['lstm_footprint_mean_m']:.2f} m"
    )
    print("| rule / policy | PyShoe ratio [95 % CI] | hallway footprint m [95 % CI] | median |")
    print("|---|---|---|---|")
    for key, m in res.items():
        if not isinstance(m, dict):
            continue
        lo, hi = m["pyshoe_ratio_ci95"]
        hlo, hhi = m["hallway_mean_ci95"]
        print(
            f"| {key} | {m['pyshoe_ratio']:.2f}× [{lo:.2f}, {hi:.2f}] | "
            f"{m['hallway_mean_m']:.2f} [{hlo:.2f}, {hhi:.2f}] | {m['hallway_median_m']:.2f} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--stages", nargs="*", default=["cv", "lodo", "all"])
    ap.add_argument("--json", default=str(ROOT / "benchmarks/results/gait_rule_real_cv.json"))
    ap.add_argument("--out", default=str(ROOT / "runs/gait-rule-recordings"))
    ap.add_argument(
        "--simulated-episodes",
        type=int,
        default=0,
        help="add a group of N calibrated simulated training walks to every fit "
        "(results under the stage names + '_simN')",
    )
    ap.add_argument(
        "--constant",
        action="store_true",
        help="fit the best constant instead of the rule (slope held at 0; results under "
        "the stage names + '_const'): the comparator for what adapting adds",
    )
    args = ap.parse_args()
    sim = args.simulated_episodes
    suffix = (f"_sim{sim}" if sim else "") + ("_const" if args.constant else "")
    fit_settings = {**FIT, "simulated_episodes": sim, "constant": args.constant}
    shared = Path(args.shared)
    hallway = sorted((shared / "hallway-gcp-dev").glob("*_LLIO.mat"))
    recs = load_fit_recordings([shared / "pyshoe-vicon-dev", *hallway])
    path = Path(args.json)
    out = json.loads(path.read_text()) if path.exists() else {}
    out["fit_settings"] = FIT
    out["recordings"] = [[r.name, r.group, r.metric] for r in recs]
    save = lambda: path.write_text(json.dumps(out, indent=1) + "\n")  # noqa: E731
    t0 = time.time()
    if "references" not in out:
        refs = {}
        for r in recs:
            if r.metric == ARMSE_KEY:
                refs[r.name] = float(r.recording.metadata["pyshoe_trial_error_m"]["shoe"])
            else:
                p = next(h for h in hallway if h.stem == r.name)
                refs[r.name] = pyshoe_lstm(p)["footprint_mean_error_m"]
        out["references"] = refs
    if "baselines" not in out:
        out["baselines"] = {b: {r.name: baseline_error(r, b) for r in recs} for b in BASELINES}
        save()
    if "cv" in args.stages:
        print("4-fold cross-validation", file=sys.stderr)
        out["cv" + suffix] = cross_validate(
            recs, folds(recs, 4), progress=_progress, **fit_settings
        )
        save()
    if "lodo" in args.stages:
        print("leave one data set out", file=sys.stderr)
        groups = np.array([r.group for r in recs])
        held = [np.flatnonzero(groups == g) for g in sorted(set(groups))]
        out["lodo" + suffix] = cross_validate(recs, held, progress=_progress, **fit_settings)
        save()
    if "all" in args.stages:
        print("fit on all recordings", file=sys.stderr)
        params, record = fit(recs, progress=_progress, **fit_settings)
        out["all" + suffix] = {"c": list(params.c), **record}
        write_params(params, Path(args.out + suffix) / "gait_rule.json", record)
        save()
    out["summary"] = summary(out, recs)
    out["rule_vs_constant"] = rule_vs_constant(out, recs)
    out["seconds_last_run"] = round(time.time() - t0, 1)
    save()
    print_summary(out["summary"])
    for key, m in out["rule_vs_constant"].items():
        lo, hi = m["ratio_ci95"]
        print(
            f"held-out {key}: rule / constant {m['ratio']:.3f} [{lo:.3f}, {hi:.3f}] "
            f"({m['rule_mean_m']:.4f} m against {m['constant_mean_m']:.4f} m; "
            f"rule lower on {m['rule_lower']}/{m['recordings']})"
        )


if __name__ == "__main__":
    main()
