"""Calibrated stance dynamics (gait.stance_motion): derivatives, mid-stance quiet, walker
timing, the randomisation and its validation."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import (
    MIN_FLAT,
    MIN_SWING,
    StanceMotion,
    StanceRandomization,
    stance_motion,
    stance_table,
)


def test_stance_motion_derivatives_match_finite_differences() -> None:
    par = stance_table(StanceMotion(edge_rad=0.02, roll_rad=0.05), np.array([1.3]))[0]
    start, end, h = 0.0, 0.45, 1e-6
    for t in (0.01, 0.2, 0.4):  # after the strike, mid-stance, in the roll-over
        (_, dp, ddp), (_, dr, ddr) = stance_motion(3, t, start, end, par)
        (p_hi, dp_hi, _), (r_hi, dr_hi, _) = stance_motion(3, t + h, start, end, par)
        (p_lo, dp_lo, _), (r_lo, dr_lo, _) = stance_motion(3, t - h, start, end, par)
        # central differences are O(h²): 1e-4 relative is far above their error
        # and far below a wrong factor (ω, τ or π) in a derivative
        assert dp == pytest.approx((p_hi - p_lo) / (2 * h), rel=1e-4, abs=1e-9)
        assert ddp == pytest.approx((dp_hi - dp_lo) / (2 * h), rel=1e-4, abs=1e-6)
        assert dr == pytest.approx((r_hi - r_lo) / (2 * h), rel=1e-4, abs=1e-9)
        assert ddr == pytest.approx((dr_hi - dr_lo) / (2 * h), rel=1e-4, abs=1e-6)


def test_stance_motion_is_quietest_at_mid_stance() -> None:
    # the envelope is a floor plus decays from both edges: the pitch rate's local
    # amplitude at mid-stance is below that just after the strike and before heel-off
    par = stance_table(StanceMotion(roll_rad=0.0), np.array([1.0]))[0]
    ts = np.linspace(0.0, 0.6, 601)
    rate = np.abs([stance_motion(2, t, 0.0, 0.6, par)[0][1] for t in ts])
    early, middle, late = rate[:60].max(), rate[250:350].max(), rate[-60:].max()
    assert middle < 0.5 * early and middle < 0.5 * late


def test_calibrated_stance_changes_only_stance_samples() -> None:
    rng = np.random.default_rng(5)
    motion = StanceRandomization().draw(rng)
    cfg = SpeedRouteConfig(speed_mps=(0.8, 1.3), duration_s=(10.0, 12.0))
    base = speed_route(np.random.default_rng(9), cfg)
    calib = speed_route(
        np.random.default_rng(9),
        SpeedRouteConfig(speed_mps=(0.8, 1.3), duration_s=(10.0, 12.0), stance_motion=motion),
    )
    sim = FootSimConfig(rate_hz=200.0)
    a, b = simulate_foot(base, sim), simulate_foot(calib, sim)
    differs = np.any(a.omega_b[0] != b.omega_b[0], axis=1)
    assert differs.any()
    # the old roll-over and micro-motion act in stances too; swing samples away from
    # stance (a 3-sample margin for the quadrature nodes) are identical
    near_stance = np.convolve(a.stance[0].astype(float), np.ones(7), mode="same") > 0
    assert not differs[~near_stance].any()


def test_walker_timing_sets_the_cycle_shares_and_keeps_the_route_draws() -> None:
    base = SpeedRouteConfig(speed_mps=(0.3, 1.9), duration_s=(25.0, 30.0))
    walker = StanceMotion(
        flat_fraction=0.45, flat_speed_slope=-0.1, heel_fraction=0.12, swing_pitch_scale=1.5
    )
    a = speed_route(np.random.default_rng(4), base)
    b = speed_route(np.random.default_rng(4), replace(base, stance_motion=walker))
    assert len(a.strides) == len(b.strides) > 10
    for sa, sb in zip(a.strides, b.strides, strict=True):
        ha, hb = sa.shape, sb.shape
        # the same draws: cycle, speed and stride length unchanged (1e-12: round-off
        # of the sum of the four phases)
        assert hb.cycle_s == pytest.approx(ha.cycle_s, abs=1e-12)
        assert hb.speed == pytest.approx(ha.speed, abs=1e-12)
        assert hb.heel_off_s == pytest.approx(0.12 * hb.cycle_s)
        assert hb.heel_strike_s == pytest.approx(0.12 * hb.cycle_s)
        share = hb.stance_s / hb.cycle_s
        # 0.45 − 0.1 ln v, plus the stride's jitter: today's stance share less 0.34,
        # within ±0.04
        today = ha.stance_s / ha.cycle_s
        assert share == pytest.approx(0.45 - 0.1 * math.log(hb.speed) + today - 0.34)
        assert hb.toe_off_pitch == pytest.approx(min(1.5 * ha.toe_off_pitch, 1.35))
        assert hb.heel_strike_pitch == pytest.approx(1.5 * ha.heel_strike_pitch)


def test_cycle_fractions_stay_in_bounds() -> None:
    walker = StanceMotion(flat_fraction=0.6, flat_speed_slope=-0.3, heel_fraction=0.1)
    # slow walkers stand longer (a negative slope)
    assert walker.cycle_fractions(0.8)[0] > walker.cycle_fractions(1.5)[0]
    flat, _, swing = walker.cycle_fractions(0.3)  # 0.6 + 0.36: beyond the bound
    assert flat == pytest.approx(1 - 2 * 0.1 - MIN_SWING) and swing == pytest.approx(MIN_SWING)
    flat, _, _ = StanceMotion(flat_fraction=0.1, flat_speed_slope=-0.3).cycle_fractions(3.0)
    assert flat == MIN_FLAT
    with pytest.raises(ValueError, match="flat_fraction"):
        StanceMotion().cycle_fractions(1.0)


def test_stance_randomization_draws_walker_timing_only_when_asked() -> None:
    plain = StanceRandomization().draw(np.random.default_rng(1))
    assert plain.flat_fraction is None and plain.swing_pitch_scale == 1.0
    timed = StanceRandomization(
        flat_fraction=0.4, flat_fraction_std=0.05, swing_pitch_log10_std=0.1
    )
    walkers = [timed.draw(np.random.default_rng(i)) for i in range(200)]
    flats = np.array([w.flat_fraction for w in walkers])
    scales = np.log10([w.swing_pitch_scale for w in walkers])
    # 200 normal draws: the sample mean is within 4 standard errors of the mean
    assert abs(flats.mean() - 0.4) < 4 * 0.05 / math.sqrt(200)
    assert abs(scales.std() - 0.1) < 0.02  # std of a 200-sample std ≈ 0.1/√400 = 0.005


def test_stance_randomization_rejects_bad_values() -> None:
    with pytest.raises(ValueError, match="quiet_log10_std"):
        StanceRandomization(quiet_log10_std=-0.1)
    with pytest.raises(ValueError, match="roll_fraction"):
        StanceMotion(roll_fraction=0.0)


def test_swing_scale_hand_computed() -> None:
    # k(v) = 1.2 · v^0.5: 1.2 · 0.5 = 0.6 at 0.25 m/s, 1.2 · 2 = 2.4 at 4 m/s
    walker = StanceMotion(flat_fraction=0.3, swing_pitch_scale=1.2, swing_speed_exponent=0.5)
    assert walker.swing_scale(0.25) == pytest.approx(0.6)
    assert walker.swing_scale(4.0) == pytest.approx(2.4)
    assert walker.swing_scale(1.0) == pytest.approx(1.2)
    # exponent 0 (the default): the scale itself at every speed, exactly
    plain = StanceMotion(flat_fraction=0.3, swing_pitch_scale=1.2)
    assert [plain.swing_scale(v) for v in (0.3, 1.0, 3.0)] == [1.2, 1.2, 1.2]


def test_swing_speed_exponent_scales_the_knots_by_the_stride_speed() -> None:
    base = SpeedRouteConfig(speed_mps=(0.3, 1.9), duration_s=(25.0, 30.0))
    flat = StanceMotion(flat_fraction=0.3, swing_pitch_scale=1.1)
    steep = replace(flat, swing_speed_exponent=0.6)
    a = speed_route(np.random.default_rng(6), replace(base, stance_motion=flat))
    b = speed_route(np.random.default_rng(6), replace(base, stance_motion=steep))
    plain = speed_route(np.random.default_rng(6), base)
    assert len(a.strides) == len(b.strides) == len(plain.strides) > 10
    slow = fast = 0
    for sa, sb, sp in zip(a.strides, b.strides, plain.strides, strict=True):
        ha, hb, hp = sa.shape, sb.shape, sp.shape
        # the same draws: cycle and timing unchanged, only the pitch knots differ
        assert hb.cycle_s == ha.cycle_s and hb.stance_s == ha.stance_s
        k = 1.1 * hb.speed**0.6
        assert hb.toe_off_pitch == pytest.approx(min(k * hp.toe_off_pitch, 1.35))
        assert hb.heel_strike_pitch == pytest.approx(max(k * hp.heel_strike_pitch, -1.35))
        assert ha.toe_off_pitch == pytest.approx(min(1.1 * hp.toe_off_pitch, 1.35))
        # gentler than the speed-independent scale below 1 m/s, more vigorous above
        gentler = abs(hb.heel_strike_pitch) < abs(ha.heel_strike_pitch)
        assert gentler == (hb.speed < 1.0)
        slow += hb.speed < 1.0
        fast += hb.speed > 1.0
    assert slow > 0 and fast > 0


def test_swing_speed_exponent_is_drawn_for_every_walker_without_changing_the_draws() -> None:
    shipped = StanceRandomization.calibrated()
    assert shipped.swing_speed_exponent == 0.0
    steep = replace(shipped, swing_speed_exponent=0.5)
    a = shipped.draw(np.random.default_rng(11))
    b = steep.draw(np.random.default_rng(11))
    assert a.swing_speed_exponent == 0.0 and b.swing_speed_exponent == 0.5
    assert replace(b, swing_speed_exponent=0.0) == a


def test_swing_speed_exponent_rejects_bad_values() -> None:
    with pytest.raises(ValueError, match="swing_speed_exponent"):
        StanceMotion(swing_speed_exponent=2.5)
    with pytest.raises(ValueError, match="swing_speed_exponent"):
        StanceMotion(swing_speed_exponent=float("nan"))
    with pytest.raises(ValueError, match="swing_speed_exponent needs flat_fraction"):
        StanceRandomization(swing_speed_exponent=0.3)
