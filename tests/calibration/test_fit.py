"""The calibration fit (pednav_env.calibration.fit), its objective (.objective) and simulated
walks as recordings for the real-data runner (agents.choose_shoe)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import wasserstein_distance

from agents.choose_shoe import errors_by_recording, simulated_recordings
from pednav_env.calibration.compare import MODELS, SPEED_BANDS
from pednav_env.calibration.fit import fit, groups, minimize_in_box
from pednav_env.calibration.objective import (
    COVERAGE_SEED_OFFSET,
    GRADE,
    MISSING_BIN_DECADES,
    band_distance,
    coverage_distance,
    coverage_seed,
    distance,
    pooled_w1,
    stride_distance,
    swing_distance,
)
from pednav_env.calibration.parameters import (
    GAIT_PRIORS,
    LOWER,
    NAMES,
    START,
    SWING_SPEED,
    UPPER,
    box,
    parameter_set,
    randomization,
)
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.stats import SpeedSource, StanceSource, StrideStats, WalkStats
from pednav_env.replay.setup import real_fixed_setup


def test_pooled_w1_matches_scipy() -> None:
    rng = np.random.default_rng(0)
    a = rng.normal(6.0, 1.0, 20_000)
    b = np.concatenate((rng.normal(5.5, 0.5, 8_000), rng.normal(9.0, 0.4, 15_000)))
    # the 400-point midpoint rule is within 1e-2 decades of the exact W1 for
    # samples of this spread (its error is the quantile function's variation within
    # one 1/400 step, largest in the tails); a wrong sign or scale is off by ≥ 0.5
    assert pooled_w1(a, b) == pytest.approx(wasserstein_distance(a, b), abs=1e-2)


def _walk(
    level: float,
    stride_speeds: list[float] = (),
    stride_p5: list[float] = (),
    swing_gyro: list[float] | None = None,
) -> WalkStats:
    """A walk whose log10 SHOE is ``level`` throughout (p10 = p50 = level) and
    whose strides have the given speeds, quietness and swing |ω| medians (rad/s;
    default 0, no swing value)."""
    n = len(stride_speeds)
    swing = np.zeros(n) if swing_gyro is None else np.asarray(swing_gyro, float)
    cols = (
        [np.zeros(n)] * 2
        + [np.asarray(stride_speeds, float)]
        + [np.zeros(n)] * 3
        + [swing, np.zeros(n)]
    )
    return WalkStats(
        "w",
        200.0,
        StanceSource.LABELS,
        SpeedSource.TRUTH,
        1.0,
        10.0,
        0.0,
        np.full(100, level),
        StrideStats(*cols, np.asarray(stride_p5, float)),
    )


def test_coverage_distance_hand_computed() -> None:
    sim = [_walk(float(v)) for v in range(21)]  # 5–95 % of 0, 1, …, 20 is [1, 19]
    # inside: 0; at 25: 6 decades above on p10 and on p50; at 0.5: 0.5 below on each
    assert coverage_distance([_walk(10.0)], sim) == 0.0
    assert coverage_distance([_walk(25.0), _walk(0.5)], sim) == pytest.approx((12 + 1) / 2)


def test_stride_distance_by_stride_speed_bin() -> None:
    # 12 recorded strides at 1 m/s (bin 0.8–1.3) quietness 6.0, 12 at 2 m/s (bin
    # 1.8–2.6) at 8.0, and 5 at 0.5 m/s: too few for a bin of their own.
    real = [_walk(0.0, [1.0] * 12 + [2.0] * 12 + [0.5] * 5, [6.0] * 12 + [8.0] * 12 + [5.0] * 5)]
    # the simulator 0.5 decades louder at 1 m/s, no stride at 2 m/s
    sim = [_walk(0.0, [1.1] * 30, [6.5] * 30)]
    out = stride_distance(real, sim)
    assert out == {1: pytest.approx(0.5), 3: MISSING_BIN_DECADES}


def test_swing_distance_zero_for_identical_strides_and_grows_with_a_shift() -> None:
    # 12 recorded strides at 1 m/s (bin 0.8–1.3) with swing |ω| medians 2, 3, 4 rad/s
    # and 12 at 2 m/s (bin 1.8–2.6) at 5–7 rad/s; 5 at 0.5 m/s, too few for a bin
    speeds = [1.0] * 12 + [2.0] * 12 + [0.5] * 5
    swing = [2.0, 3.0, 4.0] * 4 + [5.0, 6.0, 7.0] * 4 + [1.0] * 5
    real = [_walk(0.0, speeds, [6.0] * 29, swing)]
    assert swing_distance(real, real) == {1: 0.0, 3: 0.0}
    # every simulated swing twice as vigorous: log10 2 = 0.301 decades in each bin
    louder = [_walk(0.0, speeds, [6.0] * 29, [2 * v for v in swing])]
    out = swing_distance(real, louder)
    assert out == {1: pytest.approx(np.log10(2.0)), 3: pytest.approx(np.log10(2.0))}
    # four times: twice the W1; and a bin without simulated strides counts as missing
    fast_only = [_walk(0.0, [2.0] * 12, [6.0] * 12, [4 * v for v in swing[12:24]])]
    assert swing_distance(real, fast_only) == {
        1: MISSING_BIN_DECADES,
        3: pytest.approx(np.log10(4.0)),
    }
    # strides without a swing value (NaN, or zero samples) are left out on both sides
    holes = [_walk(0.0, speeds + [1.0, 2.0], [6.0] * 31, swing + [np.nan, 0.0])]
    assert swing_distance(holes, real) == {1: 0.0, 3: 0.0}


def test_coverage_seeds_never_meet_the_w1_seeds() -> None:
    for seed in (0, 7, 12_345):
        for bands in range(1, COVERAGE_SEED_OFFSET + 1):
            w1 = {seed * 100 + k for k in range(bands)}
            cover = {coverage_seed(seed, k, bands) for k in range(bands)}
            assert len(cover) == bands and not w1 & cover
    assert coverage_seed(7, 2) == 752
    with pytest.raises(ValueError, match="bands = 51"):
        coverage_seed(7, 0, COVERAGE_SEED_OFFSET + 1)
    with pytest.raises(ValueError, match="band = 5"):
        coverage_seed(7, len(SPEED_BANDS))


def test_distance_draws_the_coverage_walks_from_their_own_seeds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    calls: list[tuple[int, int, int, bool]] = []

    def fake_simulate(
        self: SimModel,
        band: tuple[float, float],
        walks: int,
        seed: int,
        duration_s: tuple[float, float],
        per_stride: bool = True,
        turns_per_walk: object = None,
    ) -> list[WalkStats]:
        calls.append((SPEED_BANDS.index(band), walks, seed, per_stride))
        return [_walk(6.0 + 0.1 * i, [1.0] * 12, [6.0] * 12, [3.0] * 12) for i in range(walks)]

    monkeypatch.setattr(SimModel, "simulate", fake_simulate)
    real = [_walk(6.2, [1.0] * 12, [6.0] * 12, [3.0] * 12)]  # a walk at 1 m/s
    terms: dict[str, float] = {}
    distance(START, real, 4, 7, terms, coverage_walks=5, swing=True)
    w1 = [c for c in calls if c[1] == 4]
    cover = [c for c in calls if c[1] == 5]
    assert [c[0] for c in w1] == [1] and [c[0] for c in cover] == [1]
    assert w1[0][2] == 701 and w1[0][3] is True
    assert cover[0][2] == 751 and cover[0][3] is False  # no per-stride statistics
    assert terms["stride_swing"] == 0.0 and "coverage" in terms


def test_groups_split_by_session_and_place() -> None:
    class Named:
        def __init__(self, name: str) -> None:
            self.name = name

    walks = [Named(n) for n in ("2017-11-22-11-30-14", "2017-11-22-11-35-59", "Data_31_LLIO")]
    out = groups(walks)  # type: ignore[arg-type]
    assert [[w.name for w in v] for v in out.values()] == [
        ["2017-11-22-11-30-14"],
        ["2017-11-22-11-35-59"],
        ["Data_31_LLIO"],
    ]


@pytest.fixture(scope="module")
def pseudo_recordings() -> list:
    """Simulated walks of the start point's model standing in for recordings (two
    bands, other seeds than the fit's)."""
    model = SimModel("truth", GRADE, randomization(START))
    return model.simulate((0.8, 1.3), 4, 99, (20.0, 25.0), False) + model.simulate(
        (1.3, 1.8), 4, 98, (20.0, 25.0), False
    )


