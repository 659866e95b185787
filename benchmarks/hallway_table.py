"""The hallway-walk table of docs/REAL_DATA.md: footprint errors per walk.

    .venv/bin/python benchmarks/hallway_table.py [--shared DIR] [--policies P ...] [--json FILE]

Runs every policy (default ``paper`` and ``real-fixed``) through ``pednav
run``'s code on each hallway walk (``DIR/hallway-gcp-dev/*_LLIO.mat``, truth
at the footfalls only) and puts the footprint errors beside those of PyShoe's
LSTM tracks stored in the same files (``pyshoeTrajectory``), computed with the
same metric (:func:`pednav_env.replay.metrics.footprint_errors`: origin at the
first footprint, one best rotation about the vertical). Prints a Markdown
table and each policy's mean and median (over the walks) of the mean footprint
error; ``--json`` writes every number (those under ``summary``). DIR defaults to
../shared/data.

Policies as in ``benchmarks/real_data_table.py`` (``real-fixed``, ``paper``,
``tuned`` = the shoe family's CMA-ES constant, ``tuned:paper``, ``adaptive``,
``pretrained``, a run directory or a setup JSON); the privileged ``oracle`` is
not applicable on recordings and is refused before anything runs.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from agents.run_recording import check_policies, run_named, summarize
from pednav_env.io import load_recording
from pednav_env.io.matfile import read_mat
from pednav_env.replay.metrics import footprint_errors

ROOT = Path(__file__).resolve().parents[1]
ERROR_KEYS = ("footprint_mean_error_m", "footprint_final_error_m", "footprint_final_error_pct")


def walk_facts(rec) -> dict:
    """Duration, footprint path length and stride speeds (footprint to footprint)."""
    fp = rec.footprints
    step_m = np.linalg.norm(np.diff(fp.pos, axis=0), axis=1)
    step_s = np.diff(rec.time[fp.sample])
    speed = step_m / step_s
    return {
        "walk": rec.name.removesuffix("_LLIO"),
        "duration_s": rec.duration_s,
        "footprints": fp.count,
        "path_m": float(step_m.sum()),
        "median_stride_speed_m_s": float(np.median(speed)),
        "max_stride_speed_m_s": float(speed.max()),
    }


def pyshoe_lstm(path: Path) -> dict:
    """PyShoe's LSTM track in the file at its footfalls, against the footprints
    (both as stored: one frame, so no reflection is needed)."""
    d = read_mat(path)
    idx = np.asarray(d["strideIndex"]).ravel().astype(int)
    track = np.asarray(d["pyshoeTrajectory"], dtype=float)
    m = footprint_errors(track[idx], np.asarray(d["GCP"], dtype=float))
    return {k: m[k] for k in ERROR_KEYS}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--policies", nargs="+", default=["paper", "real-fixed"])
    ap.add_argument("--json", default=None, help="write all numbers to this file")
    args = ap.parse_args()
    check_policies(args.policies)
    paths = sorted((Path(args.shared) / "hallway-gcp-dev").glob("*_LLIO.mat"))
    if not paths:
        raise SystemExit(f"no *_LLIO.mat in {Path(args.shared) / 'hallway-gcp-dev'}")
    out: dict = {"policies": args.policies, "walks": []}
    t0 = time.time()
    for path in paths:
        rec = load_recording(path)
        row = walk_facts(rec)
        row["pyshoe_lstm"] = pyshoe_lstm(path)
        for pol in args.policies:
            run = run_named(rec, pol)
            s = summarize(rec, run)
            row[pol] = {k: s[k] for k in ERROR_KEYS + ("distance_m", "stances")}
            row[pol]["diverged"] = bool(run.diverged[0])
        out["walks"].append(row)
        print(row["walk"], {p: round(row[p][ERROR_KEYS[0]], 3) for p in args.policies}, flush=True)
    out["summary"] = footprint_summary(out["walks"], args.policies)
    out["seconds"] = round(time.time() - t0, 1)
    print(markdown(out))
    print()
    for key, m in out["summary"].items():
        print(
            f"{key}: mean footprint error over the walks {m['mean_m']:.2f} m, "
            f"median {m['median_m']:.2f} m"
        )
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


def footprint_summary(rows: list[dict], policies: list[str]) -> dict[str, dict[str, float]]:
    """Per policy (and PyShoe's LSTM): mean and median over the walks of the mean
    footprint error (m)."""
    out = {}
    for key in ["pyshoe_lstm", *policies]:
        errors = [r[key][ERROR_KEYS[0]] for r in rows]
        out[key] = {"mean_m": float(np.mean(errors)), "median_m": float(np.median(errors))}
    return out


def _cell(m: dict) -> str:
    """``mean / final (final %)``; a diverged run's final is where it froze: not shown."""
    mean, final, pct = (m[k] for k in ERROR_KEYS)
    fmt = (lambda x: f"{x:.2f}") if mean < 100 else (lambda x: f"{x:.0f}")
    if m.get("diverged"):
        return f"{fmt(mean)} / — (diverged)"
    return f"{fmt(mean)} / {fmt(final)} ({pct:.1f} %)"


def markdown(out: dict) -> str:
    pols = out["policies"]
    cols = ["PyShoe LSTM"] + pols
    lines = [
        "| walk | s | footprints | path m | median / max stride m/s | " + " | ".join(cols) + " |",
        "|" + "---|" * (5 + len(cols)),
    ]
    rows = out["walks"]
    for r in rows:
        cells = [
            r["walk"],
            f"{r['duration_s']:.0f}",
            str(r["footprints"]),
            f"{r['path_m']:.1f}",
            f"{r['median_stride_speed_m_s']:.2f} / {r['max_stride_speed_m_s']:.2f}",
        ]
        cells += [_cell(r["pyshoe_lstm"])] + [_cell(r[p]) for p in pols]
        lines.append("| " + " | ".join(cells) + " |")
    mean = ["**mean**", "", "", f"{np.mean([r['path_m'] for r in rows]):.1f}", ""]
    for key in ["pyshoe_lstm"] + pols:
        m = {k: float(np.mean([r[key][k] for r in rows])) for k in ERROR_KEYS}
        mean.append(f"**{_cell(m)}**")
    lines.append("| " + " | ".join(mean) + " |")
    med = ["median", "", "", "", ""]
    for key in ["pyshoe_lstm"] + pols:
        m = {k: float(np.median([r[key][k] for r in rows])) for k in ERROR_KEYS}
        med.append(_cell(m))
    lines.append("| " + " | ".join(med) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
