"""`pednav run` for users: defaults, footprints, and every error path as one line
(exit code 2, no traceback)."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from testdata import DATA

from agents.cli import main

XIO = DATA / "xio_short_walk_13.5-17s.csv"
PYSHOE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
HALLWAY_MAT = DATA / "hallway" / "SensorConnectData_31_first9s_LLIO.mat"
HALLWAY_CSV = DATA / "hallway" / "SensorConnectData_31_first5s.csv"
FOOTPRINT_KEYS = {
    "footprints",
    "footprint_mean_error_m",
    "footprint_final_error_m",
    "footprint_final_error_pct",
}


def one_line_error(capsys, argv: list[str], pattern: str) -> str:
    """Run the CLI expecting a clean failure: exit code 2, one stderr line, no traceback."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    assert re.search(pattern, err), err
    return err


def test_default_policy_is_real_fixed(capsys):
    assert main(["run", str(PYSHOE), "--json"]) == 0
    default = json.loads(capsys.readouterr().out)
    assert main(["run", str(PYSHOE), "--json", "--policy", "real-fixed"]) == 0
    assert json.loads(capsys.readouterr().out) == default
    assert main(["run", str(PYSHOE), "--json", "--policy", "paper"]) == 0
    assert json.loads(capsys.readouterr().out) != default


