"""Each part of a ``calibrate_foot.py`` output beside the point it was started from:
the fit's distance at the start and at the stored end, and (``--check``) ``pednav
sim2real``'s check of the start, as ``calibrate_foot.py`` checks a fit
(docs/SIM_TO_REAL.md, "The fit").

    PYTHONPATH=. .venv/bin/python benchmarks/fit_starts.py \\
        --fits benchmarks/results/calibrate_foot.json \\
        --starts benchmarks/results/calibrate_foot_previous.json \\
        --pyshoe ../shared/data/pyshoe-vicon-dev --hallway ../shared/data/hallway-gcp-dev \\
        [--check hallway]

A fit made before ``pednav_env.calibration.fit`` scored its start returned the
search's best even when the start scored lower; this says for which parts that
happened, and what the part's checks are with the start kept. The distance uses
the output's own settings (walks per band, seed); a start of 15 values for a
16-value fit gets the 16th value's start (0). ``--starts`` is the warm-start file
the output was made from (the ``settings`` record the path it had then).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from calibrate_foot import (  # benchmarks/ (the script directory is on sys.path)
    check,
    load_recordings,
)

from pednav_env.calibration.fit import groups
from pednav_env.calibration.objective import distance
from pednav_env.calibration.parameters import SWING_SPEED

KEYS = ("covered", "covered_other_seeds", "p10_inside", "p50_inside", "total")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fits", required=True, help="a calibrate_foot.py output")
    ap.add_argument("--starts", required=True, help="the warm-start file it was made from")
    ap.add_argument("--pyshoe", required=True)
    ap.add_argument("--hallway", required=True)
    ap.add_argument("--check", nargs="*", default=[], help="parts whose start to check")
    args = ap.parse_args()
    fits = json.loads(Path(args.fits).read_text())
    starts = json.loads(Path(args.starts).read_text())
    walks, seed = fits["settings"]["walks"], fits["settings"]["seed"]
    stats, _ = load_recordings(args)
    folds = groups(stats)
    for part, stored in fits["parts"].items():
        train = [s for s in stats if s.name in set(stored["train"])]
        x0 = list(starts["parts"][part]["fit"]["x"])
        end = stored["fit"]["x"]
        if len(end) == len(x0) + 1:
            x0.append(SWING_SPEED.start)
        d0 = distance(x0, train, walks, seed)
        d1 = distance(end, train, walks, seed)
        better = "the start" if d0 <= d1 else "the search"
        print(
            f"{part}: start {d0:.4f}, stored end {d1:.4f} "
            f"(recorded {stored['fit']['distance']:.4f}); the better: {better}",
            flush=True,
        )
        if part in args.check:
            x = np.asarray(x0)
            sets = [("in sample", train)] + ([("held out", folds[part])] if part != "all" else [])
            for name, recs in sets:
                c = check(recs, x)
                print(f"  start, {name}: " + ", ".join(f"{k} {c[k]}" for k in KEYS), flush=True)


if __name__ == "__main__":
    main()
