"""Episodes of ``pednav/MarkerTrack-v0``: a walk and its UWB record per lane.

:func:`generate_episode` draws one lane's episode from its generator: the
scenario's walk of the heel–knee truth simulator
(:func:`~pednav_env.gait.heel_knee.simulate_heel_knee`) seen by the UWB
sensor model of the episode's condition
(:func:`~pednav_env.sensors.uwb.measure_uwb`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.envs.marker_config import MarkerTrackConfig, uwb_spec
from pednav_env.gait.heel_knee import HeelKneeConfig, simulate_heel_knee
from pednav_env.nav.marker_model import DIM_Z
from pednav_env.sensors.uwb import UwbSpec, measure_uwb

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass
class Episode:
    """One lane's walk: UWB record and the truth used for reward and info."""

    z: Array  # (K, 4) reports [heel x, heel z, knee x, knee z] (m)
    valid: BoolArray  # (K, 2) per marker
    truth: Array  # (K, 4) true positions (m)
    uwb_condition: str
    uwb_noise_factor: float = 1.0  #: factor on the condition's UWB σ (1)


@functools.lru_cache(maxsize=16)
def _condition_cdf(weights: tuple[float, ...]) -> Array:
    """Cumulative UWB condition weights, normalised (computed once per weights)."""
    return np.cumsum(weights) / np.sum(weights)


def generate_episode(
    config: MarkerTrackConfig, rng: np.random.Generator, gait: HeelKneeConfig | None = None
) -> Episode:
    """Draw one episode from ``rng``.

    Draw order (random scenario): duration, UWB condition (one uniform against
    the cumulative weights), σ factor, the walk
    (:func:`simulate_heel_knee`), the UWB errors
    (:func:`~pednav_env.sensors.uwb.measure_uwb`).
    Paper scenario: the walk and the UWB noise only. ``gait`` may pass
    ``config.truth_gait`` precomputed.
    """
    gait = gait or config.truth_gait
    rate = config.rate_hz
    if config.scenario == "paper":
        k = round(config.paper_duration_s * rate)
        condition = "paper"
        spec = UwbSpec.paper(rate)
        noise_factor = 1.0
    else:
        k = max(2, round(rng.uniform(*config.duration_s) * rate))
        cdf = _condition_cdf(tuple(config.uwb_condition_weights))
        pick = min(int(np.searchsorted(cdf, rng.random(), side="right")), len(cdf) - 1)
        condition = config.uwb_conditions[pick]
        noise_factor = float(rng.uniform(*config.noise_factor_range))
        spec = uwb_spec(condition, rate, noise_factor)
    walk = simulate_heel_knee(gait, k, [rng])
    markers = walk.markers[0]
    uwb = measure_uwb(spec, markers[None], [rng])
    return Episode(
        uwb.z[0].reshape(k, DIM_Z), uwb.valid[0], markers.reshape(k, DIM_Z), condition, noise_factor
    )
