"""``pednav tune``: the CMA-ES constant (:mod:`baselines.tuned`) and, with
``--per-context``, the privileged oracle's table (:mod:`baselines.oracle`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from agents.cli_options import (
    add_backend_options,
    add_env_options,
    backend_from_args,
    env_kwargs_from_args,
)
from agents.cli_types import nonnegative_int, output_dir, positive_float, positive_int


def run_tune(args: argparse.Namespace) -> int:
    import gymnasium as gym

    import pednav_env  # noqa: F401  (registers the environments)
    from agents.evaluate import check_env_kwargs
    from agents.policies import FAMILY_ENVS
    from agents.progress import progress_bar, wanted
    from baselines import oracle
    from baselines.tuned import (
        RESULT_NAME,
        RESULTS_FILE,
        read_results,
        result_key,
        save_result,
        search,
    )
    from pednav_env.envs.foot_filters import LEARNED_FAMILY

    env_kwargs = env_kwargs_from_args(args)
    check_env_kwargs(args.env_id, env_kwargs)
    if args.per_context and set(env_kwargs) - {"filter"}:
        raise ValueError("--per-context sets the env's config itself: no env options but --filter")
    family = None
    if args.env_id in FAMILY_ENVS:
        family = env_kwargs.setdefault("filter", LEARNED_FAMILY)
    key = result_key(args.env_id, family)
    action_dim = gym.make(args.env_id, **env_kwargs).action_space.shape[0]
    run_dir = Path(args.run_dir or f"runs/{args.env_id.split('/')[-1]}/tune_seed{args.seed}")
    output_dir(run_dir, "--run-dir")  # before the search, not after it
    backend = backend_from_args(args)
    options = {
        "episodes": args.episodes,
        "generations": args.generations,
        "popsize": args.popsize,
        "seed": args.seed,
        "map_fn": backend.map,
        "n_tasks": backend.workers,
        "reevaluate_episodes": args.reevaluate,
    }
    if args.per_context:
        split = oracle.context_split(args.env_id, family)
        shipped = read_results(RESULTS_FILE) if RESULTS_FILE.exists() else {}
        if key in shipped:  # refine the shipped CMA-ES constant per context
            options["x0"] = shipped[key]["action"]
            options["sigma0"] = args.sigma0
        total = (args.generations + 1) * len(split.searched)
        with progress_bar("CMA-ES generations", total, wanted(False)) as advance:
            entry = oracle.search_per_context(
                args.env_id,
                action_dim,
                search,
                filter_family=family,
                unsearched_action=options.get("x0"),
                on_generation=advance,
                **options,
            )
        written = [oracle.save_table_entry(key, entry, run_dir / oracle.RESULT_NAME)]
        if args.install:
            written.append(oracle.save_table_entry(key, entry, oracle.RESULTS_FILE))
        print(json.dumps(entry, indent=2))
        for path in written:
            print(f"wrote {path}", file=sys.stderr)
        return 0
    with progress_bar("CMA-ES generations", args.generations + 1, wanted(False)) as advance:
        result = search(
            args.env_id, action_dim, env_kwargs=env_kwargs, on_generation=advance, **options
        )
    if args.speed is not None:  # the walks' speed range, readable beside the config's repr
        result["speed_mps"] = list(args.speed)
    written = [save_result(key, result, run_dir / RESULT_NAME)]
    if args.install:
        written.append(save_result(key, result, RESULTS_FILE))
    print(json.dumps(result, indent=2))
    for path in written:
        print(f"wrote {path}", file=sys.stderr)
    if not args.install:
        print(
            f"evaluate it with: pednav evaluate {args.env_id} --policy paper tuned {run_dir}; "
            "--install replaces the shipped `tuned` baseline",
            file=sys.stderr,
        )
    return 0


def add_tune_command(sub: argparse._SubParsersAction) -> None:
    """Add ``pednav tune`` to the subcommands."""
    tu = sub.add_parser(
        "tune",
        help="search the best constant action (tuned-fixed baseline)",
        description="CMA-ES over constant actions on training episodes. Writes "
        "RUN_DIR/tuned_actions.json and prints the result; evaluate it with "
        "`pednav evaluate ENV --policy RUN_DIR`. The shipped baseline that `--policy tuned` "
        "reads (baselines/tuned_actions.json) is replaced only with --install.",
    )
    tu.add_argument("env_id", help="e.g. pednav/FootZupt-v0")
    tu.add_argument(
        "--episodes", type=positive_int, default=16, help="training episodes per candidate"
    )
    tu.add_argument("--generations", type=positive_int, default=8, help="CMA-ES generations")
    tu.add_argument("--popsize", type=positive_int, default=8, help="candidates per generation")
    tu.add_argument("--seed", type=nonnegative_int, default=1, help="CMA-ES seed")
    tu.add_argument(
        "--run-dir",
        default=None,
        help="output dir for tuned_actions.json (default runs/ENV/tune_seedS)",
    )
    tu.add_argument(
        "--install",
        action="store_true",
        help="also replace this env's entry in the shipped baselines/tuned_actions.json, "
        "which `--policy tuned` reads (with --per-context: baselines/oracle_actions.json, "
        "which `--policy oracle` reads)",
    )
    tu.add_argument(
        "--reevaluate",
        type=nonnegative_int,
        default=0,
        metavar="N",
        help="play the chosen action on N fresh training episodes and report that mean",
    )
    tu.add_argument(
        "--per-context",
        action="store_true",
        help="one search per context (sensor grade, UWB condition, foot speed band), each started "
        "from the shipped CMA-ES constant: the privileged oracle's table, written as "
        "RUN_DIR/oracle_actions.json",
    )
    tu.add_argument(
        "--sigma0",
        type=positive_float,
        default=0.25,
        help="--per-context: CMA-ES initial step size around the shipped constant",
    )
    add_env_options(tu)
    add_backend_options(tu, "a generation's candidates run")
    tu.set_defaults(func=run_tune)
