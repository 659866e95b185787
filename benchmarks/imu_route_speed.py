"""How fast a walk's strides read from its IMU, against the truth, as the route filter's
SHOE threshold changes (docs/SIM_TO_REAL.md, "A threshold chosen on the walk's own
twins").

For each of the 23 PyShoe development trials and the 8 hallway walks (``*_LLIO.mat``) and
each γ of the twin grid (:data:`agents.twin_choice.TWIN_THRESHOLDS`, ``real-fixed``'s
other knobs): the route :func:`agents.twin_choice.imu_stride_sequences` reads (the
filter's detected stances and track; one filter run, a lane per γ), its median stride
speed over the median stride speed from the truth or the footprints
(:func:`pednav_env.calibration.path_turns.stride_sequence`), and its number of strides
over the truth's. A description: nothing is chosen on it.

    PYTHONPATH=. .venv/bin/python benchmarks/imu_route_speed.py \\
        [--shared DIR] [--json benchmarks/results/imu_route_speed.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from agents.twin_choice import TWIN_THRESHOLDS, imu_stride_sequences
from pednav_env.calibration.path_turns import stride_sequence
from pednav_env.calibration.sources import samples_from_recording
from pednav_env.io import load_recording
from pednav_env.replay.setup import real_fixed_setup

ROOT = Path(__file__).resolve().parents[1]
SETS = {
    "PyShoe trials": ("pyshoe-vicon-dev", "*.mat"),
    "hallway walks": ("hallway-gcp-dev", "*_LLIO.mat"),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "imu_route_speed.json"))
    args = ap.parse_args()
    setup = real_fixed_setup()
    out: dict[str, Any] = {"thresholds": list(TWIN_THRESHOLDS)}
    for set_name, (folder, pattern) in SETS.items():
        rows = []
        for path in tqdm(
            sorted((Path(args.shared) / folder).glob(pattern)), desc=set_name, leave=False
        ):
            rec = load_recording(path)
            truth = stride_sequence(samples_from_recording(rec))
            truth_speed = float(np.median(truth.speed_mps))
            speed_ratio, count_ratio = [], []
            for route in imu_stride_sequences(rec, setup, TWIN_THRESHOLDS):
                n = route.speed_mps.size
                speed_ratio.append(float(np.median(route.speed_mps)) / truth_speed if n else None)
                count_ratio.append(n / truth.speed_mps.size)
            rows.append(
                {
                    "recording": rec.name,
                    "truth_median_speed_mps": truth_speed,
                    "speed_ratio": speed_ratio,
                    "stride_count_ratio": count_ratio,
                }
            )
        out[set_name] = rows
        print(f"{set_name}: median stride speed read from the IMU / truth, per gamma")
        print("  recording (truth m/s) | " + " | ".join(f"{g:.1e}" for g in TWIN_THRESHOLDS))
        for row in rows:
            cells = " | ".join("--" if r is None else f"{r:.2f}" for r in row["speed_ratio"])
            print(f"  {row['recording']} ({row['truth_median_speed_mps']:.2f}) | {cells}")
    Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
