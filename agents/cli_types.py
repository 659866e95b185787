"""Argument types and output-path checks shared by the ``pednav`` subcommands.

A bad value is reported in one line naming its option: the types through argparse
(:func:`agents.cli.build_parser`), :func:`output_dir` as a ``ValueError`` that
:func:`agents.cli.main` prints.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path


def _integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None


def positive_int(text: str) -> int:
    value = _integer(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be ≥ 1, got {value}")
    return value


def nonnegative_int(text: str) -> int:
    """A seed or a count that may be 0 (numpy's generators take seeds ≥ 0)."""
    value = _integer(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be ≥ 0, got {value}")
    return value


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def output_dir(path: str | Path, option: str) -> Path:
    """``path`` as an output directory, created now (before a long run, not after it);
    ValueError naming ``option`` when it is a file, cannot be created or is not
    writable."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option} {path}: is a file; give a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"{option} {path}: cannot create the directory ({exc.strerror})") from None
    if not os.access(path, os.W_OK):
        raise ValueError(f"{option} {path}: directory not writable")
    return path
