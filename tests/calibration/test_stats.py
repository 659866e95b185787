"""Walk statistics (pednav_env.calibration.stats) against hand-computed walks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from labelled_walk import phase_walk
from testdata import HALLWAY_DATA, PYSHOE_SAMPLE

from pednav_env.calibration.sources import distinct_walks, load_walk
from pednav_env.calibration.stats import (
    SHOE_ACCEL_SIGMA,
    SHOE_GYRO_SIGMA,
    SpeedSource,
    StanceSource,
    StrideStats,
    WalkSamples,
    clean_labels,
    log10_shoe,
    runs,
    walk_stats,
)
from pednav_env.calibration.strides import merge_split_stances
from pednav_env.constants import STANDARD_GRAVITY

RATE = 200.0
STAND, SWING, STANCE, STRIDES = 400, 120, 80, 5
W_STANCE, W_SWING, W_STAND = 0.1, 3.0, 0.001  # |ω| (rad/s) in each phase
HALLWAY_SAMPLE = HALLWAY_DATA / "SensorConnectData_31_first9s_LLIO.mat"


def _hand_walk() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A 2 s stand, 5 strides (0.6 s swing moving 1 m along x, 0.4 s stance), the last
    stance running into a 2 s stand. |f| = g throughout; ω about x."""
    phases = [(STAND, W_STAND, True, 0.0)]
    for _ in range(STRIDES):
        phases += [(SWING, W_SWING, False, 1.0), (STANCE, W_STANCE, True, 0.0)]
    phases.append((STAND, W_STAND, True, 0.0))
    return phase_walk(phases)


def test_log10_shoe_of_a_constant_rotation_is_the_gyro_term() -> None:
    # SHOE = (1/W) Σ |f − g f̄/|f̄||²/σ_a² + |ω|²/σ_ω²; f = (0, 0, g) makes the first
    # term 0, so log10 SHOE = 2 log10(|ω|/σ_ω) once the window is full.
    omega = np.tile([0.0, 0.3, 0.4], (20, 1))  # |ω| = 0.5
    f = np.tile([0.0, 0.0, STANDARD_GRAVITY], (20, 1))
    got = log10_shoe(omega, f, RATE)
    assert got[5:] == pytest.approx(2 * math.log10(0.5 / SHOE_GYRO_SIGMA), abs=1e-9)


def test_log10_shoe_accel_term_uses_pyshoe_sigma() -> None:
    # f alternating between (0, 0, g ± a): the window mean points along z, so the
    # reference g f̄/|f̄| is (0, 0, g) and every sample is off by a: a²/σ_a² (ω = 0).
    a = 0.05
    f = np.zeros((40, 3))
    f[:, 2] = STANDARD_GRAVITY + a * np.where(np.arange(40) % 2 == 0, 1.0, -1.0)
    got = log10_shoe(np.zeros((40, 3)), f, RATE)
    # (a deviation from the window mean instead would give a²(1 − 1/25): 0.018
    # decades lower); 1e-9 is float round-off
    expected = math.log10(a * a / SHOE_ACCEL_SIGMA**2)
    assert got[10:] == pytest.approx(expected, abs=1e-9)


