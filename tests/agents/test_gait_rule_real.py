"""The gait rule fitted on recordings (agents.gait_rule_real, `pednav fit-rule`):
its objective, folds, loader errors, agreement with `pednav run`, and the CLI."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest
from testdata import DATA, HALLWAY_DATA, PYSHOE_SAMPLE

from agents.cli import main
from agents.gait_rule import GaitRuleParams, read_params, write_params
from agents.gait_rule_real import (
    ARMSE_KEY,
    FOOTPRINT_KEY,
    FitRecording,
    cross_validate,
    fit,
    folds,
    load_fit_recordings,
    objective,
    recording_errors,
)
from agents.run_recording import run_with_policy, summarize

HALLWAY_MAT = HALLWAY_DATA / "SensorConnectData_31_first9s_LLIO.mat"
XIO = DATA / "xio_short_walk_13.5-17s.csv"


def fake(name: str, group: str) -> FitRecording:
    return FitRecording(name, group, None, ARMSE_KEY)  # type: ignore[arg-type]


def test_objective_is_the_mean_over_groups_of_mean_log10_errors():
    errors = np.array([[1.0, 10.0, 100.0], [0.1, 0.1, 1000.0]])
    got = objective(errors, ["a", "a", "b"])
    # row 0: group a mean(0, 1) = 0.5, group b 2 → 1.25; row 1: a −1, b 3 → 1.0
    np.testing.assert_allclose(got, [1.25, 1.0])


def test_folds_hold_out_contiguous_blocks_of_every_group_once():
    recs = [fake(f"p{i}", "pyshoe") for i in (3, 0, 4, 1, 2)] + [
        fake(f"h{i}", "hallway") for i in (1, 0, 2)
    ]
    out = folds(recs, 2)
    names = [sorted(recs[i].name for i in f) for f in out]
    # pyshoe sorted p0..p4 → blocks [p0 p1 p2] [p3 p4]; hallway [h0 h1] [h2]
    assert names == [["h0", "h1", "p0", "p1", "p2"], ["h2", "p3", "p4"]]
    with pytest.raises(ValueError, match="group 'hallway' has 3 recordings, fewer than 4"):
        folds(recs, 4)
    with pytest.raises(ValueError, match="at least 2"):
        folds(recs, 1)


def test_cross_validate_refuses_sets_that_do_not_hold_out_each_recording_once():
    recs = [fake("a", "g"), fake("b", "g")]
    with pytest.raises(ValueError, match="held out exactly once"):
        cross_validate(recs, [np.array([0]), np.array([0])])


def test_loader_errors_name_the_path(tmp_path):
    with pytest.raises(ValueError, match=r"nope\.mat: no such file"):
        load_fit_recordings([tmp_path / "nope.mat"])
    with pytest.raises(ValueError, match="no recordings"):
        load_fit_recordings([tmp_path])
    with pytest.raises(ValueError, match="given twice"):
        load_fit_recordings([PYSHOE_SAMPLE, PYSHOE_SAMPLE])
    with pytest.raises(ValueError, match=r"xio_short_walk.*no truth track and no footprints"):
        load_fit_recordings([XIO])
    (tmp_path / "copy").mkdir()
    shutil.copy(PYSHOE_SAMPLE, tmp_path / "copy" / "other_name.mat")
    with pytest.raises(ValueError, match=r"other_name\.mat: the same samples as .*first7s\.mat"):
        load_fit_recordings([PYSHOE_SAMPLE, tmp_path / "copy"])


def test_one_walk_in_two_formats_is_refused():
    csv = HALLWAY_DATA / "SensorConnectData_31_first5s.csv"
    assert load_fit_recordings([csv])[0].metric == FOOTPRINT_KEY
    with pytest.raises(ValueError, match="same samples"):
        load_fit_recordings([csv, HALLWAY_MAT])


def test_groups_and_metrics_follow_the_files(tmp_path):
    (tmp_path / "a").mkdir()
    shutil.copy(PYSHOE_SAMPLE, tmp_path / "a" / "trial.mat")
    recs = load_fit_recordings([tmp_path / "a", HALLWAY_MAT])
    assert [(r.group, r.metric) for r in recs] == [("a", ARMSE_KEY), ("hallway", FOOTPRINT_KEY)]


@pytest.mark.parametrize("path", [PYSHOE_SAMPLE, HALLWAY_MAT])
def test_each_lane_scores_what_pednav_run_prints_for_its_parameters(tmp_path, path):
    [fr] = load_fit_recordings([path])
    cs = np.array([[0.3, 0.8, 0.0, -0.2, 0.1], [-0.4, 0.0, 0.5, 0.3, -0.6]])
    got = recording_errors(fr, cs, GaitRuleParams(c=(0.0,) * 5))
    for j, c in enumerate(cs):
        file = write_params(GaitRuleParams(c=tuple(c)), tmp_path / f"r{j}.json", {})
        run, _ = run_with_policy(fr.recording, str(file))
        assert got[j] == summarize(fr.recording, run)[fr.metric]
    assert got[0] != got[1]


def test_fit_is_never_worse_than_its_start():
    recs = load_fit_recordings([PYSHOE_SAMPLE, HALLWAY_MAT])
    params, record = fit(recs, generations=2, popsize=3, seed=3)
    assert record["objective_log10_m"] <= record["start_objective_log10_m"]
    errors = recording_errors(recs[0], np.array([params.c]), params)
    assert errors[0] == pytest.approx(record["errors_m"][recs[0].name], abs=1e-5)
    with pytest.raises(ValueError, match="popsize"):
        fit(recs, popsize=1)
    with pytest.raises(ValueError, match="at least one"):
        fit([])
    with pytest.raises(ValueError, match="simulated_episodes: must be ≥ 0, got -1"):
        fit(recs, simulated_episodes=-1)


def test_constant_fit_holds_the_slope_at_zero_and_searches_the_rest():
    recs = load_fit_recordings([PYSHOE_SAMPLE, HALLWAY_MAT])
    params, record = fit(recs, generations=2, popsize=3, seed=3, constant=True)
    assert params.c[1] == 0.0 and record["constant"] is True
    assert record["objective_log10_m"] <= record["start_objective_log10_m"]
    if not record["kept_start"]:
        assert params.c != tuple(record["initial_c"])
    rule, _ = fit(recs, generations=2, popsize=3, seed=3)
    assert rule.c[1] != 0.0  # without the flag the slope is searched


def test_cli_writes_a_rule_that_pednav_run_plays(tmp_path, capsys):
    out = tmp_path / "fit"
    argv = ["fit-rule", str(PYSHOE_SAMPLE), str(HALLWAY_MAT), "--out", str(out)]
    assert main([*argv, "--generations", "1", "--popsize", "2", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    params = read_params(out / "gait_rule.json")
    assert list(params.c) == printed["c"]
    assert main(["run", str(PYSHOE_SAMPLE), "--policy", str(out / "gait_rule.json"), "--json"]) == 0
    armse = json.loads(capsys.readouterr().out)[ARMSE_KEY]
    assert armse == pytest.approx(printed["errors_m"][PYSHOE_SAMPLE.stem], abs=1e-5)
    const = tmp_path / "const"
    argv = ["fit-rule", str(PYSHOE_SAMPLE), "--out", str(const), "--constant", "--json"]
    assert main([*argv, "--generations", "1", "--popsize", "2"]) == 0
    assert json.loads(capsys.readouterr().out)["c"][1] == 0.0
    assert read_params(const / "gait_rule.json").c[1] == 0.0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--folds", "1"], "--folds: 0 .* or at least 2, got 1"),
        (["--folds", "3"], "group 'replay' has 1 recordings, fewer than 3"),
        (["--simulated-episodes", "-1"], "--simulated-episodes: must be ≥ 0, got -1"),
    ],
)
def test_cli_bad_options_give_one_line(tmp_path, capsys, extra, message):
    argv = ["fit-rule", str(PYSHOE_SAMPLE), "--out", str(tmp_path / "o"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert re.search(message, err)


def test_cli_missing_recording_is_one_line(tmp_path, capsys):
    assert main(["fit-rule", str(tmp_path / "x.mat"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "x.mat: no such file or directory" in err and err.count("\n") == 1
