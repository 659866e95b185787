"""Does the calibrated simulator predict which SHOE threshold works on real walks?
(docs/SIM_TO_REAL.md, "The threshold's response, simulated and recorded")

One knob, the SHOE threshold γ, swept over the same grid in four places, every other
setting at ``real-fixed``'s:

- simulated walks of pednav/FootZupt-v0's calibrated scenario (shoe family, action
  a₀ = log₁₀₀(γ / 2.25·10⁷), the other knobs 0), in the walking regime R_room
  (every stride at 0.3–2.0 m/s) and in the scenario's full 0.3–3 m/s: the mean
  time-averaged error and the divergence rate over the same development episodes;
- the 23 PyShoe development trials (walking, at most 1.4 m/s): the mean of PyShoe's
  ARMSE (:func:`agents.choose_shoe.threshold_sweep`);
- the 8 hallway walks (walking to running): the mean footprint error.

The question is where each curve has its minimum, so the figure draws every curve
divided by its own minimum. Nothing is chosen on these runs; the grid is fixed below
(every second point of ``benchmarks/choose_shoe_on_sim.py``'s hallway grid that the
action can reach).

    PYTHONPATH=. .venv/bin/python benchmarks/gamma_response.py --episodes 200 --seed 22400 \\
        --json benchmarks/results/gamma_response.json --plot docs/figures/gamma_response.png
    PYTHONPATH=. .venv/bin/python benchmarks/gamma_response.py \\
        --load benchmarks/results/gamma_response.json --plot docs/figures/gamma_response.png
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

import pednav_env  # noqa: F401  (registers the environments)
from agents.choose_shoe import simulated_recordings, threshold_knobs, threshold_sweep
from agents.cli_options import speed_config
from agents.evaluate import evaluate
from baselines.tuned import result_key
from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.path_turns import pooled_turn_range
from pednav_env.calibration.sources import load_walk
from pednav_env.io import load_recording
from pednav_env.replay.metrics import pyshoe_armse_as_published, track_errors
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import real_fixed_setup

ENV_ID = "pednav/FootZupt-v0"
#: γ of action 0 (``real-fixed``) and the knob's factor per unit action.
GAMMA_0, GAMMA_STEP = 2.25e7, 100.0
#: The grid (fixed before any run): 10^(7.125 + 0.25 k), k = 0 … 8 (1.3·10⁷ … 1.3·10⁹;
#: the knob reaches 2.25·10⁹).
THRESHOLDS = tuple(float(10.0 ** (7.125 + 0.25 * k)) for k in range(9))
#: Simulated regimes: name → stride speeds (m/s).
REGIMES = {"sim 0.3–2.0 m/s (R_room)": (0.3, 2.0), "sim 0.3–3 m/s": (0.3, 3.0)}


def action_of(gamma: float) -> float:
    """The shoe family's threshold knob a₀ for ``gamma``."""
    return math.log(gamma / GAMMA_0, GAMMA_STEP)


