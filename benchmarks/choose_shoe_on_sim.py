"""Choose a SHOE configuration on calibrated simulated walks only, then score it on
the development recordings (docs/SIM_TO_REAL.md, "Does it predict what works").

1. :func:`agents.choose_shoe.choose_on_simulation`: the SHOE part of
   ``real-fixed``'s search (γ, process and ZUPT noise scales, update mode;
   refined around the winner) on ``--walks`` walks of the calibrated simulator,
   every stride's speed in 0.3–3 m/s, scored by PyShoe's ARMSE against the
   simulated truth. No recording is used.
2. The PyShoe development trials: the chosen setup's ARMSE against
   ``real-fixed``'s (target: mean within 2×).
3. The hallway walks: the chosen setup's mean footprint error against the best
   single γ on those walks (a sweep of γ with the noise scales and update mode
   of the chosen setup, and of ``real-fixed``; the better one; target: within
   1.5×).

Writes ``--out`` (the chosen setup under ``"setup"``: ``pednav run --policy
FILE`` reads it) and prints the figures:

    PYTHONPATH=. .venv/bin/python benchmarks/choose_shoe_on_sim.py \\
        --pyshoe ../shared/data/pyshoe-vicon-dev --hallway ../shared/data/hallway-gcp-dev \\
        --out benchmarks/results/shoe_from_sim.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from agents.choose_shoe import choose_on_simulation, errors_by_recording, threshold_sweep
from pednav_env.io import load_recording
from pednav_env.replay.setup import RealFilterSetup, real_fixed_setup

#: γ of the hallway sweep: 10^6 … 10^9.5, 8 per decade (PyShoe's units).
SWEEP_THRESHOLDS = tuple(float(v) for v in 10.0 ** np.arange(6.0, 9.5 + 1e-9, 0.125))


def mean(values: dict[str, float]) -> float:
    """Mean over recordings (inf if the filter diverged on one)."""
    return float(np.mean(list(values.values())))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pyshoe", required=True, help="directory of PyShoe .mat trials")
    ap.add_argument("--hallway", required=True, help="directory of hallway _LLIO.mat walks")
    ap.add_argument("--walks", type=int, default=24, help="simulated walks for the choice")
    ap.add_argument("--seed", type=int, default=0, help="simulation seed")
    ap.add_argument("--out", default=None, help="write the result as JSON here")
    args = ap.parse_args()
    t0 = time.process_time()
    search = choose_on_simulation(walks=args.walks, seed=args.seed)
    chosen = RealFilterSetup.from_dict(search["setup"])
    cpu_search = time.process_time() - t0
    print(f"chosen on {args.walks} simulated walks ({cpu_search:.0f} s CPU): {search['chosen']}")

    pyshoe = [load_recording(p) for p in sorted(Path(args.pyshoe).glob("*.mat"))]
    hallway = [load_recording(p) for p in sorted(Path(args.hallway).glob("*_LLIO.mat"))]
    fixed = real_fixed_setup()
    py_chosen = errors_by_recording(chosen, pyshoe)
    py_fixed = errors_by_recording(fixed, pyshoe)
    ratio_py = mean(py_chosen) / mean(py_fixed)
    print(
        f"PyShoe dev ({len(pyshoe)} trials), mean ARMSE: chosen on simulation "
        f"{mean(py_chosen):.3f} m, real-fixed "
        f"{mean(py_fixed):.3f} m, ratio {ratio_py:.2f} (target ≤ 2)"
    )
    hw_chosen = errors_by_recording(chosen, hallway)
    hw_fixed = errors_by_recording(fixed, hallway)
    sweeps = {}
    for label, setup in (("chosen", chosen), ("real-fixed", fixed)):
        errors = threshold_sweep(setup, hallway, SWEEP_THRESHOLDS)
        means = errors.mean(axis=0)
        j = int(np.argmin(means))
        sweeps[label] = {
            "thresholds": list(SWEEP_THRESHOLDS),
            "mean_footprint_error_m": [round(float(v), 4) for v in means],
            "best_threshold": SWEEP_THRESHOLDS[j],
            "best_mean_footprint_error_m": float(means[j]),
            "best_per_walk_m": dict(
                zip([r.name for r in hallway], errors[:, j].tolist(), strict=True)
            ),
        }
    best_label = min(sweeps, key=lambda k: sweeps[k]["best_mean_footprint_error_m"])
    best = sweeps[best_label]
    ratio_hw = mean(hw_chosen) / best["best_mean_footprint_error_m"]
    print(
        f"hallway ({len(hallway)} walks), mean footprint error: chosen on simulation "
        f"{mean(hw_chosen):.3f} m, real-fixed "
        f"{mean(hw_fixed):.3f} m, best single γ "
        f"{best['best_mean_footprint_error_m']:.3f} m (γ = {best['best_threshold']:.3g}, "
        f"{best_label}'s noise scales), ratio {ratio_hw:.2f} (target ≤ 1.5)"
    )
    result = {
        "setup": search["setup"],
        "chosen_on_simulation": search["chosen"],
        "simulation": {
            "walks": args.walks,
            "seed": args.seed,
            "model": "calibrated",
            "speed_mps": [0.3, 3.0],
            "stages": search["stages"],
            "folds": search["folds"],
            "per_walk_armse_pyshoe_m": search["per_trial_armse_pyshoe_m"],
            "standing_still_armse_m": search["standing_still_armse_m"],
            "cpu_s": round(cpu_search, 1),
        },
        "pyshoe_dev": {
            "chosen_armse_pyshoe_m": py_chosen,
            "real_fixed_armse_pyshoe_m": py_fixed,
            "ratio_of_means": round(ratio_py, 3),
        },
        "hallway": {
            "chosen_footprint_mean_error_m": hw_chosen,
            "real_fixed_footprint_mean_error_m": hw_fixed,
            "sweeps": sweeps,
            "best_single_threshold_from": best_label,
            "ratio_to_best_single_threshold": round(ratio_hw, 3),
        },
        "cpu_s": round(time.process_time() - t0, 1),
    }
    if args.out:
        Path(args.out).write_text(json.dumps(result, indent=1, default=float) + "\n")


if __name__ == "__main__":
    main()
