"""Walks with footprint truth: the ``.mat`` with ground control points and the
MicroStrain SensorConnect CSV export (docs/REAL_DATA.md).

``gcp-mat`` — MATLAB file (as read by :func:`scipy.io.loadmat`), the layout
of the gait-driven inertial navigation data set's own recordings:

| key | shape | content |
|---|---|---|
| ``imu_data`` | N×6 | accelerometer x, y, z (m/s²), gyroscope x, y, z (rad/s) |
| ``timestamps`` | 1×N | time (s) |
| ``strideIndex`` | 1×K | 0-based sample of each footfall (the foot is down there) |
| ``GCP`` | K×2 | footprint position (m) at those footfalls ¹ |

Other keys (the source's own processing: ``pyshoeTrajectory``, rotated
frames, …) are not used.

``sensorconnect`` — the CSV that MicroStrain's SensorConnect exports: a
``Time`` column (s), then per channel ``<device>:<channel>``, either the
sensor's scaled readings ``scaledAccelX/Y/Z`` (g) and ``scaledGyroX/Y/Z``
(rad/s), or the outputs of its estimation filter ``estCompensatedAccelX/Y/Z``
(m/s²) and ``estAngularRateX/Y/Z`` (rad/s), each with a ``:valid`` flag
column that must be 1 (the scaled channels are used when both are present;
magnetometer and attitude columns are ignored). Its footprints come from the
footprint CSV beside it (``<stem>_footprints.csv``,
:mod:`pednav_env.io.footprints`), placed by their timestamps.

¹ Footprints are (x, y) of a frame that is left-handed with z up (like
PyShoe's ``gt``, which its z-down filter produces); the loaders negate y
(``GCP_AXES``). Checked on the data: with y as stored the shipped
``real-fixed`` filter's footprint error on walk 31 is 1.25 m, with y negated
0.24 m; PyShoe's own track in the files matches the footprints as stored,
i.e. both are in that frame.

Rows are named ``sample i`` in the ``.mat`` and ``line n`` in the CSV; a
footprint is named ``strideIndex[k]`` or by its line in the footprint file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pednav_env.io.csv_format import CsvLayout, load_csv, read_columns, split_header
from pednav_env.io.footprints import (
    FootprintTable,
    footprint_table,
    footprints_beside,
    read_footprints_csv,
)
from pednav_env.io.matfile import read_mat
from pednav_env.io.recording import Recording
from pednav_env.io.text import read_header
from pednav_env.io.validate import LoadOptions, build_recording

#: Signs applied to the footprints' (x, y): the source's frame → right-handed, z up.
GCP_AXES = (1.0, -1.0)
#: SensorConnect channels (after the device name and ':', normalised):
#: (accelerometer, its unit, gyro, its unit), in order of preference.
SENSORCONNECT_CHANNELS = (
    (
        ("scaledaccelx", "scaledaccely", "scaledaccelz"),
        "g",
        ("scaledgyrox", "scaledgyroy", "scaledgyroz"),
        "rad/s",
    ),
    (
        ("estcompensatedaccelx", "estcompensatedaccely", "estcompensatedaccelz"),
        "m/s^2",
        ("estangularratex", "estangularratey", "estangularratez"),
        "rad/s",
    ),
)

#: ``footprints`` argument: ``AUTO`` = the file's own (gcp-mat) or the
#: footprint file beside it (sensorconnect), required; a path = that footprint
#: CSV; None = none (the walk then has no truth).
AUTO = "auto"
FootprintChoice = str | Path | None


def _footprint_file(path: Path, footprints: FootprintChoice) -> FootprintTable | None:
    """The footprint table for a recording without footprints of its own."""
    if footprints is None:
        return None
    if footprints == AUTO:
        beside = footprints_beside(path)
        if not beside.is_file():
            raise ValueError(
                f"{path.name}: its footprint file {beside.name} is not beside it; give the "
                "footprint file (--footprints FILE) or run without truth (--footprints none)"
            )
        return _gcp_frame(read_footprints_csv(beside))
    return _gcp_frame(read_footprints_csv(footprints))


def _gcp_frame(table: FootprintTable) -> FootprintTable:
    return FootprintTable(table.source, table.row, table.pos, table.names, table.time, GCP_AXES)


def load_gcp_mat(
    path: str | Path, options: LoadOptions | None = None, footprints: FootprintChoice = AUTO
) -> Recording:
    """Load a ``.mat`` walk with ground control points (module docstring).

    Raises
    ------
    ValueError
        A missing variable or wrong shapes (named), footprints outside the
        recording or not increasing (named by their ``strideIndex`` entry), and
        every check of :func:`pednav_env.io.validate.build_recording`.
    """
    path = Path(path)
    data = read_mat(path)
    keys = sorted(k for k in data if not k.startswith("__"))
    for key in ("imu_data", "timestamps"):
        if key not in data:
            raise ValueError(f"{path.name}: missing variable {key!r} (has {keys})")
    imu = np.asarray(data["imu_data"], dtype=float)
    ts = np.asarray(data["timestamps"], dtype=float).ravel()
    if imu.ndim != 2 or imu.shape[1] != 6:
        raise ValueError(f"{path.name}: 'imu_data' must be N×6 (accel, gyro), got {imu.shape}")
    if imu.shape[0] != ts.size:
        raise ValueError(
            f"{path.name}: 'imu_data' has {imu.shape[0]} rows but 'timestamps' {ts.size}"
        )
    table = None
    if footprints == AUTO:
        present = [k for k in ("strideIndex", "GCP") if k in data]
        if len(present) < 2:
            missing = sorted({"strideIndex", "GCP"} - set(present))
            raise ValueError(
                f"{path.name}: missing variable(s) {missing} for the footprints (has {keys}); "
                "give a footprint file (--footprints FILE) or run without truth "
                "(--footprints none)"
            )
        idx = np.asarray(data["strideIndex"]).ravel()
        names = tuple(f"strideIndex[{k}]" for k in range(idx.size))
        table = footprint_table(path.name, idx, data["GCP"], names, axes=GCP_AXES)
    else:
        table = _footprint_file(path, footprints)
    return build_recording(
        ts,
        imu[:, 3:6],
        imu[:, 0:3],
        None,
        namer=lambda i: f"sample {i}",
        options=options or LoadOptions(),
        name=path.stem,
        metadata={"format": "gcp-mat", "path": str(path)},
        footprints=None if table is None else table.checked(ts),
    )


def sensorconnect_layout(header: list[str]) -> tuple[CsvLayout, list[str]] | None:
    """(layout, ``:valid`` flag columns) of a SensorConnect header, or None."""
    by_channel: dict[str, str] = {}
    for cell in header:
        parts = cell.split(":")
        channel = split_header(parts[-1] if len(parts) < 3 else ":".join(parts[1:]))[0]
        by_channel.setdefault(channel, cell)
    if "time" not in by_channel:
        return None
    for accel, accel_unit, gyro, gyro_unit in SENSORCONNECT_CHANNELS:
        if all(c in by_channel for c in accel + gyro):
            layout = CsvLayout(
                time=by_channel["time"],
                gyro=tuple(by_channel[c] for c in gyro),
                accel=tuple(by_channel[c] for c in accel),
                truth=None,
                time_unit="s",
                gyro_unit=gyro_unit,
                accel_unit=accel_unit,
            )
            valid = [by_channel[c + ":valid"] for c in accel + gyro if c + ":valid" in by_channel]
            return layout, valid
    return None


def looks_like_sensorconnect(header: list[str]) -> bool:
    """True when a CSV header has SensorConnect's accelerometer and gyro channels."""
    return sensorconnect_layout(header) is not None


def load_sensorconnect_csv(
    path: str | Path, options: LoadOptions | None = None, footprints: FootprintChoice = AUTO
) -> Recording:
    """Load a SensorConnect CSV export with its footprints (module docstring)."""
    path = Path(path)
    header = read_header(path)
    found = sensorconnect_layout(header)
    if found is None:
        raise ValueError(
            f"{path.name}: not a SensorConnect export (needs Time and <device>:scaledAccelX/Y/Z "
            "and scaledGyroX/Y/Z, or estCompensatedAccelX/Y/Z and estAngularRateX/Y/Z columns)"
        )
    layout, valid = found
    if valid:
        cols = [header.index(c) for c in valid]
        flags, lines = read_columns(path, cols, valid)
        bad = np.flatnonzero((flags != 1).any(axis=1))
        if bad.size:
            k = int(bad[0])
            column = valid[int(np.argmax(flags[k] != 1))]
            raise ValueError(
                f"{path.name}: line {lines[k]}: the sensor flags {column!r} as not valid "
                f"({bad.size} such lines); cut the data there"
            )
    table = _footprint_file(path, footprints)
    return load_csv(path, layout, options, fmt="sensorconnect", footprints=table)
