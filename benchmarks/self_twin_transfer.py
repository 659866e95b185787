"""A SHOE threshold chosen per walk on simulated twins of the walk's own strides as its
IMU shows them (no truth), scored on the walk (docs/SIM_TO_REAL.md, "A threshold
chosen on the walk's own twins").

The protocol was written before the run and is not changed after it:

- Per recording (23 PyShoe development trials; 8 hallway walks ``*_LLIO.mat``):
  :func:`agents.twin_choice.choose_threshold_on_twins` with ``real-fixed``'s setup: the
  route from ``real-fixed``'s own detected stance and position track, 20 footfall twins
  of the shipped calibrated model (recording r of its set's sorted list: seed
  100 000·1 + r), the γ grid 1.3·10⁷ … 1.3·10⁹ (that of ``benchmarks/gamma_response.py``),
  the twins' median error (PyShoe ARMSE for the PyShoe trials, the mean footprint error
  for the hallway walks, mirroring how each set is scored). No truth and no footprint of
  any recording enters a choice.
- The recording run with its chosen γ through ``pednav run``'s code path; the ratio of
  means against the targets' references (``real-fixed`` per trial, target ≤ 2; the best
  single γ per walk on the hallway walks, 1.56 m, target ≤ 1.5), the paired BCa interval
  and verdict of ``benchmarks/transfer_by_regime.py`` (met only when the interval's
  upper end is below the target).
- Information only: the same with the route from the filter at the grid's top γ
  (1.3·10⁹); the median stride speed of the IMU route over that of the truth or
  footprint route.

    PYTHONPATH=. .venv/bin/python benchmarks/self_twin_transfer.py [--shared DIR] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from agents.run_recording import summarize
from agents.twin_choice import TWIN_THRESHOLDS, choose_threshold_on_twins, with_threshold
from benchmarks.transfer_by_regime import paired_ratio_ci, verdict
from pednav_env.calibration.path_turns import stride_sequence
from pednav_env.calibration.sources import samples_from_recording
from pednav_env.io import load_recording
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import load_setup, real_fixed_setup

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SEED = 1
#: per set: the pednav run metric, the twins' metric, directory, file pattern, target.
SETS = {
    "PyShoe trials": ("armse_pyshoe_m", "armse", "pyshoe-vicon-dev", "*.mat", 2.0),
    "hallway walks": ("footprint_mean_error_m", "footprints", "hallway-gcp-dev", "*_LLIO.mat", 1.5),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--json", default=str(RESULTS / "self_twin_transfer.json"))
    ap.add_argument(
        "--base",
        default="real-fixed",
        help="the base setup: real-fixed, or a setup JSON file (e.g. "
        "benchmarks/results/shoe_from_sim.json, chosen on simulated walks only)",
    )
    args = ap.parse_args()
    references = json.loads((RESULTS / "transfer_by_regime_choices.json").read_text())
    setup = real_fixed_setup() if args.base == "real-fixed" else load_setup(args.base)
    routes = {"base": setup, "top gamma": with_threshold(setup, TWIN_THRESHOLDS[-1])}
    out: dict[str, Any] = {"base": args.base, "seed": SEED, "thresholds": list(TWIN_THRESHOLDS)}
    t0 = time.process_time()
    for set_name, (metric, twin_metric, folder, pattern, target) in SETS.items():
        paths = sorted((Path(args.shared) / folder).glob(pattern))
        rows: list[dict[str, Any]] = []
        for r, path in enumerate(tqdm(paths, desc=set_name, leave=False)):
            rec = load_recording(path)
            row: dict[str, Any] = {"recording": rec.name}
            truth_speed = float(np.median(stride_sequence(samples_from_recording(rec)).speed_mps))
            for route_name, route_setup in routes.items():
                try:
                    choice = choose_threshold_on_twins(
                        rec,
                        100_000 * SEED + r,
                        setup=setup,
                        route_setup=route_setup,
                        twin_metric=twin_metric,
                    )
                except ValueError as err:  # no route (e.g. one long stance at the top γ)
                    row[route_name] = {"no_route": str(err)}
                    continue
                err = summarize(rec, run_prepared(prepare(rec, choice.setup)))[metric]
                row[route_name] = {
                    "threshold": choice.threshold,
                    "error_m": float(err),
                    "twin_median_m": [
                        float(v) if np.isfinite(v) else None for v in choice.twin_median_m
                    ],
                    "strides": int(choice.strides.speed_mps.size),
                    "median_speed_ratio": float(np.median(choice.strides.speed_mps)) / truth_speed,
                }
            if set_name == "PyShoe trials":  # real-fixed's own error
                ref_run = run_prepared(prepare(rec, real_fixed_setup()))
                row["reference_m"] = float(summarize(rec, ref_run)[metric])
            else:
                row["reference_m"] = float(references["hallway_reference"]["per_walk_m"][rec.name])
            rows.append(row)
        ref = [row["reference_m"] for row in rows]
        summary: dict[str, Any] = {
            "per_recording": rows,
            "target": target,
            "reference_mean_m": float(np.mean(ref)),
        }
        for route_name in routes:
            failed = [row["recording"] for row in rows if "no_route" in row[route_name]]
            if failed:
                summary[route_name] = {"no_route": failed}
                print(f"{set_name}, route from {route_name}: no route on {len(failed)}: {failed}")
                continue
            errs = [row[route_name]["error_m"] for row in rows]
            ci = paired_ratio_ci(errs, ref)
            summary[route_name] = {
                "mean_m": float(np.mean(errs)),
                **ci,
                "verdict": verdict(ci, target),
            }
            lo, hi = ci["ci95"]
            print(
                f"{set_name}, route from {route_name}: mean {np.mean(errs):.3f} m against "
                f"{np.mean(ref):.3f} m: {ci['ratio']:.2f}x [{lo:.2f}, {hi:.2f}] "
                f"(target <= {target}): {summary[route_name]['verdict']}"
            )
            print(
                "  gamma:",
                ", ".join(f"{row[route_name]['threshold']:.1e}" for row in rows),
                "\n  IMU/truth median stride speed:",
                ", ".join(f"{row[route_name]['median_speed_ratio']:.2f}" for row in rows),
                flush=True,
            )
        out[set_name] = summary
    out["cpu_s"] = time.process_time() - t0
    Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
