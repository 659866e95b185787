"""The ``pednav`` command line.

Subcommands (their JSON formats are contracts, see DESIGN.md):

- ``pednav reproduce ID [--runs N] [--seed S] [--json] [--plots DIR]`` — a
  paper's figures beside ours.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from pednav_env import reproduce

    kwargs: dict = {"seed": args.seed}
    if args.runs is not None:
        kwargs["runs"] = args.runs
    if args.plots is not None:
        kwargs["plot_dir"] = args.plots
    result = reproduce.run(args.paper, **kwargs)
    if args.json:
        print(json.dumps(result.to_json_dict()))
    else:
        print(result.format_table())
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pednav",
        description="Gait-aware pedestrian navigation: paper reproductions, environments, tuners.",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    rep = sub.add_parser("reproduce", help="reproduce a paper's published figures")
    rep.add_argument("paper", help="paper id: 000, 001, 002, 003 or 004")
    rep.add_argument(
        "--runs",
        type=_positive_int,
        default=None,
        help="Monte-Carlo runs per configuration (paper default when omitted)",
    )
    rep.add_argument("--seed", type=int, default=0, help="root random seed (default 0)")
    rep.add_argument("--json", action="store_true", help="print one JSON object (DESIGN.md)")
    rep.add_argument("--plots", metavar="DIR", default=None, help="write figures to DIR")
    rep.set_defaults(func=_cmd_reproduce)
    return parser


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be ≥ 1, got {value}")
    return value


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
