"""Fit the calibrated foot simulator to the development recordings (CMA-ES), with
leave-one-group-out cross-validation.

The parameters, the distance and the optimiser are those of
:mod:`pednav_env.calibration.parameters`, :mod:`pednav_env.calibration.objective` and
:mod:`pednav_env.calibration.fit` (docs/SIM_TO_REAL.md). Parts:

- ``all``: a fit on all recordings (the shipped
  ``StanceRandomization.calibrated()``), then ``pednav sim2real``'s check on them
  (60 walks per band, seed 0, and the coverage for seeds 1 and 2: walks the fit
  never saw);
- ``pyshoe_early``, ``pyshoe_late``, ``hallway``: the three groups (the PyShoe
  trials before 11:35 and after, two sessions of one day; the hallway walks,
  another walker, place and day). Each fits on the two other groups and reports
  the held-out group's coverage and distance, and the training groups' coverage
  (in-sample) beside them.

The four parts are independent; run them in one process or split over several
(``--parts``, one ``--out`` each) and join the outputs with ``--merge``:

    PYTHONPATH=. .venv/bin/python benchmarks/calibrate_foot.py \\
        --pyshoe ../shared/data/pyshoe-vicon-dev --hallway ../shared/data/hallway-gcp-dev \\
        --parts all hallway --out /tmp/a.json
    PYTHONPATH=. .venv/bin/python benchmarks/calibrate_foot.py ... \\
        --parts pyshoe_early pyshoe_late --out /tmp/b.json
    PYTHONPATH=. .venv/bin/python benchmarks/calibrate_foot.py \\
        --merge /tmp/a.json /tmp/b.json --out benchmarks/results/calibrate_foot.json

Each part scores its start point first (``START`` or ``--warm-start``'s values)
and keeps it when the CMA-ES search finds nothing better; the output's
``fit`` says which (``kept_start``, ``start_distance``, ``search_distance``).

About 4–6 min of CPU per part with the defaults (1000 evaluations of 8 walks of
20–30 s in each band holding recordings), and 1 min for its checks.

``--swing-speed-exponent`` fits a 16th value, the swing vigour's speed exponent
(:data:`pednav_env.calibration.parameters.SWING_SPEED`), from 0 (today's behaviour; a
15-value warm start is extended by it): the candidate v3 of
docs/SIM_TO_REAL_CANDIDATES.md ("A candidate: the swing's vigour by speed"), stored as
``benchmarks/results/calibrate_foot_v3.json``.

``--heel-rocker`` fits (and checks) the model whose walkers land the heel at rest
on its footfall (``StanceRandomization.heel_rocker``, not a fitted value); the
output's ``settings`` and ``randomization`` record it, and ``--recheck`` reads it
from there.

``--cadence-law`` gives every simulated walker the walking cadence law
f = a + b·v with a walker-to-walker spread
(:class:`pednav_env.gait.stance_motion.StanceRandomization`'s ``cadence_*``
fields), **regressed per part on that part's training recordings only**
(:func:`pednav_env.calibration.cadence.fit_cadence_law` on their strides; not a
CMA-ES value): a fold's law never sees its held-out group. The part's output
holds the law (``cadence_law``) and its model options (``model_options``, also in
its ``randomization``, so ``pednav sim2real --model`` reads them; ``--recheck``
uses them); the start point is scored with the law.

``--pitch-knots`` fits one value more, last: the stride length below which the
swing's pitch knots shrink (:data:`pednav_env.calibration.parameters.PITCH_KNOTS`,
``StanceRandomization.pitch_knot_stride_m``), from 0 (off: a warm start without
it is extended by 0, its own behaviour); combines with the options above.

``--swing-term`` adds the fit distance's opt-in swing term (per stride-speed bin,
the W1 of the strides' log10 swing |ω| median, ``stride_swing``;
:func:`pednav_env.calibration.objective.swing_distance`), and the checks then report its
per-bin W1 on the check's walks (``swing_w1_by_bin``). ``--coverage-walks N``
measures the distance's coverage term on N other simulated walks per band
(:func:`pednav_env.calibration.objective.coverage_seed`) instead of the W1 terms' walks;
the checks are not affected (they measure coverage with ``pednav sim2real``'s own
envelope). Both are stored in ``settings``; ``--recheck`` reads ``swing_term`` from
there. Candidate v7 of docs/SIM_TO_REAL_CANDIDATES.md used both.

``--gait-priors`` narrows the box of the gait timing to ranges from published gait
studies (:data:`pednav_env.calibration.parameters.GAIT_PRIORS`: foot flat at 1 m/s
0.15–0.43 of the cycle, its change per unit ln speed −0.15–0, each heel phase
0.12–0.20; Perry & Burnfield 2010, Levangie & Norkin, Kirtley et al. 1985);
a warm start outside is clipped to it. Stored in ``settings`` (``gait_priors``).
Candidate v8 of docs/SIM_TO_REAL_CANDIDATES.md.

``--match-turns`` gives every recording its turn per stride (the 25th–75th percentile
of its |turn per stride| from its truth at stance or its footprints, at most π/2,
:func:`pednav_env.calibration.path_turns.route_turn_range`), so that the simulated walks of
the fit and of the checks walk the circles of the band's recordings
(:func:`pednav_env.calibration.compare.band_turns`; the PyShoe trials turn about 1 rad
per stride) instead of the scenario's straight legs; the held-out check's walks take the
held-out recordings' turns, as they take their speeds. Stored in ``settings``
(``match_turns``, absent without it); ``--recheck`` reads it. Candidate v9.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from pednav_env.calibration.cadence import (
    CadenceLaw,
    RecordedStrides,
    fit_cadence_law,
    recorded_strides,
)
from pednav_env.calibration.compare import DEFAULT_WALKS_PER_BAND, SPEED_BANDS, band_label, compare
from pednav_env.calibration.fit import fit, groups
from pednav_env.calibration.objective import GRADE, band_distance, by_band, swing_distance
from pednav_env.calibration.parameters import (
    GAIT_PRIORS,
    NAMES,
    PITCH_KNOTS,
    START,
    SWING_SPEED,
    randomization,
)
from pednav_env.calibration.path_turns import route_turn_range
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.sources import load_walk
from pednav_env.calibration.stats import WalkStats, walk_stats

PARTS = ("all", "pyshoe_early", "pyshoe_late", "hallway")
#: sim2real's envelope: walks per band (its default) and seed; the coverage is
#: also reported for the seeds of CHECK_OTHER_SEEDS (how much the envelope's
#: sampling moves it).
CHECK_WALKS, CHECK_SEED = DEFAULT_WALKS_PER_BAND, 0
CHECK_OTHER_SEEDS = (1, 2)


def check(
    stats: list[WalkStats],
    x: np.ndarray,
    options: dict | None = None,
    knots: bool = False,
    swing: bool = False,
) -> dict:
    """``pednav sim2real``'s comparison of ``stats`` with the model ``x``: coverage,
    p10-only coverage, the largest envelope excess, and the distance of the fit
    (its terms) measured on the check's walks; ``options`` fixed model options
    (:func:`pednav_env.calibration.parameters.randomization`, as ``knots``). With
    ``swing``, also the swing term's per-bin W1 on the check's walks
    (``swing_w1_by_bin``, decades of rad/s)."""
    model = SimModel("calibrated", GRADE, randomization(x, options, knots))
    report = compare(stats, model, CHECK_WALKS, CHECK_SEED)
    covered, total = report.coverage
    other = [compare(stats, model, CHECK_WALKS, seed).coverage[0] for seed in CHECK_OTHER_SEEDS]
    p10 = sum(
        b.p10_envelope[0] <= s.log_shoe_p10 <= b.p10_envelope[1]
        for b in report.bands
        for s in b.real
    )
    p50 = sum(
        b.p50_envelope[0] <= s.log_shoe_p50 <= b.p50_envelope[1]
        for b in report.bands
        for s in b.real
    )
    terms: dict[str, float] = {}
    for b in report.bands:
        if b.real:
            for name, value in band_distance(b.real, b.sim).items():
                terms[name] = terms.get(name, 0.0) + len(b.real) / total * value
    excess = [b.excess_width() for b in report.bands if b.real]
    extra = {}
    if swing:
        sim = [s for b in report.bands for s in b.sim]
        extra["swing_w1_by_bin"] = {
            band_label(SPEED_BANDS[k]): round(v, 3) for k, v in swing_distance(stats, sim).items()
        }
    return {
        "covered": covered,
        "covered_other_seeds": dict(zip(map(str, CHECK_OTHER_SEEDS), other, strict=True)),
        "p10_inside": p10,
        "p50_inside": p50,
        "total": total,
        "max_envelope_excess_decades": round(max(excess), 3),
        "distance": round(sum(terms.values()), 4),
        "distance_terms": {k: round(v, 4) for k, v in terms.items()},
        "w1_pooled_by_band": {
            f"{b.band[0]:g}": round(b.distance(), 3) for b in report.bands if b.real
        },
        **extra,
        "text": report.format_text(),
    }


def cadence_values(law: CadenceLaw) -> dict[str, float]:
    """The StanceRandomization fields of a fitted cadence law (5 digits)."""
    return {
        "cadence_intercept_hz": round(law.intercept_hz, 5),
        "cadence_slope_hz_per_mps": round(law.slope_hz_per_mps, 5),
        "cadence_log10_std": round(law.log10_std, 5),
    }


def run_part(
    part: str,
    stats: list[WalkStats],
    args: argparse.Namespace,
    strides: dict[str, RecordedStrides] | None = None,
) -> dict:
    folds = groups(stats)
    train = stats if part == "all" else [s for g, v in folds.items() if g != part for s in v]
    log = lambda gen, best: print(f"  [{part}] generation {gen}: best {best:.4f}", flush=True)  # noqa: E731
    t0 = time.perf_counter()
    x0 = START
    if args.warm_start:
        x0 = json.loads(Path(args.warm_start).read_text())["parts"][part]["fit"]["x"]
    if args.swing_speed_exponent and len(x0) == len(NAMES):
        x0 = [*x0, SWING_SPEED.start]
    knots = args.pitch_knots
    if knots and len(x0) == len(NAMES) + int(args.swing_speed_exponent):
        x0 = [*x0, PITCH_KNOTS.start]
    options: dict = model_options(args.heel_rocker)
    law = None
    if strides is not None:
        law = fit_cadence_law([strides[s.name] for s in train])
        options.update(cadence_values(law))
        print(
            f"  [{part}] cadence law from the training recordings: f = "
            f"{law.intercept_hz:.3f} + {law.slope_hz_per_mps:.3f} v Hz, walker spread "
            f"{law.log10_std:.3f} (log10; {law.recordings} recordings, {law.strides} strides)",
            flush=True,
        )
    result = fit(
        train,
        args.walks,
        args.max_evaluations,
        args.seed,
        args.popsize,
        log,
        x0,
        args.sigma0,
        options,
        knots,
        args.swing_term,
        args.coverage_walks,
        args.gait_priors,
    )
    out = {
        "train": sorted(s.name for s in train),
        "bands_trained": [int(k) for k in by_band(train)],
        "fit": result.to_json(),
        "randomization": asdict(randomization(result.x, options, knots)),
        "in_sample": check(train, result.x, options, knots, args.swing_term),
    }
    if law is not None:
        out["cadence_law"] = asdict(law)
        out["model_options"] = options
    if part != "all":
        out["held_out"] = check(folds[part], result.x, options, knots, args.swing_term)
    print(
        f"{part}: distance {result.distance:.4f} "
        f"({'the start kept' if result.kept_start else 'the search'}; start "
        f"{result.start_distance:.4f}, search {result.search_distance:.4f}) "
        f"after {result.evaluations} evaluations "
        f"({result.cpu_s:.0f} s CPU, {time.perf_counter() - t0:.0f} s wall); in-sample covered "
        f"{out['in_sample']['covered']}/{out['in_sample']['total']}"
        + (
            f"; held-out covered {out['held_out']['covered']}/{out['held_out']['total']}"
            if part != "all"
            else ""
        ),
        flush=True,
    )
    return out


def model_options(heel_rocker: bool) -> dict:
    """The fixed model options of a fit: ``heel_rocker`` only when set (a fit
    without it builds the same StanceRandomization as before the option)."""
    return {"heel_rocker": True} if heel_rocker else {}


def load_recordings(
    args: argparse.Namespace, strides: bool = False, turns: bool = False
) -> tuple[list[WalkStats], dict[str, RecordedStrides] | None]:
    """The statistics of the PyShoe trials and the hallway walks (``_LLIO.mat``),
    and with ``strides`` each recording's strides (:func:`recorded_strides`) by
    walk name; with ``turns`` each recording's turn per stride in its statistics
    (``--match-turns``); every file is read once."""
    if not (args.pyshoe and args.hallway):
        raise SystemExit("--pyshoe and --hallway are required (with --recheck too)")
    paths = sorted(Path(args.pyshoe).glob("*.mat"))
    paths += sorted(Path(args.hallway).glob("*_LLIO.mat"))
    stats, by_name = [], {}
    for p in paths:
        samples = load_walk(p)
        walk = walk_stats(samples)
        if turns:
            walk = replace(walk, turn_per_stride_rad=route_turn_range(samples))
        stats.append(walk)
        if strides:
            by_name[samples.name] = recorded_strides(samples)
    return stats, (by_name if strides else None)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pyshoe", help="directory of PyShoe .mat trials")
    ap.add_argument("--hallway", help="directory of hallway _LLIO.mat walks")
    ap.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS))
    ap.add_argument("--walks", type=int, default=8, help="simulated walks per band in the fit")
    ap.add_argument("--max-evaluations", type=int, default=1000, help="CMA-ES budget per fit")
    ap.add_argument("--popsize", type=int, default=12, help="CMA-ES population")
    ap.add_argument("--seed", type=int, default=7, help="fit seed (not sim2real's)")
    ap.add_argument("--sigma0", type=float, default=0.2, help="CMA-ES step in the unit box")
    ap.add_argument(
        "--warm-start",
        metavar="JSON",
        help="start each part from the same part's parameters in this earlier output "
        "(a fold's start then never saw its held-out group)",
    )
    ap.add_argument(
        "--swing-speed-exponent",
        action="store_true",
        help="also fit the swing vigour's speed exponent (a 16th value, from 0)",
    )
    ap.add_argument(
        "--heel-rocker",
        action="store_true",
        help="walkers land the heel at rest on its footfall (StanceRandomization.heel_rocker)",
    )
    ap.add_argument(
        "--cadence-law",
        action="store_true",
        help="give the walkers the cadence law f = a + b v (and its walker spread) "
        "regressed on each part's TRAINING recordings' strides (not searched)",
    )
    ap.add_argument(
        "--pitch-knots",
        action="store_true",
        help="also fit the stride length below which the swing pitch knots shrink "
        "(StanceRandomization.pitch_knot_stride_m; one value more, from 0 = off)",
    )
    ap.add_argument(
        "--swing-term",
        action="store_true",
        help="add the distance's swing term (per stride-speed bin, W1 of log10 swing |omega|)",
    )
    ap.add_argument(
        "--coverage-walks",
        type=int,
        default=0,
        metavar="N",
        help="measure the distance's coverage term on N other simulated walks per band "
        "(seeds disjoint from the W1 walks'); 0: on the W1 walks (default)",
    )
    ap.add_argument(
        "--gait-priors",
        action="store_true",
        help="narrow the gait timing's box to published ranges (GAIT_PRIORS: foot flat at "
        "1 m/s 0.15-0.43 of the cycle, its slope per ln speed -0.15-0, each heel phase "
        "0.12-0.20; Perry & Burnfield 2010, Levangie & Norkin, Kirtley et al. 1985); "
        "a warm start outside is clipped",
    )
    ap.add_argument(
        "--match-turns",
        action="store_true",
        help="simulated walks walk the circles of their band's recordings (each recording's "
        "25th-75th percentile of |turn per stride|) instead of straight legs",
    )
    ap.add_argument("--merge", nargs="+", metavar="JSON", help="join the outputs of parts")
    ap.add_argument(
        "--recheck",
        action="store_true",
        help="with --merge: redo the checks of the fitted parameters (no fit)",
    )
    ap.add_argument("--out", default=None, help="write the results as JSON here")
    args = ap.parse_args()
    if args.coverage_walks < 0:
        ap.error(f"--coverage-walks must be >= 0, got {args.coverage_walks}")
    names = [*NAMES, SWING_SPEED.name] if args.swing_speed_exponent else list(NAMES)
    names += [PITCH_KNOTS.name] if args.pitch_knots else []
    result: dict = {"names": names, "parts": {}}
    if args.merge:
        for path in args.merge:
            part = json.loads(Path(path).read_text())
            result["parts"].update(part["parts"])
            result.update({k: v for k, v in part.items() if k != "parts"})
        if args.recheck:
            settings = result.get("settings", {})
            stats, _ = load_recordings(args, turns=settings.get("match_turns", False))
            folds = groups(stats)
            shared = model_options(settings.get("heel_rocker", False))
            knots = settings.get("pitch_knots", False)
            swing = settings.get("swing_term", False)
            for name, part in result["parts"].items():
                x = np.asarray(part["fit"]["x"])
                options = part.get("model_options", shared)  # a part's cadence law too
                train = [s for s in stats if s.name in set(part["train"])]
                part["in_sample"] = check(train, x, options, knots, swing)
                if name != "all":
                    part["held_out"] = check(folds[name], x, options, knots, swing)
                print(f"{name}: rechecked", flush=True)
    else:
        stats, strides = load_recordings(args, args.cadence_law, args.match_turns)
        result["settings"] = {
            "warm_start": args.warm_start,
            "sigma0": args.sigma0,
            "walks": args.walks,
            "max_evaluations": args.max_evaluations,
            "popsize": args.popsize,
            "seed": args.seed,
            "swing_speed_exponent": args.swing_speed_exponent,
            "heel_rocker": args.heel_rocker,
            "cadence_law": args.cadence_law,
            "pitch_knots": args.pitch_knots,
            "swing_term": args.swing_term,
            "coverage_walks": args.coverage_walks,
        }
        if args.gait_priors:  # absent without it: the shipped fit's settings unchanged
            result["settings"]["gait_priors"] = {k: list(v) for k, v in GAIT_PRIORS.items()}
        if args.match_turns:  # likewise
            result["settings"]["match_turns"] = True
        for part in args.parts:
            result["parts"][part] = run_part(part, stats, args, strides)
            if args.out:
                Path(args.out).write_text(json.dumps(result, indent=1))
    if "all" in result["parts"]:
        result["randomization"] = result["parts"]["all"]["randomization"]
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
