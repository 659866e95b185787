"""False-stance shares (pednav_env.calibration.false_stance) on a hand-built walk."""

from __future__ import annotations

import numpy as np
import pytest
from labelled_walk import phase_walk

from pednav_env.calibration.false_stance import false_stance
from pednav_env.calibration.stats import SHOE_GYRO_SIGMA, WalkSamples

RATE = 200.0
# (samples, |ω| rad/s, stance, metres moved along x): a 2 s stand, 5 strides whose swing
# has a slow half (0.1 m at |ω| 0.1) and a fast half (0.9 m at |ω| 3), a 2 s stand.
STRIDE = [(60, 0.1, False, 0.1), (60, 3.0, False, 0.9), (80, 0.01, True, 0.0)]
PHASES = [(400, 0.001, True, 0.0)] + STRIDE * 5 + [(400, 0.001, True, 0.0)]


def _walk() -> WalkSamples:
    omega_b, f_b, stance, pos = phase_walk(PHASES)
    return WalkSamples(omega_b, f_b, RATE, "hand", stance, pos)


def test_shares_follow_the_swing_halves() -> None:
    # log10 SHOE is 2·log10(|ω|/σ_ω): 6.1 in the slow half, 9.1 in the fast half, 4.1 in stance
    slow, fast = (2 * np.log10(w / SHOE_GYRO_SIGMA) for w in (0.1, 3.0))
    assert slow < 7.5 < fast < 9.5
    out = false_stance(_walk(), [5.0, 7.5, 9.5])
    assert out["stance_source"] == "labels"
    # walking part: 5 swings and 4 stances (the last stance runs into the stand)
    assert out["nonstance_share"] == pytest.approx(600 / 920, abs=0.01)
    # window edges blur a few samples per transition
    assert out["below"] == pytest.approx([0.0, 0.5, 1.0], abs=0.04)
    assert out["below_quiet_free"] == pytest.approx([0.0, 0.5, 1.0], abs=0.04)
    # the slow half carries 0.1 m of the swing's 1 m
    assert out["speed_weighted"] == pytest.approx([0.0, 0.1, 1.0], abs=0.04)
    assert out["swing_speed_mps"] == pytest.approx(1.0 / 0.6, rel=0.05)


def test_no_truth_no_speed_weighting() -> None:
    w = _walk()
    bare = WalkSamples(w.omega_b, w.f_b, RATE, "bare", w.stance)
    out = false_stance(bare, [7.5])
    assert out["speed_weighted"] == [None] and out["swing_speed_mps"] is None
    assert out["below"] == pytest.approx([0.5], abs=0.04)
