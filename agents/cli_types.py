"""Argument types and output-path checks shared by the ``pednav`` subcommands.

A bad value is reported in one line naming its option: the types through argparse
(:func:`agents.cli.build_parser`), :func:`output_dir` as a ``ValueError`` that
:func:`agents.cli.main` prints. :func:`output_dir` creates its directory before the
run; inside :func:`removing_created_dirs_on_failure` (which :func:`agents.cli.main`
runs every command in) the directories it created are removed again, if still empty,
when the command fails.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

# One list per open removing_created_dirs_on_failure(), innermost last: the directories
# output_dir created while it was open, in the order they were created.
_open_registries: list[list[Path]] = []


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
    missing = _missing_dirs(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _remove_empty(missing)  # parents made before a deeper mkdir failed
        raise ValueError(f"{option} {path}: cannot create the directory ({exc.strerror})") from None
    if _open_registries:
        _open_registries[-1].extend(reversed(missing))
    if not os.access(path, os.W_OK):
        raise ValueError(f"{option} {path}: directory not writable")
    return path


@contextmanager
def removing_created_dirs_on_failure() -> Iterator[Callable[[], None]]:
    """Run a command; if it raises (any exception, KeyboardInterrupt included), remove
    the directories :func:`output_dir` created meanwhile (with their created parents)
    that are still empty, deepest first, then re-raise. Directories that existed
    before, or that hold anything, are left as they are (``rmdir``, never a recursive
    delete). The value yielded removes them the same way without an exception: for a
    command that fails by its exit code."""
    created: list[Path] = []
    _open_registries.append(created)
    try:
        yield lambda: _remove_empty(reversed(created))
    except BaseException:
        _remove_empty(reversed(created))
        raise
    finally:
        _open_registries.pop()


def _missing_dirs(path: Path) -> list[Path]:
    """``path`` and those of its parents that do not exist yet, deepest first."""
    missing = []
    absolute = path.absolute()
    for candidate in (absolute, *absolute.parents):
        if candidate.exists() or candidate.is_symlink():
            break
        missing.append(candidate)
    return missing


def _remove_empty(paths: Iterable[Path]) -> None:
    """``rmdir`` each of ``paths`` in order; one that is not empty (or gone) stays."""
    for path in paths:
        try:
            path.rmdir()
        except OSError:
            pass
