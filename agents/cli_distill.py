"""``pednav distill``: the teacher–student tuner (:mod:`agents.distill`) from the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agents.cli_types import nonnegative_int, output_dir, positive_int


def run_distill(args: argparse.Namespace) -> int:
    from agents.distill import distill
    from agents.evaluate import RECORDING_ENVS, env_options
    from agents.policies import FAMILY_ENVS
    from agents.run_dirs import check_seeds, claim_run_dirs
    from pednav_env.envs.foot_filters import LEARNED_FAMILY

    env_options(args.env_id)  # ValueError for an unknown env id
    if args.env_id in RECORDING_ENVS:
        raise ValueError(
            f"{args.env_id} plays recordings: distillation's teacher is the privileged "
            "oracle, which only the simulated envs have (distill on pednav/FootZupt-v0 and "
            "play the student on recordings with pednav evaluate --recordings)"
        )
    family = (args.filter or LEARNED_FAMILY) if args.env_id in FAMILY_ENVS else None
    if args.filter is not None and family is None:
        raise ValueError(f"--filter: {args.env_id} has no filter families")
    check_seeds(args.seeds)
    base = Path(args.run_dir or f"runs/{args.env_id.split('/')[-1]}/distill")
    run_dirs = [base / f"seed{s}" for s in args.seeds] if len(args.seeds) > 1 else [base]
    output_dir(base, "--run-dir")
    for path in claim_run_dirs(base, run_dirs, "", args.overwrite):
        print(f"removed {path}", file=sys.stderr)
    for seed, run_dir in zip(args.seeds, run_dirs, strict=True):
        distill(
            args.env_id,
            run_dir,
            seed=seed,
            lanes=args.lanes,
            iterations=args.iterations,
            steps_per_iteration=args.steps,
            filter_family=family,
            on_iteration=lambda i, loss: print(
                f"iteration {i}: loss {loss:.4f}", file=sys.stderr, flush=True
            ),
        )
        print(f"saved {run_dir / 'model.zip'} (+ vecnormalize.pkl, meta.json)")
    return 0


def add_distill_command(sub: argparse._SubParsersAction) -> None:
    """Add ``pednav distill`` to the subcommands."""
    di = sub.add_parser(
        "distill",
        help="train a sensor-only tuner from the privileged oracle (DAgger)",
        description="Teacher–student distillation (agents/distill.py): the student, the actor "
        "of a PPO MlpPolicy over the observation and its episode history, regresses the "
        "oracle's action along its own rollouts on training episodes. Writes a run directory "
        "(model.zip, vecnormalize.pkl, meta.json) for `pednav evaluate --policy RUN_DIR`.",
    )
    di.add_argument(
        "env_id", help="pednav/WaistStep-v0, pednav/MarkerTrack-v0 or pednav/FootZupt-v0"
    )
    di.add_argument(
        "--filter",
        choices=("paper", "shoe"),
        default=None,
        help="foot envs: the filter family (default shoe; its oracle table teaches)",
    )
    di.add_argument(
        "--seeds",
        type=nonnegative_int,
        nargs="+",
        default=[0],
        help="training run seeds (one run each)",
    )
    di.add_argument("--iterations", type=positive_int, default=6, help="DAgger iterations")
    di.add_argument(
        "--steps", type=positive_int, default=400, help="decision steps per iteration and lane"
    )
    di.add_argument("--lanes", type=positive_int, default=64, help="parallel episodes")
    di.add_argument("--run-dir", default=None, help="output dir (default runs/ENV/distill[/seedS])")
    di.add_argument(
        "--overwrite",
        action="store_true",
        help="remove what earlier runs left first (model.zip, vecnormalize.pkl, meta.json, "
        "checkpoints/, tb/ of a run directory; RUN_DIR/seedS of seeds not given); without "
        "it such a run directory is refused",
    )
    di.set_defaults(func=run_distill)
