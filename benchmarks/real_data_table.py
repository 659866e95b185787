"""The per-trial tables of docs/REAL_DATA.md.

    .venv/bin/python benchmarks/real_data_table.py [--shared DIR] [--policies P ...]

Runs every policy on the PyShoe development trials (errors against the
VICON reference, PyShoe's metric beside PyShoe's own per-trial-optimised
figures) and on the two x-io loops (loop closure), and prints Markdown
tables, each policy's ratio of its mean PyShoe ARMSE to the mean of PyShoe's
per-trial-optimised SHOE errors, and a JSON dump (``--json FILE``, the ratios
under ``ratio_to_pyshoe_shoe``). DIR defaults to ../shared/data.

Policies (:mod:`agents.run_recording`, as ``pednav run --policy``): the fixed
setups ``paper`` and ``real-fixed``; ``tuned`` (the shoe family's CMA-ES
constant), ``tuned:paper`` (the paper family's), ``adaptive``, ``pretrained``
(``NAME:FAMILY`` for the other family), a run directory or a setup JSON. The
privileged ``oracle`` is not applicable on recordings (it plays the simulator's
true context) and is refused, as is an unknown name, before anything runs.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from agents.run_recording import check_policies, run_named, summarize
from pednav_env.io import find_recordings, load_recording
from pednav_env.replay.metrics import pyshoe_armse_as_published, track_errors
from pednav_env.replay.runner import prepare
from pednav_env.replay.setup import named_setup

ROOT = Path(__file__).resolve().parents[1]
XIO_PUBLISHED_M = {"short_walk": 0.082, "long_walk": 0.421}


def pyshoe_ratios(rows: list[dict], policies: list[str]) -> dict[str, float]:
    """Per policy: mean PyShoe ARMSE over the trials / mean of PyShoe's
    per-trial-optimised SHOE errors (the issue's "× PyShoe" figure)."""
    shoe = float(np.mean([r["pyshoe"]["shoe"] for r in rows]))
    return {p: float(np.mean([r[p]["armse_pyshoe_m"] for r in rows])) / shoe for p in policies}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--policies", nargs="+", default=["paper", "real-fixed", "adaptive", "tuned"])
    ap.add_argument("--json", default=None, help="write all numbers to this file")
    args = ap.parse_args()
    check_policies(args.policies)
    shared = Path(args.shared)
    out: dict = {"pyshoe": [], "xio": [], "policies": args.policies}
    t0 = time.time()
    for path in find_recordings(shared / "pyshoe-vicon-dev"):
        rec = load_recording(path)
        prep = prepare(rec, named_setup("paper"))
        na = prep.n_align
        truth = prep.truth_pos
        path_m = float(np.sum(np.linalg.norm(np.diff(truth[na:, :2], axis=0), axis=1)))
        row = {
            "trial": rec.name,
            "duration_s": rec.duration_s,
            "truth_path_m": path_m,
            "mean_speed_m_s": path_m / ((prep.num_samples - na) / prep.rate_hz),
            "pyshoe": rec.metadata["pyshoe_trial_error_m"],
        }
        for pol in args.policies:
            run = run_named(rec, pol)
            m = track_errors(run.pos[0], run.prepared.truth_pos, run.start_sample)
            m["armse_pyshoe_published_rotation_m"] = pyshoe_armse_as_published(
                run.pos[0], run.prepared.truth_pos
            )
            m["diverged"] = bool(run.diverged[0])
            row[pol] = m
        out["pyshoe"].append(row)
        print(rec.name, {p: round(row[p]["armse_pyshoe_m"], 3) for p in args.policies}, flush=True)
    for name in ("short_walk", "long_walk"):
        rec = load_recording(shared / "xio-gait-tracking" / f"{name}.csv")
        row = {"walk": name, "published_m": XIO_PUBLISHED_M[name]}
        for pol in args.policies:
            row[pol] = summarize(rec, run_named(rec, pol))
        out["xio"].append(row)
        print(name, {p: round(row[p]["loop_closure_m"], 3) for p in args.policies}, flush=True)
    out["ratio_to_pyshoe_shoe"] = pyshoe_ratios(out["pyshoe"], args.policies)
    out["seconds"] = round(time.time() - t0, 1)
    print(markdown(out))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1, default=float) + "\n")


def markdown(out: dict) -> str:
    pols = out["policies"]
    head = (
        "| trial | s | path m | m/s | PyShoe SHOE | PyShoe best | "
        + " | ".join(pols)
        + " | real-fixed ARMSE (ours) |"
    )
    lines = [head, "|" + "---|" * (6 + len(pols) + 1)]
    for r in out["pyshoe"]:
        best = min(v for k, v in r["pyshoe"].items())
        cells = [
            r["trial"],
            f"{r['duration_s']:.0f}",
            f"{r['truth_path_m']:.1f}",
            f"{r['mean_speed_m_s']:.2f}",
            f"{r['pyshoe']['shoe']:.3f}",
            f"{best:.3f}",
        ]
        cells += [_fmt(r[p]["armse_pyshoe_m"], r[p]["diverged"]) for p in pols]
        cells.append(f"{r['real-fixed']['armse_m']:.3f}" if "real-fixed" in r else "—")
        lines.append("| " + " | ".join(cells) + " |")
    mean = ["**mean**", "", "", ""]
    rows = out["pyshoe"]
    mean.append(f"**{np.mean([r['pyshoe']['shoe'] for r in rows]):.3f}**")
    mean.append(f"**{np.mean([min(r['pyshoe'].values()) for r in rows]):.3f}**")
    mean += [f"**{np.mean([r[p]['armse_pyshoe_m'] for r in rows]):.3f}**" for p in pols]
    if "real-fixed" in pols:
        mean.append(f"**{np.mean([r['real-fixed']['armse_m'] for r in rows]):.3f}**")
    lines.append("| " + " | ".join(mean) + " |")
    lines.append("")
    shoe = np.mean([r["pyshoe"]["shoe"] for r in rows])
    ratios = out.get("ratio_to_pyshoe_shoe") or pyshoe_ratios(rows, pols)
    lines.append(
        f"Mean PyShoe ARMSE / PyShoe's per-trial-optimised SHOE ({shoe:.4f} m): "
        + ", ".join(f"{p} {ratios[p]:.2f}×" for p in pols)
    )
    lines.append("")
    lines.append("| walk | xio published | " + " | ".join(pols) + " |")
    lines.append("|" + "---|" * (2 + len(pols)))
    for r in out["xio"]:
        cells = [r["walk"], f"{r['published_m']:.3f}"]
        cells += [
            f"{r[p]['loop_closure_m']:.3f} ({r[p]['distance_m']:.1f} m, {r[p]['stances']} st.)"
            for p in pols
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _fmt(x: float, diverged: bool) -> str:
    s = f"{x:.3f}" if x < 10 else f"{x:.0f}"
    return s + (" (div.)" if diverged else "")


if __name__ == "__main__":
    main()
