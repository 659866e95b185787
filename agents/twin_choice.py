"""Choose a walk's SHOE threshold on simulated twins of the walk itself, from its IMU
alone (docs/SIM_TO_REAL.md, "A threshold chosen on the walk's own twins").

No truth and no footprints enter the choice:

1. **The route from the IMU.** The recording is filtered with a route setup
   (default ``real-fixed``, :func:`pednav_env.replay.setup.real_fixed_setup`) through
   ``pednav run``'s runner. The filter's own detected stance and its position track
   take the place of stance labels and a truth track in
   :func:`pednav_env.calibration.path_turns.stride_sequence`: per stride the speed
   between its footfalls, its heading change and the stand before it.
2. **Twins.** ``walks`` simulated walks of that stride sequence
   (:func:`agents.error_level.footfall_twin_recordings`, the shipped calibrated model by
   default), each with its own walker, stride shapes and IMU errors.
3. **The choice.** ``setup`` with each threshold of ``thresholds`` on every twin
   (:func:`agents.choose_shoe.threshold_sweep`); per threshold the twins' median error
   (PyShoe's ARMSE against the twins' truth, or their mean footprint error with
   ``twin_metric="footprints"``; a diverged twin counts as infinite). The chosen γ
   minimises it (the first on ties).

The default grid is 10^7.125 … 10^9.125 in quarter decades, the grid of
``benchmarks/gamma_response.py``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from agents.choose_shoe import threshold_knobs, threshold_sweep
from agents.error_level import MIN_TWIN_STRIDES, footfall_twin_recordings
from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.path_turns import StrideSequence, stride_sequence
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.stats import WalkSamples
from pednav_env.io import Recording
from pednav_env.nav.detectors import ShoeDetectorConfig
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import RealFilterSetup, real_fixed_setup

Array = NDArray[np.float64]

#: SHOE thresholds γ tried (PyShoe's units): 10^7.125 … 10^9.125, quarter decades.
TWIN_THRESHOLDS: tuple[float, ...] = tuple(float(v) for v in 10.0 ** np.arange(7.125, 9.2, 0.25))
#: Simulated twins per recording.
TWIN_WALKS = 20
TwinMetric = Literal["armse", "footprints"]


@dataclass(frozen=True)
class TwinThresholdChoice:
    """The result of :func:`choose_threshold_on_twins`.

    ``threshold`` the chosen γ; ``thresholds`` the grid; ``twin_median_m`` per
    threshold the twins' median error (m, inf where more than half diverged);
    ``strides`` the route the twins walked (from the IMU); ``setup`` the scoring setup
    with the chosen γ.
    """

    threshold: float
    thresholds: tuple[float, ...]
    twin_median_m: Array
    strides: StrideSequence
    setup: RealFilterSetup


def with_threshold(setup: RealFilterSetup, threshold: float) -> RealFilterSetup:
    """``setup`` with its SHOE threshold γ replaced (``ValueError`` for another
    detector or a threshold that is not positive and finite)."""
    if not isinstance(setup.filter.detector, ShoeDetectorConfig):
        raise ValueError("with_threshold needs a SHOE detector setup")
    if not (np.isfinite(threshold) and threshold > 0):
        raise ValueError(f"threshold must be positive and finite, got {threshold}")
    detector = replace(setup.filter.detector, threshold=float(threshold))
    return replace(setup, filter=replace(setup.filter, detector=detector))


def imu_stride_sequence(recording: Recording, route_setup: RealFilterSetup) -> StrideSequence:
    """The recording's strides as ``route_setup``'s filter sees them: its detected
    stance as stance labels and its position track (from the end of the alignment)
    as the track, through :func:`stride_sequence`. Uses the IMU only."""
    return imu_stride_sequences(recording, route_setup)[0]


def imu_stride_sequences(
    recording: Recording, route_setup: RealFilterSetup, thresholds: Sequence[float] = ()
) -> list[StrideSequence]:
    """:func:`imu_stride_sequence` for ``route_setup`` with each SHOE threshold of
    ``thresholds`` (one filter run, a lane per threshold;
    :func:`agents.choose_shoe.threshold_knobs`), or for ``route_setup`` itself when
    ``thresholds`` is empty."""
    prep = prepare(recording, route_setup)
    knobs = threshold_knobs(route_setup, thresholds) if len(thresholds) else None
    run = run_prepared(prep, max(1, len(thresholds)), knobs=knobs)
    start = prep.n_align
    out = []
    for lane in range(run.pos.shape[0]):
        track = np.array(run.pos[lane, start:], dtype=float)
        track[~np.all(np.isfinite(track), axis=1)] = np.nan
        samples = WalkSamples(
            omega_b=prep.omega_b[start:],
            f_b=prep.f_b[start:],
            rate_hz=prep.rate_hz,
            name=recording.name,
            stance=np.asarray(run.stance[lane, start:], dtype=bool),
            truth_pos=track,
            g=prep.g,
        )
        out.append(stride_sequence(samples))
    return out


def choose_threshold_on_twins(
    recording: Recording,
    seed: int,
    *,
    setup: RealFilterSetup | None = None,
    route_setup: RealFilterSetup | None = None,
    model: SimModel | None = None,
    thresholds: Sequence[float] = TWIN_THRESHOLDS,
    walks: int = TWIN_WALKS,
    twin_metric: TwinMetric = "armse",
    strides: StrideSequence | None = None,
) -> TwinThresholdChoice:
    """The SHOE threshold for ``recording`` chosen on ``walks`` twins of its own
    IMU-estimated strides (module docstring); twin i draws from
    ``numpy.random.default_rng([seed, i])``. ``setup`` (default ``real-fixed``) gives
    the other knobs, ``route_setup`` (default ``setup``) the route, ``model`` the
    simulator (default the shipped calibrated model). ``strides`` replaces the route
    from the IMU (e.g. a route from footprints,
    :func:`pednav_env.calibration.path_turns.stride_sequence`); ``route_setup`` is then
    not used.

    Raises
    ------
    ValueError
        ``walks`` < 1, an empty or non-positive grid, an unknown ``twin_metric``, a
        recording with fewer than :data:`agents.error_level.MIN_TWIN_STRIDES` strides
        as the filter sees them, or a grid on which every threshold's median diverged.
    """
    if walks < 1:
        raise ValueError(f"walks must be at least 1, got {walks}")
    grid = tuple(float(v) for v in thresholds)
    if not grid or not all(np.isfinite(v) and v > 0 for v in grid):
        raise ValueError(f"thresholds must be positive and finite, got {thresholds}")
    if twin_metric not in ("armse", "footprints"):
        raise ValueError(f"twin_metric must be 'armse' or 'footprints', got {twin_metric!r}")
    setup = real_fixed_setup() if setup is None else setup
    route_setup = setup if route_setup is None else route_setup
    model = MODELS["calibrated"] if model is None else model
    if strides is None:
        strides = imu_stride_sequence(recording, route_setup)
    if strides.speed_mps.size < MIN_TWIN_STRIDES:
        raise ValueError(
            f"{recording.name}: {strides.speed_mps.size} strides in its route; "
            f"twins need at least {MIN_TWIN_STRIDES}"
        )
    twins = footfall_twin_recordings(
        model, walks, seed, strides, footprints=twin_metric == "footprints"
    )
    median = np.median(threshold_sweep(setup, twins, grid), axis=0)
    if not np.any(np.isfinite(median)):
        raise ValueError(f"{recording.name}: the twins diverged at every threshold tried")
    best = int(np.argmin(median))
    return TwinThresholdChoice(grid[best], grid, median, strides, with_threshold(setup, grid[best]))
