"""Figure: per hallway walk, its own error and its twins' over the SHOE threshold, with
the γ `pednav run --policy twins` chooses (docs/SIM_TO_REAL.md, "A threshold chosen on
the walk's own twins").

Reads two stored results and runs nothing: the walks' own mean footprint error per γ
(``benchmarks/results/twin_gamma_response.json``, ``real-fixed``'s other settings) and
the median error of the twins that walk each walk's strides as its IMU reads them
(``benchmarks/results/self_twin_transfer.json``, the ``real-fixed`` base).

    PYTHONPATH=. .venv/bin/python benchmarks/plot_twin_choice.py \\
        --plot docs/figures/twin_choice_hallway.png
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from benchmarks.gamma_response import as_array
from pednav_env.files import save_figure

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SET = "hallway walks"
REAL_FIXED_THRESHOLD = 2.25e7


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--own", default=str(RESULTS / "twin_gamma_response.json"))
    ap.add_argument("--choice", default=str(RESULTS / "self_twin_transfer.json"))
    ap.add_argument("--plot", required=True, help="the figure (.png)")
    args = ap.parse_args()
    own = json.loads(Path(args.own).read_text())
    choice = json.loads(Path(args.choice).read_text())
    thresholds = np.asarray(choice["thresholds"], dtype=float)
    if not np.allclose(thresholds, own["thresholds"], rtol=1e-9):
        raise ValueError(f"{args.own} and {args.choice} use different threshold grids")
    own_by_name = dict(zip(own[SET]["recordings"], own[SET]["own_m"], strict=True))
    rows = choice[SET]["per_recording"]

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    fig, axes = plt.subplots(2, 4, figsize=(13.0, 6.2), sharex=True)
    for ax, row in zip(axes.ravel(), rows, strict=True):
        name = row["recording"]
        walk = as_array(own_by_name[name])
        twins = as_array(row["base"]["twin_median_m"])
        chosen = row["base"]["threshold"]
        k = int(np.argmin(np.abs(thresholds - chosen)))
        ax.plot(thresholds, walk, "k-s", markersize=4, label="the walk")
        ax.plot(thresholds, twins, "C3--o", markersize=4, label="its twins (median)")
        ax.plot([chosen], [walk[k]], "C3*", markersize=14, label="γ chosen on the twins")
        ax.axvline(REAL_FIXED_THRESHOLD, color="0.5", linestyle=":", label="real-fixed's γ")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ratio = row["base"]["median_speed_ratio"]
        ax.set_title(f"{name.split('_')[1]}: route speed {ratio:.2f}× the footprints'", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        for axis in (ax.yaxis,):
            axis.set_major_formatter(ticker.FormatStrFormatter("%g"))
            axis.set_minor_formatter(ticker.NullFormatter())
    for ax in axes[1]:
        ax.set_xlabel("SHOE threshold γ")
    for ax in axes[:, 0]:
        ax.set_ylabel("mean footprint error (m)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(
        "Hallway walks: each walk's footprint error and its IMU-route twins' over γ "
        "(real-fixed's other settings; a missing point diverged)",
        fontsize=10,
    )
    fig.tight_layout()
    save_figure(fig, args.plot, dpi=110)
    plt.close(fig)
    print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
