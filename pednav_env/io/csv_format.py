"""CSV recordings: a documented generic layout and the x-io Gait-Tracking export.

Generic CSV (``format="csv"``)
------------------------------
Comma-separated, one header line, one sample per line, any column order,
extra columns ignored. Default column names (case and spaces ignored)::

    time, gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z [, pos_x, pos_y, pos_z]

A unit may follow a name in parentheses or brackets — ``gyro_x (deg/s)``,
``accel_z [g]``, ``time (ms)`` — otherwise SI is assumed (s, rad/s, m/s², m).
A column layout (:class:`CsvLayout`; ``pednav run --layout``) may instead
name the columns and give their units; its units override the header's. A
file without a time column needs the sample rate (``CsvLayout.rate_hz``,
``pednav run --rate``): sample k is then at k / rate. Units understood:

| quantity | units |
|---|---|
| time | ``s``, ``ms``, ``us`` |
| angular rate | ``rad/s``, ``deg/s`` (also ``dps``, ``°/s``) |
| specific force | ``m/s^2`` (also ``m/s2``, ``m/s²``), ``g``, ``mg`` |
| truth position | ``m``, ``cm``, ``mm`` |

``pos_*`` (optional) is a reference position of the foot, one per sample;
empty cells there mean "no reference at this sample". Rows are named by
their line number in the file (the header is line 1).

x-io CSV (``format="xio"``)
---------------------------
The export of x-io Technologies' Gait-Tracking example (NGIMU):
``Time (s)``, ``Gyroscope X/Y/Z (deg/s)``, ``Accelerometer X/Y/Z (g)``;
no truth. It is the generic loader with that layout.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.io.footprints import FootprintTable
from pednav_env.io.recording import Recording
from pednav_env.io.text import iter_csv_rows, read_header
from pednav_env.io.validate import LoadOptions, build_recording

TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}
GYRO_UNITS = {"rad/s": 1.0, "deg/s": math.pi / 180.0, "dps": math.pi / 180.0}
GYRO_UNITS["°/s"] = GYRO_UNITS["deg/s"]
ACCEL_UNITS = {
    "m/s^2": 1.0,
    "m/s2": 1.0,
    "m/s²": 1.0,
    "g": STANDARD_GRAVITY,
    "mg": 1e-3 * STANDARD_GRAVITY,
}
TRUTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
#: How to give a column layout, for messages (command line and Python).
LAYOUT_HINT = "a column layout (pednav run --layout; CsvLayout in Python)"

_UNIT_RE = re.compile(r"^\s*(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")


def split_header(cell: str) -> tuple[str, str | None]:
    """``"Gyro X (deg/s)"`` → (``"gyrox"``, ``"deg/s"``): normalised name and unit."""
    m = _UNIT_RE.match(cell)
    name, unit = (m.group(1), m.group(2)) if m else (cell, None)
    return re.sub(r"[\s_]+", "", name.strip().lower()), (unit.strip() if unit else None)


@dataclass(frozen=True)
class CsvLayout:
    """Column names and units of a CSV recording.

    Names are matched after lower-casing and removing spaces, underscores and
    any unit in parentheses/brackets. A unit of None means "from the header,
    else SI". ``rate_hz`` is for files without a time column (sample k at
    k / rate_hz); a file that has the time column must not be given one.
    """

    time: str = "time"
    gyro: tuple[str, str, str] = ("gyro_x", "gyro_y", "gyro_z")
    accel: tuple[str, str, str] = ("accel_x", "accel_y", "accel_z")
    truth: tuple[str, str, str] | None = ("pos_x", "pos_y", "pos_z")
    time_unit: str | None = None
    gyro_unit: str | None = None
    accel_unit: str | None = None
    truth_unit: str | None = None
    #: Truth columns must be present (False: used when present).
    require_truth: bool = False
    #: Hz, sample rate of a file without a time column.
    rate_hz: float | None = None

    def __post_init__(self) -> None:
        for name, table in (
            ("time_unit", TIME_UNITS),
            ("gyro_unit", GYRO_UNITS),
            ("accel_unit", ACCEL_UNITS),
            ("truth_unit", TRUTH_UNITS),
        ):
            u = getattr(self, name)
            if u is not None and u not in table:
                raise ValueError(f"layout {name} must be one of {sorted(table)}, got {u!r}")
        for name in ("gyro", "accel", "truth"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, str):
                object.__setattr__(self, name, tuple(v))
        if len(self.gyro) != 3 or len(self.accel) != 3:
            raise ValueError("layout gyro and accel need three column names each")
        if self.truth is not None and len(self.truth) != 3:
            raise ValueError("layout truth needs three column names (or null)")
        if self.rate_hz is not None and not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"layout rate_hz must be > 0, got {self.rate_hz!r}")

    @classmethod
    def from_dict(cls, d: dict[str, Any], source: str = "layout") -> CsvLayout:
        """A layout from a JSON object with the field names (unknown keys refused)."""
        if not isinstance(d, dict):
            raise ValueError(f"{source}: a column layout is a JSON object, got {d!r}")
        allowed = [f.name for f in fields(cls)]
        unknown = sorted(set(d) - set(allowed))
        if unknown:
            raise ValueError(f"{source}: unknown layout key(s) {unknown}; allowed: {allowed}")
        try:
            return cls(**d)
        except TypeError as exc:
            raise ValueError(f"{source}: {exc}") from None

    @classmethod
    def from_json(cls, text_or_path: str) -> CsvLayout:
        """A layout from inline JSON (``{"gyro_unit": "deg/s"}``) or a JSON file."""
        text = text_or_path.strip()
        source = "--layout"
        if not text.startswith("{"):
            path = Path(text)
            if not path.is_file():
                raise ValueError(f"layout {text!r}: neither inline JSON nor an existing file")
            source, text = path.name, path.read_text()
        try:
            d = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{source}: not valid JSON ({exc})") from None
        return cls.from_dict(d, source)


#: x-io Gait-Tracking export (deg/s, g, no truth).
XIO_LAYOUT = CsvLayout(
    time="Time",
    gyro=("Gyroscope X", "Gyroscope Y", "Gyroscope Z"),
    accel=("Accelerometer X", "Accelerometer Y", "Accelerometer Z"),
    truth=None,
    time_unit="s",
    gyro_unit="deg/s",
    accel_unit="g",
)


def looks_like_xio(header: list[str]) -> bool:
    """True when a header has the x-io Gait-Tracking columns."""
    names = {split_header(c)[0] for c in header}
    return {"time", "gyroscopex", "accelerometerx"} <= names


def read_columns(path: Path, usecols: list[int], names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Float columns ``usecols`` of a CSV file and each row's line number.

    Blank lines are skipped (their numbers are not reused); an empty cell is
    NaN (reported with its line by the validation); a cell that is not a
    number, or a line with too few fields, raises ``ValueError`` naming the line.
    """
    need = max(usecols) + 1
    cells: list[list[str]] = []
    lines: list[int] = []
    rows = iter_csv_rows(path)
    next(rows, None)
    for line, row in rows:
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) < need:
            raise ValueError(
                f"{path.name}: line {line} has {len(row)} fields, expected at least {need}"
            )
        cells.append([row[c].strip() or "nan" for c in usecols])
        lines.append(line)
    if len(cells) < 2:
        raise ValueError(f"{path.name}: fewer than 2 data lines")
    text = np.array(cells)
    try:
        data = text.astype(float)
    except ValueError:
        for i, row in enumerate(cells):
            for j, c in enumerate(row):
                try:
                    float(c)
                except ValueError:
                    raise ValueError(
                        f"{path.name}: line {lines[i]}, column {names[j]!r}: {c!r} is not a number"
                    ) from None
        raise
    return data, np.array(lines)


