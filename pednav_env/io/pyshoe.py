"""PyShoe VICON trials (MATLAB ``.mat``, University of Toronto PyShoe data set).

Layout, as read by :func:`scipy.io.loadmat`:

| key | shape | content |
|---|---|---|
| ``imu`` | N×6 | accelerometer x, y, z (m/s²), gyroscope x, y, z (rad/s) |
| ``ts`` | 1×N | time (s) |
| ``gt`` | N×3 | motion-capture foot position (m) per IMU sample (optional) ¹ |
| ``trial_error`` | 1×5 | PyShoe's ARMSE (m) per detector ² (optional) |
| ``G_*_opt`` | 1×1 | those thresholds (optional) |
| ``zv_vicon_opt`` | 1×N | zero-velocity labels from motion capture (optional) |

¹ loaded with y negated (``GT_TO_RIGHT_HANDED``, see there).
² [SHOE, ARED, ARED, MBGTD, VICON], each with a threshold optimised on that trial.

The IMU (MicroStrain 3DM-GX5-25) reads about (−2.8, 0.3, −9.4) m/s² at
rest: its z axis points down, so the runner's mounting step matters.
Rows are named ``sample i`` (0-based, as in the arrays).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pednav_env.io.footprints import FootprintTable
from pednav_env.io.matfile import read_mat
from pednav_env.io.recording import Recording
from pednav_env.io.validate import LoadOptions, build_recording

#: PyShoe's ``gt`` is (x, y) of a z-down frame with z reported up — a
#: left-handed triple (PyShoe's filter navigates in a z-down frame and negates
#: z at the end). Negating y gives a right-handed, z-up frame like the
#: project's. Checked on the data: without it no horizontal rotation matches
#: a filtered track (ARMSE 1.4 m against 0.14 m on the first trial).
GT_TO_RIGHT_HANDED = np.array([1.0, -1.0, 1.0])

#: Order of PyShoe's ``trial_error`` entries (its script duplicates ARED).
TRIAL_ERROR_DETECTORS = ("shoe", "ared", "ared_duplicate", "mbgtd", "vicon")


def load_pyshoe_mat(
    path: str | Path,
    options: LoadOptions | None = None,
    footprints: FootprintTable | None = None,
) -> Recording:
    """Load one PyShoe ``.mat`` trial (``footprints``: extra sparse truth, rarely).

    Raises
    ------
    ValueError
        A missing ``imu``/``ts`` key or wrong shapes (named), and every check
        of :func:`pednav_env.io.validate.build_recording`.
    """
    path = Path(path)
    data = read_mat(path)
    for key in ("imu", "ts"):
        if key not in data:
            keys = sorted(k for k in data if not k.startswith("__"))
            raise ValueError(f"{path.name}: missing variable {key!r} (has {keys})")
    imu = np.asarray(data["imu"], dtype=float)
    ts = np.asarray(data["ts"], dtype=float).ravel()
    if imu.ndim != 2 or imu.shape[1] != 6:
        raise ValueError(f"{path.name}: 'imu' must be N×6 (accel, gyro), got {imu.shape}")
    if imu.shape[0] != ts.size:
        raise ValueError(f"{path.name}: 'imu' has {imu.shape[0]} rows but 'ts' {ts.size}")
    truth = None
    if "gt" in data:
        truth = np.asarray(data["gt"], dtype=float)
        if truth.shape != (ts.size, 3):
            raise ValueError(f"{path.name}: 'gt' must be {ts.size}×3, got {truth.shape}")
        truth = truth * GT_TO_RIGHT_HANDED
    meta: dict = {"format": "pyshoe", "path": str(path)}
    if "trial_error" in data:
        err = np.asarray(data["trial_error"], dtype=float).ravel()
        meta["pyshoe_trial_error_m"] = dict(zip(TRIAL_ERROR_DETECTORS, err.tolist(), strict=False))
    for key in ("G_shoe_opt", "G_ared_opt", "G_mbgtd_opt", "G_vicon_opt"):
        if key in data:
            meta[key] = float(np.asarray(data[key]).ravel()[0])
    if "best_detector" in data:
        meta["pyshoe_best_detector"] = str(np.asarray(data["best_detector"]).ravel()[0]).strip()
    if "zv_vicon_opt" in data:
        zv = np.asarray(data["zv_vicon_opt"]).ravel()
        if zv.size == ts.size:
            meta["reference_stance"] = zv.astype(bool)
    return build_recording(
        ts,
        imu[:, 3:6],
        imu[:, 0:3],
        truth,
        namer=lambda i: f"sample {i}",
        options=options or LoadOptions(),
        name=path.stem,
        metadata=meta,
        footprints=None if footprints is None else footprints.checked(ts),
    )
