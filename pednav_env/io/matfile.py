"""Reading MATLAB ``.mat`` files: every failure is a ``ValueError`` naming the file.

scipy raises many kinds of exceptions on a file that is not a MATLAB file
(``IndexError``, ``ValueError``, ``struct.error``, …); all mean the same
thing to a user and become one sentence here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import scipy.io


def _unreadable(path: Path, exc: Exception) -> ValueError:
    return ValueError(f"{path.name}: not a readable MATLAB .mat file ({type(exc).__name__}: {exc})")


def read_mat(path: str | Path) -> dict[str, Any]:
    """``scipy.io.loadmat`` of ``path``."""
    path = Path(path)
    try:
        return scipy.io.loadmat(path)
    except Exception as exc:
        raise _unreadable(path, exc) from None


def mat_variables(path: str | Path) -> set[str]:
    """Names of the variables in a ``.mat`` file (without loading them)."""
    path = Path(path)
    try:
        return {name for name, _, _ in scipy.io.whosmat(path)}
    except Exception as exc:
        raise _unreadable(path, exc) from None
