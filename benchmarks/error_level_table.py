"""The error level (``pednav sim2real --nav``, :mod:`agents.error_level`) of several
simulator models at several SHOE thresholds, on the 23 PyShoe development trials (PyShoe
ARMSE) and the 8 hallway walks (``*_LLIO.mat``; mean footprint error)
(docs/SIM_TO_REAL.md, "Matched twins").

Each recording against 20 simulated twins per model (``--twins``: by default each twin
walks the recording's own strides, footfall to footfall; ``circles``: its walking speed
(±10 %), length and turn per stride; ``straight``: its speed and length on the
scenario's straight legs, as the table was first measured); the filter is
``real-fixed``'s with its threshold γ replaced by each value of :data:`GAMMAS`
(``real-fixed``'s own 2.25·10⁷ first). Per (model, γ): the recordings covered by their
twins' 5–95 % range, the geometric mean of twins' median over the recording's error,
and the mean percentile (50 ± 6.0 for 23 trials if the twins were the trials' own
distribution). A recording's twins draw from ``default_rng([seed, key, i])``, ``key`` its
:func:`agents.error_level.twin_key` (its footfall points), so they are the twins
``pednav sim2real --nav`` draws for it with the same ``--seed``; the stored
``error_level_table.json`` and ``error_level_table_turns.json`` were measured before
(recording r of a set, walk i: ``default_rng([100000·seed + r, i])``). Nothing is chosen
on these runs.

    PYTHONPATH=. .venv/bin/python benchmarks/error_level_table.py \\
        --json benchmarks/results/error_level_table_footfalls.json
    PYTHONPATH=. .venv/bin/python benchmarks/error_level_table.py --twins circles \\
        --json benchmarks/results/error_level_table_turns.json
    PYTHONPATH=. .venv/bin/python benchmarks/error_level_table.py --twins straight \\
        --json benchmarks/results/error_level_table.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from agents.error_level import DEFAULT_WALKS, TWIN_FORMS, error_level
from agents.twin_choice import with_threshold
from pednav_env.calibration.compare import MODELS, model_from_json
from pednav_env.io import load_recording
from pednav_env.replay.setup import real_fixed_setup

#: Models: the shipped calibrated one, today's (before calibration), the calibrated
#: values with the opt-in heel rocker, unfitted and refitted (v4), and with the
#: heel-strike phase at 0.77 of heel-off (``heel_strike_scale``) and with the mid-swing
#: pitch knot at the midpoint (``mid_pitch_midpoint``) and with 0.25 rad of swing roll
#: (``swing_roll_rad``), none refitted.
MODEL_NAMES = (
    "calibrated",
    "today",
    "benchmarks/results/calibrated_heel_rocker.json",
    "benchmarks/results/calibrate_foot_v4.json",
    "benchmarks/results/calibrated_heel_strike_0.77.json",
    "benchmarks/results/calibrated_mid_pitch_midpoint.json",
    "benchmarks/results/calibrated_swing_roll_0.25.json",
)
GAMMAS = (2.25e7, 1.3e8, 1.3e9)


def run(
    pyshoe: Path,
    hallway: Path,
    gammas: tuple[float, ...],
    walks: int,
    seed: int,
    models: tuple[str, ...] = MODEL_NAMES,
    twins: str = "footfalls",
) -> dict[str, Any]:
    sets = {
        "PyShoe trials": [load_recording(p) for p in sorted(pyshoe.glob("*.mat"))],
        "hallway walks": [load_recording(p) for p in sorted(hallway.glob("*_LLIO.mat"))],
    }
    base = real_fixed_setup()
    out: dict[str, Any] = {
        "walks": walks,
        "seed": seed,
        "gammas": list(gammas),
        "twins": twins,
        "rows": [],
    }
    for name in models:
        model = MODELS[name] if name in MODELS else model_from_json(name)
        for gamma in gammas:
            setup = with_threshold(base, gamma)
            for set_name, recordings in sets.items():
                report = error_level(
                    recordings, model, walks, seed, setup, f"γ = {gamma:.3g}", twins
                )
                summary = report.to_json()
                summary.pop("rows")
                out["rows"].append({"set": set_name, "gamma": gamma, **summary})
    return out


def print_table(result: dict[str, Any]) -> None:
    print(
        f"{'set':14s} {'model':24s} {'γ':>8s} {'covered':>8s} {'median ratio':>13s} "
        f"{'mean pct':>9s}"
    )
    for r in result["rows"]:
        print(
            f"{r['set']:14s} {r['model']:24s} {r['gamma']:8.3g} "
            f"{r['covered']:4d}/{r['recordings']:<3d} "
            f"{r['ratio_geomean']:13.2f} {r['mean_percentile']:9.1f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pyshoe", type=Path, default=Path("../shared/data/pyshoe-vicon-dev"))
    parser.add_argument("--hallway", type=Path, default=Path("../shared/data/hallway-gcp-dev"))
    parser.add_argument("--walks", type=int, default=DEFAULT_WALKS)
    parser.add_argument("--seed", type=int, default=0, help="simulation seed (development)")
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--load", type=Path, help="a stored --json result: run nothing")
    parser.add_argument(
        "--models", nargs="+", default=list(MODEL_NAMES), help="model names or JSON files"
    )
    parser.add_argument(
        "--twins",
        choices=TWIN_FORMS,
        default="footfalls",
        help="how twins walk: each recording's own strides (default), circles of its turn "
        "per stride, or the scenario's straight legs (as first measured)",
    )
    args = parser.parse_args()
    if args.load:
        result = json.loads(args.load.read_text())
    else:
        result = run(
            args.pyshoe,
            args.hallway,
            GAMMAS,
            args.walks,
            args.seed,
            tuple(args.models),
            args.twins,
        )
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
