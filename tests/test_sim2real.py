"""Calibrated stance dynamics, speed routes, the sim-vs-real comparison and its CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from agents.cli import main
from pednav_env.calibration.compare import MODELS, Sim2RealReport, band_of, compare
from pednav_env.calibration.sources import load_walk
from pednav_env.calibration.stats import walk_stats
from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import Gait, SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import (
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
    today = compare(real, MODELS["today"], walks_per_band=10, seed=0)
    calibrated = compare(real, MODELS["calibrated"], walks_per_band=10, seed=0)
    # a slow, a normal and a fast PyShoe trial and a fast hallway walk. Mid-stance
    # quietness (p10): today's model covers at most one, the calibrated one at least
    # 3 of 4. (p50 is not yet covered: docs/SIM_TO_REAL.md, "What is left".)
    assert _p10_inside(today) <= 1
    assert _p10_inside(calibrated) >= 3


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