def test_walk_stats_from_labels_hand_computed() -> None:
    omega_b, f_b, stance, pos = _hand_walk()
    s = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos))
    assert s.stance_source is StanceSource.LABELS
    assert s.speed_source is SpeedSource.TRUTH
    # stands: the first 2 s and the last stance + 2 s; walking 5 swings + 4 stances
    walking = STRIDES * SWING + (STRIDES - 1) * STANCE
    assert s.walking_s == pytest.approx(walking / RATE)
    assert s.standing_s == pytest.approx((2 * STAND + STANCE) / RATE)
    # 5 m in the walking part (the first step out of the stand is a stand step: the
    # path counts steps with both samples walking, 1 swing step of 1/120 m less)
    assert s.speed_mps == pytest.approx((STRIDES - 1 / SWING) / (walking / RATE))
    # p10: 304 pure-stance samples (4 per stance mix swing into the window) of 920
    assert s.log_shoe_p10 == pytest.approx(2 * math.log10(W_STANCE / SHOE_GYRO_SIGMA), abs=1e-9)
    # p50: beyond the 336 stance and mixed samples, a pure swing sample
    assert s.log_shoe_p50 == pytest.approx(2 * math.log10(W_SWING / SHOE_GYRO_SIGMA), abs=1e-9)
    st = s.strides
    # strides between stance starts; the one leaving the first stand is dropped
    assert_hand_walk_strides(st)
    assert st.stance_accel_dev_median == pytest.approx(np.zeros(4), abs=1e-12)
    # a stride (stance start to stance start: 80 stance then 120 swing samples) holds
    # at least 76 pure-stance samples, 38 % of it: its 5th percentile is stance's
    assert st.log_shoe_p5 == pytest.approx(
        np.full(4, 2 * math.log10(W_STANCE / SHOE_GYRO_SIGMA)), abs=1e-9
    )


def assert_hand_walk_strides(st: StrideStats) -> None:
    """The hand walk's strides: 4 of 1 s at 1 m/s (the one leaving the first stand
    dropped), stances of 0.4 s, stance and swing |ω| as built."""
    assert st.count == STRIDES - 1
    assert st.duration_s == pytest.approx(np.full(4, (SWING + STANCE) / RATE))
    assert st.speed_mps == pytest.approx(np.full(4, 1.0 / ((SWING + STANCE) / RATE)))
    assert st.stance_s[:3] == pytest.approx(np.full(3, STANCE / RATE))
    assert st.stance_gyro_median == pytest.approx(np.full(4, W_STANCE))
    assert st.swing_gyro_median == pytest.approx(np.full(4, W_SWING))


def _split_second_stance(gap: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The hand walk with its second walking stance's labels split by ``gap`` samples
    in its middle; the foot and the IMU stay still there (PyShoe's flicker)."""
    omega_b, f_b, stance, pos = _hand_walk()
    middle = STAND + SWING + STANCE + SWING + STANCE // 2
    stance[middle - gap // 2 : middle + gap - gap // 2] = False
    return omega_b, f_b, stance, pos


def test_a_stance_split_without_movement_is_one_stride() -> None:
    # 16 samples (0.08 s): longer than the label cleaning's 10, so two runs remain
    omega_b, f_b, stance, pos = _split_second_stance(16)
    st = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos)).strides
    # as without the split: 4 strides of 1 s at 1 m/s, the split stance 0.4 s whole
    # (unmerged: a 0.24 s stride at 0 m/s, and a successor starting 0.24 s late)
    assert_hand_walk_strides(st)


#: Stances B and C of the short-swing walk (0.35 s): B → C lasts 0.45–0.65 s, longer
#: than the minimum stride, so only the split-stance rule can join them.
SHORT = 70


def _short_swing_walk(samples: int, metres: float) -> WalkSamples:
    """Stance A, 1 m swing, stance B, a short swing of ``samples`` moving ``metres``,
    stance C, 1 m swing, stance D, 1 m swing, stance E into a stand."""
    phases = [(STAND, W_STAND, True, 0.0), (SWING, W_SWING, False, 1.0)]
    phases += [(STANCE, W_STANCE, True, 0.0), (SWING, W_SWING, False, 1.0)]
    phases += [(SHORT, W_STANCE, True, 0.0), (samples, W_SWING, False, metres)]
    phases += [(SHORT, W_STANCE, True, 0.0), (SWING, W_SWING, False, 1.0)]
    phases += [(STANCE, W_STANCE, True, 0.0), (SWING, W_SWING, False, 1.0)]
    phases.append((STANCE + STAND, W_STAND, True, 0.0))
    omega_b, f_b, stance, pos = phase_walk(phases)
    return WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos)


