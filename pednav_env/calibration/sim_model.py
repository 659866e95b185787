"""The simulator model of the sim-to-real comparisons (:class:`SimModel`): an IMU grade
and a walker population, and the simulated walks it draws, at a speed band
(:meth:`SimModel.batch`, :meth:`SimModel.simulate`) or along a given stride sequence
(:meth:`SimModel.footfall_batch`). Used by :mod:`pednav_env.calibration.compare`, the
fit's objective and the error level of ``pednav sim2real --nav``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pednav_env.calibration.sources import samples_from_simulation
from pednav_env.calibration.stats import WalkStats, walk_stats
from pednav_env.gait.foot import FootSimConfig, FootTrajectory, simulate_foot
from pednav_env.gait.foot_route import Route
from pednav_env.gait.speed_route import SpeedRouteConfig, footfall_route, speed_route
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.sensors.imu import IMU_GRADES, ImuMeasurements, simulate_imu

#: Fastest simulated speed (m/s), the top of the open band.
SIM_TOP_SPEED_MPS = 3.8
#: Simulated walks are this long (s) before their stands, at this rate (Hz).
SIM_DURATION_S = (30.0, 60.0)
SIM_RATE_HZ = 200.0


def walk_entropy(seed: int | Sequence[int], walk: int) -> list[int]:
    """The entropy list walk ``walk`` of a batch seeded with ``seed`` draws from
    (``numpy.random.default_rng(walk_entropy(seed, walk))``): ``[seed, walk]`` for an
    integer seed, ``[*seed, walk]`` for a sequence of non-negative integers (e.g. a
    seed and a recording's key, as ``pednav sim2real --nav``'s twins draw)."""
    if isinstance(seed, (int, np.integer)):
        return [int(seed), walk]
    return [*(int(s) for s in seed), walk]


@dataclass(frozen=True)
class SimModel:
    """A simulator configuration: IMU grade and stance dynamics.

    ``stance`` None: today's realistic stance terms (roll-over A = 0.011 v²,
    micro-motion 0.2 v² mm at mid-stance; :mod:`pednav_env.gait.foot`).
    """

    name: str
    imu_grade: str
    stance: StanceRandomization | None = None

    def __post_init__(self) -> None:
        if self.imu_grade not in IMU_GRADES:
            raise ValueError(f"unknown IMU grade {self.imu_grade!r}; known: {sorted(IMU_GRADES)}")

    def batch(
        self,
        speed_mps: tuple[float, float],
        walks: int,
        seed: int | Sequence[int],
        duration_s: tuple[float, float] = SIM_DURATION_S,
        turn_per_stride_rad: tuple[float, float] | None = None,
        turns_per_walk: Sequence[tuple[float, float] | None] | None = None,
    ) -> tuple[FootTrajectory, ImuMeasurements]:
        """``walks`` simulated walks with every stride's speed in ``speed_mps``,
        ``duration_s`` long, truth and IMU readings; walk i draws from
        ``default_rng([seed, i])`` (its walker, route and IMU errors;
        ``[*seed, i]`` for a sequence, :func:`walk_entropy`). With
        ``turn_per_stride_rad`` every leg walks a circle
        (:class:`pednav_env.gait.speed_route.SpeedRouteConfig`); ``turns_per_walk``
        (``walks`` entries) gives walk i its own, None for the scenario's legs; giving
        both is a ``ValueError``."""
        if turns_per_walk is not None and turn_per_stride_rad is not None:
            raise ValueError("give turn_per_stride_rad or turns_per_walk, not both")
        if turns_per_walk is not None and len(turns_per_walk) != walks:
            raise ValueError(
                f"turns_per_walk must have one entry per walk ({walks}), got {len(turns_per_walk)}"
            )
        rngs = [np.random.default_rng(walk_entropy(seed, i)) for i in range(walks)]
        routes = []
        for i, rng in enumerate(rngs):
            motion = None if self.stance is None else self.stance.draw(rng)
            turn = turn_per_stride_rad if turns_per_walk is None else turns_per_walk[i]
            cfg = SpeedRouteConfig(
                speed_mps=speed_mps,
                duration_s=duration_s,
                stance_motion=motion,
                turn_per_stride_rad=turn,
            )
            routes.append(speed_route(rng, cfg))
        return self._walk(routes, rngs)

    def footfall_batch(
        self,
        speed_mps: Sequence[float],
        turn_rad: Sequence[float],
        stop_s: Sequence[float],
        walks: int,
        seed: int | Sequence[int],
    ) -> tuple[FootTrajectory, ImuMeasurements]:
        """``walks`` simulated walks of one stride sequence
        (:func:`pednav_env.gait.speed_route.footfall_route`: stride i at ``speed_mps[i]``,
        turning by ``turn_rad[i]`` after a stand of ``stop_s[i]`` s); walk i draws its
        walker, stride shapes and IMU errors from ``default_rng([seed, i])``
        (``[*seed, i]`` for a sequence, :func:`walk_entropy`)."""
        rngs = [np.random.default_rng(walk_entropy(seed, i)) for i in range(walks)]
        routes = []
        for rng in rngs:
            motion = None if self.stance is None else self.stance.draw(rng)
            routes.append(footfall_route(rng, speed_mps, turn_rad, stop_s, motion))
        return self._walk(routes, rngs)

    def _walk(
        self, routes: Sequence[Route], rngs: Sequence[np.random.Generator]
    ) -> tuple[FootTrajectory, ImuMeasurements]:
        truth = simulate_foot(list(routes), FootSimConfig(rate_hz=SIM_RATE_HZ), full_state=False)
        spec = IMU_GRADES[self.imu_grade]()
        imu = simulate_imu(
            truth.omega_b, truth.f_b, SIM_RATE_HZ, spec, list(rngs), gait_step_index=truth.gait_step
        )
        return truth, imu

    def simulate(
        self,
        band: tuple[float, float],
        walks: int,
        seed: int,
        duration_s: tuple[float, float] = SIM_DURATION_S,
        per_stride: bool = True,
        turns_per_walk: Sequence[tuple[float, float] | None] | None = None,
    ) -> list[WalkStats]:
        """The statistics of :meth:`batch`'s walks at the band's speeds (the open band
        up to :data:`SIM_TOP_SPEED_MPS`). ``per_stride`` as in
        :func:`pednav_env.calibration.stats.walk_stats`; ``turns_per_walk`` as in
        :meth:`batch`."""
        lo, hi = band
        truth, imu = self.batch(
            (lo, min(hi, SIM_TOP_SPEED_MPS)), walks, seed, duration_s, None, turns_per_walk
        )
        return [
            walk_stats(samples_from_simulation(truth, imu, i, f"{self.name}{i}"), per_stride)
            for i in range(walks)
        ]
