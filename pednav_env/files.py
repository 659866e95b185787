"""Writing output files: a write that fails names the file it was writing.

A write can fail after every up-front check passed: the disk fills, a permission is
lost, a network mount goes away. The ``OSError`` that ``open`` raises names its file,
but one raised part-way through the writing often does not: ``np.savetxt``,
``Path.write_text``, ``Figure.savefig``, ``pickle.dump`` and Stable-Baselines3's
``model.save`` on a full disk all raise ``OSError(28, 'No space left on device')``
with no file name. Every writer of the project writes inside :func:`writing`, which
gives such an error the path, so the ``pednav`` command can print ``FILE: reason``
(docs/CONVENTIONS.md, Configuration and bad input).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


@contextmanager
def writing(path: str | os.PathLike[str]) -> Iterator[None]:
    """Run the block that writes ``path``; an ``OSError`` it raises without a file name
    is raised again naming ``path`` (the same errno, so the same subclass, e.g.
    ``PermissionError``; the original error chained as its cause). An error that
    already names a file, and any other exception, passes unchanged."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None:
            raise
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise OSError(exc.errno, reason, os.fspath(path)) from exc


def save_figure(fig: Any, path: str | os.PathLike[str], **kwargs: Any) -> Path:
    """``fig.savefig(path, **kwargs)`` (a matplotlib figure) inside :func:`writing`;
    returns ``path``."""
    with writing(path):
        fig.savefig(path, **kwargs)
    return Path(path)
