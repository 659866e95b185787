"""How many walks drawn from the simulator itself fall inside its own envelope.

``pednav sim2real`` calls a recording covered when its p10 and its p50 of log10
SHOE both lie inside the 5–95 % range of its band's simulated walks (60 walks,
seed 0). This script asks the same of simulated walks from other seeds, as if they
were recordings: the coverage a perfect simulator would reach under the check
(docs/SIM_TO_REAL_CANDIDATES.md, "Candidate v6"). Per band (the four with development
recordings), ``--walks`` pseudo-recordings of seeds ``[seed · 100 + k, i]`` are
checked against the envelope ``pednav sim2real`` builds (seeds ``[k, i]``).

    PYTHONPATH=. .venv/bin/python benchmarks/self_coverage.py [--model PATH] \\
        [--walks 200] [--seed 7] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from pednav_env.calibration.compare import (
    DEFAULT_WALKS_PER_BAND,
    MODELS,
    SPEED_BANDS,
    BandComparison,
    band_label,
    model_from_json,
)

#: The bands holding development recordings (0.3–0.8 … 1.8–2.6 m/s).
CHECKED_BANDS = SPEED_BANDS[:4]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="calibrated", help="'calibrated', 'today' or a JSON")
    ap.add_argument("--walks", type=int, default=200, help="pseudo-recordings per band")
    ap.add_argument("--seed", type=int, default=7, help="pseudo-recordings' seed (not 0)")
    ap.add_argument("--json", default=None, help="write the figures here")
    args = ap.parse_args()
    if args.seed == 0:
        raise SystemExit("--seed 0 is the envelope's own seed; choose another")
    model = MODELS[args.model] if args.model in MODELS else model_from_json(args.model)
    rows = []
    print("band (m/s)   p10 inside  p50 inside  both inside  (of N)")
    for k, band in enumerate(CHECKED_BANDS):
        envelope = BandComparison(
            band, [], model.simulate(band, DEFAULT_WALKS_PER_BAND, k, per_stride=False)
        )
        pseudo = model.simulate(band, args.walks, args.seed * 100 + k, per_stride=False)
        (a, b), (c, d) = envelope.p10_envelope, envelope.p50_envelope
        p10 = np.array([a <= s.log_shoe_p10 <= b for s in pseudo])
        p50 = np.array([c <= s.log_shoe_p50 <= d for s in pseudo])
        both = np.array([envelope.covered(s) for s in pseudo])
        row = {
            "band": band_label(band),
            "walks": args.walks,
            "p10_inside": float(p10.mean()),
            "p50_inside": float(p50.mean()),
            "both_inside": float(both.mean()),
        }
        rows.append(row)
        print(
            f"{row['band']:<12} {row['p10_inside']:10.3f}  {row['p50_inside']:10.3f}  "
            f"{row['both_inside']:11.3f}  ({args.walks})"
        )
    pooled = float(np.mean([r["both_inside"] for r in rows]))
    print(f"both inside, mean over the bands: {pooled:.3f}")
    if args.json:
        out = {"model": args.model, "seed": args.seed, "bands": rows, "both_inside_mean": pooled}
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
