"""One entry point for every recording format."""

from __future__ import annotations

from pathlib import Path

from pednav_env.io.csv_format import CsvLayout, load_csv, load_xio_csv, looks_like_xio
from pednav_env.io.footprints import is_footprint_file, read_footprints_csv
from pednav_env.io.hallway import (
    AUTO,
    FootprintChoice,
    load_gcp_mat,
    load_sensorconnect_csv,
    looks_like_sensorconnect,
)
from pednav_env.io.matfile import mat_variables
from pednav_env.io.pyshoe import load_pyshoe_mat
from pednav_env.io.recording import Recording
from pednav_env.io.text import read_header
from pednav_env.io.validate import LoadOptions

#: Format names understood by :func:`load_recording` (``auto`` guesses).
FORMATS = ("auto", "csv", "xio", "sensorconnect", "pyshoe", "gcp-mat")
#: Formats whose files carry (or come with) footprints by default.
FOOTPRINT_FORMATS = ("sensorconnect", "gcp-mat")
#: File suffixes searched by :func:`find_recordings`.
SUFFIXES = (".csv", ".mat")


def detect_format(path: str | Path) -> str:
    """The format of a file, from its suffix and content.

    ``.mat``: ``pyshoe`` with a variable ``imu``, ``gcp-mat`` with
    ``imu_data``. ``.csv``: ``xio`` or ``sensorconnect`` by
    their headers, else the generic ``csv``.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".mat":
        names = mat_variables(path)
        if "imu" in names:
            return "pyshoe"  # its loader names a missing ts
        if "imu_data" in names:
            return "gcp-mat"
        raise ValueError(
            f"{path.name}: not a known .mat layout (variables {sorted(names)}); expected "
            "imu/ts (PyShoe) or imu_data/timestamps (with footprints)"
        )
    if suffix == ".csv":
        header = read_header(path)
        if looks_like_xio(header):
            return "xio"
        if looks_like_sensorconnect(header):
            return "sensorconnect"
        return "csv"
    raise ValueError(
        f"{path.name}: cannot tell the format from the suffix (.csv or .mat); pass a format "
        f"({', '.join(FORMATS[1:])})"
    )


def load_recording(
    path: str | Path,
    format: str = "auto",
    options: LoadOptions | None = None,
    layout: CsvLayout | None = None,
    footprints: FootprintChoice = AUTO,
) -> Recording:
    """Load a recording in any supported format (``FORMATS``).

    ``layout`` names CSV columns and units (generic ``csv`` only).
    ``footprints``: ``"auto"`` — the file's own footprints (``gcp-mat``) or
    the ``<stem>_footprints.csv`` beside it (``sensorconnect``; required),
    none for the other formats; a path — that footprint CSV, for any format;
    None — no footprints.
    """
    path = Path(path)
    if format not in FORMATS:
        raise ValueError(f"unknown format {format!r}; use one of {', '.join(FORMATS)}")
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    try:
        return _load(path, format, options, layout, footprints)
    except ValueError as exc:
        # every message names the file (some checks know only the rows): a folder's
        # run, evaluation or comparison must say which recording is bad
        msg = str(exc)
        if path.name in msg:
            raise
        if msg.startswith(f"{path.stem}: "):  # named by the recording's name (the stem)
            msg = msg[len(path.stem) + 2 :]
        raise ValueError(f"{path.name}: {msg}") from None


def _load(
    path: Path,
    format: str,
    options: LoadOptions | None,
    layout: CsvLayout | None,
    footprints: FootprintChoice,
) -> Recording:
    """:func:`load_recording` of an existing file."""
    fmt = detect_format(path) if format == "auto" else format
    if layout is not None and fmt != "csv":
        raise ValueError(
            f"{path.name}: a column layout (or sample rate) is for the generic CSV format; "
            f"this file is read as {fmt!r}"
        )
    if fmt == "gcp-mat":
        return load_gcp_mat(path, options, footprints)
    if fmt == "sensorconnect":
        return load_sensorconnect_csv(path, options, footprints)
    table = None if footprints in (None, AUTO) else read_footprints_csv(footprints)
    if fmt == "pyshoe":
        return load_pyshoe_mat(path, options, table)
    if fmt == "xio":
        return load_xio_csv(path, options, table)
    return load_csv(path, layout, options, footprints=table)


def find_recordings(directory: str | Path) -> list[Path]:
    """Recording files (``.csv``, ``.mat``) directly in ``directory``, sorted by
    name; footprint files (``*_footprints.csv``) are companions, not recordings."""
    d = Path(directory)
    if not d.is_dir():
        raise ValueError(f"{d}: not a directory")
    return sorted(
        p
        for p in d.iterdir()
        if p.is_file() and p.suffix.lower() in SUFFIXES and not is_footprint_file(p)
    )
