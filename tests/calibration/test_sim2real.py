"""Calibrated stance dynamics, speed routes, the sim-vs-real comparison and its CLI."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from agents.cli import main
from pednav_env.calibration.compare import (
    DEFAULT_WALKS_PER_BAND,
    MODELS,
    Sim2RealReport,
    band_of,
    compare,
)
from pednav_env.calibration.sources import load_walk
from pednav_env.calibration.stats import walk_stats
from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import Gait, SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import (
    MIN_FLAT,
    MIN_SWING,
    StanceMotion,
    StanceRandomization,
    stance_motion,
    stance_table,
)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
PYSHOE_SAMPLE = Path(__file__).parent / "data" / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"


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


def test_speed_route_strides_stay_in_the_band_and_gait_follows_speed() -> None:
    for band in ((0.3, 0.8), (1.3, 1.8), (2.6, 3.8)):
        route = speed_route(np.random.default_rng(3), SpeedRouteConfig(speed_mps=band))
        speeds = np.array([s.shape.speed for s in route.strides])
        assert speeds.min() >= band[0] - 1e-12 and speeds.max() <= band[1] + 1e-12
        gaits = {s.shape.gait for s in route.strides}
        if band[0] >= 2.0:
            assert gaits == {Gait.RUN}
        if band[1] <= 0.8:
            assert Gait.RUN not in gaits and Gait.FAST_WALK not in gaits


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


def test_compare_envelope_and_coverage_on_the_test_excerpt() -> None:
    real = [walk_stats(load_walk(PYSHOE_SAMPLE))]
    report = compare(real, MODELS["calibrated"], walks_per_band=4, seed=1)
    out = report.to_json()
    assert out["recordings"] == 1 and len(out["bands"]) == 5
    band = next(b for b in report.bands if b.real)
    assert band.band == band_of(real[0].speed_mps)
    lo, hi = band.p10_envelope
    assert lo <= hi and out["covered"] == int(band.covered(real[0]))


def _p10_inside(report: Sim2RealReport) -> int:
    """Recordings whose p10 lies inside their band's simulated p10 envelope."""
    return sum(
        b.p10_envelope[0] <= s.log_shoe_p10 <= b.p10_envelope[1]
        for b in report.bands
        for s in b.real
    )


@pytest.mark.skipif(not DATA.is_dir(), reason="development recordings not present")
def test_calibrated_envelope_covers_development_recordings() -> None:
    names = ["2017-11-22-11-27-30.mat", "2017-11-22-11-38-45.mat", "2017-11-22-11-36-45.mat"]
    paths = [DATA / "pyshoe-vicon-dev" / n for n in names]
    paths.append(DATA / "hallway-gcp-dev" / "SensorConnectData_43_LLIO.mat")
    real = [walk_stats(load_walk(p)) for p in paths]
    today = compare(real, MODELS["today"], walks_per_band=20, seed=0)
    calibrated = compare(real, MODELS["calibrated"], walks_per_band=20, seed=0)
    # a slow (0.42 m/s), a normal and a fast PyShoe trial and a fast hallway walk.
    # Today's model covers none (slow mid-stance a decade too quiet, p50 too low at
    # speed). The calibrated one has all four p10 inside and covers (p10 and p50) at
    # least 2: on seeds 0-2 it covers 3, 3, 2 (20 walks per band); the slow trial's
    # p50 lies below the envelope (docs/SIM_TO_REAL.md, "What is left").
    assert today.coverage[0] == 0 and _p10_inside(today) <= 1
    assert _p10_inside(calibrated) >= 3
    assert calibrated.coverage[0] >= 2


def test_cli_sim2real_default_walks_is_the_library_default() -> None:
    from agents.cli import build_parser

    args = build_parser().parse_args(["sim2real", "walk.mat"])
    assert args.walks == DEFAULT_WALKS_PER_BAND


def test_cli_sim2real_json(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["sim2real", str(PYSHOE_SAMPLE), "--walks", "3", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"] == "calibrated" and out["recordings"] == 1


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["/nonexistent/walk.mat"], "no such file"),
        ([str(PYSHOE_SAMPLE), "--model", "nope"], "--model"),
    ],
)
def test_cli_sim2real_bad_input_is_one_line(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["sim2real", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err


def test_cli_sim2real_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim2real", str(PYSHOE_SAMPLE), "--walks", "3", "--plot", str(tmp_path)]) == 0
    assert list(tmp_path.glob("sim2real_calibrated_*.png"))
    assert "covered" in capsys.readouterr().out
