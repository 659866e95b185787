"""How hard are simulated walks to navigate, beside the recordings, and which part of the
simulator makes them so? (docs/SIM_TO_REAL.md, "The error level and where it comes from")

The recordings' measure on simulated walks: calibrated walks at the PyShoe trials' own
speeds (every stride at 0.3–1.4 m/s, 30–60 s, turns and stops;
``agents.choose_shoe.simulated_recordings``, walk i from ``default_rng([seed, i])``)
replayed by ``pednav run``'s runner with ``real-fixed``'s setup, scored by PyShoe's
ARMSE against the simulated truth, over a grid of SHOE thresholds γ (the other settings
``real-fixed``'s; ``agents.choose_shoe.threshold_sweep``). Beside them, the 23 PyShoe
development trials on the same grid. Simulator arms on the same walks (same routes
and walkers; each arm changes one part):

- ``calibrated``: the shipped model (MicroStrain 3DM-GX5-25 grade, calibrated stance);
- ``ideal IMU``: the same motion, IMU readings without any error;
- ``no stance micro-motion``: the calibrated IMU grade; the stance's micro-motion and
  roll-over amplitudes at their floor (quiet and edge 10⁻⁷ rad, roll-over 0), every other
  walker value kept;
- ``ideal IMU, no micro-motion``: both;
- ``shorter heel strike``: the shipped model with the heel-strike phase at 0.77 of the
  heel-off phase (``StanceRandomization.heel_strike_scale``; 0.23/0.30, the recorded
  and simulated shares of the non-stance run after the pitch rate's last zero crossing),
  not refitted;
- ``mid pitch at the midpoint``: the shipped model with each walking stride's mid-swing
  pitch knot at the midpoint of its toe-off and heel-strike knots
  (``StanceRandomization.mid_pitch_midpoint``), not refitted;
- ``swing roll``: the shipped model with 0.25 rad added to every stride's mid-swing roll
  knot (``StanceRandomization.swing_roll_rad``), not refitted;
- ``heel rocker``: the shipped model with its opt-in heel rocker
  (``StanceRandomization.heel_rocker``: the heel comes to rest on its footfall instead of
  running past it and sliding back; docs/SIM_TO_REAL_CANDIDATES.md), not refitted.

With ``--circles`` every leg of every simulated walk is on the trials' circles: each
stride turns by the leg's drawn heading change in the trials' pooled 25th–75th
percentile of |turn per stride| (0.79–1.43 rad;
:func:`pednav_env.calibration.path_turns.pooled_turn_range`), the PyShoe trials'
kind of walk (docs/SIM_TO_REAL.md, "The trials walk circles").

Nothing is chosen on these runs.

    PYTHONPATH=. .venv/bin/python benchmarks/sim_error_budget.py --walks 100 \\
        --json benchmarks/results/sim_error_budget.json
    PYTHONPATH=. .venv/bin/python benchmarks/sim_error_budget.py --walks 100 --circles \\
        --json benchmarks/results/sim_error_budget_circles.json
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import bootstrap

from agents.choose_shoe import simulated_recordings, threshold_sweep
from pednav_env.calibration.path_turns import pooled_turn_range
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.sources import load_walk
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.io import load_recording
from pednav_env.replay.setup import real_fixed_setup

#: The PyShoe trials' walking speeds (m/s, from their truth: 0.34–1.36).
SPEED_MPS = (0.3, 1.4)
#: Walk length (s), ``agents.choose_shoe``'s (the trials are 17–56 s).
DURATION_S = (30.0, 60.0)
#: Development seed of the walks.
SEED = 22_600
#: γ grid: ``benchmarks/gamma_response.py``'s, 10^(7.125 + 0.25 k), k = 0 … 8.
THRESHOLDS = tuple(float(10.0 ** (7.125 + 0.25 * k)) for k in range(9))
#: Index of the grid point next to ``real-fixed``'s γ (2.25·10⁷): 2.37·10⁷.
REAL_FIXED_INDEX = 1


def arms() -> dict[str, SimModel]:
    """The simulator arms of the module docstring."""
    calibrated = StanceRandomization.calibrated()
    still = replace(
        calibrated,
        quiet_log10_mean=-7.0,
        quiet_log10_std=0.0,
        edge_log10_mean=-7.0,
        edge_log10_std=0.0,
        roll_rad=0.0,
    )
    return {
        "calibrated": SimModel("calibrated", "microstrain_gx5", calibrated),
        "ideal IMU": SimModel("ideal IMU", "ideal", calibrated),
        "no stance micro-motion": SimModel("no micro-motion", "microstrain_gx5", still),
        "ideal IMU, no micro-motion": SimModel("ideal, no micro-motion", "ideal", still),
        "heel rocker": SimModel(
            "heel rocker", "microstrain_gx5", replace(calibrated, heel_rocker=True)
        ),
        "heel rocker, monotone pitch": SimModel(
            "heel rocker, monotone pitch",
            "microstrain_gx5",
            replace(calibrated, heel_rocker=True, monotone_pitch=True),
        ),
        "shorter heel strike": SimModel(
            "shorter heel strike", "microstrain_gx5", replace(calibrated, heel_strike_scale=0.77)
        ),
        "mid pitch at the midpoint": SimModel(
            "mid pitch at the midpoint",
            "microstrain_gx5",
            replace(calibrated, mid_pitch_midpoint=True),
        ),
        "swing roll": SimModel(
            "swing roll", "microstrain_gx5", replace(calibrated, swing_roll_rad=0.25)
        ),
    }


def summary(errors: np.ndarray) -> dict[str, Any]:
    """Per γ over walks: the mean (95 % percentile bootstrap interval over walks, 10 000
    resamples, seed 0), the median and the number of diverged walks; means and medians
    over the walks on which no γ diverged."""
    kept = np.isfinite(errors).all(axis=1)
    e = errors[kept]
    ci = bootstrap((e,), np.mean, n_resamples=10_000, method="percentile", random_state=0)
    return {
        "walks": int(errors.shape[0]),
        "walks_kept": int(kept.sum()),
        "diverged_walks": [int(v) for v in np.sum(~np.isfinite(errors), axis=0)],
        "mean_armse_m": [float(v) for v in e.mean(axis=0)],
        "mean_ci_low_m": [float(v) for v in ci.confidence_interval.low],
        "mean_ci_high_m": [float(v) for v in ci.confidence_interval.high],
        "median_armse_m": [float(v) for v in np.median(e, axis=0)],
    }


def run(walks: int, seed: int, pyshoe: Path, circles: bool = False) -> dict[str, Any]:
    setup = real_fixed_setup()
    paths = sorted(pyshoe.glob("*.mat"))
    turn = pooled_turn_range([load_walk(p) for p in paths]) if circles else None
    result: dict[str, Any] = {
        "speed_mps": list(SPEED_MPS),
        "duration_s": list(DURATION_S),
        "seed": seed,
        "thresholds": list(THRESHOLDS),
        "turn_per_stride_rad": None if turn is None else list(turn),
    }
    trials = [load_recording(p) for p in paths]
    result["PyShoe trials"] = summary(threshold_sweep(setup, trials, THRESHOLDS))
    for name, model in arms().items():
        recordings = simulated_recordings(model, walks, seed, SPEED_MPS, DURATION_S, turn)
        result[name] = summary(threshold_sweep(setup, recordings, THRESHOLDS))
    return result


def print_table(result: dict[str, Any]) -> None:
    k = REAL_FIXED_INDEX
    print(f"at γ = {THRESHOLDS[k]:.3g} (real-fixed's 2.25e7), PyShoe ARMSE (m):")
    print(f"{'':28s} {'kept':>9s} {'mean [95 % CI]':>22s} {'median':>8s} {'best γ (mean)':>14s}")
    for name, s in result.items():
        if not isinstance(s, dict):
            continue
        mean = np.array(s["mean_armse_m"])
        print(
            f"{name:28s} {s['walks_kept']:4d}/{s['walks']:<4d} "
            f"{mean[k]:7.3f} [{s['mean_ci_low_m'][k]:.3f}, {s['mean_ci_high_m'][k]:.3f}] "
            f"{s['median_armse_m'][k]:8.3f} {THRESHOLDS[int(np.argmin(mean))]:14.3g}"
        )
    print("mean ARMSE (m) per γ:")
    print(f"{'γ':28s} " + " ".join(f"{g:7.2g}" for g in THRESHOLDS))
    for name, s in result.items():
        if isinstance(s, dict):
            print(f"{name:28s} " + " ".join(f"{v:7.3f}" for v in s["mean_armse_m"]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--walks", type=int, default=100)
    parser.add_argument("--seed", type=int, default=SEED, help="development seeds only")
    parser.add_argument("--pyshoe", type=Path, default=Path("../shared/data/pyshoe-vicon-dev"))
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--load", type=Path, help="a stored --json result: run nothing")
    parser.add_argument(
        "--circles", action="store_true", help="every leg on the PyShoe trials' circles"
    )
    args = parser.parse_args()
    result = (
        json.loads(args.load.read_text())
        if args.load
        else run(args.walks, args.seed, args.pyshoe, args.circles)
    )
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
