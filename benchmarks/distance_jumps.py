"""How much the stance-onset corrections add to ``pednav run``'s ``distance_m``
(the figures in docs/CONTRACTS.md, "pednav run").

``distance_m`` sums the estimated horizontal path sample to sample. At a stance
onset the zero-velocity update moves the estimate in one sample; this script
measures that extra length: the step at each onset minus the median step of
the three samples before it.

    .venv/bin/python benchmarks/distance_jumps.py ../shared/data/pyshoe-vicon-dev
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pednav_env.io import load_recording
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import SETUP_NAMES, named_setup


def onset_excess_m(path: Path, setup: str) -> tuple[np.ndarray, float]:
    """Extra length (m) at each detected stance onset, and the path length (m)."""
    run = run_prepared(prepare(load_recording(path), named_setup(setup)))
    start = run.start_sample
    step = np.linalg.norm(np.diff(run.pos[0, start:, :2], axis=0), axis=1)
    stance = run.stance[0, start + 1 :]
    onsets = np.flatnonzero(stance[1:] & ~stance[:-1]) + 1
    before = np.array([np.median(step[max(0, k - 3) : k]) for k in onsets])
    return np.clip(step[onsets] - before, 0.0, None), float(step.sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path, help="a folder of .mat or .csv recordings")
    ap.add_argument("--policy", default="real-fixed", choices=SETUP_NAMES)
    args = ap.parse_args()
    files = sorted(p for p in args.folder.iterdir() if p.suffix in (".mat", ".csv"))
    if not files:
        raise SystemExit(f"no .mat or .csv recordings in {args.folder}")
    excess, shares = [], []
    for path in files:
        e, length = onset_excess_m(path, args.policy)
        excess.append(e)
        shares.append(100.0 * e.sum() / length)
    e = np.concatenate(excess)
    print(f"{len(files)} recordings, {e.size} stance onsets, policy {args.policy}")
    print(
        f"extra length per onset: median {np.median(e):.4f} m, "
        f"99th percentile {np.percentile(e, 99):.3f} m, max {e.max():.3f} m"
    )
    print(
        f"share of distance_m: median {np.median(shares):.1f} %, "
        f"range {min(shares):.1f}–{max(shares):.1f} %"
    )


if __name__ == "__main__":
    main()
