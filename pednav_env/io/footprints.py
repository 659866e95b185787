"""Footprints: the foot's position known only at footfalls (sparse truth).

Some recordings have no reference track, only the position of the foot at
each footfall — read off floor tiles, survey marks or a mat ("ground control
points"). A :class:`Footprints` holds them: the recording sample at which the
foot is down, and its horizontal position there (m) in the reference's own
frame. The metrics of :func:`pednav_env.replay.metrics.footprint_errors`
compare the filter's position at those samples with them.

Footprint CSV (``strideIndex,timestamp,gcpX,gcpY``; names matched ignoring
case, spaces and underscores; extra columns ignored):

- ``strideIndex``: 0-based sample index of the footfall (data rows, header
  excluded) in the sampling the footprints were made on;
- ``timestamp``: time of the footfall (s) on the recording's clock: the
  footprint goes to the recording sample nearest it (the index may refer to
  another sampling of the same clock, e.g. 200 Hz against a 250 Hz export);
- ``gcpX``, ``gcpY``: footprint position (m).

Rows are named by their line in the file (the header is line 1).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from pednav_env.io.text import read_csv_cells

Array = NDArray[np.float64]

#: Suffix of a footprint file beside its recording (``walk.csv`` → ``walk_footprints.csv``).
FOOTPRINT_SUFFIX = "_footprints.csv"
#: Footprint CSV columns (normalised: lower case, no spaces or underscores).
FOOTPRINT_COLUMNS = ("strideindex", "timestamp", "gcpx", "gcpy")


@dataclass(frozen=True, eq=False)
class Footprints:
    """Foot positions at footfalls.

    Parameters
    ----------
    sample : (K,) int, recording sample of each footfall, strictly increasing.
    pos : (K, 2) m, horizontal footprint position in the reference's frame.
    source : where they come from (file name), for messages.
    """

    sample: NDArray[np.int64]
    pos: Array
    source: str = "footprints"

    def __post_init__(self) -> None:
        s = np.asarray(self.sample)
        p = np.asarray(self.pos, dtype=float)
        if s.ndim != 1 or s.size < 2:
            raise ValueError(f"{self.source}: need ≥ 2 footprints, got {s.size}")
        if not np.issubdtype(s.dtype, np.integer):
            raise ValueError(f"{self.source}: footprint samples must be integers")
        if p.shape != (s.size, 2):
            raise ValueError(
                f"{self.source}: footprint positions must be ({s.size}, 2), got {p.shape}"
            )
        if not np.isfinite(p).all():
            k = int(np.flatnonzero(~np.isfinite(p).all(axis=1))[0])
            raise ValueError(f"{self.source}: footprint {k} has a non-finite position")
        if s[0] < 0 or np.any(np.diff(s) <= 0):
            k = 0 if s[0] < 0 else int(np.flatnonzero(np.diff(s) <= 0)[0]) + 1
            raise ValueError(
                f"{self.source}: footprint samples must be ≥ 0 and increase strictly; "
                f"footprint {k} is at sample {int(s[k])}"
            )
        for name, value in (("sample", s.astype(np.int64)), ("pos", p)):
            value = value.copy()
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def count(self) -> int:
        return int(self.sample.size)

    @property
    def path_length_m(self) -> float:
        """Length of the polyline through the footprints (m)."""
        return float(np.sum(np.linalg.norm(np.diff(self.pos, axis=0), axis=1)))

    def reindexed(self, sample: NDArray[np.integer]) -> Footprints:
        """The same footprints at other sample indices (after a crop or regridding)."""
        return Footprints(np.asarray(sample, dtype=np.int64), self.pos, self.source)


def footprints_beside(recording: str | Path) -> Path:
    """The footprint file expected beside a recording: ``<stem>_footprints.csv``."""
    p = Path(recording)
    return p.with_name(p.stem + FOOTPRINT_SUFFIX)


def is_footprint_file(path: str | Path) -> bool:
    """True for a file named like a footprint file (``*_footprints.csv``)."""
    return Path(path).name.lower().endswith(FOOTPRINT_SUFFIX)


@dataclass(frozen=True)
class FootprintTable:
    """Footprints as read from a source, before they are checked against a recording.

    ``row`` indexes the recording's source rows (data rows of a CSV, samples of
    a MATLAB array); ``time`` (s) is each footprint's timestamp or None;
    ``names`` names each footprint in messages (``"line 5"``); ``axes`` are
    signs applied to (x, y) to make the frame right-handed with z up.
    """

    source: str
    row: NDArray[np.int64]
    pos: Array
    names: tuple[str, ...]
    time: Array | None = None
    axes: tuple[float, float] = (1.0, 1.0)

    def checked(self, time: Array) -> Footprints:
        """:class:`Footprints` on the recording's source rows, whose raw ``time`` is
        given. With timestamps, each footprint goes to the sample nearest its
        timestamp, which must lie within half a sample interval of it (the
        row index may refer to another sampling of the same clock); without,
        the row index is the sample. Either way it must lie inside the recording."""
        time = np.asarray(time, dtype=float)
        n = len(time)
        span = f"samples 0…{n - 1}, {float(time[0]):.3f}…{float(time[-1]):.3f} s"
        if self.time is None:
            row = self.row
            out = np.flatnonzero((row < 0) | (row >= n))
            if out.size:
                k = int(out[0])
                raise ValueError(
                    f"{self.source}: {self.names[k]}: footprint at sample {int(row[k])} is "
                    f"outside the recording ({span})"
                )
        else:
            nominal = float(np.median(np.diff(time)))
            half = 0.5 * nominal
            right = np.clip(np.searchsorted(time, self.time), 1, n - 1)
            left = right - 1
            row = np.where(self.time - time[left] <= time[right] - self.time, left, right)
            outside = (self.time < time[0] - half) | (self.time > time[-1] + half)
            in_gap = (time[right] - time[left] > 1.5 * nominal) & (
                np.abs(time[row] - self.time) > half
            )
            bad = np.flatnonzero(outside | in_gap)
            if bad.size:
                k = int(bad[0])
                where = (
                    f"is outside the recording ({span})"
                    if outside[k]
                    else f"falls in a gap of the recording ({time[left[k]]:.4f}…"
                    f"{time[right[k]]:.4f} s)"
                )
                raise ValueError(
                    f"{self.source}: {self.names[k]}: the footprint at t = "
                    f"{float(self.time[k]):.4f} s {where}"
                )
        return Footprints(row.astype(np.int64), self.pos * np.asarray(self.axes), self.source)


def read_footprints_csv(path: str | Path) -> FootprintTable:
    """Read and check a footprint CSV (module docstring).

    Raises
    ------
    ValueError
        Missing file or columns, non-numeric, NaN or non-integer indices, indices
        not increasing — each naming the file and the line.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: footprint file not found")
    header, rows, lines = read_csv_cells(path)
    names = [c.strip().lower().replace(" ", "").replace("_", "") for c in header]
    missing = [c for c in FOOTPRINT_COLUMNS if c not in names]
    if missing:
        raise ValueError(
            f"{path.name}: missing footprint column(s) {missing} (header has {header}); "
            "expected strideIndex,timestamp,gcpX,gcpY"
        )
    cols = [names.index(c) for c in FOOTPRINT_COLUMNS]
    data = np.empty((len(rows), 4))
    for i, row in enumerate(rows):
        for j, c in enumerate(cols):
            cell = row[c].strip() if c < len(row) else ""
            try:
                data[i, j] = float(cell)
            except ValueError:
                raise ValueError(
                    f"{path.name}: line {lines[i]}, column {header[c]!r}: {cell!r} is not a number"
                ) from None
    if len(rows) < 2:
        raise ValueError(f"{path.name}: fewer than 2 footprints")
    bad = ~np.isfinite(data).all(axis=1)
    if bad.any():
        raise ValueError(f"{path.name}: line {lines[int(np.argmax(bad))]}: NaN or inf value")
    return footprint_table(
        path.name, data[:, 0], data[:, 2:4], tuple(f"line {n}" for n in lines), data[:, 1]
    )


