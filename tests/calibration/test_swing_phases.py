"""calibration.swing_phases on hand-built walks: phases, speeds, rates and the
fast-and-still share per bin, the swings left out, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from labelled_walk import phase_walk

from pednav_env.calibration.stats import WalkSamples
from pednav_env.calibration.swing_phases import fast_below, swing_phase_profile, swing_samples

RATE = 200.0
#: stance 0.5 s; a 0.5 s swing: 50 samples turning at 3 rad/s over 1 m (4 m/s), then
#: 50 samples turning at 0.5 rad/s over 0.5 m (2 m/s); stance; a 0.1 s flicker of swing
#: (too short to be a swing); stance.
PHASES = [
    (100, 0.0, True, 0.0),
    (50, 3.0, False, 1.0),
    (50, 0.5, False, 0.5),
    (100, 0.0, True, 0.0),
    (20, 2.0, False, 0.2),
    (100, 0.0, True, 0.0),
]


def walk(truth: bool = True, labels: bool = True) -> WalkSamples:
    omega_b, f_b, stance, pos = phase_walk(PHASES)
    return WalkSamples(
        omega_b,
        f_b,
        RATE,
        "hand",
        stance=stance if labels else None,
        truth_pos=pos if truth else None,
    )


def test_one_swing_at_its_phases():
    phase, speed, rate, sagittal, _ = swing_samples(walk())
    assert phase.size == 100  # the 0.1 s flicker is not a swing
    assert phase[0] == pytest.approx(0.005) and phase[-1] == pytest.approx(0.995)
    assert rate[:50].tolist() == [3.0] * 50 and rate[50:].tolist() == [0.5] * 50
    # ω about x only: the sagittal axis; signed positive over the middle (+3 then +0.5)
    np.testing.assert_allclose(sagittal, rate)
    assert np.median(speed[5:45]) == pytest.approx(4.0)
    assert np.median(speed[55:95]) == pytest.approx(2.0)


def test_profile_per_bin():
    p = swing_phase_profile([walk(), walk()], bins=10)
    assert p["swing_samples"] == 200
    assert p["samples"] == [20] * 10
    assert p["fast_still_share"] == [0.0] * 5 + [1.0] * 5
    assert p["rate_median_rad_s"] == [3.0] * 5 + [0.5] * 5
    assert p["sagittal_rate_median_rad_s"] == pytest.approx([3.0] * 5 + [0.5] * 5)
    assert p["off_sagittal_rate_median_rad_s"] == pytest.approx([0.0] * 10, abs=1e-9)
    assert p["speed_median_mps"][2] == pytest.approx(4.0)
    assert p["speed_median_mps"][7] == pytest.approx(2.0)
    two = swing_phase_profile([walk()], bins=2)
    assert two["fast_still_share"] == [0.0, 1.0]
    assert two["bin_edges"] == [0.0, 0.5, 1.0]


def test_refusals():
    with pytest.raises(ValueError, match="hand: swing phases need truth positions"):
        swing_samples(walk(truth=False))
    sparse = walk(labels=False)
    sparse.truth_pos[::5] = np.nan  # a fifth of the reference missing: no truth stance
    with pytest.raises(ValueError, match="hand: swing phases need stance labels or truth"):
        swing_samples(sparse)
    with pytest.raises(ValueError, match="bins must be"):
        swing_phase_profile([walk()], bins=0)


def test_the_sagittal_rate_is_signed_by_the_middle_of_the_swing():
    # the same walk turning the other way about x, and a steady 0.1 rad/s about y: the
    # principal direction is still x, and its sign makes the middle of the swing positive
    omega_b, f_b, stance, pos = phase_walk(PHASES)
    omega_b[:, 0] *= -1.0
    omega_b[:, 1] = 0.1
    w = WalkSamples(omega_b, f_b, RATE, "flipped", stance=stance, truth_pos=pos)
    _, _, rate, sagittal, _ = swing_samples(w)
    np.testing.assert_allclose(sagittal, [3.0] * 50 + [0.5] * 50)
    # what is left is the turning about y: 0.1 rad/s
    np.testing.assert_allclose(np.sqrt(rate**2 - sagittal**2), 0.1, atol=1e-9)


def test_fast_swing_samples_below_a_threshold():
    # the fast samples (4 m/s turning at 3 rad/s, 2 m/s at 0.5 rad/s): with |f| = g the
    # SHOE statistic is ω²/σ_ω² (PyShoe's σ_ω = 8.7266e-5 rad/s), 10^9.07 and 10^7.52
    shoe_fast, shoe_slow = (3.0 / 8.7266463e-5) ** 2, (0.5 / 8.7266463e-5) ** 2
    lo, mid, hi = 0.5 * shoe_slow, 0.5 * (shoe_slow + shoe_fast), 2 * shoe_fast
    # the samples next to the swing's ends are slower than 1 m/s or mixed: count them
    every = swing_samples(walk())
    fast = every.speed_mps > 1.0
    share_slow = float(np.mean(every.rate_rad_s[fast] == 0.5))
    assert fast_below([walk()], [lo, mid, hi]) == pytest.approx([0.0, share_slow, 1.0])
    assert 0.4 < share_slow < 0.6