@pytest.mark.parametrize(
    ("samples", "metres", "merged"),
    [
        (30, 0.06, False),  # 0.15 s, 6 cm: a real (short) swing, a stride of its own
        (30, 0.04, True),  # 4 cm: below MIN_SWING_M
        (28, 0.06, False),  # 0.14 s, 6 cm: with truth positions the movement decides
        (20, 0.06, False),  # 0.1 s, 6 cm: likewise
        (60, 0.04, True),  # 0.3 s, 4 cm: a long gap without a step
    ],
)
def test_a_real_short_swing_is_not_merged(samples: int, metres: float, merged: bool) -> None:
    st = walk_stats(_short_swing_walk(samples, metres)).strides
    if merged:  # A → B, B → D (B and C one stance), D → E
        want = [SWING + STANCE, SHORT + samples + SHORT + SWING, SWING + STANCE]
        stance = [STANCE, SHORT + samples + SHORT, STANCE]
    else:  # A → B, B → C, C → D, D → E
        want = [SWING + STANCE, SHORT + samples, SHORT + SWING, SWING + STANCE]
        stance = [STANCE, SHORT, SHORT, STANCE]
    assert st.duration_s == pytest.approx(np.array(want) / RATE)
    assert st.stance_s == pytest.approx(np.array(stance) / RATE)
    if not merged:
        assert st.speed_mps[1] == pytest.approx(metres / ((SHORT + samples) / RATE))


def test_without_truth_positions_only_the_gap_length_merges() -> None:
    # labels alone: the split-stance rule merges a 0.08 s split, not a 0.2 s one (with
    # truth positions the still foot merges both); the 0.2 s split's second part then
    # starts 0.3 s after the first, less than a minimum stride, and joins it
    for gap, split_runs in ((16, 0), (40, 1)):
        omega_b, f_b, stance, pos = _split_second_stance(gap)
        starts, ends = runs(clean_labels(stance, 10))
        merged, _ = merge_split_stances(starts, ends, RATE)
        assert merged.size == starts.size - 1 + split_runs
        assert merge_split_stances(starts, ends, RATE, pos)[0].size == starts.size - 1
        labels_only = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance)).strides
        assert labels_only.count == STRIDES - 1
        with_truth = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos))
        assert with_truth.strides.count == STRIDES - 1


def test_merge_split_stances_rules() -> None:
    starts, ends = np.array([0, 50, 100, 200]), np.array([40, 70, 160, 260])
    pos = np.zeros((300, 3))
    pos[70:100, 0] = np.linspace(0.0, 0.5, 30)  # the foot moves 0.5 m in gap 2 only
    pos[100:, 0] = 0.5
    pos[160:200, 0] = 0.5 + np.linspace(0.0, 0.02, 40)  # gap 3: 2 cm in 0.2 s
    pos[200:, 0] = 0.52
    # at 100 Hz: gap 1 (0.1 s) is short; gap 2 (0.3 s, 0.5 m) a swing; gap 3 still
    s, e = merge_split_stances(starts, ends, 100.0, pos)
    assert (s.tolist(), e.tolist()) == ([0, 100], [70, 260])
    # no positions, or none where gap 3 is judged: the time criterion alone
    s, e = merge_split_stances(starts, ends, 100.0)
    assert (s.tolist(), e.tolist()) == ([0, 100, 200], [70, 160, 260])
    pos[200, 0] = np.nan
    s, e = merge_split_stances(starts, ends, 100.0, pos)
    assert (s.tolist(), e.tolist()) == ([0, 100, 200], [70, 160, 260])


def test_merge_split_stances_with_positions_the_movement_decides() -> None:
    # a 0.1 s gap (shorter than MIN_SWING_S) in which the foot moves 6 cm: a step with
    # truth positions, a split stance without them
    starts, ends = np.array([0, 50]), np.array([40, 90])
    pos = np.zeros((100, 3))
    pos[40:50, 0] = np.linspace(0.0, 0.06, 10)
    pos[50:, 0] = 0.06
    s, e = merge_split_stances(starts, ends, 100.0, pos)
    assert (s.tolist(), e.tolist()) == ([0, 50], [40, 90])
    s, e = merge_split_stances(starts, ends, 100.0)
    assert (s.tolist(), e.tolist()) == ([0], [90])


