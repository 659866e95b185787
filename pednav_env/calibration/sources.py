"""Walks for the statistics of :mod:`pednav_env.calibration.stats`, from any source.

- :func:`samples_from_recording` — a :class:`pednav_env.io.Recording`
  (stance labels from ``metadata["reference_stance"]`` when the loader found
  them, e.g. PyShoe's ``zv_vicon_opt``; truth positions if any);
- :func:`load_walk` — a file: the hallway ``.mat`` layout (``imu_data``,
  ``timestamps``, ``strideIndex``, ``GCP``; footprint truth at footfalls) or
  anything :func:`pednav_env.io.load_recording` reads;
- :func:`samples_from_simulation` — one lane of a simulated walk (truth stance
  and positions, IMU readings with errors);
- :func:`recording_from_simulation` — the same lane as a
  :class:`pednav_env.io.Recording` (IMU readings and truth positions), for the
  real-data filter runner (``pednav run``'s).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from pednav_env.calibration.stats import WalkSamples
from pednav_env.gait.foot import FootTrajectory
from pednav_env.io import Recording, load_recording
from pednav_env.sensors.imu import ImuMeasurements

#: Variables of the hallway ``.mat`` layout.
HALLWAY_KEYS = ("imu_data", "timestamps", "strideIndex", "GCP")


def samples_from_recording(rec: Recording) -> WalkSamples:
    """The recording's samples, labels and truth (rate from the median interval)."""
    stance = rec.metadata.get("reference_stance")
    foot_idx = rec.metadata.get("footfall_index")
    footprints = rec.metadata.get("footprints_m")
    return WalkSamples(
        omega_b=rec.omega_b,
        f_b=rec.f_b,
        rate_hz=rec.rate_hz,
        name=rec.name,
        stance=None if stance is None else np.asarray(stance, dtype=bool),
        truth_pos=rec.truth_pos if rec.has_truth else None,
        footfall_index=None if foot_idx is None else np.asarray(foot_idx, dtype=np.int64),
        footprints_m=None if footprints is None else np.asarray(footprints, dtype=float),
    )


def _hallway_samples(path: Path, data: dict) -> WalkSamples:
    """The hallway layout: accelerometer then gyroscope (m/s², rad/s), footprints."""
    imu = np.asarray(data["imu_data"], dtype=float)
    t = np.asarray(data["timestamps"], dtype=float).ravel()
    idx = np.asarray(data["strideIndex"]).ravel().astype(np.int64)
    gcp = np.asarray(data["GCP"], dtype=float)
    if imu.ndim != 2 or imu.shape[1] != 6 or imu.shape[0] != t.size:
        raise ValueError(f"{path.name}: 'imu_data' must be {t.size}×6, got {imu.shape}")
    if gcp.shape != (idx.size, 2):
        raise ValueError(f"{path.name}: 'GCP' must be {idx.size}×2, got {gcp.shape}")
    if not np.isfinite(imu).all():
        row = int(np.flatnonzero(~np.isfinite(imu).all(axis=1))[0])
        raise ValueError(f"{path.name}: 'imu_data' has a non-finite value at sample {row}")
    return WalkSamples(
        omega_b=imu[:, 3:6],
        f_b=imu[:, 0:3],
        rate_hz=float(1.0 / np.median(np.diff(t))),
        name=path.stem,
        footfall_index=idx,
        footprints_m=gcp,
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
    if path.suffix.lower() == ".mat":
        try:
            data = scipy.io.loadmat(path)
        except (OSError, ValueError, NotImplementedError) as exc:
            raise ValueError(f"{path.name}: not a readable MATLAB file ({exc})") from None
        if all(k in data for k in HALLWAY_KEYS):
            return _hallway_samples(path, data)
    return samples_from_recording(load_recording(path))


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
