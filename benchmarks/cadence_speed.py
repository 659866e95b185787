"""The recorded walkers' cadence against the simulator's law (docs/SIM_TO_REAL_CANDIDATES.md,
"The walking cadence").

    PYTHONPATH=. .venv/bin/python benchmarks/cadence_speed.py \\
        [--shared ../shared/data] [--json benchmarks/results/cadence_speed.json]

Per recorded stride (:func:`pednav_env.calibration.cadence.recorded_strides`: the
23 PyShoe development trials from their cleaned VICON stance labels and VICON
positions, the 8 hallway walks from their footprints; walking strides only,
0.1–2 m/s; strides overlapping a truth glitch left out and listed): the cycle
(footfall to footfall, s) and the stride speed (m/s). Printed:

- per recording, its group (PyShoe session before / after 11:35, hallway walker),
  strides, median stride speed, length and cycle (10–90 %), the cycle of the
  simulator's law T = 1/(0.55 + 0.3 v) at that speed and the ratio recorded/law;
- per stride-speed bin, pooled over each group: median cycle against the law's;
- the law f = a + b·v fitted (:func:`pednav_env.calibration.cadence.fit_cadence_law`)
  to all recordings, to each group, and to each cross-validation fold's training
  recordings (``benchmarks/calibrate_foot.py --cadence-law``'s laws), with the
  walker spread.

No simulation, no seeds. ``--json`` writes every recording's strides and the laws.

``--with-laws FITS --write FILE``: a copy of a ``benchmarks/calibrate_foot.py``
output ``FITS`` whose every part's model gets the law of that part's training
recordings (as ``calibrate_foot.py --cadence-law`` sets it: ``model_options`` and
``randomization``, 5 digits), the fitted values unchanged: the quick check of a
law on a fit without refitting, through ``calibrate_foot.py --merge FILE
--recheck`` and ``slow_walk_phases.py --fits FILE`` (docs/SIM_TO_REAL_CANDIDATES.md).
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from pednav_env.calibration.cadence import RecordedStrides, fit_cadence_law, recorded_strides
from pednav_env.calibration.sources import load_walk

ROOT = Path(__file__).resolve().parents[1]
#: Stride-speed bins of the pooled table (m/s).
BINS = ((0.1, 0.5), (0.5, 0.8), (0.8, 1.1), (1.1, 1.4), (1.4, 2.0))
#: The simulator's default law (Hz): 0.55 + 0.3 v.
DEFAULT = (0.55, 0.3)


def group_of(name: str) -> str:
    """The cross-validation group (benchmarks/calibrate_foot.py): PyShoe session
    before 11:35 or after, or the hallway walker."""
    if name.startswith("2017-") and len(name) >= 16:
        return "pyshoe_early" if name[11:13] + name[14:16] < "1135" else "pyshoe_late"
    return "hallway"


def law_cycle(speed: float, law: tuple[float, float] = DEFAULT) -> float:
    return 1.0 / (law[0] + law[1] * speed)


def load(shared: Path) -> list[RecordedStrides]:
    paths = sorted((shared / "pyshoe-vicon-dev").glob("*.mat"))
    paths += sorted((shared / "hallway-gcp-dev").glob("*_LLIO.mat"))
    if not paths:
        raise SystemExit(f"{shared}: no PyShoe or hallway recordings found")
    return [recorded_strides(load_walk(p)) for p in paths]


def recording_rows(walks: list[RecordedStrides]) -> list[dict]:
    rows = []
    for w in walks:
        v, t = float(np.median(w.speed_mps)), w.cycle_s
        rows.append(
            {
                "name": w.name,
                "group": group_of(w.name),
                "strides": int(t.size),
                "speed_mps": round(v, 3),
                "length_m": round(float(np.median(w.speed_mps * t)), 3),
                "cycle_s": round(float(np.median(t)), 3),
                "cycle_p10_p90_s": [round(float(np.percentile(t, q)), 3) for q in (10, 90)],
                "law_cycle_s": round(law_cycle(v), 3),
                "ratio_to_law": round(float(np.median(t)) / law_cycle(v), 3),
                "strides_left_out_truth_glitch": int(w.glitch_left_out_s.shape[0]),
            }
        )
    return rows


def bin_rows(walks: list[RecordedStrides]) -> list[dict]:
    rows = []
    for group in ("pyshoe_early", "pyshoe_late", "hallway"):
        ws = [w for w in walks if group_of(w.name) == group]
        v = np.concatenate([w.speed_mps for w in ws])
        t = np.concatenate([w.cycle_s for w in ws])
        for lo, hi in BINS:
            m = (v >= lo) & (v < hi)
            if m.sum() < 5:
                continue
            vm = float(np.median(v[m]))
            rows.append(
                {
                    "group": group,
                    "bin_mps": [lo, hi],
                    "strides": int(m.sum()),
                    "recordings": sum(
                        bool(((w.speed_mps >= lo) & (w.speed_mps < hi)).any()) for w in ws
                    ),
                    "speed_mps": round(vm, 3),
                    "cycle_s": round(float(np.median(t[m])), 3),
                    "law_cycle_s": round(law_cycle(vm), 3),
                }
            )
    return rows


def laws(walks: list[RecordedStrides]) -> dict[str, dict]:
    sets = {"all": walks}
    for group in ("pyshoe_early", "pyshoe_late", "hallway"):
        sets[group] = [w for w in walks if group_of(w.name) == group]
        sets[f"train_without_{group}"] = [w for w in walks if group_of(w.name) != group]
    out = {}
    for name, ws in sets.items():
        law = fit_cadence_law(ws)
        out[name] = {
            **{k: round(v, 4) if isinstance(v, float) else v for k, v in asdict(law).items()},
            "cycle_s_at": {
                f"{v:g}": round(law_cycle(v, (law.intercept_hz, law.slope_hz_per_mps)), 3)
                for v in (0.4, 0.8, 1.2, 1.6)
            },
        }
    return out


#: The law of each part of benchmarks/calibrate_foot.py: its training recordings.
PART_LAWS = {
    "all": "all",
    "pyshoe_early": "train_without_pyshoe_early",
    "pyshoe_late": "train_without_pyshoe_late",
    "hallway": "train_without_hallway",
}


def with_laws(fits: dict, walks: list[RecordedStrides]) -> dict:
    """``fits`` (a calibrate_foot.py output) with each part's training law set."""
    out = json.loads(json.dumps(fits))
    by_name = {w.name: w for w in walks}
    for name, part in out["parts"].items():
        law = fit_cadence_law([by_name[n] for n in part["train"]])
        options = {
            "cadence_intercept_hz": round(law.intercept_hz, 5),
            "cadence_slope_hz_per_mps": round(law.slope_hz_per_mps, 5),
            "cadence_log10_std": round(law.log10_std, 5),
        }
        part["cadence_law"] = asdict(law)
        part["model_options"] = options
        part["randomization"] = {**part["randomization"], **options}
        print(f"{name}: f = {law.intercept_hz:.4f} + {law.slope_hz_per_mps:.4f} v")
    if "all" in out["parts"]:
        out["randomization"] = out["parts"]["all"]["randomization"]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shared", type=Path, default=ROOT.parent / "shared" / "data")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--with-laws", type=Path, metavar="FITS", help="a calibrate_foot.py output")
    ap.add_argument("--write", type=Path, metavar="FILE", help="with --with-laws: write here")
    args = ap.parse_args()
    if (args.with_laws is None) != (args.write is None):
        raise SystemExit("--with-laws and --write go together")
    walks = load(args.shared)
    if args.with_laws is not None:
        fits = with_laws(json.loads(args.with_laws.read_text()), walks)
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(json.dumps(fits, indent=1))
        return
    rec = recording_rows(walks)
    print(
        "| recording | group | strides | speed (m/s) | length (m) | cycle (s), 10–90 % "
        "| law's cycle (s) | recorded / law |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in sorted(rec, key=lambda r: r["speed_mps"]):
        lo, hi = r["cycle_p10_p90_s"]
        print(
            f"| {r['name']} | {r['group']} | {r['strides']} | {r['speed_mps']:.2f} "
            f"| {r['length_m']:.2f} | {r['cycle_s']:.2f} ({lo:.2f}–{hi:.2f}) "
            f"| {r['law_cycle_s']:.2f} | {r['ratio_to_law']:.2f} |"
        )
    for w in walks:
        if w.glitch_left_out_s.size:
            spans = ", ".join(f"{a:.2f}–{b:.2f} s" for a, b in w.glitch_left_out_s)
            print(f"left out for a truth glitch: {w.name} {spans}")
    bins = bin_rows(walks)
    print("\n| group | stride speed (m/s) | strides (recordings) | cycle (s) | law's cycle (s) |")
    print("|---|---|---|---|---|")
    for b in bins:
        print(
            f"| {b['group']} | {b['bin_mps'][0]:g}–{b['bin_mps'][1]:g} (median "
            f"{b['speed_mps']:.2f}) | {b['strides']} ({b['recordings']}) | {b['cycle_s']:.2f} "
            f"| {b['law_cycle_s']:.2f} |"
        )
    fitted = laws(walks)
    print(
        "\n| law fitted to | a (Hz) | b (Hz per m/s) | walker spread (log10) "
        "| recordings (strides) | cycle at 0.4 / 0.8 / 1.2 / 1.6 m/s (s) |"
    )
    print("|---|---|---|---|---|---|")
    print(
        "| simulator (default) | 0.55 | 0.3 | 0 | – | "
        + " / ".join(f"{law_cycle(v):.2f}" for v in (0.4, 0.8, 1.2, 1.6))
        + " |"
    )
    for name, law in fitted.items():
        print(
            f"| {name} | {law['intercept_hz']:.3f} | {law['slope_hz_per_mps']:.3f} "
            f"| {law['log10_std']:.3f} | {law['recordings']} ({law['strides']}) | "
            + " / ".join(f"{c:.2f}" for c in law["cycle_s_at"].values())
            + " |"
        )
    if args.json:
        strides = {
            w.name: {
                "start_s": np.round(w.start_s, 3).tolist(),
                "cycle_s": np.round(w.cycle_s, 3).tolist(),
                "speed_mps": np.round(w.speed_mps, 3).tolist(),
                "truth_glitch_strides_s": np.round(w.glitch_left_out_s, 3).tolist(),
            }
            for w in walks
        }
        out = {"recordings": rec, "bins": bins, "laws": fitted, "strides": strides}
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
