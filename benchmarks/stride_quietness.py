"""How quiet the quietest part of each stride is, by stride speed: recordings beside
the calibrated simulator (docs/SIM_TO_REAL.md, "Per stride: the threshold a stride
needs").

    PYTHONPATH=. .venv/bin/python benchmarks/stride_quietness.py \
        [--shared DIR] [--walks 16] [--seed 0] [--json FILE]

For every stride (footfall to footfall, strides through a stand dropped;
:func:`pednav_env.calibration.stats.walk_stats`) the 5th percentile of log10 of
the SHOE statistic over the stride's samples (PyShoe's window and noise figures):
the SHOE threshold log10 γ must exceed it for at least 5 % of the stride (10
samples of a 1 s stride at 200 Hz) to count as stance. It needs no stance labels,
so recordings with labels, with truth only, or with footprints only are measured
alike. Strides are binned by their own speed (truth or footprint path over the
stride's duration), not by the walk's median, so the fast strides of mixed walks
count where they belong.

Recordings: the PyShoe development trials and the hallway walks (the ``.mat``
copies). Simulator: the shipped calibrated model (walker population
:meth:`StanceRandomization.calibrated`, MicroStrain grade), ``--walks`` walks
per speed band, walk i of a band drawn from ``default_rng([seed, i])`` as in
``pednav sim2real``. The last columns give, per bin, the share of strides whose
statistic lies above the γ of ``real-fixed``, of the shipped shoe CMA-ES constant
and of the configuration chosen on simulation (``shoe_from_sim.json``): the
strides each threshold cannot catch with 5 % of their samples.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import WalkSamples, walk_stats
from pednav_env.envs.foot_filters import shoe_knobs
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.replay.setup import real_fixed_setup

ROOT = Path(__file__).resolve().parents[1]
#: Stride-speed bins (m/s).
BINS = ((0.3, 0.8), (0.8, 1.3), (1.3, 1.8), (1.8, 2.6), (2.6, 4.0))
#: Speed bands simulated (the calibrated scenario's 0.3–3 m/s).
SIM_BANDS = ((0.3, 0.8), (0.8, 1.3), (1.3, 1.8), (1.8, 2.6), (2.6, 3.0))


def stride_quietness(samples: WalkSamples) -> np.ndarray:
    """Rows (speed m/s, 5th percentile of log10 SHOE) per stride of ``samples``
    (:attr:`pednav_env.calibration.stats.StrideStats.log_shoe_p5`)."""
    s = walk_stats(samples, per_stride=True).strides
    keep = np.isfinite(s.speed_mps) & np.isfinite(s.log_shoe_p5)
    return np.stack([s.speed_mps[keep], s.log_shoe_p5[keep]], axis=1)


def thresholds() -> dict[str, float]:
    """log10 γ of the shipped SHOE configurations."""
    sim_chosen = json.loads((ROOT / "benchmarks/results/shoe_from_sim.json").read_text())
    out = {
        "real-fixed": math.log10(real_fixed_setup().filter.detector.threshold),
        "chosen on sim": math.log10(sim_chosen["setup"]["detector"]["threshold"]),
    }
    tuned = json.loads((ROOT / "baselines/tuned_actions.json").read_text())
    entry = tuned.get("pednav/FootZupt-v0:shoe")
    if entry is not None:
        knob = shoe_knobs(real_fixed_setup().filter)[0]
        out["tuned (shoe)"] = math.log10(float(knob.value(entry["action"][0])))
    return out


def table(groups: dict[str, np.ndarray], gammas: dict[str, float]) -> tuple[str, list[dict]]:
    names = list(gammas)
    lines = [
        "| stride speed (m/s) | source | strides | median | 10–90 % | "
        + " | ".join(f"above {n} (10^{g:.2f})" for n, g in gammas.items())
        + " |",
        "|---|---|---|---|---|" + "---|" * len(names),
    ]
    records = []
    for lo, hi in BINS:
        for source, rows in groups.items():
            m = (rows[:, 0] >= lo) & (rows[:, 0] < hi)
            if not m.any():
                continue
            q = rows[m, 1]
            above = {n: float(np.mean(q > g)) for n, g in gammas.items()}
            rec = {
                "bin_mps": [lo, hi],
                "source": source,
                "strides": int(m.sum()),
                "median": float(np.median(q)),
                "p10": float(np.percentile(q, 10)),
                "p90": float(np.percentile(q, 90)),
                "share_above": above,
            }
            records.append(rec)
            lines.append(
                f"| {lo}–{hi} | {source} | {rec['strides']} | {rec['median']:.2f} | "
                f"{rec['p10']:.2f}–{rec['p90']:.2f} | "
                + " | ".join(f"{100 * above[n]:.0f} %" for n in names)
                + " |"
            )
    return "\n".join(lines), records


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--walks", type=int, default=16, help="simulated walks per speed band")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None, help="write every number to this file")
    args = ap.parse_args()
    shared = Path(args.shared)
    groups: dict[str, list[np.ndarray]] = {"PyShoe": [], "hallway": [], "simulator": []}
    for path in sorted((shared / "pyshoe-vicon-dev").glob("*.mat")):
        groups["PyShoe"].append(stride_quietness(load_walk(path)))
    for path in sorted((shared / "hallway-gcp-dev").glob("*_LLIO.mat")):
        groups["hallway"].append(stride_quietness(load_walk(path)))
    model = SimModel("calibrated", "microstrain_gx5", StanceRandomization.calibrated())
    for band in SIM_BANDS:
        truth, imu = model.batch(band, args.walks, args.seed)
        for i in range(args.walks):
            groups["simulator"].append(stride_quietness(samples_from_simulation(truth, imu, i)))
    pooled = {k: np.concatenate(v) for k, v in groups.items()}
    text, records = table(pooled, thresholds())
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": records}, indent=1) + "\n")


if __name__ == "__main__":
    main()
