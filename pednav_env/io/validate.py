"""Checks shared by every loader: raw arrays in SI units → a :class:`Recording`.

Each problem is either a ``ValueError`` naming the row (as the source names
it: ``"line 17"`` of a CSV file, ``"sample 16"`` of a MATLAB array) or, where
:class:`LoadOptions` says so, a documented repair listed in
``Recording.issues``:

| Problem | Default | Alternatives |
|---|---|---|
| NaN / inf / unreadable IMU value | ``ValueError`` | — |
| exact duplicate row (same time, same values) | removed, reported | ``duplicates="error"`` |
| time not increasing (different values) | ``ValueError`` | — |
| gap longer than ``max_gap_s`` | ``ValueError`` | raise ``max_gap_s`` |
| shorter gap (see :mod:`pednav_env.io.uniform`) | reported; interpolated when run | — |
| timestamp jitter > 10 % of the interval | reported; nominal rate used | — |
| saturated samples | reported | ``saturation="bridge"`` (quintic, C²) or ``"error"`` |
| static accelerometer norm ≈ 1 or ≈ 96 m/s² | ``ValueError`` (says g / m/s²) | ``check_units`` |
| gyro beyond 40 rad/s | ``ValueError`` ("looks like deg/s") | ``check_units`` |
| NaN truth rows | reported; metrics skip them | — |
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.io.footprints import Footprints
from pednav_env.io.recording import Recording, RecordingIssue
from pednav_env.io.saturation import bridge_saturated, runs, saturation_mask
from pednav_env.io.uniform import grid_steps

Array = NDArray[np.float64]
RowNamer = Callable[[int], str]

#: Rates the loaders accept (Hz), from the issue: 100 Hz to 1 kHz (±10 %).
MIN_RATE_HZ = 90.0
MAX_RATE_HZ = 1100.0
#: Largest plausible angular rate (rad/s): above every MEMS gyro range
#: (±2000 °/s = 35 rad/s); a larger value means the data are in °/s.
MAX_PLAUSIBLE_RATE = 40.0
#: Plausible static specific-force norms (m/s²).
STATIC_NORM_RANGE = (7.0, 13.0)
#: Rows listed in an error or issue message.
MAX_ROWS_LISTED = 5
#: How to give a unit, for messages (header, command line, Python).
UNIT_HINT = (
    "in the header, e.g. 'gyro_x (deg/s)', or in a column layout: pednav run --layout; "
    "CsvLayout in Python; or skip this check: --no-unit-check, LoadOptions(check_units=False)"
)


@dataclass(frozen=True)
class LoadOptions:
    """How loaders treat problems in the data (see the module table).

    Parameters
    ----------
    duplicates : ``"drop"`` (remove exact duplicate rows, report them) or ``"error"``.
    max_gap_s : s; a time step longer than this raises ``ValueError``.
    saturation : ``"flag"`` (report), ``"bridge"`` (report and replace by a
        quintic bridge) or ``"error"``.
    gyro_range : rad/s, the gyro's declared range; None = detect clipping
        plateaus (runs of ≥ 3 samples at the column's extreme).
    accel_range : m/s², likewise for the accelerometer.
    check_units : test the static accelerometer norm and the gyro magnitude
        for unit mistakes.
    """

    duplicates: str = "drop"
    max_gap_s: float = 0.1
    saturation: str = "flag"
    gyro_range: float | None = None
    accel_range: float | None = None
    check_units: bool = True

    def __post_init__(self) -> None:
        if self.duplicates not in ("drop", "error"):
            raise ValueError(
                f"LoadOptions.duplicates must be 'drop' or 'error', got {self.duplicates!r}"
            )
        if self.saturation not in ("flag", "bridge", "error"):
            raise ValueError(
                "LoadOptions.saturation must be 'flag', 'bridge' or 'error', "
                f"got {self.saturation!r}"
            )
        if not (math.isfinite(self.max_gap_s) and self.max_gap_s > 0):
            raise ValueError(f"LoadOptions.max_gap_s must be > 0, got {self.max_gap_s!r}")
        for name in ("gyro_range", "accel_range"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise ValueError(f"LoadOptions.{name} must be None or > 0, got {v!r}")


def _list(rows: NDArray[np.integer], namer: RowNamer) -> str:
    shown = ", ".join(namer(int(r)) for r in rows[:MAX_ROWS_LISTED])
    more = len(rows) - MAX_ROWS_LISTED
    return shown + (f" and {more} more" if more > 0 else "")


def check_finite(columns: Mapping[str, Array], namer: RowNamer) -> None:
    """``ValueError`` naming the first rows and the column with NaN/inf/unreadable values."""
    for label, a in columns.items():
        bad = ~np.isfinite(a)
        if bad.ndim > 1:
            bad = bad.any(axis=1)
        if bad.any():
            rows = np.flatnonzero(bad)
            raise ValueError(
                f"{label}: missing, unreadable, NaN or inf value at {_list(rows, namer)} "
                f"({len(rows)} rows); fix or cut the data — samples are never dropped silently"
            )


def static_window(omega_b: Array, rate_hz: float, window_s: float = 0.25) -> slice:
    """The ``window_s`` span with the smallest mean |ω| (the stillest one)."""
    n = max(2, int(round(window_s * rate_hz)))
    wn = np.linalg.norm(omega_b, axis=1)
    if len(wn) <= n:
        return slice(0, len(wn))
    c = np.concatenate(([0.0], np.cumsum(wn)))
    means = (c[n:] - c[:-n]) / n
    i = int(np.argmin(means))
    return slice(i, i + n)


def check_units(omega_b: Array, f_b: Array, rate_hz: float, namer: RowNamer, units: str) -> None:
    """``ValueError`` when the data do not look like rad/s and m/s² after conversion.

    ``units`` says, for the message, which units the data were read in and
    where they came from (e.g. ``"angular rate in deg/s (from the header), …"``).
    """
    w = np.linalg.norm(omega_b, axis=1)
    if w.max() > MAX_PLAUSIBLE_RATE:
        row = int(np.argmax(w))
        raise ValueError(
            f"angular rate of {w.max():.1f} rad/s at {namer(row)} is beyond any MEMS gyro range "
            f"(read as {units}) — the gyro data look like deg/s: give the unit deg/s "
            f"({UNIT_HINT})"
        )
    win = static_window(omega_b, rate_hz)
    norm = float(np.median(np.linalg.norm(f_b[win], axis=1)))
    lo, hi = STATIC_NORM_RANGE
    if lo <= norm <= hi:
        return
    where = f"the stillest span ({namer(win.start)}…{namer(win.stop - 1)})"
    if 0.7 <= norm <= 1.3:
        hint = "it looks like g: give the accelerometer unit g"
    elif 0.7 * STANDARD_GRAVITY**2 <= norm <= 1.3 * STANDARD_GRAVITY**2:
        hint = "it looks like m/s² read as g: give the accelerometer unit m/s^2"
    elif 700 <= norm <= 1300:
        hint = "it looks like mg: give the accelerometer unit mg"
    else:
        hint = "check the accelerometer unit and scale"
    raise ValueError(
        f"static accelerometer norm {norm:.3g} m/s² over {where} (read as {units}); "
        f"expected about {STANDARD_GRAVITY} m/s² — {hint} ({UNIT_HINT})"
    )


def build_recording(
    time: Array,
    omega_b: Array,
    f_b: Array,
    truth_pos: Array | None,
    namer: RowNamer,
    options: LoadOptions,
    name: str,
    metadata: Mapping[str, Any],
    units: str = "rad/s and m/s² (the format's units)",
    extra_issues: tuple[RecordingIssue, ...] = (),
    footprints: Footprints | None = None,
) -> Recording:
    """Validate raw SI arrays (rows in source order) and build a :class:`Recording`.

    ``namer(i)`` names source row ``i`` (0-based index into the arrays as given).
    ``footprints`` index source rows; they are moved with the rows kept (a
    footprint on a removed duplicate row goes to the identical row before it).
    """
    time = np.asarray(time, dtype=float).ravel()
    omega_b = np.asarray(omega_b, dtype=float)
    f_b = np.asarray(f_b, dtype=float)
    n = time.size
    if n < 2:
        raise ValueError(f"{name}: fewer than 2 samples")
    for label, a in (("angular rate", omega_b), ("specific force", f_b)):
        if a.shape != (n, 3):
            raise ValueError(f"{name}: {label} must be ({n}, 3), got {a.shape}")
    check_finite({"time": time, "angular rate": omega_b, "specific force": f_b}, namer)
    issues: list[RecordingIssue] = list(extra_issues)
    src = np.arange(n)

    # duplicates and monotonic time
    dt = np.diff(time)
    same_t = np.flatnonzero(dt == 0) + 1
    if same_t.size:
        exact = np.all(omega_b[same_t] == omega_b[same_t - 1], axis=1) & np.all(
            f_b[same_t] == f_b[same_t - 1], axis=1
        )
        if not exact.all():
            r = int(same_t[~exact][0])
            raise ValueError(
                f"time does not increase: {namer(r)} repeats t={float(time[r])!r} s of "
                f"{namer(r - 1)} with different samples"
            )
        if options.duplicates == "error":
            raise ValueError(
                f"duplicate rows (same time and values as the row before): {_list(same_t, namer)} "
                f"({same_t.size} rows); pass duplicates='drop' to remove them"
            )
        issues.append(
            RecordingIssue(
                "duplicate_rows_removed",
                tuple(namer(int(r)) for r in same_t),
                f"{same_t.size} rows repeat the row before exactly (time and values) and were "
                f"removed: {_list(same_t, namer)}",
                int(same_t.size),
            )
        )
        keep = np.ones(n, dtype=bool)
        keep[same_t] = False
        src = src[keep]
    t = time[src]
    dt = np.diff(t)
    if np.any(dt < 0):
        k = int(np.flatnonzero(dt < 0)[0]) + 1
        raise ValueError(
            f"time goes backwards: {namer(int(src[k]))} has t={float(t[k])!r} s, before "
            f"{namer(int(src[k - 1]))} at t={float(t[k - 1])!r} s"
        )
    nominal = float(np.median(dt))
    rate = 1.0 / nominal
    if not (MIN_RATE_HZ <= rate <= MAX_RATE_HZ):
        raise ValueError(
            f"{name}: sample rate {rate:.1f} Hz (median interval) is outside "
            f"{MIN_RATE_HZ:.0f}–{MAX_RATE_HZ:.0f} Hz — is the time column in seconds?"
        )
    gaps = np.flatnonzero(dt > options.max_gap_s)
    if gaps.size:
        k = int(gaps[0]) + 1
        raise ValueError(
            f"gap of {dt[k - 1]:.3f} s before {namer(int(src[k]))} (t={float(t[k])!r} s) is "
            f"longer than max_gap_s={options.max_gap_s} s ({gaps.size} such gaps); cut the "
            "record there or raise max_gap_s (--max-gap)"
        )
    _, steps = grid_steps(t)
    short = np.flatnonzero(steps > 1)
    if short.size:
        missing = int(np.sum(steps[short] - 1))
        issues.append(
            RecordingIssue(
                "gap_filled",
                tuple(namer(int(src[k + 1])) for k in short),
                f"{short.size} gaps (longest {dt[short].max() * 1e3:.1f} ms, {missing} samples "
                f"missing in all) before {_list(src[short + 1], namer)}; linearly interpolated "
                "onto the uniform grid when the filter runs",
                missing,
            )
        )
    jitter = np.abs(dt - nominal)
    jitter[short] = 0.0
    if jitter.max() > 0.1 * nominal:
        rows = np.flatnonzero(jitter > 0.1 * nominal)
        issues.append(
            RecordingIssue(
                "time_jitter",
                tuple(namer(int(src[k + 1])) for k in rows[:MAX_ROWS_LISTED]),
                f"time steps deviate from the nominal {nominal * 1e3:.3f} ms by up to "
                f"{jitter.max() * 1e3:.2f} ms at {rows.size} rows (first: "
                f"{_list(src[rows + 1], namer)}); the samples are used at the nominal rate",
                int(rows.size),
            )
        )
    w, f = omega_b[src], f_b[src]
    if options.check_units:
        check_units(w, f, rate, lambda i: namer(int(src[i])), units)

    # saturation
    for label, arr, limit in (("gyro", w, options.gyro_range), ("accel", f, options.accel_range)):
        mask = saturation_mask(arr, limit)
        if not mask.any():
            continue
        rows = np.flatnonzero(mask.any(axis=1))
        spans = runs(mask.any(axis=1))
        msg = (
            f"{label}: {rows.size} saturated samples in {len(spans)} spans "
            f"({'range ' + format(limit, '.4g') if limit else 'clipping plateaus'}), at "
            f"{_list(src[rows], namer)}"
        )
        if options.saturation == "error":
            raise ValueError(msg + "; pass saturation='flag' or 'bridge' to accept them")
        issues.append(
            RecordingIssue(
                "saturated", tuple(namer(int(src[r])) for r in rows), msg, int(rows.size)
            )
        )
        if options.saturation == "bridge":
            bridged = bridge_saturated(t, arr, mask)
            arr[...] = bridged
            issues.append(
                RecordingIssue(
                    "saturation_bridged",
                    tuple(namer(int(src[r])) for r in rows),
                    f"{label}: the saturated spans were replaced by quintic bridges (C² at the "
                    "joins, paper 003)",
                    int(rows.size),
                )
            )

    truth = None
    if truth_pos is not None:
        truth = np.asarray(truth_pos, dtype=float)
        if truth.shape != (n, 3):
            raise ValueError(f"{name}: truth position must be ({n}, 3), got {truth.shape}")
        truth = truth[src]
        bad = ~np.isfinite(truth).all(axis=1)
        if bad.all():
            raise ValueError(f"{name}: the truth position has no finite row")
        if bad.any():
            rows = np.flatnonzero(bad)
            issues.append(
                RecordingIssue(
                    "truth_missing",
                    tuple(namer(int(src[r])) for r in rows),
                    f"no reference position at {rows.size} samples ({_list(src[rows], namer)}); "
                    "metrics skip them",
                    int(rows.size),
                )
            )
            truth = np.where(bad[:, None], np.nan, truth)
    if footprints is not None:
        out = np.flatnonzero(footprints.sample >= n)
        if out.size:
            k = int(out[0])
            raise ValueError(
                f"{footprints.source}: footprint {k} at sample {int(footprints.sample[k])} is "
                f"outside the recording ({n} samples)"
            )
        footprints = footprints.reindexed(np.searchsorted(src, footprints.sample, side="right") - 1)
    return Recording(
        t, w, f, truth, name=name, metadata=metadata, issues=tuple(issues), footprints=footprints
    )
