"""Progress bars of the long commands (``evaluate``, ``tune``, ``reproduce``), on stderr.

The library functions take a plain callback (``on_progress(n)``: n more units
done); this module turns it into a rich progress bar. Bars are drawn only when
stderr is a terminal and the command does not print JSON, so piped output and
``--json`` stay clean.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TextIO


def wanted(json_output: bool, stream: TextIO | None = None) -> bool:
    """True when a bar should be drawn: ``stream`` (stderr) is a terminal and the
    command prints text, not JSON."""
    stream = sys.stderr if stream is None else stream
    return not json_output and bool(getattr(stream, "isatty", lambda: False)())


@contextmanager
def progress_bar(
    description: str, total: float | None, enabled: bool
) -> Iterator[Callable[[float], None]]:
    """A context whose value is ``advance(n)``; ``total=None`` gives an elapsed-time
    spinner for work that reports no intermediate progress."""
    if not enabled:
        yield lambda n=1: None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        SpinnerColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = [SpinnerColumn(), TextColumn("{task.description}"), BarColumn()]
    if total is not None:
        columns += [MofNCompleteColumn(), TimeRemainingColumn()]
    columns.append(TimeElapsedColumn())
    with Progress(*columns, console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task(description, total=total)
        yield lambda n=1: bar.advance(task, n)