def _unit(
    path: Path, layout_unit: str | None, header: str | None, table: dict, what: str
) -> tuple[str, str]:
    """(unit, where it came from) of one quantity: the layout, the header, else SI."""
    if layout_unit is not None:
        unit, source = layout_unit, "from the layout"
    elif header is not None:
        unit, source = header, "from the header"
    else:
        unit, source = next(iter(table)), "no unit given: SI assumed"
    if unit not in table:
        raise ValueError(
            f"{path.name}: unknown {what} unit {unit!r} ({source}); use one of {sorted(table)}"
        )
    return unit, source


def load_csv(
    path: str | Path,
    layout: CsvLayout | None = None,
    options: LoadOptions | None = None,
    fmt: str = "csv",
    footprints: FootprintTable | None = None,
) -> Recording:
    """Load a CSV recording (see the module docstring for the layout).

    ``footprints`` (rows = data rows, 0-based) are checked against the time column
    and attached to the recording.

    Raises
    ------
    ValueError
        Missing columns (named), unknown units, and every check of
        :func:`pednav_env.io.validate.build_recording`.
    """
    path = Path(path)
    layout = layout or CsvLayout()
    options = options or LoadOptions()
    header = read_header(path)
    parsed = [split_header(c) for c in header]
    index: dict[str, tuple[int, str | None]] = {}
    for i, (name, unit) in enumerate(parsed):
        index.setdefault(name, (i, unit))

    def find(names: tuple[str, ...] | list[str], optional: bool = False):
        keys = [split_header(n)[0] for n in names]
        missing = [n for n, k in zip(names, keys, strict=True) if k not in index]
        if missing:
            if optional and len(missing) == len(names):
                return None
            raise ValueError(
                f"{path.name}: missing column(s) {missing} (header has {header}); name the "
                f"columns so in the header or give {LAYOUT_HINT}"
            )
        return [index[k] for k in keys]

    has_time = split_header(layout.time)[0] in index
    if has_time and layout.rate_hz is not None:
        raise ValueError(
            f"{path.name}: has a time column {layout.time!r}; a sample rate (--rate) is only "
            "for files without one"
        )
    if not has_time and layout.rate_hz is None:
        raise ValueError(
            f"{path.name}: missing column {layout.time!r} (header has {header}); name the time "
            f"column in {LAYOUT_HINT}, or give the sample rate of a file without time "
            "(pednav run --rate HZ; CsvLayout.rate_hz)"
        )
    tcol = find([layout.time]) if has_time else []
    gcols = find(list(layout.gyro))
    acols = find(list(layout.accel))
    pcols = None
    if layout.truth is not None:
        pcols = find(list(layout.truth), optional=not layout.require_truth)
    cols = tcol + gcols + acols + (pcols or [])
    data, lines = read_columns(path, [c[0] for c in cols], [header[c[0]] for c in cols])
    if has_time:
        tu, tsrc = _unit(path, layout.time_unit, tcol[0][1], TIME_UNITS, "time")
        time = data[:, 0] * TIME_UNITS[tu]
        data = data[:, 1:]
        time_desc = f"time in {tu} ({tsrc})"
    else:
        time = np.arange(len(data)) / float(layout.rate_hz)
        time_desc = f"no time column: {float(layout.rate_hz):g} Hz given"
    gu, gsrc = _unit(path, layout.gyro_unit, gcols[0][1], GYRO_UNITS, "angular-rate")
    au, asrc = _unit(path, layout.accel_unit, acols[0][1], ACCEL_UNITS, "specific-force")
    omega = data[:, 0:3] * GYRO_UNITS[gu]
    f = data[:, 3:6] * ACCEL_UNITS[au]
    truth = None
    if pcols is not None:
        pu, _ = _unit(path, layout.truth_unit, pcols[0][1], TRUTH_UNITS, "position")
        truth = data[:, 6:9] * TRUTH_UNITS[pu]
    return build_recording(
        time,
        omega,
        f,
        truth,
        namer=lambda i: f"line {lines[i]}",
        options=options,
        name=path.stem,
        metadata={"format": fmt, "path": str(path), "units": f"{time_desc}; {gu}; {au}"},
        units=f"angular rate in {gu} ({gsrc}), specific force in {au} ({asrc})",
        footprints=None if footprints is None else footprints.checked(time),
    )


def load_xio_csv(
    path: str | Path,
    options: LoadOptions | None = None,
    footprints: FootprintTable | None = None,
) -> Recording:
    """Load an x-io Gait-Tracking CSV export (deg/s, g; no truth)."""
    return load_csv(path, XIO_LAYOUT, options, fmt="xio", footprints=footprints)
