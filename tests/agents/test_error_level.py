"""agents.error_level (``pednav sim2real --nav``): the per-recording figures on
hand-built twins, the summary, the recordings it checks and skips, and the CLI."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from testdata import HALLWAY_DATA, PYSHOE_SAMPLE

from agents.choose_shoe import errors_by_recording
from agents.cli import main
from agents.error_level import (
    ErrorLevelReport,
    RecordingLevel,
    error_level,
    twin_key,
    twin_recordings,
    twin_seed,
    twin_speed,
    write_figure,
)
from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.path_turns import route_turn_range, turn_range
from pednav_env.calibration.sources import samples_from_recording
from pednav_env.io import Footprints, load_recording
from pednav_env.replay.setup import RealFilterSetup, real_fixed_setup

TWINS = np.arange(1, 21) / 10.0  # 0.1 … 2.0 m


def test_one_recording_against_hand_built_twins():
    row = RecordingLevel("r", 1.0, 30.0, 0.15, TWINS)
    # 5 % and 95 % of 20 sorted values: the 1st and the 19th; the median the 10th
    assert row.envelope_m == (0.1, 1.9)
    assert row.median_m == 1.0
    assert row.covered
    assert row.percentile == 5.0  # one twin below 0.15
    assert row.ratio == pytest.approx(1.0 / 0.15)
    assert not RecordingLevel("r", 1.0, 30.0, 0.05, TWINS).covered
    assert not RecordingLevel("r", 1.0, 30.0, 1.95, TWINS).covered
    tie = RecordingLevel("r", 1.0, 30.0, 1.0, TWINS)
    assert tie.percentile == 47.5  # 9 below, one tie counted half


def test_diverged_twins_are_infinite_errors():
    twins = np.append(TWINS[:19], math.inf)
    row = RecordingLevel("r", 1.0, 30.0, 5.0, twins)
    assert row.envelope_m == (0.1, 1.9)
    out = row.to_json()
    assert out["twins_diverged"] == 1
    assert out["twin_envelope_m"] == [0.1, 1.9]
    late = RecordingLevel("r", 1.0, 30.0, 5.0, np.append(TWINS[:18], [math.inf, math.inf]))
    assert late.envelope_m[1] == math.inf and late.covered
    assert late.to_json()["twin_envelope_m"][1] is None


def test_the_summary():
    rows = [
        RecordingLevel("a", 1.0, 30.0, 0.5, TWINS),  # median 1.0: ratio 2
        RecordingLevel("b", 1.0, 30.0, 4.0, TWINS),  # ratio 0.25, not covered
    ]
    report = ErrorLevelReport("m", 20, 0, rows, ["fp"])
    assert report.coverage == (1, 2)
    assert report.ratio_geomean == pytest.approx(math.sqrt(2 * 0.25))
    # a: 4 twins below 0.5 and one tie (22.5 %); b: all 20 below (100 %)
    assert report.mean_percentile == pytest.approx((22.5 + 100.0) / 2)
    out = report.to_json()
    assert out["covered"] == 1 and out["recordings"] == 2 and out["not_checked"] == ["fp"]
    text = report.format_text()
    assert "covered 1/2" in text and "not checked (no truth, no footprints or no speed): fp" in text


def test_twin_speeds():
    assert twin_speed(1.0) == pytest.approx((0.9, 1.1))
    assert twin_speed(0.05) == (0.1, 0.1)
    assert twin_speed(5.0) == (3.8, 3.8)


def test_footprint_walks_get_footprint_twins_and_bare_walks_are_listed():
    walk = load_recording(HALLWAY_DATA / "SensorConnectData_31_first5s.csv")
    bare = replace(load_recording(PYSHOE_SAMPLE), truth_pos=None)
    report = error_level([bare, walk], MODELS["calibrated"], walks=2, seed=3)
    assert report.not_checked == [bare.name]
    (row,) = report.rows
    assert row.name == walk.name and row.measure == "footprint error"
    assert row.error_m == pytest.approx(errors_by_recording(real_fixed_setup(), [walk])[walk.name])
    twins = twin_recordings(MODELS["calibrated"], 2, 1, (1.0, 1.1), 12.0, footprints=True)
    for twin in twins:
        # footprints at the last sample of each stance: the truth position there, and
        # no truth track left
        assert twin.truth_pos is None and twin.footprints is not None
        assert len(twin.footprints.sample) >= 5
    dense = twin_recordings(MODELS["calibrated"], 2, 1, (1.0, 1.1), 12.0, footprints=False)
    for a, b in zip(twins, dense, strict=True):
        np.testing.assert_array_equal(a.footprints.pos, b.truth_pos[a.footprints.sample, :2])
        # the foot stands there: the sample before is within the stance micro-motion's
        # fraction of a millimetre
        np.testing.assert_allclose(
            b.truth_pos[a.footprints.sample - 1, :2], a.footprints.pos, atol=1e-3
        )


def test_recordings_with_truth_get_twins():
    rec = load_recording(PYSHOE_SAMPLE)
    report = error_level([rec], MODELS["calibrated"], walks=2, seed=3)
    assert report.not_checked == []
    (row,) = report.rows
    assert row.measure == "PyShoe ARMSE"
    # the recording's own error is pednav run's
    assert row.error_m == pytest.approx(errors_by_recording(real_fixed_setup(), [rec])[rec.name])
    assert row.twins_m.shape == (2,) and np.all(row.twins_m > 0)
    assert row.duration_s == pytest.approx(rec.duration_s)
    again = error_level([rec], MODELS["calibrated"], walks=2, seed=3)
    assert again.rows[0].twins_m.tolist() == row.twins_m.tolist()
    other = error_level([rec], MODELS["calibrated"], walks=2, seed=4)
    assert other.rows[0].twins_m.tolist() != row.twins_m.tolist()
    with pytest.raises(ValueError, match="walks must be ≥ 2"):
        error_level([rec], MODELS["calibrated"], walks=1)


def test_twins_walk_the_recordings_turns():
    # the PyShoe trial walks circles: its twins turn within its own range per stride;
    # measured on the twins' truth, not taken from the twins' draws
    rec = load_recording(PYSHOE_SAMPLE)
    turn = route_turn_range(samples_from_recording(rec))
    assert turn is not None and turn[0] > 0.3  # the trials' circles, ~1 rad per stride
    report = error_level([rec], MODELS["calibrated"], walks=2, seed=3, twins="circles")
    assert report.rows[0].turn_rad == turn
    assert report.rows[0].to_json()["twin_turn_per_stride_rad"] == list(turn)
    assert report.rows[0].form == "circles"
    assert "length and turn per stride" in report.format_text()
    twins = twin_recordings(MODELS["calibrated"], 2, 7, (0.9, 1.1), 30.0, False, turn)
    for t in twins:
        lo, hi = turn_range(samples_from_recording(t))
        assert turn[0] - 0.1 < lo <= hi < turn[1] + 0.1
    straight = error_level([rec], MODELS["calibrated"], 2, 3, twins="straight")
    assert straight.rows[0].turn_rad is None
    assert "turn per stride" not in straight.format_text()
    assert "straight legs" in straight.format_text()
    # by default the twins walk the recording's own strides
    walked = error_level([rec], MODELS["calibrated"], 2, 3)
    assert walked.rows[0].form == "footfalls"
    assert walked.rows[0].to_json()["twins_walk"] == "footfalls"
    assert "walking each recording's own strides" in walked.format_text()
    with pytest.raises(ValueError, match="twins must be one of"):
        error_level([rec], MODELS["calibrated"], 2, 3, twins="loops")
    assert straight.rows[0].twins_m.tolist() != report.rows[0].twins_m.tolist()


def test_cli_nav(tmp_path, capsys: pytest.CaptureFixture[str]):
    args = ["sim2real", str(PYSHOE_SAMPLE), "--walks", "2", "--nav", "--nav-walks", "2"]
    assert main([*args, "--json"]) == 0
    level = json.loads(capsys.readouterr().out)["error_level"]
    assert level["recordings"] == 1 and level["walks"] == 2
    assert main(args) == 0
    assert "error level: real-fixed's PyShoe ARMSE" in capsys.readouterr().out
    assert main([*args, "--nav-twins", "straight"]) == 0
    assert "straight legs" in capsys.readouterr().out
    with pytest.raises(SystemExit) as refused:  # argparse refuses an unknown form
        main([*args, "--nav-twins", "loops"])
    assert refused.value.code == 2 and "--nav-twins" in capsys.readouterr().err
    assert main([*args, "--plot", str(tmp_path)]) == 0
    assert f"wrote {tmp_path / 'error_level_calibrated.png'}" in capsys.readouterr().err
    assert main(["sim2real", str(PYSHOE_SAMPLE), "--nav", "--nav-walks", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--nav-walks must be ≥ 2" in err and "\n" not in err
    assert main(["sim2real", str(PYSHOE_SAMPLE), "--nav", "--nav-setup", "nowhere.json"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--nav-setup: setup file nowhere.json not found" in err and "\n" not in err


def test_cli_nav_setup(tmp_path, capsys: pytest.CaptureFixture[str]):
    # another setup, from a file: its name in the report, its own error on the recording
    high = real_fixed_setup().to_dict()
    high["detector"]["threshold"] = 1.3e9
    path = tmp_path / "high.json"
    path.write_text(json.dumps(high))
    args = ["sim2real", str(PYSHOE_SAMPLE), "--walks", "2", "--nav", "--nav-walks", "2"]
    assert main([*args, "--nav-setup", str(path), "--json"]) == 0
    level = json.loads(capsys.readouterr().out)["error_level"]
    assert level["setup"] == str(path)
    rec = load_recording(PYSHOE_SAMPLE)
    own = errors_by_recording(RealFilterSetup.from_dict(high), [rec])[rec.name]
    assert level["rows"][0]["error_m"] == pytest.approx(own)
    assert own != pytest.approx(errors_by_recording(real_fixed_setup(), [rec])[rec.name])


def test_the_figure(tmp_path):
    rows = [
        RecordingLevel("a", 1.0, 30.0, 0.5, TWINS),
        RecordingLevel("b", 1.4, 30.0, 4.0, np.append(TWINS[:19], math.inf)),
        RecordingLevel("c", 1.2, 60.0, 0.3, TWINS, "footprint error"),
    ]
    path = write_figure(ErrorLevelReport("m", 20, 0, rows, []), tmp_path)
    assert path == tmp_path / "error_level_m.png"
    assert path.stat().st_size > 10_000
    assert write_figure(ErrorLevelReport("m", 20, 0, [], ["x"]), tmp_path / "none") is None


def _twins_by_name(report: ErrorLevelReport) -> dict[str, list[float]]:
    return {r.name: r.twins_m.tolist() for r in report.rows}


def test_a_recordings_twins_do_not_depend_on_the_others_or_their_order():
    trial = load_recording(PYSHOE_SAMPLE)
    walk = load_recording(HALLWAY_DATA / "SensorConnectData_31_first5s.csv")
    model = MODELS["calibrated"]
    alone = {
        **_twins_by_name(error_level([trial], model, walks=2, seed=3)),
        **_twins_by_name(error_level([walk], model, walks=2, seed=3)),
    }
    first = _twins_by_name(error_level([trial, walk], model, walks=2, seed=3))
    second = _twins_by_name(error_level([walk, trial], model, walks=2, seed=3))
    assert first == second == alone
    # the two recordings' twins differ: the key is the recording's
    assert alone[trial.name] != alone[walk.name]


def test_the_twin_key_is_the_walks_footfalls_not_its_file():
    mat = load_recording(HALLWAY_DATA / "SensorConnectData_31_first9s_LLIO.mat")
    csv = load_recording(HALLWAY_DATA / "SensorConnectData_31_first5s.csv")
    # the CSV excerpt holds the footprints before sample 1000 (5 s at 200 Hz): the .mat
    # cut to those is the same walk read from another file
    assert mat.footprints is not None and csv.footprints is not None
    early = np.asarray(mat.footprints.sample) < 1000
    cut = replace(
        mat,
        footprints=Footprints(
            np.asarray(mat.footprints.sample)[early],
            np.asarray(mat.footprints.pos)[early],
            mat.footprints.source,
        ),
    )
    key = twin_key(samples_from_recording(csv))
    assert twin_key(samples_from_recording(cut)) == key
    assert twin_key(samples_from_recording(mat)) != key  # more footfalls: another walk
    assert twin_seed(5, samples_from_recording(csv)) == (5, key)
    assert 0 <= key < 2**64
    # a walk under another name keeps its key; a walk without footfall points has its
    # name's
    trial = samples_from_recording(load_recording(PYSHOE_SAMPLE))
    assert twin_key(replace(trial, name="renamed")) == twin_key(trial)
    bare = replace(trial, truth_pos=None)
    assert twin_key(bare) != twin_key(replace(bare, name="renamed"))
    with pytest.raises(ValueError, match="seed must be ≥ 0"):
        twin_seed(-1, trial)


def test_the_cli_and_the_library_draw_the_same_twins(capsys: pytest.CaptureFixture[str]):
    walk_path = HALLWAY_DATA / "SensorConnectData_31_first5s.csv"
    args = ["sim2real", str(PYSHOE_SAMPLE), str(walk_path), "--walks", "2", "--nav"]
    assert main([*args, "--nav-walks", "2", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["error_level"]["rows"]
    walk = load_recording(walk_path)
    (library,) = error_level([walk], MODELS["calibrated"], walks=2, seed=0).rows
    (cli,) = (r for r in rows if r["name"] == walk.name)
    assert cli["twin_key"] == library.key == twin_key(samples_from_recording(walk))
    assert cli["twin_median_m"] == library.median_m
    assert cli["twin_envelope_m"] == list(library.envelope_m)
