"""The ``pednav`` command line.

Subcommands (their JSON formats are contracts, see docs/CONTRACTS.md):

- ``pednav reproduce ID [--runs N] [--seed S] [--json] [--plots DIR]`` — a
  paper's figures beside ours.
- ``pednav evaluate ENV_ID --policy NAME [NAME ...] --episodes N --seed S
  [--json] [--plot DIR] [--scenario NAME] [--recordings DIR] [--env-kwarg K=V]
  [--backend serial|ray] [--ray-address A]`` — policies on the same held-out
  episodes.
- ``pednav train ENV_ID --algo ppo|sac [--timesteps N] [--seed S | --seeds S ...]
  [--n-envs K] [--config FILE] [--run-dir DIR] [--resume] [--backend ...]`` —
  train a tuner (SB3), one run or one per seed.
- ``pednav tune ENV_ID [--run-dir DIR] [--install] [--backend ...]`` — CMA-ES
  search of the tuned-fixed baseline.
- ``pednav run RECORDING|DIR [--format F] [--policy NAME|SETUP.json]
  [--footprints FILE|none] [--json] [--plot FILE] [--out TRACK.csv] [loader
  options]`` — the ZUPT-UKF on a recorded walk or a folder of them
  (docs/REAL_DATA.md); the default policy is ``real-fixed``.
- ``pednav simulate --out FILE [--speed LO HI | --gait G] [--duration S]
  [--rate HZ] [--imu GRADE] [--stops/--no-stops] [--seed N]`` — a simulated
  foot walk written as a CSV recording that ``pednav run`` reads.
- ``pednav bench ENV [--json] [--sizes N ...]`` — env steps/s of the native
  vector env against a filterpy reference (ENV = foot, waist, marker).
- ``pednav sim2real RECORDING... [--model M] [--walks N] [--json] [--plot DIR]``
  — the foot simulator beside recorded walks per speed band
  (docs/SIM_TO_REAL.md).

Long commands draw a progress bar on stderr when it is a terminal (not with
``--json``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.cli_distill import add_distill_command
from agents.cli_recordings import add_recording_commands
from agents.cli_types import positive_float, positive_int
from pednav_env import __version__


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from agents.progress import progress_bar, wanted
    from pednav_env import reproduce

    kwargs: dict = {"seed": args.seed}
    if args.runs is not None:
        kwargs["runs"] = args.runs
    if args.plots is not None:
        kwargs["plot_dir"] = args.plots
    with progress_bar(f"reproducing paper {args.paper}", None, wanted(args.json)):
        result = reproduce.run(args.paper, **kwargs)
    if args.json:
        print(json.dumps(result.to_json_dict()))
    else:
        print(result.format_table())
    return 0


def _env_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """Env options from --scenario, --recordings and --env-kwarg KEY=VALUE."""
    out: dict[str, Any] = {}
    for item in args.env_kwarg:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise ValueError(f"--env-kwarg {item!r}: expected KEY=VALUE")
        try:
            out[key] = json.loads(text)
        except json.JSONDecodeError:
            out[key] = text
    if args.scenario is not None:
        out["scenario"] = args.scenario
    if getattr(args, "filter", None) is not None:
        out["filter"] = args.filter
    if args.recordings is not None:
        if not Path(args.recordings).is_dir():
            raise ValueError(f"--recordings {args.recordings!r}: not a directory")
        out["data_dir"] = args.recordings
    return out


def _backend(args: argparse.Namespace) -> Any:
    from agents.backends import make_backend

    return make_backend(args.backend, args.ray_address, args.ray_cpus)


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from agents.evaluate import MAX_LANES, evaluate
    from agents.evaluate_report import format_table
    from agents.progress import progress_bar, wanted

    env_kwargs = _env_kwargs(args)
    backend = _backend(args)
    total = args.episodes * (len(set(args.policy) | {"paper"}))
    with progress_bar("episodes", total, wanted(args.json)) as advance:
        result = evaluate(
            args.env_id,
            args.policy,
            args.episodes,
            args.seed,
            env_kwargs,
            args.plot,
            backend=backend,
            on_episode=advance,
            lanes=args.lanes or MAX_LANES,
        )
    print(json.dumps(result) if args.json else format_table(result))
    return 0


def _cmd_train(args: argparse.Namespace) -> int:
    from agents.train import train, train_seeds

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

    backend = _backend(args)
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


def _cmd_tune(args: argparse.Namespace) -> int:
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

    env_kwargs = _env_kwargs(args)
    check_env_kwargs(args.env_id, env_kwargs)
    if args.per_context and env_kwargs:
        raise ValueError("--per-context sets the env's config itself: no env options with it")
    family = None
    if args.env_id in FAMILY_ENVS:
        family = env_kwargs.setdefault("filter", LEARNED_FAMILY)
    key = result_key(args.env_id, family)
    action_dim = gym.make(args.env_id, **env_kwargs).action_space.shape[0]
    run_dir = Path(args.run_dir or f"runs/{args.env_id.split('/')[-1]}/tune_seed{args.seed}")
    backend = _backend(args)
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
        split = oracle.context_split(args.env_id)
        shipped = read_results(RESULTS_FILE) if RESULTS_FILE.exists() else {}
        if args.env_id in shipped:  # refine the shipped CMA-ES constant per context
            options["x0"] = shipped[args.env_id]["action"]
            options["sigma0"] = args.sigma0
        total = (args.generations + 1) * len(split.labels)
        with progress_bar("CMA-ES generations", total, wanted(False)) as advance:
            entry = oracle.search_per_context(
                args.env_id, action_dim, search, on_generation=advance, **options
            )
        written = [oracle.save_table_entry(args.env_id, entry, run_dir / oracle.RESULT_NAME)]
        if args.install:
            written.append(oracle.save_table_entry(args.env_id, entry, oracle.RESULTS_FILE))
        print(json.dumps(entry, indent=2))
        for path in written:
            print(f"wrote {path}", file=sys.stderr)
        return 0
    with progress_bar("CMA-ES generations", args.generations + 1, wanted(False)) as advance:
        result = search(
            args.env_id, action_dim, env_kwargs=env_kwargs, on_generation=advance, **options
        )
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


def _cmd_bench(args: argparse.Namespace) -> int:
    from agents import bench

    kwargs: dict = {"sizes": tuple(args.sizes)} if args.sizes else {}
    if args.seconds is not None:
        kwargs["min_seconds"] = kwargs["reference_seconds"] = args.seconds
    result = bench.run(args.env, **kwargs)
    print(json.dumps(result) if args.json else bench.format_table(result))
    return 0


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows each option's default, unless its help already says it or there is none."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if default is None or default is False or default == [] or "default" in text:
            return text
        return super()._get_help_string(action)


def _add_backend_options(p: argparse.ArgumentParser, unit: str) -> None:
    p.add_argument(
        "--backend",
        choices=("serial", "ray"),
        default="serial",
        help=f"where {unit}: in this process, or as parallel Ray tasks "
        "(identical results; needs pip install 'pednav[ray]')",
    )
    p.add_argument(
        "--ray-address",
        metavar="ADDR",
        default=None,
        help="join this Ray cluster (e.g. auto, HOST:6379, ray://HOST:10001); implies "
        "--backend ray (default: start a local Ray instance)",
    )
    p.add_argument(
        "--ray-cpus",
        type=positive_int,
        default=None,
        help="CPUs of the local Ray instance (default: all of this machine's)",
    )


def _add_env_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--scenario", default=None, help="env scenario, e.g. random or paper (the env's default)"
    )
    p.add_argument(
        "--filter",
        choices=("paper", "shoe"),
        default=None,
        help="foot envs: the filter family (paper: eq 5 and ZUPTs at stance start and end; "
        "shoe: SHOE detector and a ZUPT at every stance sample, action 0 = real-fixed); "
        "tune and train default to shoe, evaluate runs each policy on its own family",
    )
    p.add_argument(
        "--recordings",
        metavar="DIR",
        default=None,
        help="for pednav/FootZuptReplay-v0: the folder of recordings (its data_dir); "
        "each episode plays a trial drawn by its seed",
    )
    p.add_argument(
        "--env-kwarg",
        metavar="KEY=VALUE",
        action="append",
        default=[],
        help="any other env option, VALUE read as JSON when it parses (e.g. "
        "decision_interval_s=1.0, tune_min_stance=true); repeatable",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pednav",
        description="Gait-aware pedestrian navigation: paper reproductions, environments, tuners.",
        formatter_class=_HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"pednav {__version__}")
    sub = parser.add_subparsers(
        dest="command",
        required=True,
        parser_class=lambda **kw: argparse.ArgumentParser(
            **{"formatter_class": _HelpFormatter, **kw}
        ),
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
    rep.add_argument("--seed", type=int, default=0, help="root random seed")
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
        help="paper, tuned, adaptive, pretrained, or a path: a training run directory, a "
        "saved SB3 model (.zip, with vecnormalize.pkl beside it), or a tuned_actions.json "
        "from pednav tune (or its run directory)",
    )
    ev.add_argument("--episodes", type=positive_int, default=100, help="episodes per policy")
    ev.add_argument(
        "--seed",
        type=int,
        default=5000,
        help="first episode seed; episodes use seed … seed+N-1 (all < 1 000 000)",
    )
    _add_env_options(ev)
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
    _add_backend_options(ev, "the episode batches run")
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
    tr.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_backend_options(tr, "the runs of --seeds train")
    tr.set_defaults(func=_cmd_train)

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
    tu.add_argument("--seed", type=int, default=1, help="CMA-ES seed")
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
        type=int,
        default=0,
        metavar="N",
        help="play the chosen action on N fresh training episodes and report that mean",
    )
    tu.add_argument(
        "--per-context",
        action="store_true",
        help="one search per episode context (sensor grade, UWB condition), each started "
        "from the shipped CMA-ES constant: the privileged oracle's table, written as "
        "RUN_DIR/oracle_actions.json",
    )
    tu.add_argument(
        "--sigma0",
        type=positive_float,
        default=0.25,
        help="--per-context: CMA-ES initial step size around the shipped constant",
    )
    _add_env_options(tu)
    _add_backend_options(tu, "a generation's candidates run")
    tu.set_defaults(func=_cmd_tune)

    add_distill_command(sub)

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
        type=float,
        default=None,
        help="minimum timed seconds per measurement (default 3)",
    )
    be.add_argument("--json", action="store_true", help="print one JSON object (docs/CONTRACTS.md)")
    be.set_defaults(func=_cmd_bench)

    add_recording_commands(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ValueError as exc:
        print(f"pednav: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
