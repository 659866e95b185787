"""How much do the VICON truth glitches weigh in the PyShoe ARMSE figures? (docs/REAL_DATA.md)

    PYTHONPATH=. .venv/bin/python benchmarks/truth_glitch_armse.py [--shared DIR]
        [--choices FILE] [--json FILE]

A measurement of the shipped metric's sensitivity, not a new metric. The truth
glitches are :func:`pednav_env.calibration.strides.truth_glitches`' spans (VICON
dropouts: the position frozen, then a jump faster than 20 m/s; and single-sample
jumps). On the 23 PyShoe development trials it runs ``real-fixed``, the shipped
shoe ``tuned`` constant and the regime constants of ``--choices`` (default
``benchmarks/results/transfer_by_regime_choices.json``; R_room is the one
docs/SIM_TO_REAL.md scores, R_hall is information only) through ``pednav run``'s
code path (:func:`agents.run_recording.run_named`, a constant as a ``pednav tune``
run directory, as ``benchmarks/transfer_by_regime.py`` does), and gives both ARMSE
forms of :func:`pednav_env.replay.metrics.track_errors` three ways:

- ``all``: the shipped figure, every sample with a reference;
- ``refit``: the glitch-span samples' reference set missing (NaN) and the shipped
  :func:`track_errors` run on it, so its rotation φ is fitted without them and the
  averages leave them out (both tracks are still referred to the first referenced
  sample, which no glitch span touches on these trials: checked, ``origin_in_glitch``);
- ``kept``: φ and the origins as in the shipped figure (all samples), only the
  averages leave the glitch-span samples out (:func:`armse_kept_rotation`).

Per trial also the share of referenced samples inside glitch spans (over the whole
recording, PyShoe's form, and after the alignment, ours). Then the transfer ratios of
docs/SIM_TO_REAL.md ("Per speed regime": mean PyShoe-form ARMSE of a constant / that
of ``real-fixed``) for each of the three ways, with the same paired bootstrap
(:func:`benchmarks.transfer_by_regime.paired_ratio_ci`). Prints the tables; ``--json``
writes every number.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from agents.run_recording import run_named
from baselines.tuned import save_result
from benchmarks.transfer_by_regime import KEY, RESULTS, paired_ratio_ci
from pednav_env.calibration.strides import truth_glitches
from pednav_env.io import find_recordings, load_recording
from pednav_env.replay.metrics import track_errors

ROOT = Path(__file__).resolve().parents[1]
Array = NDArray[np.float64]
FORMS = ("armse_m", "armse_pyshoe_m")
WAYS = ("all", "refit", "kept")


def glitch_mask(num_samples: int, spans: NDArray[np.int64]) -> NDArray[np.bool_]:
    """``True`` on the samples inside any inclusive span ``[first, last]``."""
    mask = np.zeros(num_samples, dtype=bool)
    for first, last in np.asarray(spans, dtype=np.int64).reshape(-1, 2):
        mask[first : last + 1] = True
    return mask


def armse_kept_rotation(
    pos_est: Array, truth: Array, start: int, leave_out: NDArray[np.bool_]
) -> dict[str, float]:
    """Both ARMSE forms with :func:`track_errors`' rotations and origins (fitted on
    every referenced sample) but the averages taken without the ``leave_out``
    samples. With nothing left out it is :func:`track_errors`' two figures (tested)."""
    m = track_errors(pos_est, truth, start, leave_out=leave_out)
    return {k: m[k] for k in FORMS}