def footprint_table(
    source: str,
    row: NDArray,
    pos: Array,
    names: tuple[str, ...],
    time: Array | None = None,
    axes: tuple[float, float] = (1.0, 1.0),
) -> FootprintTable:
    """A :class:`FootprintTable` after checking the indices: integers, ≥ 0, increasing."""
    idx = np.asarray(row, dtype=float).ravel()
    pos = np.asarray(pos, dtype=float)
    if pos.shape != (idx.size, 2):
        raise ValueError(
            f"{source}: footprint positions must be {idx.size}×2 (one per index), got {pos.shape}"
        )
    if idx.size < 2:
        raise ValueError(f"{source}: fewer than 2 footprints")
    bad = np.flatnonzero(~np.isfinite(pos).all(axis=1) | ~np.isfinite(idx))
    if bad.size:
        raise ValueError(f"{source}: {names[int(bad[0])]}: NaN or inf value")
    frac = np.flatnonzero(idx != np.round(idx))
    if frac.size:
        k = int(frac[0])
        raise ValueError(f"{source}: {names[k]}: index {float(idx[k])!r} is not a sample index")
    row_idx = idx.astype(np.int64)
    dec = np.flatnonzero(np.diff(row_idx) <= 0)
    if row_idx[0] < 0 or dec.size:
        k = 0 if row_idx[0] < 0 else int(dec[0]) + 1
        raise ValueError(
            f"{source}: {names[k]}: footprint at sample {int(row_idx[k])} — footprint samples "
            "must be ≥ 0 and increase strictly"
        )
    return FootprintTable(source, row_idx, pos, names, time, axes)
