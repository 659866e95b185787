"""agents.twin_choice: the route from the IMU, the threshold chosen on a walk's own
twins, and its bad-input errors."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from agents.error_level import footfall_twin_recordings
from agents.twin_choice import (
    TWIN_THRESHOLDS,
    choose_threshold_on_twins,
    imu_stride_sequence,
    with_threshold,
)
from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.path_turns import StrideSequence
from pednav_env.nav.detectors import ShoeDetectorConfig
from pednav_env.replay.setup import real_fixed_setup


def simulated_walk(speed_mps: float, strides: int, seed: int):
    """One simulated recording (truth kept) walking ``strides`` strides at
    ``speed_mps`` on a gentle curve, with a stand of 1 s before the first."""
    route = StrideSequence(
        np.full(strides, speed_mps), np.full(strides, 0.05), np.r_[1.0, np.zeros(strides - 1)]
    )
    return footfall_twin_recordings(MODELS["calibrated"], 1, seed, route, footprints=False)[0]


def test_with_threshold():
    setup = real_fixed_setup()
    out = with_threshold(setup, 3.0e8)
    assert out.filter.detector.threshold == 3.0e8
    assert out.filter.process_noise_scale == setup.filter.process_noise_scale
    assert setup.filter.detector.threshold != 3.0e8  # the original is untouched
    for bad in (0.0, -1.0, np.inf, np.nan):
        with pytest.raises(ValueError, match="threshold"):
            with_threshold(setup, bad)
    not_shoe = replace(setup, filter=replace(setup.filter, detector=object()))
    with pytest.raises(ValueError, match="SHOE"):
        with_threshold(not_shoe, 1.0e8)


def test_the_grid_is_quarter_decades():
    assert len(TWIN_THRESHOLDS) == 9
    assert TWIN_THRESHOLDS[0] == pytest.approx(10**7.125)
    assert TWIN_THRESHOLDS[-1] == pytest.approx(10**9.125)
    assert np.allclose(np.diff(np.log10(TWIN_THRESHOLDS)), 0.25)


@pytest.mark.parametrize("speed_mps", [0.6, 0.8])
def test_the_imu_route_walks_the_walks_strides(speed_mps: float):
    """Walking speeds at which ``real-fixed``'s detector sees the simulated stances."""
    rec = simulated_walk(speed_mps, 24, seed=3)
    strides = imu_stride_sequence(rec, real_fixed_setup())
    # a footfall the detector splits or misses joins two strides: fewer strides, the
    # same speed (length and time both add up)
    assert 8 <= strides.speed_mps.size <= 25
    assert np.median(strides.speed_mps) == pytest.approx(speed_mps, rel=0.15)
    assert np.median(np.abs(strides.turn_rad[1:])) < 0.2  # a gentle curve, no corners


def test_a_filter_that_misses_stances_overestimates_the_route():
    """At 2.8 m/s ``real-fixed`` misses the simulated running stances; at 10^9 it
    sees them but calls part of the swing stance and shortens every stride."""
    rec = simulated_walk(2.8, 24, seed=3)
    assert imu_stride_sequence(rec, real_fixed_setup()).speed_mps.size < 3
    high = imu_stride_sequence(rec, with_threshold(real_fixed_setup(), 1.0e9))
    assert high.speed_mps.size >= 20
    assert np.median(high.speed_mps) < 0.5 * 2.8


def test_running_twins_choose_a_higher_threshold_than_slow_ones():
    """The simulator's running stance is loud (docs/SIM_TO_REAL.md): a threshold
    that misses running stances fails, so running twins choose a higher γ."""
    grid = (1.0e7, 1.0e8, 1.0e9)
    rec = simulated_walk(1.0, 4, seed=5)
    routes = [StrideSequence(np.full(20, v), np.zeros(20), np.zeros(20)) for v in (0.6, 2.8)]
    slow, fast = (
        choose_threshold_on_twins(rec, 0, thresholds=grid, walks=3, strides=route)
        for route in routes
    )
    assert fast.threshold > slow.threshold
    for choice in (slow, fast):
        assert choice.twin_median_m.shape == (3,)
        assert choice.threshold == grid[int(np.argmin(choice.twin_median_m))]
        assert choice.setup.filter.detector.threshold == choice.threshold
        assert isinstance(choice.setup.filter.detector, ShoeDetectorConfig)


def test_bad_input():
    rec = simulated_walk(1.0, 6, seed=1)
    with pytest.raises(ValueError, match="walks"):
        choose_threshold_on_twins(rec, 0, walks=0)
    with pytest.raises(ValueError, match="thresholds"):
        choose_threshold_on_twins(rec, 0, thresholds=())
    with pytest.raises(ValueError, match="thresholds"):
        choose_threshold_on_twins(rec, 0, thresholds=(1.0e8, -1.0))
    with pytest.raises(ValueError, match="twin_metric"):
        choose_threshold_on_twins(rec, 0, twin_metric="median")  # type: ignore[arg-type]
    short = simulated_walk(1.0, 2, seed=1)
    with pytest.raises(ValueError, match="strides"):
        choose_threshold_on_twins(short, 0, walks=1)
    two = StrideSequence(np.ones(2), np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="strides"):
        choose_threshold_on_twins(rec, 0, walks=1, strides=two)