def trial_figures(pos_est: Array, truth: Array, start: int, rate_hz: float) -> dict:
    """The glitch spans of one trial's reference, their share of its samples, and
    both ARMSE forms the three ways of the module docstring."""
    ref = np.asarray(truth, dtype=float)
    spans = truth_glitches(ref, rate_hz)
    mask = glitch_mask(ref.shape[0], spans)
    finite = np.isfinite(ref).all(axis=1)
    nav = np.zeros_like(finite)
    nav[start:] = True
    masked = ref.copy()
    masked[mask] = np.nan
    first_nav = start + int(np.argmax(finite[start:]))
    return {
        "glitch_spans": spans.tolist(),
        "glitch_samples": int(np.sum(mask & finite)),
        "share_all": float(np.sum(mask & finite) / np.sum(finite)),
        "share_navigation": float(np.sum(mask & finite & nav) / np.sum(finite & nav)),
        "origin_in_glitch": bool(mask[first_nav] or mask[int(np.argmax(finite))]),
        "all": {k: v for k, v in track_errors(pos_est, ref, start).items() if k in FORMS},
        "refit": {k: v for k, v in track_errors(pos_est, masked, start).items() if k in FORMS},
        "kept": armse_kept_rotation(pos_est, ref, start, mask),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--choices", default=str(RESULTS / "transfer_by_regime_choices.json"))
    ap.add_argument("--json", default=None, help="write all numbers to this file")
    args = ap.parse_args()
    choices = json.loads(Path(args.choices).read_text())
    recs = [load_recording(p) for p in find_recordings(Path(args.shared) / "pyshoe-vicon-dev")]
    t0 = time.time()
    trials: dict[str, dict] = {r.name: {} for r in recs}
    with tempfile.TemporaryDirectory() as tmp:
        policies = {"real-fixed": "real-fixed", "tuned": "tuned"}
        for regime, entry in choices["regimes"].items():
            save_result(KEY, entry["result"], Path(tmp) / regime / "tuned_actions.json")
            policies[regime] = str(Path(tmp) / regime)
        for rec in recs:
            for label, policy in policies.items():
                run = run_named(rec, policy)
                prep = run.prepared
                f = trial_figures(run.pos[0], prep.truth_pos, run.start_sample, prep.rate_hz)
                t = trials[rec.name]
                for key in ("glitch_spans", "glitch_samples", "share_all", "share_navigation"):
                    t[key] = f[key]
                t["origin_in_glitch"] = t.get("origin_in_glitch", False) or f["origin_in_glitch"]
                t["glitch_spans_s"] = [
                    [
                        round((prep.skipped + a) / prep.rate_hz, 2),
                        round((prep.skipped + b) / prep.rate_hz, 2),
                    ]
                    for a, b in f["glitch_spans"]
                ]
                t[label] = {w: f[w] for w in WAYS}
            print(rec.name, len(trials[rec.name]["glitch_spans"]), "glitches", flush=True)
    names = [r.name for r in recs]
    ratios = []
    for label in policies:
        if label == "real-fixed":
            continue
        for form in FORMS:
            for way in WAYS:
                a = [trials[n][label][way][form] for n in names]
                b = [trials[n]["real-fixed"][way][form] for n in names]
                ratios.append(
                    {
                        "policy": label,
                        "form": form,
                        "way": way,
                        "mean_m": float(np.mean(a)),
                        "reference_mean_m": float(np.mean(b)),
                        **paired_ratio_ci(a, b),
                    }
                )
    out = {
        "policies": list(policies),
        "trials": trials,
        "means_m": {
            label: {
                way: {
                    form: float(np.mean([trials[n][label][way][form] for n in names]))
                    for form in FORMS
                }
                for way in WAYS
            }
            for label in policies
        },
        "ratios_to_real_fixed": ratios,
        "seconds": round(time.time() - t0, 1),
    }
    print(markdown(out))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


def markdown(out: dict) -> str:
    """The per-trial table (glitched trials only, then the means) and the ratio table."""
    pols = ["real-fixed", "tuned", "room"]
    pols = [p for p in pols if p in out["policies"]]
    head = ["trial", "glitches", "share % (all / nav.)"]
    for p in pols:
        head += [f"{p} PyShoe all / refit / kept", f"{p} ours all / refit / kept"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def cells(fig: dict) -> list[str]:
        return [
            " / ".join(f"{fig[w][form]:.4f}" for w in WAYS)
            for form in ("armse_pyshoe_m", "armse_m")
        ]

    for name, t in out["trials"].items():
        if not t["glitch_spans"]:
            continue
        row = [
            name,
            str(len(t["glitch_spans"])),
            f"{100 * t['share_all']:.2f} / {100 * t['share_navigation']:.2f}",
        ]
        for p in pols:
            row += cells(t[p])
        lines.append("| " + " | ".join(row) + " |")
    n_all = len(out["trials"])
    share = np.mean([t["share_all"] for t in out["trials"].values()])
    row = [
        f"**mean of {n_all}**",
        str(sum(len(t["glitch_spans"]) for t in out["trials"].values())),
        f"{100 * share:.2f} / —",
    ]
    for p in pols:
        row += cells(out["means_m"][p])
    lines.append("| " + " | ".join(row) + " |")
    lines += [
        "",
        "| policy | form | way | mean (m) | real-fixed (m) | ratio | 95 % CI |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in out["ratios_to_real_fixed"]:
        lo, hi = r["ci95"]
        method = "" if r["method"] == "BCa" else f" ({r['method']})"
        lines.append(
            f"| {r['policy']} | {r['form']} | {r['way']} | {r['mean_m']:.4f} | "
            f"{r['reference_mean_m']:.4f} | {r['ratio']:.3f} | [{lo:.2f}, {hi:.2f}]{method} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    main()
