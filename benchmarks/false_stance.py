"""How much of the swing does a too-high SHOE threshold call stance, simulated and
recorded? (docs/SIM_TO_REAL.md, "The threshold's response, simulated and recorded")

At γ = 1.3·10⁹ the error is 1.26–1.3× its minimum on calibrated simulated walks but
3.5× on the hallway walks (4.6× against 7.1× on walking; ``gamma_response.py``). The
hypothesis tested here: under a high γ the recorded swings have more samples, or more
samples at high foot speed, below γ than the simulated ones. Per walk and γ
(:func:`pednav_env.calibration.false_stance.false_stance`): the share of the walking
part's non-stance samples with log10 SHOE (PyShoe's settings) below log10 γ, stance
from the walk's own source (PyShoe labels, simulator truth; the hallway walks have
neither and use the detector rule of :mod:`pednav_env.calibration.stats`); the same
share outside the label-free quiet phase (one rule everywhere); and the share weighted
by the truth foot speed (PyShoe, simulated).

Walks: the 23 PyShoe trials, the 8 hallway walks, and ``pednav sim2real``'s simulated
walks of the calibrated model (60 per speed band, seed 0, as its envelope). Per band
the table gives medians over walks, and for the simulated walks the 5th and 95th
percentiles over walks. Nothing is chosen or changed.

    PYTHONPATH=. .venv/bin/python benchmarks/false_stance.py \\
        --json benchmarks/results/false_stance.json
    PYTHONPATH=. .venv/bin/python benchmarks/false_stance.py \\
        --load benchmarks/results/false_stance.json
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.calibration.compare import (
    DEFAULT_WALKS_PER_BAND,
    MODELS,
    SPEED_BANDS,
    band_label,
    band_of,
)
from pednav_env.calibration.false_stance import false_stance
from pednav_env.calibration.sim_model import SIM_TOP_SPEED_MPS
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import walk_stats

#: log10 γ: ``real-fixed``'s 2.25·10⁷ for reference, then the three high thresholds.
LOG10_GAMMAS = (math.log10(2.25e7), 8.5, 9.0, 9.5)
MEASURES = ("below", "below_quiet_free", "speed_weighted")


def recorded(pyshoe: Path, hallway: Path) -> list[dict[str, Any]]:
    """One row per recording: its source, band and :func:`false_stance` shares."""
    rows = []
    for source, paths in (
        ("PyShoe", sorted(pyshoe.glob("*.mat"))),
        ("hallway", sorted(hallway.glob("*_LLIO.mat"))),
    ):
        for p in paths:
            s = load_walk(p)
            band = band_of(walk_stats(s, per_stride=False).speed_mps)
            rows.append(
                {"source": source, "band": None if band is None else band_label(band)}
                | false_stance(s, LOG10_GAMMAS)
            )
    return rows


def simulated(walks: int, seed: int) -> list[dict[str, Any]]:
    """One row per simulated walk: ``pednav sim2real``'s calibrated walks, band k
    from seed ``seed * 100 + k`` (as :func:`pednav_env.calibration.compare.compare`)."""
    model = MODELS["calibrated"]
    rows = []
    for k, (lo, hi) in enumerate(SPEED_BANDS):
        truth, imu = model.batch((lo, min(hi, SIM_TOP_SPEED_MPS)), walks, seed * 100 + k)
        for i in range(walks):
            s = samples_from_simulation(truth, imu, i, f"sim{k}-{i}")
            rows.append(
                {"source": "sim", "band": band_label((lo, hi))} | false_stance(s, LOG10_GAMMAS)
            )
    return rows


def rounded(row: dict[str, Any]) -> dict[str, Any]:
    """``row`` with its numbers to 4 decimals (the stored file; the band table is
    computed from the rounded rows, so a stored file prints the same table)."""

    def r(v: Any) -> Any:
        if isinstance(v, float):
            return round(v, 4)
        return [r(x) for x in v] if isinstance(v, list) else v

    return {k: r(v) for k, v in row.items()}


def band_medians(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (band, source): walk count and the median over walks of each measure at
    each γ (None where no walk has it), and (``_p5``, ``_p95``) its 5th and 95th
    percentiles over walks."""
    out = []
    for band in (band_label(b) for b in SPEED_BANDS):
        for source in ("sim", "PyShoe", "hallway"):
            sel = [r for r in rows if r["band"] == band and r["source"] == source]
            if not sel:
                continue
            entry: dict[str, Any] = {"band": band, "source": source, "walks": len(sel)}
            for m in MEASURES:
                for key, q in (("", 50.0), ("_p5", 5.0), ("_p95", 95.0)):
                    cells = []
                    for k in range(len(LOG10_GAMMAS)):
                        vals = [r[m][k] for r in sel if r[m][k] is not None]
                        cells.append(float(np.percentile(vals, q)) if vals else None)
                    entry[m + key] = cells
            speeds = [r["swing_speed_mps"] for r in sel if r["swing_speed_mps"] is not None]
            entry["swing_speed_mps"] = float(np.median(speeds)) if speeds else None
            entry["nonstance_share"] = float(np.median([r["nonstance_share"] for r in sel]))
            out.append(entry)
    return out


