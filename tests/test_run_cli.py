"""`pednav run` for users: defaults, footprints, and every error path as one line
(exit code 2, no traceback)."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from agents.cli import main

DATA = Path(__file__).parent / "data"
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