def test_stride_quietness_is_the_quietest_five_percent() -> None:
    # The second stride's stance shortened to 12 samples (longer than the label
    # cleaning's 10): with the window's 4-sample mixing only 8 pure stance samples of
    # the stride's 200 remain (4 %), so its 5th percentile sits above the stance
    # level, in the mixed samples; the other strides keep theirs.
    omega_b, f_b, stance, pos = _hand_walk()
    first = STAND + SWING  # the first walking stance
    second = first + STANCE + SWING
    omega_b[second + 12 : second + STANCE, 0] = W_SWING
    stance[second + 12 : second + STANCE] = False
    s = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos))
    p5 = s.strides.log_shoe_p5
    stance_level = 2 * math.log10(W_STANCE / SHOE_GYRO_SIGMA)
    assert p5.size == STRIDES - 1
    assert p5[1] > stance_level + 0.5
    others = np.delete(p5, 1)
    assert others == pytest.approx(np.full(p5.size - 1, stance_level), abs=1e-9)


def test_a_stand_split_by_a_label_flicker_is_still_a_stand() -> None:
    omega_b, f_b, stance, pos = _hand_walk()
    flicker = stance.copy()
    flicker[STAND // 2] = False  # one sample in the middle of the first 2 s stand
    whole = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos))
    split = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=flicker, truth_pos=pos))
    # without cleaning the two 1 s halves are stands, but the flickered sample would
    # be walking; with it the stand is whole and the walking part unchanged
    assert split.standing_s == whole.standing_s
    assert np.array_equal(split.log_shoe, whole.log_shoe)


def test_quiet_phase_of_the_hand_walk() -> None:
    # The quiet level is the log-midpoint of p10 (stance, |ω| = 0.1) and p50 (swing,
    # |ω| = 3): |ω|² = 0.3 in SHOE's gyro units. A stance sample whose 5-sample window
    # holds one swing sample reads (9 + 4·0.01)/5 = 1.8 > 0.3: not quiet. So each of
    # the 4 walking stances has its 80 − 4 pure samples quiet (as for p10 above).
    omega_b, f_b, stance, pos = _hand_walk()
    s = walk_stats(WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos))
    pure = STANCE - 4
    walking = STRIDES * SWING + (STRIDES - 1) * STANCE
    assert s.quiet_fraction == pytest.approx((STRIDES - 1) * pure / walking)
    assert s.quiet_runs_s == pytest.approx(np.full(STRIDES - 1, pure / RATE))
    assert s.quiet_s_median == pytest.approx(pure / RATE)
    # p90 is a pure swing sample (swing holds 600 − 4·4 of the 920)
    assert s.log_shoe_p90 == pytest.approx(2 * math.log10(W_SWING / SHOE_GYRO_SIGMA), abs=1e-9)


def test_walk_stats_without_strides_keeps_the_walk_measures() -> None:
    omega_b, f_b, stance, pos = _hand_walk()
    samples = WalkSamples(omega_b, f_b, RATE, stance=stance, truth_pos=pos)
    full, light = walk_stats(samples), walk_stats(samples, per_stride=False)
    assert light.strides.count == 0 and full.strides.count == STRIDES - 1
    assert np.array_equal(light.log_shoe, full.log_shoe)
    assert light.speed_mps == full.speed_mps and light.quiet_fraction == full.quiet_fraction


def test_walk_stats_from_truth_velocity_without_labels() -> None:
    omega_b, f_b, _, pos = _hand_walk()
    s = walk_stats(WalkSamples(omega_b, f_b, RATE, truth_pos=pos))
    assert s.stance_source is StanceSource.TRUTH_VELOCITY
    # the 0.05 s speed smoothing moves each stand edge by up to 5 samples
    assert s.standing_s == pytest.approx((2 * STAND + STANCE) / RATE, abs=10 / RATE)