def print_table(result: dict[str, Any]) -> None:
    gammas = "  ".join(f"{10**g:9.2e}" for g in result["log10_gammas"])
    titles = {
        "below": "share of non-stance samples (own stance source) below γ",
        "below_quiet_free": "share of samples outside the quiet phase below γ",
        "speed_weighted": "share of non-stance truth foot speed below γ",
    }
    for m in MEASURES:
        print(f"\n{titles[m]} (median over walks)")
        print(f"{'band':>8s} {'source':>8s} {'walks':>5s}  {gammas}")
        for e in result["bands"]:
            rows = [(e["source"], e[m])]
            if e["source"] == "sim":
                rows += [("sim p5", e[m + "_p5"]), ("sim p95", e[m + "_p95"])]
            for name, values in rows:
                cells = "  ".join(f"{'-':>9s}" if v is None else f"{v:9.4f}" for v in values)
                print(f"{e['band']:>8s} {name:>8s} {e['walks']:5d}  {cells}")
    print("\nnon-stance share of walking time, mean truth speed in it (median over walks)")
    for e in result["bands"]:
        v = e["swing_speed_mps"]
        speed = "-" if v is None else f"{v:.2f} m/s"
        print(f"{e['band']:>8s} {e['source']:>8s}  {e['nonstance_share']:.3f}  {speed}")
    unbanded = [r["name"] for r in result["walks"] if r["band"] is None]
    if unbanded:
        print("no band (speed below 0.3 m/s or unknown): " + ", ".join(unbanded))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--walks", type=int, default=DEFAULT_WALKS_PER_BAND, help="per band")
    parser.add_argument("--seed", type=int, default=0, help="sim2real's envelope seed")
    parser.add_argument("--pyshoe", type=Path, default=Path("../shared/data/pyshoe-vicon-dev"))
    parser.add_argument("--hallway", type=Path, default=Path("../shared/data/hallway-gcp-dev"))
    parser.add_argument("--json", type=Path, help="also write the result here")
    parser.add_argument("--load", type=Path, help="a stored --json result: compute nothing")
    args = parser.parse_args()
    if args.load:
        result = json.loads(args.load.read_text())
        result["bands"] = band_medians(result["walks"])
    else:
        walks = [rounded(w) for w in recorded(args.pyshoe, args.hallway)]
        walks += [rounded(w) for w in simulated(args.walks, args.seed)]
        result = {
            "model": "calibrated",
            "walks_per_band": args.walks,
            "seed": args.seed,
            "log10_gammas": list(LOG10_GAMMAS),
            "bands": band_medians(walks),
            "walks": walks,
        }
    print_table(result)
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
