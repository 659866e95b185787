"""The sim-vs-real comparison (calibration.compare) and `pednav sim2real`; the calibrated
stance dynamics are tested in tests/gait/test_stance_motion.py."""

from __future__ import annotations

import json
from dataclasses import asdict, replace
from pathlib import Path

import pytest
from scipy.stats import beta
from testdata import PYSHOE_SAMPLE

from agents.cli import main
from pednav_env.calibration.compare import (
    DEFAULT_WALKS_PER_BAND,
    MODELS,
    Sim2RealReport,
    band_of,
    compare,
    coverage_interval,
    model_from_json,
)
from pednav_env.calibration.sources import load_walk
from pednav_env.calibration.stats import walk_stats
from pednav_env.gait.stance_motion import StanceRandomization

DATA = Path(__file__).resolve().parents[3] / "shared" / "data"


def test_compare_envelope_and_coverage_on_the_test_excerpt() -> None:
    real = [walk_stats(load_walk(PYSHOE_SAMPLE))]
    report = compare(real, MODELS["calibrated"], walks_per_band=4, seed=1)
    out = report.to_json()
    assert out["recordings"] == 1 and len(out["bands"]) == 5
    band = next(b for b in report.bands if b.real)
    assert band.band == band_of(real[0].speed_mps)
    lo, hi = band.p10_envelope
    assert lo <= hi and out["covered"] == int(band.covered(real[0]))


@pytest.mark.parametrize(("covered", "total"), [(27, 31), (15, 31), (1, 4), (0, 5), (5, 5)])
def test_coverage_interval_is_clopper_pearson(covered: int, total: int) -> None:
    # the exact interval from its beta-quantile form (Clopper & Pearson 1934), written
    # out here rather than through scipy's binomtest, which the code uses
    lo = 0.0 if covered == 0 else beta.ppf(0.025, covered, total - covered + 1)
    hi = 1.0 if covered == total else beta.ppf(0.975, covered + 1, total - covered)
    assert coverage_interval(covered, total) == pytest.approx((lo, hi), abs=1e-9)


def test_coverage_interval_of_27_of_31_reaches_below_80_percent() -> None:
    # 27 of 31 (87 %) is above 80 % as a count, not by its interval (docs/SIM_TO_REAL.md)
    lo, hi = coverage_interval(27, 31)
    assert lo < 0.80 < 27 / 31 < hi


@pytest.mark.parametrize(("covered", "total"), [(3, 2), (-1, 4), (0, 0)])
def test_coverage_interval_rejects_impossible_counts(covered: int, total: int) -> None:
    with pytest.raises(ValueError, match="coverage_interval"):
        coverage_interval(covered, total)


def _p10_inside(report: Sim2RealReport) -> int:
    """Recordings whose p10 lies inside their band's simulated p10 envelope."""
    return sum(
        b.p10_envelope[0] <= s.log_shoe_p10 <= b.p10_envelope[1]
        for b in report.bands
        for s in b.real
    )


def test_calibrated_envelope_covers_development_recordings() -> None:
    # Not skipped when the recordings are missing: the check is part of the suite.
    assert DATA.is_dir(), f"the development recordings are read from {DATA} (../shared/data)"
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
    lo, hi = out["coverage_ci95"]
    assert 0.0 <= lo <= out["coverage_fraction"] <= hi <= 1.0 and hi - lo > 0.5


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["/nonexistent/walk.mat"], "no such file"),
        ([str(PYSHOE_SAMPLE), "--model", "nope"], "--model"),
        ([str(PYSHOE_SAMPLE), "--walks", "1"], "--walks must be ≥ 2"),
        # refused before any walk is simulated (the path is the recording, a file)
        ([str(PYSHOE_SAMPLE), "--plot", str(PYSHOE_SAMPLE)], "is a file; give a directory"),
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
    assert list(tmp_path.glob("sim2real_calibrated_0*.png"))  # a band's histogram
    assert (tmp_path / "sim2real_calibrated_strides.png").exists()
    out = capsys.readouterr().out
    assert "covered" in out and "per stride, by stride speed" in out


def test_model_from_json_reads_a_fit_output_and_a_plain_object(tmp_path: Path) -> None:
    shipped = StanceRandomization.calibrated()
    fit_output = tmp_path / "fit_output.json"
    fit_output.write_text(json.dumps({"names": [], "randomization": asdict(shipped)}))
    model = model_from_json(fit_output)
    assert model.name == "fit_output" and model.imu_grade == "microstrain_gx5"
    assert model.stance == shipped
    plain = tmp_path / "mine.json"
    plain.write_text(
        json.dumps({"flat_fraction": 0.3, "swing_speed_exponent": 0.4, "imu_grade": "adis16470"})
    )
    model = model_from_json(plain)
    assert model.imu_grade == "adis16470"
    # the given keys, and StanceRandomization's defaults for the others
    assert model.stance == StanceRandomization(flat_fraction=0.3, swing_speed_exponent=0.4)
    flags = tmp_path / "flags.json"
    flags.write_text(
        json.dumps({"heel_rocker": True, "monotone_pitch": True, "mid_pitch_midpoint": True})
    )
    assert model_from_json(flags).stance == StanceRandomization(
        heel_rocker=True, monotone_pitch=True, mid_pitch_midpoint=True
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{not json", "not a JSON file"),
        ("[1, 2]", "expected a JSON object"),
        ('{"quiet_mean": -2.0}', "unknown key 'quiet_mean'"),
        ('{"tau_hs_s": "0.1"}', "key 'tau_hs_s' must be a number"),
        ('{"tau_hs_s": true}', "key 'tau_hs_s' must be a number"),
        ('{"quiet_log10_std": 5.0}', "quiet_log10_std must be in [0, 2]"),
        ('{"imu_grade": "phone"}', "key 'imu_grade' 'phone' unknown"),
        ('{"randomization": {"edge_log10_mean": null}}', "key 'edge_log10_mean'"),
        ('{"heel_rocker": 1}', "key 'heel_rocker' must be true or false"),
        ('{"heel_rocker": "yes"}', "key 'heel_rocker' must be true or false"),
        ('{"monotone_pitch": 0}', "key 'monotone_pitch' must be true or false"),
    ],
)
def test_model_from_json_rejects_malformed_files(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "model.json"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"model\.json") as info:
        model_from_json(path)
    assert message in str(info.value)
    with pytest.raises(ValueError, match="cannot read"):
        model_from_json(tmp_path / "missing.json")


def test_cli_sim2real_model_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    good = tmp_path / "candidate.json"
    good.write_text(json.dumps(asdict(StanceRandomization.calibrated())))
    assert (
        main(["sim2real", str(PYSHOE_SAMPLE), "--walks", "3", "--json", "--model", str(good)]) == 0
    )
    assert json.loads(capsys.readouterr().out)["model"] == "candidate"
    bad = tmp_path / "broken.json"
    bad.write_text('{"heel_fraction": "wide"}')
    assert main(["sim2real", str(PYSHOE_SAMPLE), "--model", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "broken.json" in err and "'heel_fraction'" in err and "\n" not in err


def test_model_from_json_reads_the_heel_rocker_flag(tmp_path: Path) -> None:
    path = tmp_path / "rocker.json"
    path.write_text(json.dumps({**asdict(StanceRandomization.calibrated()), "heel_rocker": True}))
    assert model_from_json(path).stance == replace(
        StanceRandomization.calibrated(), heel_rocker=True
    )
    # a fit output written before the flag existed has no such key: off
    path.write_text(json.dumps({"randomization": {"flat_fraction": 0.3}}))
    assert model_from_json(path).stance.heel_rocker is False
