"""A SHOE threshold chosen on simulated twins of *other* recordings, scored on the
held-out one (docs/SIM_TO_REAL.md, "A threshold chosen on other walks' twins").

The protocol was written before the computation and is not changed after it:

- Input: ``benchmarks/results/twin_gamma_response.json`` as stored by
  ``benchmarks/twin_gamma_response.py`` (20 footfall twins per recording of the shipped
  calibrated model, ``real-fixed``'s setup with the SHOE threshold γ on the grid
  1.3·10⁷ … 1.3·10⁹ of ``benchmarks/gamma_response.py``; per recording and γ the twins'
  median error, PyShoe ARMSE or mean footprint error).
- Choice for held-out recording i of a set (23 PyShoe trials; 8 hallway walks): the γ
  minimising the arithmetic mean over the set's *other* recordings of their twins'
  median error (a diverged median counts as infinite; the first γ on ties). Nothing
  of recording i enters its choice: neither its IMU signal nor its truth nor its route.
- Scoring: recording i with ``real-fixed``'s setup and its γ_i through ``pednav run``'s
  code path (:func:`agents.run_recording.summarize` of
  :func:`pednav_env.replay.runner.run_prepared`): PyShoe ARMSE, or the mean footprint
  error. The script checks the stored own errors against it.
- Ratio of means over recordings against the targets' references: ``real-fixed`` per
  trial (PyShoe, target ≤ 2) and the stored best single γ per walk (hallway, 1.56 m,
  ``transfer_by_regime_choices.json``; target ≤ 1.5); 95 % paired BCa interval and
  verdict as in ``benchmarks/transfer_by_regime.py`` (met only when the upper end is
  below the target).
- Information only: the one γ chosen on all of a set's twins (their routes are the
  scored recordings' own footfalls, so it is not held out) and its ratio.

    PYTHONPATH=. .venv/bin/python benchmarks/twin_choice_transfer.py \\
        [--shared DIR] [--twins FILE] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from agents.run_recording import summarize
from agents.twin_choice import with_threshold
from benchmarks.transfer_by_regime import paired_ratio_ci, verdict
from pednav_env.io import load_recording
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import real_fixed_setup

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
#: per set: the pednav run metric, the set's directory and file pattern, the target.
SETS = {
    "PyShoe trials": ("armse_pyshoe_m", "pyshoe-vicon-dev", "*.mat", 2.0),
    "hallway walks": ("footprint_mean_error_m", "hallway-gcp-dev", "*_LLIO.mat", 1.5),
}


def leave_one_out_choice(twin_median_m: np.ndarray) -> np.ndarray:
    """Per recording i, the index of the γ minimising the mean over the other
    recordings of ``twin_median_m`` (recordings × thresholds; inf = diverged)."""
    errors = np.asarray(twin_median_m, dtype=float)
    n = errors.shape[0]
    if n < 2:
        raise ValueError("leave-one-out needs at least two recordings")
    chosen = np.empty(n, dtype=int)
    for i in range(n):
        others = np.delete(errors, i, axis=0)
        chosen[i] = int(np.argmin(np.mean(others, axis=0)))
    return chosen


def as_array(rows: list[list[float | None]]) -> np.ndarray:
    """A stored table with ``None`` (diverged) as inf."""
    return np.array([[np.inf if v is None else v for v in row] for row in rows], dtype=float)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--twins", default=str(RESULTS / "twin_gamma_response.json"))
    ap.add_argument("--json", default=str(RESULTS / "twin_choice_transfer.json"))
    args = ap.parse_args()
    stored = json.loads(Path(args.twins).read_text())
    references = json.loads((RESULTS / "transfer_by_regime_choices.json").read_text())
    thresholds = np.asarray(stored["thresholds"], dtype=float)
    setup = real_fixed_setup()
    out: dict[str, Any] = {"twins": Path(args.twins).name, "thresholds": thresholds.tolist()}
    for set_name, (metric, folder, pattern, target) in SETS.items():
        entry = stored[set_name]
        names = entry["recordings"]
        twin = as_array(entry["twin_median_m"])
        own = as_array(entry["own_m"])
        paths = {p.stem: p for p in sorted((Path(args.shared) / folder).glob(pattern))}
        chosen = leave_one_out_choice(twin)
        held_out, reference = [], []
        for i, name in enumerate(names):
            rec = load_recording(paths[name])
            chosen_setup = with_threshold(setup, thresholds[chosen[i]])
            err = summarize(rec, run_prepared(prepare(rec, chosen_setup)))[metric]
            if not np.isclose(err, own[i, chosen[i]], rtol=1e-9):
                stored_m = own[i, chosen[i]]
                raise ValueError(f"{name}: pednav run gives {err}, stored own error {stored_m}")
            held_out.append(float(err))
            if set_name == "PyShoe trials":
                reference.append(float(summarize(rec, run_prepared(prepare(rec, setup)))[metric]))
            else:
                reference.append(float(references["hallway_reference"]["per_walk_m"][name]))
        ci = paired_ratio_ci(held_out, reference)
        pooled = int(np.argmin(np.mean(twin, axis=0)))
        pooled_ci = paired_ratio_ci(list(own[:, pooled]), reference)
        out[set_name] = {
            "metric": metric,
            "reference": "real-fixed" if set_name == "PyShoe trials" else "best single gamma",
            "per_recording": [
                {"recording": n, "threshold": float(thresholds[c]), "error_m": e, "reference_m": r}
                for n, c, e, r in zip(names, chosen, held_out, reference, strict=True)
            ],
            "mean_m": float(np.mean(held_out)),
            "reference_mean_m": float(np.mean(reference)),
            **ci,
            "target": target,
            "verdict": verdict(ci, target),
            "in_sample_information": {
                "threshold": float(thresholds[pooled]),
                "mean_m": float(np.mean(own[:, pooled])),
                **pooled_ci,
            },
        }
        lo, hi = ci["ci95"]
        print(
            f"{set_name}: held-out choice mean {np.mean(held_out):.3f} m against "
            f"{np.mean(reference):.3f} m: {ci['ratio']:.2f}x [{lo:.2f}, {hi:.2f}] "
            f"(target <= {target}): {out[set_name]['verdict']}"
        )
        print("  chosen gamma per recording:", ", ".join(f"{thresholds[c]:.2e}" for c in chosen))
        print(
            f"  information, one gamma on all twins (not held out): {thresholds[pooled]:.2e}, "
            f"{pooled_ci['ratio']:.2f}x [{pooled_ci['ci95'][0]:.2f}, {pooled_ci['ci95'][1]:.2f}]"
        )
    Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
