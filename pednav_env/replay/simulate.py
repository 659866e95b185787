"""Simulated foot walks written as recordings (``pednav simulate``).

A walk from the foot simulator (:mod:`pednav_env.gait.foot`) with the IMU
errors of a grade (:mod:`pednav_env.sensors.imu`), written in the generic CSV
format of docs/REAL_DATA.md so that ``pednav run`` (or any tool) reads it like
a recording. Columns, one line per IMU sample:

| column | unit | content |
|---|---|---|
| ``time (s)`` | s | end of the sample's interval, (k + 1) / rate |
| ``gyro_x/y/z (rad/s)`` | rad/s | angular rate with the grade's errors, body axes ¹ |
| ``accel_x/y/z (m/s^2)`` | m/s² | specific force with the grade's errors, body axes |
| ``pos_x/y/z (m)`` | m | truth: IMU position at ``time``, east-north-up, 0 at the start |
| ``stance`` | 0/1 | truth: the sample lies in a stance phase (Γ₀) |
| ``gait`` | — | truth: gait class (0 standing, 1 slow walk, 2 walk, 3 fast walk, 4 run) |

¹ x forward, y left, z up: a level IMU reads +g on z at rest.

The route: :func:`pednav_env.gait.speed_route.speed_route`, each stride's speed
drawn in a range and the gait following from the speed. The range is the one
given, or with a gait class instead the class's speeds
(:data:`GAIT_SPEEDS_MPS`), so that every stride is of that class. It starts
with a 2 s stand (the alignment of ``pednav run``) and ends with a 1 s stand;
stops (standing 1–5 s at the start of a leg) are on by default.

The simulator model — IMU grade and stance dynamics — defaults to
:data:`DEFAULT_MODEL`. Its walker (:class:`StanceRandomization`) applies in
full with a speed range and with a gait class alike: stance micro-motion and
roll-over, heel rocker and monotone pitch, and the stride shapes of
:func:`pednav_env.gait.speed_route.speed_stride_shape` (cadence law, cycle
shares, swing scale, pitch knots, swing roll).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from pednav_env.files import writing
from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import Gait
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.io.validate import MAX_RATE_HZ, MIN_RATE_HZ
from pednav_env.sensors.imu import IMU_GRADES, simulate_imu

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SimulatorModel:
    """IMU grade (a name in :data:`pednav_env.sensors.imu.IMU_GRADES`) and stance
    dynamics (a factory of :class:`StanceRandomization`, or None for the
    generator's built-in stance terms)."""

    name: str
    imu_grade: str
    stance: Callable[[], StanceRandomization] | None = None


#: The model ``pednav simulate`` uses unless told otherwise: the IMU grade and
#: stance dynamics calibrated to the development recordings (docs/SIM_TO_REAL.md;
#: ``pednav sim2real``'s "calibrated" model).
DEFAULT_MODEL = SimulatorModel("calibrated", "microstrain_gx5", StanceRandomization.calibrated)
#: Gait names accepted by :class:`SimulateConfig` (``--gait``).
GAIT_NAMES = {"slow_walk": Gait.SLOW_WALK, "walk": Gait.WALK, "fast_walk": Gait.FAST_WALK}
GAIT_NAMES["run"] = Gait.RUN
#: Stride speed range (m/s) of each gait class (``--gait``): the speeds, stride length
#: over cycle, that :func:`pednav_env.gait.foot_route.random_route` gives the class
#: (slow walk 0.27–0.67, walk 0.67–1.2, fast walk 1.2–1.65, run 2.0–3.7 m/s), kept
#: inside the class's band of :func:`pednav_env.gait.speed_route.gait_for_speed`
#: (slow walk below 0.75, walk below 1.25, fast walk below 2 m/s, run above).
GAIT_SPEEDS_MPS = {
    "slow_walk": (0.27, 0.67),
    "walk": (0.75, 1.2),
    "fast_walk": (1.25, 1.65),
    "run": (2.0, 3.7),
}
#: Stride speed range (m/s) when neither a speed range nor a gait is given.
DEFAULT_SPEED_MPS = SpeedRouteConfig().speed_mps
#: Longest walk (s): two hours, 1.4 million samples at 200 Hz (a longer one would
#: fill memory before it is written).
MAX_DURATION_S = 7200.0
#: CSV header written by :func:`write_recording_csv`.
CSV_COLUMNS = (
    "time (s)",
    "gyro_x (rad/s)",
    "gyro_y (rad/s)",
    "gyro_z (rad/s)",
    "accel_x (m/s^2)",
    "accel_y (m/s^2)",
    "accel_z (m/s^2)",
    "pos_x (m)",
    "pos_y (m)",
    "pos_z (m)",
    "stance",
    "gait",
)


@dataclass(frozen=True)
class SimulateConfig:
    """One simulated walk.

    Parameters
    ----------
    speed_mps : (lo, hi) m/s, range of every stride's speed (0.1 ≤ lo ≤ hi ≤ 4),
        or None; exclusive with ``gait``. Neither: :data:`DEFAULT_SPEED_MPS`.
    gait : a name of :data:`GAIT_NAMES` or None: one gait class, every stride's
        speed in the class's range (:data:`GAIT_SPEEDS_MPS`).
    duration_s : s, length of the walk (it ends with the last stride that fits),
        5 s to :data:`MAX_DURATION_S`.
    rate_hz : Hz, IMU sample rate, in the range the loaders read
        (:data:`pednav_env.io.validate.MIN_RATE_HZ` … ``MAX_RATE_HZ``, 90–1100 Hz).
    imu_grade : IMU error grade (None: the model's).
    stops : stand still for 1–5 s at the start of some legs (15 %).
    seed : the walk draws only from ``numpy.random.default_rng(seed)``.
    model : grade and stance dynamics (:data:`DEFAULT_MODEL`).
    """

    speed_mps: tuple[float, float] | None = None
    gait: str | None = None
    duration_s: float = 60.0
    rate_hz: float = 200.0
    imu_grade: str | None = None
    stops: bool = True
    seed: int = 0
    model: SimulatorModel = DEFAULT_MODEL

    def __post_init__(self) -> None:
        if self.speed_mps is not None and self.gait is not None:
            raise ValueError("give a speed range or a gait, not both (the gait follows the speed)")
        if self.speed_mps is not None:
            lo, hi = (float(v) for v in self.speed_mps)
            if not (0.1 <= lo <= hi <= 4.0):
                raise ValueError(f"speed range must satisfy 0.1 ≤ LO ≤ HI ≤ 4 m/s, got {lo} {hi}")
            object.__setattr__(self, "speed_mps", (lo, hi))
        if self.gait is not None and self.gait not in GAIT_NAMES:
            raise ValueError(f"unknown gait {self.gait!r}; use one of {', '.join(GAIT_NAMES)}")
        if not (math.isfinite(self.duration_s) and 5.0 <= self.duration_s <= MAX_DURATION_S):
            raise ValueError(
                f"duration must be 5…{MAX_DURATION_S:.0f} s (2 s stand, strides, 1 s stand), "
                f"got {self.duration_s}"
            )
        if not (math.isfinite(self.rate_hz) and MIN_RATE_HZ <= self.rate_hz <= MAX_RATE_HZ):
            raise ValueError(
                f"rate must be in {MIN_RATE_HZ:.0f}…{MAX_RATE_HZ:.0f} Hz (what the loaders "
                f"read back), got {self.rate_hz}"
            )
        grade = self.grade
        if grade not in IMU_GRADES:
            raise ValueError(f"unknown IMU grade {grade!r}; use one of {', '.join(IMU_GRADES)}")

    @property
    def grade(self) -> str:
        return self.imu_grade if self.imu_grade is not None else self.model.imu_grade


@dataclass(frozen=True)
class SimulatedWalk:
    """A simulated recording: ``(T,)`` time, ``(T, 3)`` IMU readings and truth."""

    config: SimulateConfig
    time: Array
    omega_b: Array
    f_b: Array
    pos_n: Array
    stance: NDArray[np.bool_]
    gait: NDArray[np.int8]

    @property
    def distance_m(self) -> float:
        """Horizontal path length of the truth (m)."""
        return float(np.sum(np.linalg.norm(np.diff(self.pos_n[:, :2], axis=0), axis=1)))


def simulate_walk(config: SimulateConfig) -> SimulatedWalk:
    """Simulate the walk of ``config`` (module docstring)."""
    rng = np.random.default_rng(config.seed)
    motion = None if config.model.stance is None else config.model.stance().draw(rng)
    stop = SpeedRouteConfig().stop_probability if config.stops else 0.0
    duration = (config.duration_s, config.duration_s)
    speed = config.speed_mps or DEFAULT_SPEED_MPS
    if config.gait is not None:
        speed = GAIT_SPEEDS_MPS[config.gait]
    cfg = SpeedRouteConfig(
        speed_mps=speed, duration_s=duration, stop_probability=stop, stance_motion=motion
    )
    route = speed_route(rng, cfg)
    truth = simulate_foot(route, FootSimConfig(rate_hz=config.rate_hz))
    imu = simulate_imu(
        truth.omega_b,
        truth.f_b,
        truth.rate_hz,
        IMU_GRADES[config.grade](),
        [rng],
        gait_step_index=truth.gait_step,
    )
    return SimulatedWalk(
        config,
        truth.t[1:],
        imu.omega_b[0],
        imu.f_b[0],
        truth.pos_n[0, 1:],
        truth.stance[0],
        truth.gait[0],
    )


def check_output_path(path: str | Path) -> Path:
    """``path`` as a file to write: ValueError when it is a directory or its directory
    does not exist or is not writable (checked before a walk is simulated, and by
    ``pednav run`` before a run)."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path}: is a directory; give a file name")
    if not path.parent.is_dir():
        raise ValueError(f"{path}: directory {path.parent} does not exist")
    if not os.access(path.parent, os.W_OK):
        raise ValueError(f"{path}: directory {path.parent} not writable")
    return path


def write_recording_csv(walk: SimulatedWalk, path: str | Path) -> Path:
    """Write ``walk`` as a generic CSV recording (module docstring)."""
    path = check_output_path(path)
    data = np.column_stack(
        (walk.time, walk.omega_b, walk.f_b, walk.pos_n, walk.stance.astype(int), walk.gait)
    )
    fmt = ["%.6f"] + ["%.9g"] * 9 + ["%d", "%d"]
    with writing(path):
        np.savetxt(path, data, delimiter=",", header=",".join(CSV_COLUMNS), comments="", fmt=fmt)
    return path
