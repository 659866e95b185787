"""Does the simulator predict where the SHOE threshold works, when its walks walk the
recordings' own strides? (docs/SIM_TO_REAL.md, "The threshold's response on the
recordings' own strides")

For each of the 23 PyShoe development trials and the 8 hallway walks (``*_LLIO.mat``),
20 simulated twins that walk the recording's strides (``pednav sim2real --nav``'s
footfall twins, :mod:`agents.error_level`; the shipped calibrated model; a recording's
twin i from ``default_rng([seed, key, i])``, ``key`` its
:func:`agents.error_level.twin_key`, as ``pednav sim2real --nav`` and
``benchmarks/error_level_table.py`` draw them), and ``real-fixed``'s setup
with its threshold γ on the grid of ``benchmarks/gamma_response.py`` (1.3·10⁷ …
1.3·10⁹), the other knobs ``real-fixed``'s. Per recording and γ: the recording's own
error and its twins' median (PyShoe ARMSE, or the mean footprint error for the hallway
walks; a diverged twin counts as infinite). Per set and γ: the geometric mean over the
recordings of each. Each curve's best γ, and its value at 1.3·10⁹ over its minimum.
Nothing is chosen on these runs (the verdict's rule was written before them).

    PYTHONPATH=. .venv/bin/python benchmarks/twin_gamma_response.py \\
        --json benchmarks/results/twin_gamma_response_stable_seeds.json \\
        --plot docs/figures/twin_gamma_response_stable_seeds.png

``benchmarks/results/twin_gamma_response.json`` and ``docs/figures/twin_gamma_response.png``
are the first run's, whose twins drew from ``default_rng([r, i])``, r the recording's
place in its set (``--load`` shows them).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import gmean
from tqdm import tqdm

from agents.choose_shoe import threshold_sweep
from agents.error_level import (
    DEFAULT_WALKS,
    MIN_TWIN_STRIDES,
    footfall_twin_recordings,
    twin_seed,
)
from benchmarks.gamma_response import THRESHOLDS
from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.path_turns import stride_sequence
from pednav_env.calibration.sources import samples_from_recording
from pednav_env.io import load_recording
from pednav_env.replay.setup import real_fixed_setup


def geometric_mean(values: np.ndarray) -> float:
    """Geometric mean of positive values (inf if any is inf; :func:`scipy.stats.gmean`)."""
    return float(gmean(values))


def run(pyshoe: Path, hallway: Path, walks: int, seed: int) -> dict[str, Any]:
    setup = real_fixed_setup()
    model = MODELS["calibrated"]
    sets = {
        "PyShoe trials": sorted(pyshoe.glob("*.mat")),
        "hallway walks": sorted(hallway.glob("*_LLIO.mat")),
    }
    out: dict[str, Any] = {"thresholds": list(THRESHOLDS), "walks": walks, "seed": seed}
    for set_name, paths in sets.items():
        own_rows, twin_rows, names = [], [], []
        for path in tqdm(paths, desc=set_name, leave=False):
            rec = load_recording(path)
            samples = samples_from_recording(rec)
            strides = stride_sequence(samples)
            if strides.speed_mps.size < MIN_TWIN_STRIDES:
                raise ValueError(f"{path}: fewer than {MIN_TWIN_STRIDES} strides for twins")
            twins = footfall_twin_recordings(
                model, walks, twin_seed(seed, samples), strides, footprints=not rec.has_truth
            )
            own_rows.append(threshold_sweep(setup, [rec], THRESHOLDS)[0])
            twin_rows.append(np.median(threshold_sweep(setup, twins, THRESHOLDS), axis=0))
            names.append(rec.name)
        own, twin = np.array(own_rows), np.array(twin_rows)
        out[set_name] = {
            "recordings": names,
            "own_m": finite_or_none(own),
            "twin_median_m": finite_or_none(twin),
            "own_geomean_m": finite_or_none(
                np.array([geometric_mean(own[:, k]) for k in range(len(THRESHOLDS))])
            ),
            "twin_geomean_m": finite_or_none(
                np.array([geometric_mean(twin[:, k]) for k in range(len(THRESHOLDS))])
            ),
        }
    return out


def finite_or_none(values: np.ndarray) -> list:
    """``values`` as (nested) lists with None (JSON null) where infinite (diverged)."""
    return np.where(np.isfinite(values), values, None).tolist()


def curve_summary(curve: list[float | None]) -> tuple[float, float]:
    """Best γ and the value at the grid's top over the minimum."""
    c = np.array([math.inf if v is None else v for v in curve], dtype=float)
    k = int(np.argmin(np.where(np.isfinite(c), c, np.inf)))
    return THRESHOLDS[k], float(c[-1] / c[k])


def print_table(result: dict[str, Any]) -> None:
    for set_name in ("PyShoe trials", "hallway walks"):
        s = result[set_name]
        print(f"{set_name}: geometric mean over recordings (m)")
        print("  γ          " + " ".join(f"{g:8.2g}" for g in THRESHOLDS))
        for label, key in (("recordings", "own_geomean_m"), ("twins", "twin_geomean_m")):
            print(
                f"  {label:10s} "
                + " ".join("    div." if v is None else f"{v:8.3f}" for v in s[key])
            )
            best, top = curve_summary(s[key])
            print(f"    best γ {best:.3g}; at {THRESHOLDS[-1]:.3g} {top:.2f}× the minimum")


def plot(result: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    for ax, set_name in zip(axes, ("PyShoe trials", "hallway walks"), strict=True):
        s = result[set_name]
        own, twin = (
            np.array([np.nan if v is None else v for v in s[key]], dtype=float)
            for key in ("own_geomean_m", "twin_geomean_m")
        )
        ax.plot(THRESHOLDS, own, "k-s", label=f"{set_name} (recorded)")
        ax.plot(THRESHOLDS, twin, "C3--o", label="their footfall twins (median)")
        ax.axvline(2.25e7, color="0.5", linewidth=1, linestyle=":", label="real-fixed's γ")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("SHOE threshold γ (other settings real-fixed's)")
        ax.set_ylabel(
            "geometric mean of "
            + ("PyShoe ARMSE (m)" if set_name == "PyShoe trials" else "footprint error (m)")
        )
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        ax.set_title(set_name, fontsize=10)
    fig.suptitle(
        "The threshold's response: recordings and twins walking their own strides", fontsize=10
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pyshoe", type=Path, default=Path("../shared/data/pyshoe-vicon-dev"))
    parser.add_argument("--hallway", type=Path, default=Path("../shared/data/hallway-gcp-dev"))
    parser.add_argument("--walks", type=int, default=DEFAULT_WALKS, help="twins per recording")
    parser.add_argument("--seed", type=int, default=0, help="simulation seed (development)")
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--load", type=Path, help="a stored --json result: run nothing")
    parser.add_argument("--plot", type=Path, help="save the figure here")
    args = parser.parse_args()
    result = (
        json.loads(args.load.read_text())
        if args.load
        else run(args.pyshoe, args.hallway, args.walks, args.seed)
    )
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    if args.plot:
        plot(result, args.plot)


if __name__ == "__main__":
    main()
