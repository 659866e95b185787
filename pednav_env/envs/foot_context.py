"""The privileged context of the foot environments: what the walker is doing
in the coming decision interval (truth, never in the observation).

``info["context"]`` is a float64 row of :data:`CONTEXT_FIELDS` (scalar env
``(3,)``, vector env ``(num_envs, 3)``), in the info of every reset and step;
after an autoreset it is the new episode's (``final_info["context"]`` the old
one's). Categorical fields are integer codes stored as floats:

- ``speed_band``: index in :data:`SPEED_BANDS` of ``speed_mps``;
- ``imu_grade``: index in :data:`CONTEXT_GRADES` of the episode's IMU grade
  (``"recorded"`` for a replayed recording);
- ``speed_mps``: the truth walking speed over the interval that the next
  action governs, widened by half an interval on each side: distance walked
  by the foot over that window / its duration (m/s).

It is for analysis and for oracles keyed on (speed band, IMU grade); a policy
that reads it is not deployable.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

CONTEXT_FIELDS: tuple[str, ...] = ("speed_band", "imu_grade", "speed_mps")
#: Walking-speed bands (m/s): standing, then the bands of docs/SIM_TO_REAL.md.
SPEED_BANDS: tuple[tuple[float, float], ...] = (
    (0.0, 0.2),
    (0.2, 0.8),
    (0.8, 1.3),
    (1.3, 1.8),
    (1.8, 2.6),
    (2.6, math.inf),
)
#: IMU grade codes (pednav_env.sensors.imu.IMU_GRADES, then replayed data).
CONTEXT_GRADES: tuple[str, ...] = (
    "paper003",
    "adis16470",
    "consumer",
    "microstrain_gx5",
    "adis16405",
    "ideal",
    "recorded",
)
_BAND_EDGES = np.array([hi for _, hi in SPEED_BANDS[:-1]])


def grade_code(grade: str) -> int:
    """Code of an IMU grade in :data:`CONTEXT_GRADES`."""
    return CONTEXT_GRADES.index(grade)


def interval_context(
    distance_m: Array,
    lanes: NDArray[np.integer],
    cursor: NDArray[np.integer],
    length: NDArray[np.integer],
    interval_samples: int,
    dt: float | Array,
    grade_codes: NDArray[np.integer],
) -> Array:
    """Context rows ``(B, 3)`` of ``lanes`` (B,) whose next interval starts at
    sample ``cursor`` (B,), from the distance walked ``distance_m`` (N, T+1) of
    every lane and the lanes' record lengths ``length`` (B,) (module docstring).
    Reads two entries per lane."""
    half = interval_samples // 2
    lo = np.clip(cursor - half, 0, length)
    hi = np.clip(cursor + interval_samples + half, 0, length)
    walked = distance_m[lanes, hi] - distance_m[lanes, lo]
    speed = np.where(hi > lo, walked / (np.maximum(hi - lo, 1) * dt), 0.0)
    band = np.searchsorted(_BAND_EDGES, speed, side="right")
    return np.stack((band.astype(float), grade_codes.astype(float), speed), axis=1)
