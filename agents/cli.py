"""The ``pednav`` command line.

Subcommands (their JSON formats are contracts, see docs/CONTRACTS.md):

- ``pednav reproduce ID [--runs N] [--seed S] [--json] [--plots DIR]`` — a
  paper's figures beside ours.
- ``pednav evaluate ENV_ID --policy NAME [NAME ...] --episodes N --seed S
  [--json] [--plot DIR] [--scenario NAME] [--speed LO HI] [--recordings DIR] [--env-kwarg K=V]
  [--backend serial|ray] [--ray-address A]`` — policies on the same held-out
  episodes.
- ``pednav train ENV_ID --algo ppo|sac [--timesteps N] [--seed S | --seeds S ...]
  [--n-envs K] [--config FILE] [--run-dir DIR] [--resume] [--overwrite] [--backend ...]`` —
  train a tuner (SB3), one run or one per seed.
- ``pednav tune ENV_ID [--speed LO HI] [--run-dir DIR] [--install] [--backend ...]`` — CMA-ES
  search of the tuned-fixed baseline (:mod:`agents.cli_tune`).
- ``pednav run RECORDING|DIR [--format F] [--policy NAME|SETUP.json]
  [--footprints FILE|none] [--json] [--plot FILE] [--out TRACK.csv] [loader
  options]`` — the ZUPT-UKF on a recorded walk or a folder of them
  (docs/REAL_DATA.md); the default policy is ``real-fixed``.
- ``pednav simulate --out FILE [--speed LO HI | --gait G] [--duration S]
  [--rate HZ] [--imu GRADE] [--stops/--no-stops] [--seed N] [--model M]`` — a
  simulated foot walk written as a CSV recording that ``pednav run`` reads.
- ``pednav bench ENV [--json] [--sizes N ...]`` — env steps/s of the native
  vector env against a filterpy reference (ENV = foot, waist, marker).
- ``pednav fit-rule RECORDING|DIR ... --out DIR [--folds K]`` — the gait-adaptive
  SHOE rule fitted on recordings with truth (:mod:`agents.cli_fit_rule`).
- ``pednav sim2real RECORDING... [--model M] [--walks N] [--nav] [--json] [--plot DIR]``
  — the foot simulator beside recorded walks per speed band
  (docs/SIM_TO_REAL.md).

``distill`` is defined in :mod:`agents.cli_distill`, ``run``/``simulate``/``sim2real``
in :mod:`agents.cli_recordings`; the option groups several commands share in
:mod:`agents.cli_options`.

Long commands draw a progress bar on stderr when it is a terminal (not with
``--json``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from agents.cli_distill import add_distill_command
from agents.cli_fit_rule import add_fit_rule_command
from agents.cli_options import (
    add_backend_options,
    add_env_options,
    backend_from_args,
    env_kwargs_from_args,
)
from agents.cli_recordings import add_recording_commands
from agents.cli_tune import add_tune_command
from agents.cli_types import (
    nonnegative_int,
    output_dir,
    positive_float,
    positive_int,
    removing_created_dirs_on_failure,
)
from pednav_env import __version__


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from agents.progress import progress_bar, wanted
    from pednav_env import reproduce

    kwargs: dict = {"seed": args.seed}
    if args.runs is not None:
        kwargs["runs"] = args.runs
    if args.plots is not None:
        kwargs["plot_dir"] = output_dir(args.plots, "--plots")
    with progress_bar(f"reproducing paper {args.paper}", None, wanted(args.json)):
        result = reproduce.run(args.paper, **kwargs)
    if args.json:
        print(json.dumps(result.to_json_dict()))
    else:
        print(result.format_table())
    return 0


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from agents.evaluate import MAX_LANES, evaluate
    from agents.evaluate_report import format_table
    from agents.progress import progress_bar, wanted
    from pednav_env.io import find_recordings

    env_kwargs = env_kwargs_from_args(args)
    backend = backend_from_args(args)
    plot_dir = None if args.plot is None else output_dir(args.plot, "--plot")
    episodes = args.episodes
    if episodes is None:  # one episode per recording, else 100
        data_dir = env_kwargs.get("data_dir")
        episodes = len(find_recordings(data_dir)) if data_dir is not None else 100
    total = episodes * (len(set(args.policy) | {"paper"}))
    with progress_bar("episodes", total, wanted(args.json)) as advance:
        result = evaluate(
            args.env_id,
            args.policy,
            episodes,
            args.seed,
            env_kwargs,
            plot_dir,
            backend=backend,
            on_episode=advance,
            lanes=args.lanes or MAX_LANES,
        )
    print(json.dumps(result) if args.json else format_table(result))
    return 0


def _cmd_train(args: argparse.Namespace) -> int:
    from agents.policies import FAMILY_ENVS
    from agents.run_dirs import check_seeds, claim_run_dirs
    from agents.train import (
        check_resumable,
        default_run_dir,
        load_hyperparams,
        train,
        train_seeds,
    )
    from pednav_env.seeds import training_seed

    if args.filter is not None and args.env_id not in FAMILY_ENVS:
        raise ValueError(f"--filter: {args.env_id} has no filter families")
    load_hyperparams(args.algo, args.env_id, args.config)  # a bad file before the run dir
    if args.seeds is None:
        training_seed(args.seed)
        run_dirs = [Path(args.run_dir or default_run_dir(args.env_id, args.algo, args.seed))]
        base = run_dirs[0]
    else:
        check_seeds(args.seeds)
        run_dirs = [default_run_dir(args.env_id, args.algo, s, args.run_dir) for s in args.seeds]
        base = run_dirs[0].parent
    if args.resume:
        check_resumable(run_dirs)  # before --overwrite removes anything
    if args.run_dir is not None:
        output_dir(args.run_dir, "--run-dir")
    for path in claim_run_dirs(base, run_dirs, f"{args.algo}_", args.overwrite, args.resume):
        print(f"removed {path}", file=sys.stderr)

    common = {
        "timesteps": args.timesteps,
        "n_envs": args.n_envs,
        "config_file": args.config,
        "resume": args.resume,
        "filter_family": args.filter,
    }
    if args.seeds is None:
        if args.backend != "serial" or args.ray_address or args.ray_cpus:
            raise ValueError("--backend ray runs several training seeds: give --seeds S [S ...]")
        run_dir = train(
            args.env_id,
            args.algo,
            seed=args.seed,
            run_dir=args.run_dir,
            progress_bar=not args.no_progress,
            **common,
        )
        print(f"saved {run_dir / 'model.zip'} (+ vecnormalize.pkl, meta.json)")
        return 0
    from agents.progress import progress_bar, wanted

    backend = backend_from_args(args)
    bar = wanted(False) and not args.no_progress
    with progress_bar("training runs", len(args.seeds), bar) as advance:
        run_dirs = train_seeds(
            args.env_id,
            args.algo,
            args.seeds,
            args.run_dir,
            backend=None if backend.name == "serial" else backend,
            on_run=advance,
            progress_bar=False,
            **common,
        )
    for run_dir in run_dirs:
        print(f"saved {run_dir / 'model.zip'} (+ vecnormalize.pkl, meta.json)")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from agents import bench

    kwargs: dict = {"sizes": tuple(args.sizes)} if args.sizes else {}
    if args.seconds is not None:
        kwargs["min_seconds"] = kwargs["reference_seconds"] = args.seconds
    result = bench.run(args.env, **kwargs)
    print(json.dumps(result) if args.json else bench.format_table(result))
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse's parser with a one-line usage error (no usage block): the same
    ``PROG: error: …`` line and exit code 2 as :func:`main`'s ValueErrors."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows each option's default, unless its help already says it or there is none."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if default is None or default is False or default == [] or "default" in text:
            return text
        return super()._get_help_string(action)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="pednav",
        description="Gait-aware pedestrian navigation: paper reproductions, environments, tuners.",
        formatter_class=_HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"pednav {__version__}")
    sub = parser.add_subparsers(
        dest="command",
        required=True,
        parser_class=lambda **kw: _Parser(**{"formatter_class": _HelpFormatter, **kw}),
    )

    rep = sub.add_parser(
        "reproduce",
        help="reproduce a paper's published figures",
        description="A paper's figures beside ours; JSON format in docs/CONTRACTS.md.",
    )
    rep.add_argument("paper", help="paper id: 000, 001, 002, 003 or 004")
    rep.add_argument(
        "--runs",
        type=positive_int,
        default=None,
        help="Monte-Carlo runs per configuration (default: the paper's)",
    )
    rep.add_argument("--seed", type=nonnegative_int, default=0, help="root random seed")
    rep.add_argument(
        "--json", action="store_true", help="print one JSON object (docs/CONTRACTS.md)"
    )
    rep.add_argument("--plots", metavar="DIR", default=None, help="write figures to DIR")
    rep.set_defaults(func=_cmd_reproduce)

    ev = sub.add_parser(
        "evaluate",
        help="evaluate tuning policies on held-out episodes",
        description="Every policy plays the same episodes (seeds S … S+N−1, evaluation "
        "seeds); the table pairs them with the paper policy seed by seed. JSON format in "
        "docs/CONTRACTS.md.",
    )
    ev.add_argument("env_id", help="e.g. pednav/FootZupt-v0")
    ev.add_argument(
        "--policy",
        nargs="+",
        required=True,
        help="paper, tuned, adaptive, pretrained, gait-rule, gait-rule-real (foot envs, shoe "
        "family; the rule fitted on simulated walks / on recordings), "
        "oracle (privileged; simulated envs only), or a path: a training run directory, "
        "a saved SB3 model (.zip, with vecnormalize.pkl beside it), a tuned_actions.json "
        "from pednav tune (or its run directory), or a gait_rule.json from "
        "agents.gait_rule_search",
    )
    ev.add_argument(
        "--episodes",
        type=positive_int,
        default=None,
        help="episodes per policy (default 100; with --recordings: one per recording)",
    )
    ev.add_argument(
        "--seed",
        type=int,
        default=5000,
        help="first episode seed; episodes use seed … seed+N-1 (all < 1 000 000)",
    )
    add_env_options(ev)
    ev.add_argument("--json", action="store_true", help="print one JSON object (docs/CONTRACTS.md)")
    ev.add_argument(
        "--plot",
        metavar="DIR",
        default=None,
        help="save error_over_time.png and per_episode.png to DIR",
    )
    ev.add_argument(
        "--lanes",
        type=positive_int,
        default=None,
        help="episodes per batch, one vector env each, the unit of a backend's work (default 128)",
    )
    add_backend_options(ev, "the episode batches run")
    ev.set_defaults(func=_cmd_evaluate)

    tr = sub.add_parser(
        "train",
        help="train a filter tuner with Stable-Baselines3",
        description="Train on the native vector env; episodes from training seeds only "
        "(run seed S plays lane seeds 1 000 000 + 10 000·S + i). Writes model.zip, "
        "vecnormalize.pkl and meta.json to the run directory.",
    )
    tr.add_argument("env_id", help="e.g. pednav/FootZupt-v0")
    tr.add_argument("--algo", choices=("ppo", "sac"), default="ppo", help="SB3 algorithm")
    tr.add_argument(
        "--timesteps",
        type=positive_int,
        default=None,
        help="env steps (default: the hyperparameter file's n_timesteps)",
    )
    seeds = tr.add_mutually_exclusive_group()
    seeds.add_argument("--seed", type=int, default=0, help="training run seed (0 … 9999)")
    seeds.add_argument(
        "--seeds",
        type=int,
        nargs="+",
        default=None,
        help="several training runs, one per seed, in RUN_DIR/ALGO_seedS",
    )
    tr.add_argument(
        "--n-envs", type=positive_int, default=None, help="parallel lanes (default: the file's)"
    )
    tr.add_argument(
        "--config",
        default=None,
        help="hyperparameter YAML, RL-Zoo style (default: agents/hyperparams/ppo.yml or sac.yml)",
    )
    tr.add_argument(
        "--run-dir",
        default=None,
        help="output dir (default runs/ENV/ALGO_seedS; with --seeds: the parent, default runs/ENV)",
    )
    tr.add_argument(
        "--filter",
        choices=("paper", "shoe"),
        default=None,
        help="foot envs: the filter family to tune (default shoe, the one that transfers "
        "to recordings); written to meta.json",
    )
    tr.add_argument("--resume", action="store_true", help="continue from the newest checkpoint")
    tr.add_argument(
        "--overwrite",
        action="store_true",
        help="remove what earlier runs left first (their model.zip, vecnormalize.pkl, "
        "meta.json, checkpoints/, tb/; with --seeds also RUN_DIR/ALGO_seedS of seeds not "
        "given and an earlier single run in RUN_DIR); without it such a run directory is "
        "refused. With --resume the runs it continues stay",
    )
    tr.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_backend_options(tr, "the runs of --seeds train")
    tr.set_defaults(func=_cmd_train)

    add_tune_command(sub)

    add_distill_command(sub)

    add_fit_rule_command(sub)

    be = sub.add_parser("bench", help="throughput of a native vector env vs filterpy")
    be.add_argument("env", help="foot, waist or marker")
    be.add_argument(
        "--sizes",
        type=positive_int,
        nargs="+",
        default=None,
        help="numbers of environments (default 1 16 64 256)",
    )
    be.add_argument(
        "--seconds",
        type=positive_float,
        default=None,
        help="minimum timed seconds per measurement (default 3)",
    )
    be.add_argument("--json", action="store_true", help="print one JSON object (docs/CONTRACTS.md)")
    be.set_defaults(func=_cmd_bench)

    add_recording_commands(sub)
    return parser


def _os_error_message(exc: OSError) -> str:
    """``FILE: reason`` (``FILE -> FILE2: reason`` for a rename), else the error's text."""
    if exc.filename is None or exc.strerror is None:
        return str(exc)
    names = str(exc.filename)
    if exc.filename2 is not None:
        names += f" -> {exc.filename2}"
    return f"{names}: {exc.strerror}"


def main(argv: Sequence[str] | None = None) -> int:
    """Run one subcommand. Bad input (a ValueError) is one line on stderr and exit code 2;
    a failed read or write (an OSError the up-front checks could not foresee: a full disk,
    a file removed mid-run) one line naming the file and exit code 1. Either way, on any
    other non-zero exit code and on Ctrl-C (re-raised), output directories the command
    created and left empty are removed
    (:func:`agents.cli_types.removing_created_dirs_on_failure`)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with removing_created_dirs_on_failure() as remove_created:
            code = int(args.func(args))
            if code != 0:  # failed without an exception (e.g. run DIR, every recording bad)
                remove_created()
            return code
    except ValueError as exc:
        print(f"pednav: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"pednav: error: {_os_error_message(exc)}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
