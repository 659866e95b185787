"""Where in the swing the foot moves fast without rotating, recorded and simulated
(docs/SIM_TO_REAL.md, "The error level and where it comes from").

Per phase bin of the swing (:mod:`pednav_env.calibration.swing_phases`; tenths unless
``--bins``): the median foot speed, the median and 10th percentile of |ω|, the median
signed sagittal rate and off-sagittal rate, and the share of samples faster than 1 m/s
turning slower than 1 rad/s; over the whole swing, the share of samples faster than
1 m/s below each SHOE threshold of :data:`FAST_BELOW_GAMMAS`. On the 23 PyShoe
development trials (stance from their VICON labels, speed from VICON) and on simulated
walks at the trials' speeds (0.3–1.4 m/s, 30–60 s, walk i from
``default_rng([seed, i])``; truth stance and speed): the arms of
``benchmarks/sim_error_budget.py`` named in :func:`models`. Nothing is chosen on these
runs.

    PYTHONPATH=. .venv/bin/python benchmarks/swing_phases.py --walks 40 \\
        --json benchmarks/results/swing_phases.json --plot docs/figures/swing_phases.png
    PYTHONPATH=. .venv/bin/python benchmarks/swing_phases.py --walks 40 --bins 20 \\
        --json benchmarks/results/swing_phases_20.json
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.sim_error_budget import arms
from pednav_env.calibration.path_turns import pooled_turn_range
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import WalkSamples
from pednav_env.calibration.swing_attitude import attitude_profile
from pednav_env.calibration.swing_phases import fast_below, swing_phase_profile

SPEED_MPS, DURATION_S, SEED = (0.3, 1.4), (30.0, 60.0), 22_600
#: SHOE thresholds of ``fast_below``: ``real-fixed``'s, and the error level's two others.
FAST_BELOW_GAMMAS = (2.25e7, 1.3e8, 1.3e9)


def models() -> dict[str, SimModel]:
    """The arms of ``benchmarks/sim_error_budget.py`` this compares, named as simulated."""
    budget = arms()
    names = (
        "calibrated",
        "heel rocker",
        "heel rocker, monotone pitch",
        "shorter heel strike",
        "mid pitch at the midpoint",
        "swing roll",
    )
    return {f"simulated, {name}": budget[name] for name in names}


def run(
    walks: int, seed: int, pyshoe: Path, truth_speed_stance: bool, bins: int = 10
) -> dict[str, Any]:
    """The profiles; ``truth_speed_stance``: every walk's stance from its truth speed
    (labels dropped; ``calibration.stats.truth_velocity_stance``), one rule for both."""

    def stance_of(w: WalkSamples) -> WalkSamples:
        return replace(w, stance=None) if truth_speed_stance else w

    result: dict[str, Any] = {
        "walks": walks,
        "seed": seed,
        "speed_mps": list(SPEED_MPS),
        "stance": "truth speed" if truth_speed_stance else "labels / simulator truth",
    }
    trials = [stance_of(load_walk(p)) for p in sorted(pyshoe.glob("*.mat"))]
    circle = pooled_turn_range(trials)
    result["trials_turn_per_stride_rad"] = list(circle)
    result["PyShoe trials"] = {
        **swing_phase_profile(trials, bins),
        "fast_below": fast_below(trials, FAST_BELOW_GAMMAS),
        "attitude": attitude_profile(trials, bins),
    }
    arms = [(name, model, None) for name, model in models().items()]
    arms.append(("simulated, calibrated, circles", models()["simulated, calibrated"], circle))
    for name, model, turn in arms:
        truth, imu = model.batch(SPEED_MPS, walks, seed, DURATION_S, turn)
        sims = [stance_of(samples_from_simulation(truth, imu, i)) for i in range(walks)]
        result[name] = {
            **swing_phase_profile(sims, bins),
            "fast_below": fast_below(sims, FAST_BELOW_GAMMAS),
            "attitude": attitude_profile(sims, bins),
        }
    return result


def profiles(result: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {k: v for k, v in result.items() if isinstance(v, dict)}


def print_table(result: dict[str, Any]) -> None:
    for name, p in profiles(result).items():
        print(f"{name} ({p['swing_samples']} swing samples)")
        if "fast_below" in p:
            shares = ", ".join(
                f"{g:.3g}: {v:.3f}" for g, v in zip(FAST_BELOW_GAMMAS, p["fast_below"], strict=True)
            )
            print(f"  fast swing samples below γ ({shares})")
        print("  phase      speed m/s  |ω| median  |ω| p10  sagittal  off-sag.  fast & still")
        edges = p["bin_edges"]
        for k in range(len(edges) - 1):
            print(
                f"  {edges[k]:.2f}–{edges[k + 1]:.2f} {p['speed_median_mps'][k]:9.2f}"
                f"  {p['rate_median_rad_s'][k]:10.2f}  {p['rate_p10_rad_s'][k]:7.2f}"
                f"  {p['sagittal_rate_median_rad_s'][k]:8.2f}"
                f"  {p['off_sagittal_rate_median_rad_s'][k]:8.2f}  {p['fast_still_share'][k]:12.3f}"
            )
        att = p.get("attitude")
        if att:
            print(f"  swing attitude ({att['swings']} swings), medians by phase bin, rad:")
            for key in ("yaw_median_rad", "pitch_median_rad", "roll_median_rad"):
                values = " ".join("   —  " if v is None else f"{v:6.3f}" for v in att[key])
                print(f"    {key.split('_')[0]:6s} {values}")


def plot(result: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, grid = plt.subplots(2, 2, figsize=(11.0, 7.6))
    axes = grid.ravel()
    styles = {
        "PyShoe trials": ("k", "-", "s"),
        "simulated, calibrated": ("C3", "--", "o"),
        "simulated, heel rocker": ("C0", ":", "^"),
        "simulated, heel rocker, monotone pitch": ("C2", "-.", "v"),
        "simulated, shorter heel strike": ("C1", "--", "x"),
        "simulated, mid pitch at the midpoint": ("C4", ":", "+"),
        "simulated, swing roll": ("C5", "-.", "*"),
        "simulated, calibrated, circles": ("C6", "-", "D"),
    }
    panels = (
        ("speed_median_mps", "median foot speed (m/s)"),
        ("sagittal_rate_median_rad_s", "median sagittal rate (rad/s)"),
        ("off_sagittal_rate_median_rad_s", "median off-sagittal rate (rad/s)"),
        ("fast_still_share", "share > 1 m/s and < 1 rad/s"),
    )
    for ax, (key, label) in zip(axes, panels, strict=True):
        for name, p in profiles(result).items():
            color, line, marker = styles.get(name, ("0.5", "-", "."))
            edges = np.array(p["bin_edges"])
            mid = 0.5 * (edges[1:] + edges[:-1])
            values = np.array([np.nan if v is None else v for v in p[key]], dtype=float)
            ax.plot(mid, values, color=color, linestyle=line, marker=marker, label=name)
        if key == "sagittal_rate_median_rad_s":
            ax.axhline(0.0, color="0.5", linewidth=0.8)
        ax.set_xlabel("phase in the swing (0: stance ends, 1: next stance)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[3].legend(fontsize=7, loc="upper left")
    fig.suptitle(
        f"The swing at the PyShoe trials' speeds ({result['walks']} simulated walks per model)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--walks", type=int, default=40)
    parser.add_argument("--bins", type=int, default=10, help="phase bins (default 10)")
    parser.add_argument("--seed", type=int, default=SEED, help="development seeds only")
    parser.add_argument("--pyshoe", type=Path, default=Path("../shared/data/pyshoe-vicon-dev"))
    parser.add_argument(
        "--truth-speed-stance",
        action="store_true",
        help="stance from every walk's truth speed instead of its labels (one rule for both)",
    )
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--load", type=Path, help="a stored --json result: run nothing")
    parser.add_argument("--plot", type=Path, help="save the figure here")
    args = parser.parse_args()
    result = (
        json.loads(args.load.read_text())
        if args.load
        else run(args.walks, args.seed, args.pyshoe, args.truth_speed_stance, args.bins)
    )
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    if args.plot:
        plot(result, args.plot)


if __name__ == "__main__":
    main()
