"""How rarely can any constant SHOE configuration diverge on the calibrated scenario
of pednav/FootZupt-v0? (docs/ENV_FOOT.md, "Divergence of the shoe family's constants")

The shoe family's action 0 is ``real-fixed``'s configuration, whose threshold was
chosen on PyShoe trials of at most 1.4 m/s; on the calibrated scenario's 0.3–3 m/s
walks it diverges in most episodes. This script asks whether the shoe family has a
constant that stays under a given divergence rate at all: it plays constant actions
on the same episodes, a sweep of the threshold knob a₀ (γ = 2.25·10⁷·100^a₀) with the
other knobs either at ``real-fixed``'s values (0) or at the shipped ``tuned``
constant's, beside ``real-fixed`` and ``tuned``. Nothing is chosen on these
episodes: the sweep is fixed below, and the figure of interest is the lowest rate in
it with its exact 95 % interval (Clopper–Pearson), a floor that is optimistic
because it is the minimum over the sweep on the same episodes.

    PYTHONPATH=. .venv/bin/python benchmarks/shoe_divergence_floor.py \
        --episodes 200 --seed 22200 --json benchmarks/results/shoe_divergence_floor.json \
        --plot docs/figures/shoe_divergence_floor.png
    # the figure again from the stored result, nothing played:
    PYTHONPATH=. .venv/bin/python benchmarks/shoe_divergence_floor.py \
        --load benchmarks/results/shoe_divergence_floor.json \
        --plot docs/figures/shoe_divergence_floor.png
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path
from typing import Any

import pednav_env  # noqa: F401  (registers the environments)
from agents.evaluate import evaluate
from baselines.tuned import RESULTS_FILE, read_results, result_key

ENV_ID = "pednav/FootZupt-v0"
#: The threshold knob's sweep (fixed before any run).
GAMMA_KNOB = (0.25, 0.5, 0.75, 1.0)
#: The other knobs (window, Q scale, R scale) of each sweep.
OTHER_KNOBS = ("real-fixed", "tuned")


def sweep_files(directory: Path) -> dict[str, str]:
    """Tuned-actions files of the sweep in ``directory``: label → path."""
    tuned = read_results(RESULTS_FILE)[result_key(ENV_ID, "shoe")]["action"]
    rest = {"real-fixed": [0.0, 0.0, 0.0], "tuned": [float(v) for v in tuned[1:]]}
    files = {}
    for others in OTHER_KNOBS:
        for a0 in GAMMA_KNOB:
            label = f"a0={a0:+.2f}, others {others}"
            path = directory / f"a0_{a0}_{others}.json"
            entry = {result_key(ENV_ID, "shoe"): {"action": [a0, *rest[others]]}}
            path.write_text(json.dumps(entry))
            files[label] = str(path)
    return files


def run(episodes: int, seed: int) -> dict[str, Any]:
    """Play ``real-fixed``, ``tuned`` and the sweep on seeds seed … seed+episodes−1."""
    with tempfile.TemporaryDirectory() as tmp:
        files = sweep_files(Path(tmp))
        result = evaluate(
            ENV_ID,
            ["real-fixed", "tuned", *files.values()],
            episodes,
            seed,
            env_kwargs={"filter": "shoe", "scenario": "calibrated"},
        )
    labels = {path: label for label, path in files.items()}
    rows = []
    for entry in result["policies"]:
        rows.append(
            {
                "policy": labels.get(entry["name"], entry["name"]),
                "gamma": None,
                "mean_error_m": entry["mean_error"],
                "ci95": entry["ci95"],
                "divergence_rate": entry["divergence_rate"],
                "divergence_ci95": entry["divergence_ci95"],
                "mean_error_non_diverged_m": entry["mean_error_non_diverged"],
            }
        )
    for row in rows:
        if row["policy"].startswith("a0="):
            row["gamma"] = 2.25e7 * 100 ** float(row["policy"][3:8])
    floor = min(rows[2:], key=lambda r: r["divergence_rate"])
    return {"env": ENV_ID, "episodes": episodes, "seed": seed, "rows": rows, "floor": floor}


def print_table(result: dict[str, Any]) -> None:
    print(
        f"{result['env']}, shoe family, calibrated scenario, seeds {result['seed']}…"
        f"{result['seed'] + result['episodes'] - 1}"
    )
    print(
        f"{'policy':32s} {'gamma':>9s} {'mean (m)':>9s} {'diverged':>9s} {'exact 95 %':>13s}"
        f" {'mean, not div. (m)':>19s}"
    )
    for r in result["rows"]:
        gamma = f"{r['gamma']:.2e}" if r["gamma"] else "-"
        lo, hi = r["divergence_ci95"]
        print(
            f"{r['policy']:32s} {gamma:>9s} {r['mean_error_m']:9.2f} "
            f"{100 * r['divergence_rate']:8.1f}% {100 * lo:5.1f}-{100 * hi:5.1f} % "
            f"{r['mean_error_non_diverged_m']:19.2f}"
        )
    f = result["floor"]
    print(
        f"lowest divergence in the sweep: {f['policy']}, {100 * f['divergence_rate']:.1f} % "
        f"(exact 95 % interval {100 * f['divergence_ci95'][0]:.1f}-"
        f"{100 * f['divergence_ci95'][1]:.1f} %)"
    )


def plot(result: dict[str, Any], path: Path) -> None:
    """Divergence rate (with its exact 95 % interval) against γ for both sweeps, with
    ``real-fixed`` and ``tuned`` at their own γ and the 10 % line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tuned_gamma = 2.25e7 * 100 ** float(
        read_results(RESULTS_FILE)[result_key(ENV_ID, "shoe")]["action"][0]
    )
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    for others, marker in zip(OTHER_KNOBS, ("o", "s"), strict=True):
        rows = [r for r in result["rows"] if r["policy"].endswith(f"others {others}")]
        gamma = [r["gamma"] for r in rows]
        rate = [100 * r["divergence_rate"] for r in rows]
        err = [
            [100 * (r["divergence_rate"] - r["divergence_ci95"][0]) for r in rows],
            [100 * (r["divergence_ci95"][1] - r["divergence_rate"]) for r in rows],
        ]
        ax.errorbar(
            gamma,
            rate,
            yerr=err,
            marker=marker,
            capsize=3,
            label=f"γ sweep, window/Q/R of {others}",
        )
    for name, gamma, marker in (("real-fixed", 2.25e7, "D"), ("tuned", tuned_gamma, "^")):
        r = next(r for r in result["rows"] if r["policy"] == name)
        lo, hi = r["divergence_ci95"]
        ax.errorbar(
            [gamma],
            [100 * r["divergence_rate"]],
            yerr=[[100 * (r["divergence_rate"] - lo)], [100 * (hi - r["divergence_rate"])]],
            marker=marker,
            color="k",
            capsize=3,
            linestyle="none",
            label=name,
        )
    ax.axhline(10, color="0.5", linestyle="--", linewidth=1, label="10 %")
    ax.set_xscale("log")
    ax.set_xlabel("SHOE threshold γ")
    ax.set_ylabel("episodes diverged (%), exact 95 % interval")
    ax.set_ylim(0, 100)
    ax.set_title(f"{ENV_ID}, shoe family, calibrated scenario, {result['episodes']} episodes")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=22_200, help="development seeds only")
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--load", type=Path, help="plot a stored --json result, play nothing")
    parser.add_argument("--plot", type=Path, help="save the divergence-against-γ figure here")
    args = parser.parse_args()
    result = json.loads(args.load.read_text()) if args.load else run(args.episodes, args.seed)
    if args.plot:
        plot(result, args.plot)
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