def test_walk_stats_from_detector_and_footprints() -> None:
    omega_b, f_b, _, _ = _hand_walk()
    starts = STAND + SWING + np.arange(STRIDES) * (SWING + STANCE)  # footfalls
    footprints = np.stack([np.arange(1, STRIDES + 1.0), np.zeros(STRIDES)], axis=1)
    s = walk_stats(WalkSamples(omega_b, f_b, RATE, footfall_index=starts, footprints_m=footprints))
    assert s.stance_source is StanceSource.DETECTOR
    assert s.speed_source is SpeedSource.FOOTPRINTS
    # walking runs from the first to the last footprint: 4 strides of 1 s
    assert s.walking_s == pytest.approx((starts[-1] - starts[0] + 1) / RATE)
    assert s.speed_mps == pytest.approx((STRIDES - 1) / s.walking_s)
    assert s.strides.speed_mps == pytest.approx(np.ones(STRIDES - 1))


def test_clean_labels_closes_short_gaps_and_drops_short_runs() -> None:
    flags = np.array([1, 1, 1, 0, 1, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0], dtype=bool)
    want = np.array([1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0], dtype=bool)
    assert np.array_equal(clean_labels(flags, 2), want)


def test_walk_samples_bad_input_names_the_problem() -> None:
    with pytest.raises(ValueError, match="omega_b and f_b"):
        WalkSamples(np.zeros((10, 3)), np.zeros((9, 3)), RATE, name="w")
    with pytest.raises(ValueError, match="stance must be"):
        WalkSamples(np.zeros((10, 3)), np.zeros((10, 3)), RATE, stance=np.zeros(9, bool))
    with pytest.raises(ValueError, match="footfall_index must increase"):
        WalkSamples(
            np.zeros((10, 3)),
            np.zeros((10, 3)),
            RATE,
            footfall_index=np.array([3, 2]),
            footprints_m=np.zeros((2, 2)),
        )


def test_pyshoe_excerpt_uses_vicon_labels_and_truth() -> None:
    s = walk_stats(load_walk(PYSHOE_SAMPLE))
    assert s.stance_source is StanceSource.LABELS
    assert s.speed_source is SpeedSource.TRUTH
    assert s.walking_s > 0 and np.isfinite(s.speed_mps)
    # a MicroStrain foot in walking: mid-stance 10^4.5–10^7.5, the stance/swing
    # edge 10^6.5–10^9.5 (the development trials' ranges, docs/SIM_TO_REAL.md)
    assert 4.5 < s.log_shoe_p10 < 7.5 and 6.5 < s.log_shoe_p50 < 9.5


def test_load_walk_missing_file() -> None:
    with pytest.raises(ValueError, match="no such file"):
        load_walk("/nonexistent/walk.mat")


def test_hallway_excerpt_has_footprint_speed_and_detector_stance() -> None:
    s = walk_stats(load_walk(HALLWAY_SAMPLE))
    assert s.stance_source is StanceSource.DETECTOR
    assert s.speed_source is SpeedSource.FOOTPRINTS
    # the walk's first seconds: footprints 0.6–1.4 m apart at about 1 m/s
    assert 0.5 < s.speed_mps < 2.0


def _copy(name: str, rate: float, footprints: np.ndarray, seconds: float = 2.0) -> WalkSamples:
    n = int(seconds * rate)
    return WalkSamples(
        np.zeros((n, 3)),
        np.zeros((n, 3)),
        rate,
        name=name,
        footfall_index=np.array([0, n // 2]),
        footprints_m=footprints,
    )


def test_distinct_walks_counts_a_walk_in_two_files_once() -> None:
    fp = np.array([[0.0, 0.0], [0.6, 0.1]])
    walks = [
        _copy("walk.csv at 250 Hz", 250.0, fp),
        _copy("walk.mat", 200.0, fp + 2e-4),  # the same footprints to 1 mm
        _copy("other", 200.0, fp + 0.5),
        _copy("walk, longer", 200.0, fp, seconds=2.5),
    ]
    kept, dropped = distinct_walks(walks)
    # the copy at the SHOE window's 200 Hz is kept, in the place of the first
    assert [w.name for w in kept] == ["walk.mat", "other", "walk, longer"]
    assert dropped == [("walk.csv at 250 Hz", "walk.mat")]
