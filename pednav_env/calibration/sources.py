"""Walks for the statistics of :mod:`pednav_env.calibration.stats`, from any source.

- :func:`samples_from_recording` — a :class:`pednav_env.io.Recording`
  (stance labels from ``metadata["reference_stance"]`` when the loader found
  them, e.g. PyShoe's ``zv_vicon_opt``; truth positions if any; footprints
  if any, e.g. the hallway walks' ground control points);
- :func:`load_walk` — a file, through :func:`pednav_env.io.load_recording`
  (every format ``pednav run`` reads, footprints found as it finds them);
- :func:`samples_from_simulation` — one lane of a simulated walk (truth stance
  and positions, IMU readings with errors);
- :func:`recording_from_simulation` — the same lane as a
  :class:`pednav_env.io.Recording` (IMU readings and truth positions), for the
  real-data filter runner (``pednav run``'s).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pednav_env.calibration.stats import WalkSamples
from pednav_env.gait.foot import FootTrajectory
from pednav_env.io import Recording, load_recording
from pednav_env.sensors.imu import ImuMeasurements


def samples_from_recording(rec: Recording) -> WalkSamples:
    """The recording's samples, labels, truth and footprints (rate from the median
    interval)."""
    stance = rec.metadata.get("reference_stance")
    fp = rec.footprints
    return WalkSamples(
        omega_b=rec.omega_b,
        f_b=rec.f_b,
        rate_hz=rec.rate_hz,
        name=rec.name,
        stance=None if stance is None else np.asarray(stance, dtype=bool),
        truth_pos=rec.truth_pos if rec.has_truth else None,
        footfall_index=None if fp is None else np.asarray(fp.sample, dtype=np.int64),
        footprints_m=None if fp is None else np.asarray(fp.pos, dtype=float),
    )


def load_walk(path: str | Path) -> WalkSamples:
    """A recording file as :class:`WalkSamples` (module docstring).

    Raises
    ------
    ValueError
        A missing or unreadable file, and every loader check (named).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    return samples_from_recording(load_recording(path))


def same_walk(a: WalkSamples, b: WalkSamples) -> bool:
    """Whether ``a`` and ``b`` are one walk in two files (e.g. a hallway walk's
    ``.mat`` and its SensorConnect CSV): the same footprints (to 1 mm) and
    durations within 0.1 s. Walks without footprints are never the same."""
    if a.footprints_m is None or b.footprints_m is None:
        return False
    if a.footprints_m.shape != b.footprints_m.shape:
        return False
    dur_a, dur_b = len(a.omega_b) / a.rate_hz, len(b.omega_b) / b.rate_hz
    return abs(dur_a - dur_b) < 0.1 and bool(
        np.allclose(a.footprints_m, b.footprints_m, rtol=0.0, atol=1e-3)
    )


def distinct_walks(
    walks: list[WalkSamples], rate_hz: float = 200.0
) -> tuple[list[WalkSamples], list[tuple[str, str]]]:
    """``walks`` with each walk once (:func:`same_walk`): of copies, the one sampled
    nearest ``rate_hz`` (the SHOE window's rate; within 1 % of each other, the
    first). Returns the kept
    walks in their order and (dropped, kept) name pairs."""
    kept: list[WalkSamples] = []
    dropped: list[tuple[str, str]] = []
    for w in walks:
        twin = next((i for i, k in enumerate(kept) if same_walk(k, w)), None)
        if twin is None:
            kept.append(w)
        elif abs(w.rate_hz - rate_hz) < abs(kept[twin].rate_hz - rate_hz) - 0.01 * rate_hz:
            dropped.append((kept[twin].name, w.name))
            kept[twin] = w
        else:
            dropped.append((w.name, kept[twin].name))
    return kept, dropped


def samples_from_simulation(
    traj: FootTrajectory, imu: ImuMeasurements, lane: int, name: str | None = None
) -> WalkSamples:
    """Lane ``lane`` of a simulated batch, cut at the walk's own end (truth stance)."""
    end = int(round(traj.duration_s[lane] * traj.rate_hz))
    end = min(end, traj.num_samples)
    return WalkSamples(
        omega_b=imu.omega_b[lane, :end],
        f_b=imu.f_b[lane, :end],
        rate_hz=traj.rate_hz,
        name=name or f"sim{lane}",
        stance=traj.stance[lane, :end],
        truth_pos=traj.pos_n[lane, :end],
    )


def recording_from_simulation(
    traj: FootTrajectory, imu: ImuMeasurements, lane: int, name: str | None = None
) -> Recording:
    """Lane ``lane`` of a simulated batch as a recording, cut at the walk's own end:
    sample k at the end of its interval, (k + 1)/rate, with the truth position there
    (the layout of ``pednav simulate``'s CSV files)."""
    end = min(int(round(traj.duration_s[lane] * traj.rate_hz)), traj.num_samples)
    return Recording(
        time=traj.t[1 : end + 1],
        omega_b=imu.omega_b[lane, :end],
        f_b=imu.f_b[lane, :end],
        truth_pos=traj.pos_n[lane, 1 : end + 1],
        name=name or f"sim{lane}",
        metadata={"format": "simulation"},
    )