def simulated(episodes: int, seed: int, bound_m: float | None = None) -> dict[str, Any]:
    """Per regime: mean error and divergence rate of each γ on the same episodes;
    ``bound_m``: the env's divergence bound's fixed part (``divergence_error_m``,
    default the env's 25 m)."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        files = []
        for k, gamma in enumerate(THRESHOLDS):
            path = Path(tmp) / f"g{k}.json"
            entry = {result_key(ENV_ID, "shoe"): {"action": [action_of(gamma), 0.0, 0.0, 0.0]}}
            path.write_text(json.dumps(entry))
            files.append(str(path))
        for name, speed in REGIMES.items():
            kwargs = speed_config(ENV_ID, {"filter": "shoe", "scenario": "calibrated"}, speed)
            kwargs["filter"] = "shoe"
            if bound_m is not None:
                kwargs["config"] = replace(kwargs["config"], divergence_error_m=bound_m)
            result = evaluate(ENV_ID, files, episodes, seed, env_kwargs=kwargs)
            rows = {e["name"]: e for e in result["policies"]}
            out[name] = {
                "mean_error_m": [rows[f]["mean_error"] for f in files],
                "divergence_rate": [rows[f]["divergence_rate"] for f in files],
            }
    return out


def recorded(pyshoe: Path, hallway: Path) -> dict[str, Any]:
    """Mean PyShoe ARMSE (23 trials) and mean footprint error (8 walks) per γ; inf
    where a recording diverged."""
    setup = real_fixed_setup()
    out = {}
    for name, paths in (
        ("PyShoe trials (ARMSE)", sorted(pyshoe.glob("*.mat"))),
        ("hallway walks (footprint error)", sorted(hallway.glob("*_LLIO.mat"))),
    ):
        errors = threshold_sweep(setup, [load_recording(p) for p in paths], THRESHOLDS)
        out[name] = {
            "recordings": len(paths),
            "mean_error_m": [finite_or_none(v) for v in errors.mean(axis=0)],
            "diverged_recordings": [int(v) for v in np.sum(~np.isfinite(errors), axis=0)],
        }
    return out


#: Replayed simulated walks' seed: walk i of a regime from ``default_rng([seed, i])``.
REPLAYED_SEED = 22_600
#: Regimes of the replayed walks: :data:`REGIMES` and the PyShoe trials' own speeds
#: (0.3–1.4 m/s, their walking speeds from truth; added after the first two ran).
REPLAYED_REGIMES = {**REGIMES, "sim 0.3–1.4 m/s (the trials' speeds)": (0.3, 1.4)}
#: The trials' speeds on circles: every leg turns per stride by the PyShoe trials' own
#: turn (their pooled 25th–75th percentile of |turn per stride|,
#: :func:`trials_turn_range`; added after the three above ran).
CIRCLES = "sim 0.3–1.4 m/s on circles (the trials' speeds and turns)"
#: Their length (s): ``agents.choose_shoe``'s simulated walks, the PyShoe trials' 17–56 s.
REPLAYED_DURATION_S = (30.0, 60.0)


def trials_turn_range(pyshoe: Path) -> tuple[float, float]:
    """The pooled 25th and 75th percentile of the PyShoe trials' |turn per stride|
    (rad; :mod:`pednav_env.calibration.path_turns`, from their VICON at stance)."""
    return pooled_turn_range([load_walk(p) for p in sorted(pyshoe.glob("*.mat"))])


def replayed(
    walks: int, seed: int = REPLAYED_SEED, circle_turn_rad: tuple[float, float] | None = None
) -> dict[str, Any]:
    """Simulated walks scored the way the recordings are: ``walks`` calibrated walks
    per regime (30–60 s, ``agents.choose_shoe.simulated_recordings``) replayed by
    ``pednav run``'s runner with ``real-fixed``'s setup and each γ. Per regime and γ:
    with ``circle_turn_rad`` also :data:`CIRCLES` at that turn per stride;
    the mean over walks of PyShoe's ARMSE (rotation fitted on the whole track, the
    recordings' measure) and of the same error with the rotation fitted on the
    first 0.8 m only (PyShoe's published alignment: a heading error that grows
    along the walk stays in it, as in the env's error), over the walks on which no
    γ diverged, and the number of diverged walks per γ."""
    setup = real_fixed_setup()
    knobs = threshold_knobs(setup, THRESHOLDS)
    out = {}
    regimes = [(name, speed, None) for name, speed in REPLAYED_REGIMES.items()]
    if circle_turn_rad is not None:
        regimes.append((CIRCLES, (0.3, 1.4), circle_turn_rad))
    for name, speed, turn in regimes:
        recordings = simulated_recordings(
            MODELS["calibrated"], walks, seed, speed, REPLAYED_DURATION_S, turn
        )
        whole = np.full((walks, len(THRESHOLDS)), np.inf)
        start = np.full((walks, len(THRESHOLDS)), np.inf)
        for i, rec in enumerate(recordings):
            prep = prepare(rec, setup)
            run = run_prepared(prep, len(THRESHOLDS), knobs=knobs)
            for j in np.flatnonzero(~run.diverged):
                pos = run.pos[j]
                whole[i, j] = track_errors(pos, prep.truth_pos, prep.n_align)["armse_pyshoe_m"]
                start[i, j] = pyshoe_armse_as_published(pos, prep.truth_pos)
        kept = np.isfinite(whole).all(axis=1)
        out[name.replace("sim", "replayed", 1)] = {
            "walks": walks,
            "seed": seed,
            "walks_kept": int(kept.sum()),
            "diverged_walks": [int(v) for v in np.sum(~np.isfinite(whole), axis=0)],
            "mean_error_m": [float(v) for v in whole[kept].mean(axis=0)],
            "mean_error_start_rotation_m": [float(v) for v in start[kept].mean(axis=0)],
            "turn_per_stride_rad": None if turn is None else list(turn),
        }
    return out


def finite_or_none(value: float) -> float | None:
    """``value``, or None (JSON null) where a recording diverged (inf)."""
    return float(value) if math.isfinite(value) else None


def as_array(errors: list[float | None]) -> np.ndarray:
    """Mean errors with None (diverged) as NaN."""
    return np.array([np.nan if v is None else v for v in errors], dtype=float)


def best_gamma(errors: list[float | None]) -> float:
    """γ of the smallest finite mean error."""
    e = as_array(errors)
    return THRESHOLDS[int(np.argmin(np.where(np.isfinite(e), e, np.inf)))]


def print_table(result: dict[str, Any]) -> None:
    curves = {**result["simulated"], **result["recorded"]}
    for name, c in result.get("replayed", {}).items():
        curves[name] = c
        curves[name + ", start rotation"] = {"mean_error_m": c["mean_error_start_rotation_m"]}
    print("gamma     " + "  ".join(f"{name[:24]:>24s}" for name in curves))
    for k, gamma in enumerate(THRESHOLDS):
        cells = []
        for c in curves.values():
            e = c["mean_error_m"][k]
            cells.append(f"{'diverged':>24s}" if e is None else f"{e:24.3f}")
        print(f"{gamma:8.2e}  " + "  ".join(cells))
    for name, c in curves.items():
        e = as_array(c["mean_error_m"])
        print(
            f"best γ, {name}: {best_gamma(c['mean_error_m']):.3g}; at 2.4e7 and 1.3e9 "
            f"{e[1] / np.nanmin(e):.2f}x and {e[-1] / np.nanmin(e):.2f}x its minimum"
        )


def ratio_curve(
    ax: Any, errors: list[float | None], color: str, line: str, marker: str, label: str
) -> None:
    """One curve divided by its own minimum, against the grid."""
    e = as_array(errors)
    ax.plot(THRESHOLDS, e / np.nanmin(e), color=color, linestyle=line, marker=marker, label=label)


def plot(result: dict[str, Any], path: Path) -> None:
    """Every curve divided by its own minimum, against γ (log), with ``real-fixed``'s γ."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    replayed_curves = result.get("replayed", {})
    panels = 2 if replayed_curves else 1
    fig, axes = plt.subplots(1, panels, figsize=(7.2 * panels, 4.4), squeeze=False)
    styles = {
        "sim 0.3–2.0 m/s (R_room)": ("C0", "--", "o"),
        "PyShoe trials (ARMSE)": ("C0", "-", "s"),
        "sim 0.3–3 m/s": ("C3", "--", "o"),
        "hallway walks (footprint error)": ("C3", "-", "s"),
    }
    curves = {**result["simulated"], **result["recorded"]}
    ax = axes[0, 0]
    for name, (color, line, marker) in styles.items():
        ratio_curve(ax, curves[name]["mean_error_m"], color, line, marker, name)
    bound = result.get("divergence_error_m")
    cap = "" if bound is None else f", bound {bound:g} m"
    ax.set_title(f"Env episodes ({result['episodes']} each{cap}) and recorded walks", fontsize=10)
    if replayed_curves:
        ax = axes[0, 1]
        for name in ("PyShoe trials (ARMSE)", "hallway walks (footprint error)"):
            color, line, marker = styles[name]
            ratio_curve(ax, curves[name]["mean_error_m"], color, line, marker, name)
        colors = ("C0", "C3", "C2", "C4")
        for color, (name, c) in zip(colors, replayed_curves.items(), strict=False):
            label = f"{name} (ARMSE, {c['walks_kept']} of {c['walks']} walks)"
            marker = "D" if c.get("turn_per_stride_rad") else "^"
            ratio_curve(ax, c["mean_error_m"], color, ":", marker, label)
        ax.set_title("Simulated walks scored the way recordings are", fontsize=10)
    for ax in axes[0]:
        ax.axvline(GAMMA_0, color="0.5", linewidth=1, linestyle=":", label="real-fixed's γ")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_yticks([1, 1.5, 2, 3, 4, 6, 10])
        ax.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("SHOE threshold γ (other settings real-fixed's)")
        ax.set_ylabel("mean error / the curve's minimum")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=22_400, help="development seeds only")
    parser.add_argument("--pyshoe", type=Path, default=Path("../shared/data/pyshoe-vicon-dev"))
    parser.add_argument("--hallway", type=Path, default=Path("../shared/data/hallway-gcp-dev"))
    parser.add_argument(
        "--bound",
        type=float,
        default=None,
        help="simulated episodes' divergence bound, fixed part (m; default the env's 25)",
    )
    parser.add_argument(
        "--replayed",
        type=int,
        default=0,
        metavar="WALKS",
        help="also replay WALKS simulated walks per regime the way recordings are scored",
    )
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument(
        "--load",
        type=Path,
        help="a stored --json result: play nothing again (--replayed still replays)",
    )
    parser.add_argument("--plot", type=Path, help="save the figure here")
    args = parser.parse_args()
    if args.load:
        result = json.loads(args.load.read_text())
    else:
        result = {
            "episodes": args.episodes,
            "seed": args.seed,
            "thresholds": list(THRESHOLDS),
            "divergence_error_m": args.bound,
            "simulated": simulated(args.episodes, args.seed, args.bound),
            "recorded": recorded(args.pyshoe, args.hallway),
        }
    if args.replayed:
        result["replayed"] = replayed(args.replayed, circle_turn_rad=trials_turn_range(args.pyshoe))
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    if args.plot:
        plot(result, args.plot)


if __name__ == "__main__":
    main()