def test_band_distance_of_a_set_with_itself_is_zero(pseudo_recordings: list) -> None:
    terms = band_distance(pseudo_recordings, pseudo_recordings)
    assert set(terms) >= {"log_shoe_p10", "log_shoe_p50", "quiet_fraction", "pooled_log_shoe"}
    assert all(v == pytest.approx(0.0, abs=1e-12) for v in terms.values())


def test_distance_is_deterministic_and_smallest_at_the_generating_model(
    pseudo_recordings: list,
) -> None:
    at_truth = distance(START, pseudo_recordings, 4, 7)
    assert distance(START, pseudo_recordings, 4, 7) == at_truth  # common random numbers
    for name, step in (("quiet_log10_mean", 1.0), ("flat_fraction", 0.15)):
        x = START.copy()
        x[NAMES.index(name)] += step
        # a decade louder mid-stance, or 15 % of the cycle more foot-flat, moves p10 or
        # the quiet share far beyond the spread of 4 walks against 4 others
        assert distance(x, pseudo_recordings, 4, 7) > 2 * at_truth


def test_simulated_walk_as_recording_runs_through_the_real_data_filter() -> None:
    recs = simulated_recordings(MODELS["calibrated"], 1, 3, (0.8, 1.3), (20.0, 20.0))
    rec = recs[0]
    assert rec.time[0] == pytest.approx(1 / 200.0) and np.all(np.diff(rec.time) > 0)
    assert rec.truth_pos is not None and np.allclose(rec.truth_pos[:300], 0.0, atol=1e-9)
    # real-fixed on a 20 s simulated walk at about 1 m/s: decimetres of error when the
    # axes, time and truth are passed right; a wrong rate, axis or truth sample
    # gives metres
    armse = errors_by_recording(real_fixed_setup(), recs)[rec.name]
    assert armse < 0.5


