"""Option groups and helpers shared by the ``pednav`` subcommands: the env options
(``--scenario``, ``--filter``, ``--speed``, ``--recordings``, ``--env-kwarg``) and the
backend options (``--backend``, ``--ray-address``, ``--ray-cpus``)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from agents.cli_types import positive_float, positive_int

#: The env whose calibrated walks ``--speed`` sets, and the speeds it accepts (m/s;
#: :class:`pednav_env.gait.speed_route.SpeedRouteConfig`).
SPEED_ENV = "pednav/FootZupt-v0"
SPEED_LIMITS_MPS = (0.1, 4.0)


def env_kwargs_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """Env options from --scenario, --filter, --recordings, --env-kwarg KEY=VALUE and
    --speed (:func:`speed_config`)."""
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
    speed = getattr(args, "speed", None)
    if speed is not None:
        out = speed_config(args.env_id, out, (speed[0], speed[1]))
    return out


def speed_config(
    env_id: str, env_kwargs: dict[str, Any], speed_mps: tuple[float, float]
) -> dict[str, Any]:
    """``env_kwargs`` with a ``config`` whose calibrated walks have every stride's
    speed in ``speed_mps`` (``speed_route.speed_mps``; everything else of the scenario
    unchanged); the options given stay as they are. ValueError naming ``--speed`` for
    another env, scenario or a range outside 0.1–4 m/s."""
    from dataclasses import replace

    from pednav_env.envs.foot_core import FootZuptConfig
    from pednav_env.envs.foot_filters import LEARNED_FAMILY

    lo, hi = speed_mps
    if env_id != SPEED_ENV:
        raise ValueError(f"--speed: only {SPEED_ENV} draws walks in a speed range, not {env_id}")
    if not (SPEED_LIMITS_MPS[0] <= lo <= hi <= SPEED_LIMITS_MPS[1]):
        raise ValueError(
            f"--speed {lo:g} {hi:g}: need {SPEED_LIMITS_MPS[0]:g} ≤ LO ≤ HI ≤ "
            f"{SPEED_LIMITS_MPS[1]:g} m/s"
        )
    if "config" in env_kwargs:
        raise ValueError("--speed sets the env's config: not together with --env-kwarg config=…")
    base = FootZuptConfig(
        filter_family=env_kwargs.get("filter") or LEARNED_FAMILY,
        scenario=env_kwargs.get("scenario"),
    )
    if base.scenario != "calibrated":
        raise ValueError(
            f"--speed: the calibrated scenario's walks only, not scenario {base.scenario!r} "
            "(the shoe family's default; --scenario calibrated for the paper family)"
        )
    config = replace(base, speed_route=replace(base.speed_route, speed_mps=(lo, hi)))
    return {**env_kwargs, "config": config}


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
    """--scenario, --filter, --speed, --recordings and --env-kwarg."""
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
        "--speed",
        nargs=2,
        metavar=("LO", "HI"),
        type=positive_float,
        default=None,
        help=f"{SPEED_ENV}, calibrated scenario: every stride's speed in LO…HI m/s "
        "(0.1…4; the scenario's default 0.3 3); durations, stops, turns, walkers and IMU "
        "unchanged",
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
