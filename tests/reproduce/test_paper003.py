"""Paper 003 reproduction, small (few runs). Full size: ``pednav reproduce 003``.

Tolerances come from physics, not from our own output:

- yaw is unobservable by zero-velocity updates, so with the drift read as
  white noise its error is a random walk with intensity q = (σ_ω² + σ_ν²)Δt
  (σ per sample); its RMS over a walk of duration D is √(qD/2). With 16 runs
  the sample RMS scatters by about ±10 %; the bounds are ±40 %;
- tilt is observable through the ZUPTs: between corrections it drifts by
  √(q·T_swing) ≈ 4 mrad (white reading) or σ_ν T_swing ≈ 13 mrad (per-step
  reading), so an RMS above 0.03 rad would mean a broken filter;
- the two drift readings differ by far more than Monte-Carlo scatter.
"""

import json
import math

import pytest

from agents.cli import main
from pednav_env.reproduce.paper003 import DRIFT_STD, GYRO_STD, RATE_HZ, run_config
from pednav_env.sensors.imu import DriftModel

RUNS = 16


@pytest.fixture(scope="module")
def white():
    return run_config(1.0, 0.1, RUNS, seed=7, drift_model=DriftModel.PER_SAMPLE)


@pytest.fixture(scope="module")
def per_step():
    return run_config(1.0, 0.1, RUNS, seed=7, drift_model=DriftModel.PER_GAIT_STEP)


def test_yaw_error_is_the_gyro_random_walk(white):
    q = (GYRO_STD**2 + DRIFT_STD**2) / RATE_HZ
    duration = white.truth.t[-1] - white.run.start_sample / RATE_HZ
    predicted = math.sqrt(q * duration / 2)
    assert 0.6 * predicted < white.metrics["sigma_psi"] < 1.4 * predicted


def test_tilt_errors_are_small(white, per_step):
    for res in (white, per_step):
        assert res.metrics["sigma_theta"] < 0.03
        assert res.metrics["sigma_gamma"] < 0.03


def test_drift_reading_matters(white, per_step):
    assert per_step.metrics["sigma_x"] > 2 * white.metrics["sigma_x"]
    assert per_step.metrics["sigma_psi"] > 2 * white.metrics["sigma_psi"]


def test_detection_is_clean_at_nominal_noise(white):
    assert white.metrics["false_stance_pct"] == 0.0
    assert white.metrics["missed_stance_pct"] < 1.0
    assert 1.9 < white.metrics["zupts_per_stride"] < 2.5  # start + end, rare splits


def test_resized_thresholds_make_false_stances_at_high_noise():
    """Table 2's σ_f = 1 m/s²: thresholds sized for the noise admit swing samples."""
    res = run_config(1.0, 1.0, 4, seed=7, resized_thresholds=True, square_side_m=3.0)
    fixed = run_config(1.0, 1.0, 4, seed=7, square_side_m=3.0)
    assert res.metrics["false_stance_pct"] > 0.5
    assert fixed.metrics["missed_stance_pct"] > 30.0  # fixed thresholds miss instead


def test_cli_json_follows_the_contract(capsys):
    assert main(["reproduce", "003", "--runs", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["paper"] == "003" and out["seconds"] > 0
    configs = {r["config"] for r in out["rows"]}
    assert {
        "table1_step_0.5m",
        "table1_step_1.0m",
        "table2_sigma_f_0.1",
        "table2_sigma_f_0.2",
        "table2_sigma_f_1.0",
    } <= configs
    for row in out["rows"]:
        assert set(row) == {"config", "metric", "unit", "paper", "ours"}
        assert math.isfinite(row["ours"])
    paper = {(r["config"], r["metric"]): r["paper"] for r in out["rows"]}
    assert paper[("table1_step_0.5m", "sigma_x")] == 0.064
    assert paper[("table2_sigma_f_1.0", "sigma_psi")] == 0.031
    for metric in ("sigma_x", "sigma_theta", "sigma_gamma", "sigma_psi"):
        assert (("table1_step_1.0m", metric)) in paper


def test_cli_rejects_unknown_paper(capsys):
    assert main(["reproduce", "042"]) == 2
    assert "paper_id" in capsys.readouterr().err