def test_randomization_takes_the_optional_swing_speed_exponent() -> None:
    shipped = randomization(START)
    assert shipped.swing_speed_exponent == 0.0
    extended = randomization([*START, 0.4])
    assert extended.swing_speed_exponent == pytest.approx(0.4)
    assert replace(extended, swing_speed_exponent=0.0) == shipped
    # clipped to its box [−0.5, 1.5] like the other values
    assert randomization([*START, 9.0]).swing_speed_exponent == pytest.approx(SWING_SPEED.upper)
    assert parameter_set(len(NAMES) + 1)[-1] is SWING_SPEED
    with pytest.raises(ValueError, match="15 or 16 values, got 14"):
        randomization(START[:-1])


def test_randomization_holds_fixed_model_options() -> None:
    assert randomization(START, {"heel_rocker": True}) == replace(
        randomization(START), heel_rocker=True
    )
    assert randomization(START, {}) == randomization(START)


def test_distance_defaults_leave_the_shipped_distance_unchanged(pseudo_recordings: list) -> None:
    plain: dict[str, float] = {}
    base = distance(START, pseudo_recordings, 4, 7, plain)
    explicit: dict[str, float] = {}
    assert distance(START, pseudo_recordings, 4, 7, explicit, swing=False, coverage_walks=0) == base
    assert explicit == plain and "stride_swing" not in plain
    # the options change the distance only through their own terms
    both: dict[str, float] = {}
    distance(START, pseudo_recordings, 4, 7, both, swing=True, coverage_walks=4)
    assert {k: v for k, v in both.items() if k not in ("coverage", "stride_swing")} == {
        k: v for k, v in plain.items() if k != "coverage"
    }
    assert both["coverage"] != plain["coverage"]


def test_distance_simulates_with_the_fixed_options(pseudo_recordings: list) -> None:
    # the heel strike is not among the fitted values: with the option held fixed the
    # same walks are simulated with another heel strike, so the distance moves
    base = distance(START, pseudo_recordings, 4, 7)
    rocker = distance(START, pseudo_recordings, 4, 7, options={"heel_rocker": True})
    assert rocker != base


def _counted_bowl(centre: np.ndarray) -> tuple[list[np.ndarray], object]:
    """A quadratic bowl with its minimum (0) at ``centre``, recording each point."""
    calls: list[np.ndarray] = []

    def objective(x: np.ndarray) -> float:
        calls.append(np.array(x))
        return float(np.sum((np.asarray(x) - centre) ** 2))

    return calls, objective


