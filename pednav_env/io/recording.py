"""A recorded walk from a foot-mounted IMU, in SI units, validated.

A :class:`Recording` is what every loader returns and what the filter runner
and the replay environment consume. Its arrays are always finite, its time
strictly increasing; what a loader found and changed on the way (duplicate
rows removed, saturated spans flagged or bridged, …) is listed in
``issues`` — nothing is dropped or altered without an entry there.

Axes are the IMU's own (as recorded); the runner rotates them into the
project's body convention (x forward, y left, z up) — see
:mod:`pednav_env.nav.mounting`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from pednav_env.io.footprints import Footprints

Array = NDArray[np.float64]

#: Issue kinds a loader may report (``RecordingIssue.kind``).
ISSUE_KINDS = (
    "duplicate_rows_removed",
    "gap_filled",
    "saturated",
    "saturation_bridged",
    "truth_missing",
    "time_jitter",
)


@dataclass(frozen=True)
class RecordingIssue:
    """Something a loader found in the data and what it did about it.

    Parameters
    ----------
    kind : one of :data:`ISSUE_KINDS`.
    rows : the affected rows, named as in the source (e.g. ``"line 17"``).
    message : a sentence for people.
    count : number of samples concerned.
    """

    kind: str
    rows: tuple[str, ...]
    message: str
    count: int = 0

    def __post_init__(self) -> None:
        if self.kind not in ISSUE_KINDS:
            raise ValueError(f"RecordingIssue.kind must be one of {ISSUE_KINDS}, got {self.kind!r}")


@dataclass(frozen=True, eq=False)
class Recording:
    """One walk recorded by a foot-mounted IMU.

    Parameters
    ----------
    time : (T,) s, strictly increasing (need not be uniform).
    omega_b : (T, 3) rad/s, angular rate in the IMU's axes.
    f_b : (T, 3) m/s², specific force in the IMU's axes (at rest ≈ +g along
        the axis pointing up).
    truth_pos : (T, 3) m or None, reference position of the foot per sample
        in the reference system's frame (e.g. motion capture); NaN rows mean
        "no reference at that sample" (reported in ``issues``).
    footprints : the foot's position at footfalls (sparse truth) or None;
        samples index this recording's samples.
    name : short name (file stem).
    metadata : free-form facts from the source (format, path, reference
        results stored with the data, …).
    issues : what the loader found and did (see module docstring).
    """

    time: Array
    omega_b: Array
    f_b: Array
    truth_pos: Array | None = None
    name: str = "recording"
    metadata: Mapping[str, Any] = field(default_factory=dict)
    issues: tuple[RecordingIssue, ...] = ()
    footprints: Footprints | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.time, dtype=float)
        w = np.asarray(self.omega_b, dtype=float)
        f = np.asarray(self.f_b, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise ValueError(f"Recording.time must be 1-D with ≥ 2 samples, got shape {t.shape}")
        for label, a in (("omega_b", w), ("f_b", f)):
            if a.shape != (t.size, 3):
                raise ValueError(f"Recording.{label} must be ({t.size}, 3), got {a.shape}")
            if not np.isfinite(a).all():
                row = int(np.flatnonzero(~np.isfinite(a).all(axis=1))[0])
                raise ValueError(f"Recording.{label} has a non-finite value at sample {row}")
        if not np.isfinite(t).all():
            raise ValueError(
                f"Recording.time has a non-finite value at sample {int(np.argmin(np.isfinite(t)))}"
            )
        dt = np.diff(t)
        if np.any(dt <= 0):
            row = int(np.flatnonzero(dt <= 0)[0]) + 1
            raise ValueError(
                f"Recording.time must increase strictly: sample {row} (t={float(t[row])!r} s) "
                f"is not after sample {row - 1} (t={float(t[row - 1])!r} s)"
            )
        truth = None
        if self.truth_pos is not None:
            truth = np.asarray(self.truth_pos, dtype=float)
            if truth.shape != (t.size, 3):
                raise ValueError(f"Recording.truth_pos must be ({t.size}, 3), got {truth.shape}")
        fp = self.footprints
        if fp is not None:
            if not isinstance(fp, Footprints):
                raise ValueError(f"Recording.footprints must be Footprints, got {type(fp)}")
            if fp.sample[-1] >= t.size:
                raise ValueError(
                    f"Recording.footprints: sample {int(fp.sample[-1])} is outside the "
                    f"recording ({t.size} samples)"
                )
        for name, value in (("time", t), ("omega_b", w), ("f_b", f), ("truth_pos", truth)):
            if value is not None:
                value = value.copy()
                value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "metadata", dict(self.metadata))
        object.__setattr__(self, "issues", tuple(self.issues))

    @property
    def num_samples(self) -> int:
        return int(self.time.size)

    @property
    def duration_s(self) -> float:
        return float(self.time[-1] - self.time[0])

    @property
    def rate_hz(self) -> float:
        """Nominal sample rate: 1 / median sample interval (Hz)."""
        return float(1.0 / np.median(np.diff(self.time)))

    @property
    def has_footprints(self) -> bool:
        return self.footprints is not None

    @property
    def has_truth(self) -> bool:
        return self.truth_pos is not None and bool(np.isfinite(self.truth_pos).all(axis=1).any())

    def summary(self) -> str:
        """One line per issue, for people."""
        if not self.issues:
            return f"{self.name}: no issues"
        return "\n".join(f"{self.name}: {i.kind}: {i.message}" for i in self.issues)
