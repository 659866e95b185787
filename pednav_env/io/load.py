"""One entry point for every recording format."""

from __future__ import annotations

from pathlib import Path

from pednav_env.io.csv_format import CsvLayout, load_csv, load_xio_csv, looks_like_xio, read_header
from pednav_env.io.pyshoe import load_pyshoe_mat
from pednav_env.io.recording import Recording
from pednav_env.io.validate import LoadOptions

#: Format names understood by :func:`load_recording` (``auto`` guesses).
FORMATS = ("auto", "csv", "xio", "pyshoe")
#: File suffixes searched by :func:`find_recordings`.
SUFFIXES = (".csv", ".mat")


def detect_format(path: str | Path) -> str:
    """``pyshoe`` for ``.mat``; ``xio`` for a CSV with x-io's header; else ``csv``."""
    path = Path(path)
    if path.suffix.lower() == ".mat":
        return "pyshoe"
    if path.suffix.lower() == ".csv":
        return "xio" if looks_like_xio(read_header(path)) else "csv"
    raise ValueError(f"{path.name}: cannot tell the format from the suffix; pass format=")


def load_recording(
    path: str | Path,
    format: str = "auto",
    options: LoadOptions | None = None,
    layout: CsvLayout | None = None,
) -> Recording:
    """Load a recording in any supported format (``FORMATS``).

    ``layout`` declares CSV column names and units (``format="csv"`` only).
    """
    path = Path(path)
    if format not in FORMATS:
        raise ValueError(f"unknown format {format!r}; use one of {', '.join(FORMATS)}")
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    fmt = detect_format(path) if format == "auto" else format
    if fmt == "pyshoe":
        return load_pyshoe_mat(path, options)
    if fmt == "xio":
        return load_xio_csv(path, options)
    return load_csv(path, layout, options)


def find_recordings(directory: str | Path) -> list[Path]:
    """Recording files (``.csv``, ``.mat``) directly in ``directory``, sorted by name."""
    d = Path(directory)
    if not d.is_dir():
        raise ValueError(f"{d}: not a directory")
    return sorted(p for p in d.iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)