def test_minimize_keeps_the_start_when_the_search_cannot_beat_it() -> None:
    # the start is the bowl's minimum: no sampled candidate can reach 0, so the
    # search's best is above it and the start must come back, exactly
    lower, upper = np.zeros(5), np.full(5, 10.0)
    start = np.array([3.0, 4.0, 5.0, 6.0, 7.0])
    calls, bowl = _counted_bowl(start)
    result = minimize_in_box(bowl, start, lower, upper, 24, seed=0, popsize=12, sigma0=0.2)
    assert result.kept_start
    np.testing.assert_array_equal(result.x, start)
    assert result.distance == 0.0 == result.start_distance
    assert result.search_distance > 0.0
    np.testing.assert_array_equal(calls[0], start)  # scored first
    assert result.evaluations == len(calls)
    assert result.to_json()["kept_start"] is True


def test_minimize_returns_the_search_when_it_beats_the_start() -> None:
    lower, upper = np.zeros(3), np.full(3, 10.0)
    centre = np.array([5.0, 5.0, 5.0])
    calls, bowl = _counted_bowl(centre)
    result = minimize_in_box(bowl, [1.0, 9.0, 1.0], lower, upper, 300, seed=0, sigma0=0.3)
    assert not result.kept_start
    assert result.start_distance == pytest.approx(48.0)
    assert result.distance == result.search_distance < 1.0
    assert float(np.sum((result.x - centre) ** 2)) == pytest.approx(result.distance)
    assert result.evaluations == len(calls)


def test_minimize_clips_the_start_to_the_box() -> None:
    calls, bowl = _counted_bowl(np.array([1.0, 1.0]))
    result = minimize_in_box(bowl, [5.0, -5.0], np.zeros(2), np.ones(2), 12, seed=0)
    np.testing.assert_array_equal(calls[0], [1.0, 0.0])
    assert result.start_distance == pytest.approx(1.0)


def test_fit_scores_its_start_and_returns_the_better(pseudo_recordings: list) -> None:
    result = fit(pseudo_recordings, 2, 12, 7, popsize=6, x0=START, sigma0=0.3)
    assert result.start_distance == distance(START, pseudo_recordings, 2, 7)
    assert result.distance == min(result.start_distance, result.search_distance)
    assert result.distance == distance(result.x, pseudo_recordings, 2, 7)
    if result.kept_start:
        np.testing.assert_array_equal(result.x, START)


def test_default_box_is_the_parameters_own_and_the_priors_narrow_the_gait_timing() -> None:
    lower, upper = box(len(NAMES))
    np.testing.assert_array_equal(lower, LOWER)
    np.testing.assert_array_equal(upper, UPPER)
    p_lower, p_upper = box(len(NAMES), priors=True)
    stated = {
        "flat_fraction": (0.15, 0.43),
        "flat_speed_slope": (-0.15, 0.0),
        "heel_fraction": (0.12, 0.20),
    }
    assert dict(GAIT_PRIORS) == stated
    for i, name in enumerate(NAMES):
        expected = stated.get(name, (LOWER[i], UPPER[i]))
        assert (p_lower[i], p_upper[i]) == expected, name
        assert LOWER[i] <= p_lower[i] < p_upper[i] <= UPPER[i], name  # narrowed only
    # with the knots and the swing speed exponent the extra values keep their box
    k_lower, k_upper = box(len(NAMES) + 2, knots=True, priors=True)
    np.testing.assert_array_equal(k_lower[: len(NAMES)], p_lower)
    np.testing.assert_array_equal(k_upper[len(NAMES) :], box(len(NAMES) + 2, knots=True)[1][-2:])


def test_fit_with_priors_clips_a_warm_start_outside_them(pseudo_recordings: list) -> None:
    x0 = START.copy()
    outside = {"flat_fraction": 0.49, "flat_speed_slope": 0.05, "heel_fraction": 0.06}
    for name, value in outside.items():
        x0[NAMES.index(name)] = value
    lower, upper = box(len(NAMES), priors=True)
    clipped = np.clip(x0, lower, upper)
    assert [clipped[NAMES.index(n)] for n in outside] == [0.43, 0.0, 0.12]
    result = fit(pseudo_recordings, 2, 12, 7, popsize=6, x0=x0, sigma0=0.3, priors=True)
    assert result.start_distance == distance(clipped, pseudo_recordings, 2, 7)
    assert np.all(result.x >= lower) and np.all(result.x <= upper)
