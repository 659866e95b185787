"""``pednav fit-rule``: the gait-adaptive SHOE rule fitted on recordings
(:mod:`agents.gait_rule_real`), optionally cross-validated."""

from __future__ import annotations

import argparse
import json

from agents.cli_types import nonnegative_int, output_dir, positive_float, positive_int

OUT_NAME = "gait_rule.json"


def run_fit_rule(args: argparse.Namespace) -> int:
    from agents.gait_rule import write_params
    from agents.gait_rule_real import cross_validate, fit, folds, load_fit_recordings
    from agents.progress import progress_bar, wanted

    out_dir = output_dir(args.out, "--out")  # before the fit, not after it
    if args.folds == 1 or args.folds < 0:
        raise ValueError(f"--folds: 0 (no cross-validation) or at least 2, got {args.folds}")
    if args.simulated_episodes < 0:
        raise ValueError(f"--simulated-episodes: must be ≥ 0, got {args.simulated_episodes}")
    recs = load_fit_recordings(args.recordings)
    held = folds(recs, args.folds) if args.folds else None
    settings = {
        "generations": args.generations,
        "popsize": args.popsize,
        "sigma0": args.sigma0,
        "seed": args.seed,
        "simulated_episodes": args.simulated_episodes,
        "constant": args.constant,
    }
    total = args.generations * (1 + (args.folds or 0))
    with progress_bar("fitting the gait rule", total, wanted(args.json)) as advance:

        def tick(_generation: int, _best: float) -> None:
            advance(1)

        cv = cross_validate(recs, held, progress=tick, **settings) if held else None
        params, record = fit(recs, progress=tick, **settings)
    if cv is not None:
        record["cross_validation"] = {"folds": args.folds, **cv}
    path = write_params(params, out_dir / OUT_NAME, record)
    if args.json:
        print(json.dumps({"path": str(path), "c": list(params.c), **record}))
        return 0
    kind = "constant (slope held at 0)" if args.constant else "rule"
    print(f"wrote {path} ({kind}): c = {[round(v, 4) for v in params.c]}")
    print(
        f"objective (mean over groups of mean log10 error): {record['objective_log10_m']:.4f} "
        f"(start {record['start_objective_log10_m']:.4f})"
    )
    held_out = (cv or {}).get("held_out_errors_m", {})
    print("| recording | group | metric | in-sample error m | held-out error m |")
    print("|---|---|---|---|---|")
    for r in recs:
        h = f"{held_out[r.name]:.4f}" if r.name in held_out else "—"
        print(f"| {r.name} | {r.group} | {r.metric} | {record['errors_m'][r.name]:.4f} | {h} |")
    return 0


def add_fit_rule_command(sub: argparse._SubParsersAction) -> None:
    """Add ``pednav fit-rule`` to the subcommands."""
    fr = sub.add_parser(
        "fit-rule",
        help="fit the gait-adaptive SHOE rule on recordings (docs/REAL_DATA.md)",
        description="CMA-ES over the gait rule's parameters on recordings with truth (a "
        "truth track: PyShoe's ARMSE; footprints: the mean footprint error), each directory "
        "one group of equal weight. Writes OUT/gait_rule.json; play it with "
        "`pednav run REC --policy OUT/gait_rule.json` or `pednav evaluate ... --policy "
        "OUT/gait_rule.json`. With --folds K, also the held-out error of every recording "
        "(K fits, each without one contiguous block of every group).",
    )
    fr.add_argument("recordings", nargs="+", help="recording files or directories of them")
    fr.add_argument("--out", required=True, help="directory for gait_rule.json")
    fr.add_argument(
        "--folds", type=int, default=0, help="cross-validation folds (0: none; default 0)"
    )
    fr.add_argument("--generations", type=positive_int, default=12, help="CMA-ES generations")
    fr.add_argument("--popsize", type=positive_int, default=10, help="candidates per generation")
    fr.add_argument("--sigma0", type=positive_float, default=0.3, help="CMA-ES initial step")
    fr.add_argument("--seed", type=nonnegative_int, default=1, help="CMA-ES seed")
    fr.add_argument(
        "--simulated-episodes",
        type=int,
        default=0,
        metavar="N",
        help="add a group of N calibrated simulated walks to the objective (covers gaits "
        "the recordings lack, e.g. running; the shipped rule used 16; default 0)",
    )
    fr.add_argument(
        "--constant",
        action="store_true",
        help="fit the best constant SHOE configuration instead (slope held at 0): the "
        "comparator for what adapting adds",
    )
    fr.add_argument("--json", action="store_true", help="print the result as one JSON object")
    fr.set_defaults(func=run_fit_rule)
