"""Recorded strides and the cadence law fitted to them (calibration.cadence), and the
fit's fixed values (calibration.parameters.randomization)."""

from __future__ import annotations

import numpy as np
import pytest
from labelled_walk import labelled_walk

from pednav_env.calibration.cadence import RecordedStrides, fit_cadence_law, recorded_strides
from pednav_env.calibration.parameters import START, randomization
from pednav_env.calibration.stats import WalkSamples

RATE = 100.0


def _walk(stances: list[tuple[float, float]], positions: list[float]) -> WalkSamples:
    return labelled_walk(stances, positions, RATE)


def test_strides_merge_a_stance_split_by_a_gap_without_movement() -> None:
    # stances every 1.2 s, the foot moving 1 m between them; the second stance split
    # by a 0.08 s gap (long enough to survive the 0.05 s label cleaning) in which
    # the foot stays put: that is still one stance, one footfall
    stances = [(0.0, 0.5), (1.2, 1.4), (1.48, 1.7), (2.4, 2.9), (3.6, 4.1)]
    positions = [0.0, 1.0, 1.0, 2.0, 3.0]
    strides = recorded_strides(_walk(stances, positions))
    np.testing.assert_allclose(strides.start_s, [0.0, 1.2, 2.4])
    np.testing.assert_allclose(strides.cycle_s, [1.2, 1.2, 1.2])
    np.testing.assert_allclose(strides.speed_mps, [1 / 1.2] * 3)


def test_strides_drop_stands_long_cycles_and_shuffles() -> None:
    # a 1.5 s stand, then a 3.5 s gap (not a stride), then a 0.05 m shuffle
    stances = [(0.0, 0.4), (1.0, 2.5), (3.1, 3.5), (7.0, 7.4), (8.0, 8.4), (9.0, 9.4)]
    positions = [0.0, 0.8, 1.6, 2.4, 2.45, 3.25]
    strides = recorded_strides(_walk(stances, positions))
    # kept: 0 → 1.0 (it ends where the stand starts), 8.0 → 9.0; dropped: 1.0 → 3.1
    # (the stand), 3.1 → 7.0 (3.9 s), 7.0 → 8.0 (0.05 m in 1 s, below 0.1 m/s)
    np.testing.assert_allclose(strides.start_s, [0.0, 8.0])
    np.testing.assert_allclose(strides.speed_mps, [0.8, 0.8])


def test_strides_from_footprints() -> None:
    idx = np.array([10, 130, 240, 360])
    prints = np.array([[0.0, 0.0], [1.2, 0.0], [2.4, 0.0], [3.0, 0.8]])
    still = np.zeros((400, 3))
    walk = WalkSamples(still, still, RATE, "fp", footfall_index=idx, footprints_m=prints)
    strides = recorded_strides(walk)
    np.testing.assert_allclose(strides.cycle_s, [1.2, 1.1, 1.2])
    np.testing.assert_allclose(strides.speed_mps, [1.0, 1.2 / 1.1, 1.0 / 1.2])
    with pytest.raises(ValueError, match="nolabels: strides need footprints"):
        recorded_strides(WalkSamples(still, still, RATE, "nolabels"))


def test_the_law_is_recovered_from_strides_that_follow_it() -> None:
    # three walkers on f = 0.6 + 0.25 v at 0.3–1.8 m/s, two of them 10^±0.04 off it
    # (their mean scale 1.003); one walker has many more strides, which must not pull
    # the law (each walker weighs the same: unweighted, the law would sit 4 % low)
    walks = []
    for offset, n in ((0.0, 40), (0.04, 10), (-0.04, 400)):
        v = np.linspace(0.3, 1.8, n)
        f = (0.6 + 0.25 * v) * 10**offset
        walks.append(RecordedStrides(f"w{offset}", np.arange(n, dtype=float), 1 / f, v))
    law = fit_cadence_law(walks)
    assert law.intercept_hz == pytest.approx(0.6, abs=0.01)
    assert law.slope_hz_per_mps == pytest.approx(0.25, abs=0.01)
    assert law.log10_std == pytest.approx(np.std([0.0, 0.04, -0.04]), abs=0.004)
    assert (law.recordings, law.strides) == (3, 450)
    assert law.frequency_hz(1.0) == pytest.approx(law.intercept_hz + law.slope_hz_per_mps)


def test_the_law_needs_two_walks_and_two_speeds() -> None:
    one = RecordedStrides("a", np.zeros(3), np.ones(3), np.ones(3))
    with pytest.raises(ValueError, match="needs ≥ 2 walks"):
        fit_cadence_law([one])
    with pytest.raises(ValueError, match="one speed"):
        fit_cadence_law([one, one])


def test_fixed_values_enter_the_fits_randomization() -> None:
    law = {"cadence_intercept_hz": 0.7, "cadence_slope_hz_per_mps": 0.13, "cadence_log10_std": 0.05}
    with_law = randomization(START, law)
    assert (with_law.cadence_intercept_hz, with_law.cadence_log10_std) == (0.7, 0.05)
    assert randomization(START).cadence_intercept_hz is None
    with pytest.raises(ValueError, match="cadence_log10_std"):
        randomization(START, {**law, "cadence_log10_std": 0.9})
