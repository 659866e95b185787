"""Option groups and helpers shared by the ``pednav`` subcommands: the env options
(``--scenario``, ``--filter``, ``--recordings``, ``--env-kwarg``) and the backend options
(``--backend``, ``--ray-address``, ``--ray-cpus``)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from agents.cli_types import positive_int


def env_kwargs_from_args(args: argparse.Namespace) -> dict[str, Any]:
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


def backend_from_args(args: argparse.Namespace) -> Any:
    """The backend (:mod:`agents.backends`) of --backend, --ray-address, --ray-cpus."""
    from agents.backends import make_backend

    return make_backend(args.backend, args.ray_address, args.ray_cpus)


def add_backend_options(p: argparse.ArgumentParser, unit: str) -> None:
    """--backend, --ray-address and --ray-cpus; ``unit``: what runs where (help text)."""
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


def add_env_options(p: argparse.ArgumentParser) -> None:
    """--scenario, --filter, --recordings and --env-kwarg."""
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
        help="for pednav/FootZuptReplay-v0: the folder of recordings with a truth track "
        "(its data_dir); evaluate plays them in name order (seed S+k: recording k, mod "
        "their number), so every policy plays each once; tune draws them at random",
    )
    p.add_argument(
        "--env-kwarg",
        metavar="KEY=VALUE",
        action="append",
        default=[],
        help="any other env option, VALUE read as JSON when it parses (e.g. "
        "decision_interval_s=1.0, tune_min_stance=true); repeatable",
    )