def test_footprint_walks_report_footprint_errors(capsys, tmp_path):
    plot = tmp_path / "top.png"
    assert main(["run", str(HALLWAY_MAT), "--json", "--plot", str(plot)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert FOOTPRINT_KEYS <= set(out) and "loop_closure_m" not in out
    assert out["footprints"] == 6
    # 9 s of a straight walk: real-fixed stays within decimetres of the footprints
    assert out["footprint_mean_error_m"] < 0.2 and out["footprint_final_error_pct"] < 5
    assert plot.stat().st_size > 1000
    assert main(["run", str(HALLWAY_CSV), "--footprints", "none", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert not FOOTPRINT_KEYS & set(out) and "loop_closure_m" in out
    assert main(["run", str(HALLWAY_CSV)]) == 0
    assert "footprint error" in capsys.readouterr().out


def test_unknown_policy_lists_real_fixed(capsys):
    err = one_line_error(capsys, ["run", str(XIO), "--policy", "nonsense"], "unknown policy")
    assert "real-fixed" in err and "paper" in err


def test_the_privileged_oracle_is_refused_on_recordings(capsys):
    """The oracle reads the simulator's true context: not on a recording, in one line,
    for one file and a folder, with or without a family suffix."""
    for argv in (
        ["run", str(PYSHOE), "--policy", "oracle"],
        ["run", str(DATA / "replay"), "--policy", "oracle:shoe"],
    ):
        one_line_error(capsys, argv, "oracle: not applicable on recordings")


def test_short_csv_is_a_clear_error(capsys, tmp_path):
    p = tmp_path / "short.csv"
    p.write_text("\n".join(XIO.read_text().splitlines()[:51]) + "\n")  # 50 rows, 0.13 s
    one_line_error(capsys, ["run", str(p)], r"short: 50 samples .*all of them the still start")


def test_unreadable_files_are_clear_errors(capsys, tmp_path):
    p = tmp_path / "small.mat"
    p.write_bytes(b"hello world, not a mat")
    one_line_error(capsys, ["run", str(p)], r"small.mat: not a readable MATLAB .mat file")
    p = tmp_path / "blob.csv"
    p.write_bytes(np.random.default_rng(0).bytes(3000))
    one_line_error(capsys, ["run", str(p)], r"blob.csv: a binary file")
    p = tmp_path / "walk.csv"
    shutil.copy(HALLWAY_CSV, p)
    one_line_error(capsys, ["run", str(p)], r"walk.csv: its footprint file walk_footprints.csv")


def test_plot_into_a_missing_directory_fails_before_the_run(capsys, tmp_path):
    target = tmp_path / "nodir" / "x.png"
    one_line_error(capsys, ["run", str(PYSHOE), "--plot", str(target)], r"directory .*nodir")
    assert not target.parent.exists()


def test_messages_have_no_numpy_reprs_and_say_where_units_came_from(capsys, tmp_path):
    lines = XIO.read_text().splitlines()
    lines[40], lines[41] = lines[41], lines[40]
    p = tmp_path / "swapped.csv"
    p.write_text("\n".join(lines) + "\n")
    err = one_line_error(capsys, ["run", str(p)], r"time goes backwards: line \d+ has t=\d")
    assert "np.float64" not in err
    t = np.arange(400) / 200.0
    data = np.column_stack((t, np.zeros((400, 3)), np.tile([0.0, 0.0, 1.0], (400, 1))))
    p = tmp_path / "g.csv"
    np.savetxt(
        p,
        data,
        delimiter=",",
        header="time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z",
        comments="",
    )
    err = one_line_error(capsys, ["run", str(p)], r"looks like g")
    assert "declared" not in err and "no unit given: SI assumed" in err
    assert "--layout" in err  # the command-line way, not only the Python class


def synthetic_walk_csv(path: Path, header: str, time: bool = True, scale=(1.0, 1.0)) -> Path:
    """The PyShoe excerpt as a CSV with other column names; gyro × scale[0], accel × scale[1]."""
    from pednav_env.io import load_recording

    rec = load_recording(PYSHOE)
    cols = [rec.omega_b * scale[0], rec.f_b * scale[1]]
    if time:
        cols.insert(0, rec.time[:, None])
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=header, comments="")
    return path


def test_loader_options_on_the_command_line(capsys, tmp_path):
    assert main(["run", str(PYSHOE), "--json", "--footprints", "none"]) == 0
    reference = json.loads(capsys.readouterr().out)
    # other names and deg/s, given as an inline layout
    p = synthetic_walk_csv(tmp_path / "named.csv", "t,wx,wy,wz,ax,ay,az", scale=(180 / np.pi, 1.0))
    layout = '{"time": "t", "gyro": ["wx", "wy", "wz"], "accel": ["ax", "ay", "az"], '
    layout += '"gyro_unit": "deg/s"}'
    assert main(["run", str(p), "--json", "--layout", layout]) == 0
    out = json.loads(capsys.readouterr().out)
    # same samples up to the text round trip: the same track to the millimetre
    assert out["final_position_m"] == pytest.approx(reference["final_position_m"], abs=1e-3)
    # a layout file, and a file without a time column with --rate
    layout_si = layout.replace(', "gyro_unit": "deg/s"', "")
    (tmp_path / "layout.json").write_text(layout_si)
    p = synthetic_walk_csv(tmp_path / "notime.csv", "wx,wy,wz,ax,ay,az", time=False)
    argv = ["run", str(p), "--json", "--layout", str(tmp_path / "layout.json"), "--rate", "200"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rate_hz"] == 200.0
    one_line_error(capsys, ["run", str(p), "--layout", layout_si], r"--rate HZ")
    one_line_error(
        capsys, ["run", str(p), "--layout", '{"gyro_units": "deg/s"}'], r"unknown layout key"
    )
    one_line_error(capsys, ["run", str(PYSHOE), "--layout", "{}"], r"generic CSV format")


def test_unit_check_gap_and_saturation_options(capsys, tmp_path):
    p = synthetic_walk_csv(tmp_path / "g.csv", "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z")
    lines = p.read_text().splitlines()
    del lines[600:640]  # 0.2 s missing
    p.write_text("\n".join(lines) + "\n")
    one_line_error(capsys, ["run", str(p)], r"gap of 0.20\d s before line 601")
    assert main(["run", str(p), "--max-gap", "0.5", "--json"]) == 0
    capsys.readouterr()
    with pytest.raises(SystemExit):  # argparse refuses a gap of 0
        main(["run", str(p), "--max-gap", "0"])
    capsys.readouterr()
    q = synthetic_walk_csv(
        tmp_path / "in_g.csv",
        "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z",
        scale=(1.0, 1 / 9.80665),
    )
    one_line_error(capsys, ["run", str(q)], r"looks like g")
    # without the check the file runs (and the filter, fed g as m/s², cannot align)
    assert main(["run", str(q), "--no-unit-check"]) in (0, 2)
    capsys.readouterr()
    one_line_error(
        capsys, ["run", str(PYSHOE), "--gyro-range", "2", "--saturation", "error"], r"saturated"
    )


def test_a_folder_gives_a_summary_table_and_json(capsys, tmp_path):
    folder = tmp_path / "walks"
    folder.mkdir()
    for p in (PYSHOE, HALLWAY_MAT, XIO):
        shutil.copy(p, folder)
    (folder / "broken.mat").write_bytes(b"junk")
    assert main(["run", str(folder)]) == 1  # one recording failed
    text = capsys.readouterr().out
    assert re.search(r"broken.mat +error: broken.mat: not a readable MATLAB", text)
    assert "3 of 4 recordings run, 1 failed" in text
    (folder / "broken.mat").unlink()
    plots, tracks = tmp_path / "plots", tmp_path / "tracks"
    argv = ["run", str(folder), "--json", "--plot", str(plots), "--out", str(tracks)]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    rows = {r["recording"]: r for r in result["recordings"]}
    assert result["policy"] == "real-fixed" and len(rows) == 3
    assert "armse_m" in rows[PYSHOE.name] and "footprints" in rows[HALLWAY_MAT.name]
    assert "loop_closure_m" in rows[XIO.name] and rows[XIO.name]["issues"] >= 1
    # the numbers of the recording run alone; with --out the filter advances sample
    # by sample, which changes only rounding (micrometres here)
    assert main(["run", str(PYSHOE), "--json"]) == 0
    alone = json.loads(capsys.readouterr().out)
    for k, v in alone.items():
        assert rows[PYSHOE.name][k] == pytest.approx(v, abs=1e-6), k
    assert sorted(p.name for p in plots.iterdir()) == sorted(
        f"{p.stem}.png" for p in (PYSHOE, HALLWAY_MAT, XIO)
    )
    assert len(list(tracks.glob("*_track.csv"))) == 3


def test_out_writes_the_track(capsys, tmp_path):
    out = tmp_path / "track.csv"
    assert main(["run", str(HALLWAY_MAT), "--json", "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data.shape == (1800, 21)
    np.testing.assert_allclose(data[-1, 1:4], summary["final_position_m"], atol=1e-6)
    one_line_error(
        capsys, ["run", str(PYSHOE), "--out", str(tmp_path / "no" / "t.csv")], "does not exist"
    )


def test_policy_from_a_setup_json(capsys, tmp_path):
    from pednav_env.replay.setup import REAL_FIXED_FILE, named_setup

    assert main(["run", str(PYSHOE), "--json", "--policy", str(REAL_FIXED_FILE)]) == 0
    shipped = json.loads(capsys.readouterr().out)
    assert main(["run", str(PYSHOE), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == shipped  # real_fixed.json is real-fixed
    d = named_setup("real-fixed").to_dict()
    d["detector"]["threshold"] = 5e6  # a stricter SHOE threshold: another track
    p = tmp_path / "mine.json"
    p.write_text(json.dumps(d))
    assert main(["run", str(PYSHOE), "--json", "--policy", str(p)]) == 0
    assert json.loads(capsys.readouterr().out) != shipped
    del d["detector"]
    p.write_text(json.dumps(d))
    one_line_error(capsys, ["run", str(PYSHOE), "--policy", str(p)], r"mine.json: .*'detector'")
    p.write_text("{not json")
    one_line_error(capsys, ["run", str(PYSHOE), "--policy", str(p)], r"mine.json: not a JSON")


def test_plot_draws_a_sparse_reference(tmp_path):
    """Truth at one sample in 100 (NaN elsewhere, also at the start of navigation):
    the reference is placed and turned as in the metrics, not dropped."""
    from pednav_env.io import Recording, load_recording
    from pednav_env.replay.metrics import aligned_reference, track_errors
    from pednav_env.replay.runner import prepare, run_prepared
    from pednav_env.replay.setup import named_setup

    rec = load_recording(PYSHOE)
    sparse = np.full_like(rec.truth_pos, np.nan)
    sparse[250::100] = rec.truth_pos[250::100]
    srec = Recording(rec.time, rec.omega_b, rec.f_b, sparse, name="sparse")
    run = run_prepared(prepare(srec, named_setup("real-fixed")))
    ref = aligned_reference(run.pos[0], sparse, run.start_sample)
    ok = np.isfinite(ref).all(axis=1)
    assert ok.sum() == len(range(250, len(sparse), 100))
    # at the referenced samples the error is what the metrics average
    err = np.linalg.norm(run.pos[0, ok, :2] - ref[ok], axis=1)
    assert err.mean() == pytest.approx(
        track_errors(run.pos[0], sparse, run.start_sample)["armse_m"]
    )
    from agents.run_plot import write_plot

    write_plot(srec, run, tmp_path / "sparse.png", "real-fixed")
    assert (tmp_path / "sparse.png").stat().st_size > 1000


def test_pednav_run_json_keys_with_truth(capsys, tmp_path):
    plot = tmp_path / "top.png"
    assert main(["run", str(PYSHOE), "--json", "--plot", str(plot)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {
        "duration_s",
        "rate_hz",
        "navigation_start_s",
        "distance_m",
        "final_position_m",
        "stances",
        "armse_m",
        "armse_pyshoe_m",
        "final_error_m",
        "truth_glitches",
        "truth_glitch_samples",
    }
    assert out["rate_hz"] == pytest.approx(200, rel=0.01) and len(out["final_position_m"]) == 3
    assert plot.stat().st_size > 1000


def test_pednav_run_json_keys_without_truth_and_text(capsys):
    assert main(["run", str(XIO), "--format", "xio", "--policy", "real-fixed", "--json"]) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert set(out) == {
        "duration_s",
        "rate_hz",
        "navigation_start_s",
        "distance_m",
        "final_position_m",
        "stances",
        "loop_closure_m",
    }
    assert "duplicate_rows_removed" in captured.err  # issues go to stderr
    assert main(["run", str(XIO)]) == 0
    assert "loop closure" in capsys.readouterr().out


def test_pednav_run_errors_are_reported(capsys):
    assert main(["run", str(XIO), "--policy", "nonsense"]) == 2
    assert "unknown policy" in capsys.readouterr().err
    assert main(["run", str(XIO), "--format", "pyshoe"]) == 2


def test_check_policies_refuses_in_one_line_before_a_run():
    from agents.run_recording import check_policies

    check_policies(["real-fixed", "tuned", "gait-rule"])
    with pytest.raises(SystemExit, match=r"^--policies oracle: .*not applicable on recordings"):
        check_policies(["real-fixed", "oracle"])
    with pytest.raises(SystemExit, match=r"^--only bogus: unknown policy"):
        check_policies(["bogus"], option="--only")


def test_truth_glitches_are_reported(capsys, tmp_path):
    """A tracking dropout written into a simulated walk's reference (held for 0.3 s in
    a swing, then back: a jump far above 20 m/s) is counted, sample for sample; the
    walk as simulated has none."""
    walk = tmp_path / "walk.csv"
    assert main(["simulate", "--out", str(walk), "--duration", "20", "--seed", "3"]) == 0
    capsys.readouterr()
    assert main(["run", str(walk), "--json"]) == 0
    clean = json.loads(capsys.readouterr().out)
    assert clean["truth_glitches"] == 0 and clean["truth_glitch_samples"] == 0
    lines = walk.read_text().splitlines()
    header = lines[0].split(",")
    cols = [header.index(f"pos_{a} (m)") for a in "xy"]
    rows = [line.split(",") for line in lines[1:]]
    xy = np.array([[float(r[c]) for c in cols] for r in rows])
    speed = np.linalg.norm(np.diff(xy, axis=0), axis=1) * 200.0
    a = int(np.argmax(speed[800:] > 2.0)) + 800  # a swing after the still start
    b = a + 60  # 0.3 s at 200 Hz
    assert np.linalg.norm(xy[b] - xy[a]) * 200.0 > 20.0  # the jump back is a glitch
    for r in rows[a:b]:
        for c in cols:
            r[c] = rows[a][c]
    frozen = tmp_path / "frozen.csv"
    frozen.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    assert main(["run", str(frozen), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["truth_glitches"] == 1
    assert out["truth_glitch_samples"] == b - a + 1  # the frozen samples and the one after
    assert main(["run", str(frozen)]) == 0
    assert "truth glitches   1 (61 samples" in capsys.readouterr().out


def test_twins_policy_chooses_the_threshold_it_runs(capsys):
    """``--policy twins``: real-fixed with the SHOE threshold chosen on twins of the
    recording's own strides; the JSON reports the choice and the run uses it."""
    from agents.run_recording import summarize
    from agents.twin_choice import TWIN_THRESHOLDS, with_threshold
    from pednav_env.io import load_recording
    from pednav_env.replay.runner import prepare, run_prepared
    from pednav_env.replay.setup import real_fixed_setup

    assert main(["run", str(PYSHOE), "--json", "--policy", "twins"]) == 0
    out = json.loads(capsys.readouterr().out)
    choice = out["twin_choice"]
    assert choice["shoe_threshold"] in TWIN_THRESHOLDS
    assert choice["twin_metric"] == "armse" and choice["twins"] == 20
    assert choice["route_strides"] >= 3
    medians = [m for m in choice["twin_median_m"].values() if m is not None]
    assert len(choice["twin_median_m"]) == len(TWIN_THRESHOLDS)
    assert min(medians) == choice["twin_median_m"][f"{choice['shoe_threshold']:.4g}"]
    chosen = with_threshold(real_fixed_setup(), choice["shoe_threshold"])
    rec = load_recording(PYSHOE)
    expected = summarize(rec, run_prepared(prepare(rec, chosen)))
    assert out["armse_pyshoe_m"] == pytest.approx(expected["armse_pyshoe_m"], rel=1e-12)
    assert main(["run", str(PYSHOE), "--policy", "twins"]) == 0
    assert "chosen on 20 simulated twins" in capsys.readouterr().out


def test_twins_policy_on_footprint_walks_scores_twins_by_footprints(capsys):
    assert main(["run", str(HALLWAY_MAT), "--json", "--policy", "twins"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["twin_choice"]["twin_metric"] == "footprints"
    assert FOOTPRINT_KEYS <= set(out)


def test_twins_policy_on_a_walk_too_short_for_twins_is_one_line(capsys):
    one_line_error(capsys, ["run", str(XIO), "--policy", "twins"], "strides in its route")


def test_unknown_policy_lists_twins(capsys):
    err = one_line_error(capsys, ["run", str(XIO), "--policy", "twin"], "unknown policy")
    assert "twins" in err
