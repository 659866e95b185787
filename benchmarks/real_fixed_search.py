"""Choose the ``real-fixed`` configuration on the PyShoe development trials.

    .venv/bin/python benchmarks/real_fixed_search.py [DATA_DIR] [--out FILE]

DATA_DIR defaults to ../shared/data/pyshoe-vicon-dev beside the checkout.
Writes pednav_env/replay/real_fixed.json (the shipped configuration, the
fold check and the best 20 configurations); see docs/REAL_DATA.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from pednav_env.io import find_recordings, load_recording
from pednav_env.replay.search import search, write
from pednav_env.replay.setup import REAL_FIXED_FILE

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DIR = ROOT.parent / "shared" / "data" / "pyshoe-vicon-dev"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data_dir", nargs="?", default=str(DEFAULT_DIR))
    ap.add_argument("--out", default=str(REAL_FIXED_FILE))
    args = ap.parse_args()
    recs = [load_recording(p) for p in find_recordings(args.data_dir)]
    t0 = time.time()
    result = search(recs)
    result["seconds"] = round(time.time() - t0, 1)
    write(result, Path(args.out))
    print(result["chosen"], result["folds"], f"{result['seconds']} s", sep="\n")


if __name__ == "__main__":
    main()
