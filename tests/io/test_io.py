"""Recording loaders (pednav_env.io): the shipped samples and every validation path."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from testdata import DATA

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.io import (
    CsvLayout,
    LoadOptions,
    Recording,
    detect_format,
    load_csv,
    load_recording,
    to_uniform,
)
from pednav_env.io.saturation import bridge_saturated, quintic_bridge, saturation_mask

XIO = DATA / "xio_short_walk_13.5-17s.csv"
PYSHOE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
HEADER = "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"


def synthetic(n: int = 400, rate: float = 200.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Still for 1 s, then a rocking foot (rad/s, m/s²)."""
    t = np.arange(n) / rate
    w = np.zeros((n, 3))
    w[:, 1] = np.where(t > 1.0, 3.0 * np.sin(2 * np.pi * (t - 1.0)), 0.0)
    f = np.zeros((n, 3))
    f[:, 2] = STANDARD_GRAVITY
    f[:, 0] = np.where(t > 1.0, 2.0 * np.sin(2 * np.pi * (t - 1.0)), 0.0)
    return t, w, f


def write_csv(path: Path, t, w, f, header: str = HEADER, fmt: str = "%.9g") -> Path:
    data = np.column_stack((t, w, f))
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt=fmt)
    return path


# ------------------------------------------------------------------ shipped samples
def test_xio_sample_loads_in_si_units_with_its_duplicates_reported():
    rec = load_recording(XIO)
    assert detect_format(XIO) == "xio"
    assert rec.metadata["format"] == "xio"
    assert 395 < rec.rate_hz < 400
    assert not rec.has_truth
    norm = np.linalg.norm(rec.f_b[:100], axis=1).mean()
    assert norm == pytest.approx(STANDARD_GRAVITY, rel=0.01)  # g → m/s²
    assert np.abs(rec.omega_b).max() < 20  # deg/s → rad/s
    kinds = {i.kind for i in rec.issues}
    assert "duplicate_rows_removed" in kinds  # x-io logs repeat rows; reported, not silent
    dup = next(i for i in rec.issues if i.kind == "duplicate_rows_removed")
    assert all(r.startswith("line ") for r in dup.rows)
    data_lines = len(XIO.read_text().splitlines()) - 1
    assert rec.num_samples + dup.count == data_lines  # every line accounted for


def test_pyshoe_sample_loads_with_truth_and_reference_results():
    rec = load_recording(PYSHOE)
    assert rec.metadata["format"] == "pyshoe"
    assert rec.rate_hz == pytest.approx(200.0, rel=0.01)
    assert rec.has_truth and rec.truth_pos.shape == (rec.num_samples, 3)
    raw = scipy.io.loadmat(PYSHOE)["gt"]
    np.testing.assert_allclose(rec.truth_pos[:, 1], -raw[:, 1])  # right-handed, z up
    assert rec.metadata["reference_stance"].shape == (rec.num_samples,)
    assert rec.f_b[0, 2] < -9  # MicroStrain z points down: mounting is the runner's job


def test_recording_arrays_are_read_only_and_checked():
    t, w, f = synthetic()
    rec = Recording(t, w, f)
    with pytest.raises(ValueError):
        rec.omega_b[0, 0] = 1.0
    with pytest.raises(ValueError, match="strictly"):
        Recording(t[::-1], w, f)
    with pytest.raises(ValueError, match="omega_b"):
        Recording(t, w[:, :2], f)


# ------------------------------------------------------------------ generic CSV
def test_generic_csv_with_units_in_the_header(tmp_path):
    t, w, f = synthetic()
    header = (
        "time (ms),gyro_x (deg/s),gyro_y (deg/s),gyro_z (deg/s),"
        "accel_x [g],accel_y [g],accel_z [g],extra"
    )
    data = np.column_stack((t * 1e3, np.degrees(w), f / STANDARD_GRAVITY, np.zeros(len(t))))
    p = tmp_path / "walk.csv"
    np.savetxt(p, data, delimiter=",", header=header, comments="", fmt="%.12g")
    rec = load_recording(p)
    np.testing.assert_allclose(rec.time, t, atol=1e-9)
    np.testing.assert_allclose(rec.omega_b, w, atol=1e-9)
    np.testing.assert_allclose(rec.f_b, f, atol=1e-9)


def test_generic_csv_with_a_declared_layout_and_truth(tmp_path):
    t, w, f = synthetic()
    pos = np.column_stack((t, 0 * t, 0 * t)) * 1e3  # mm
    p = tmp_path / "walk.csv"
    np.savetxt(
        p,
        np.column_stack((pos, t, w, f)),
        delimiter=",",
        header="X,Y,Z,T,GX,GY,GZ,AX,AY,AZ",
        comments="",
        fmt="%.12g",
    )
    layout = CsvLayout(
        time="T",
        gyro=("GX", "GY", "GZ"),
        accel=("AX", "AY", "AZ"),
        truth=("X", "Y", "Z"),
        truth_unit="mm",
    )
    rec = load_csv(p, layout)
    np.testing.assert_allclose(rec.truth_pos[:, 0], t, atol=1e-9)


def test_missing_column_is_named(tmp_path):
    t, w, f = synthetic()
    p = write_csv(tmp_path / "a.csv", t, w, f, header=HEADER.replace("gyro_z", "gyro_q"))
    with pytest.raises(ValueError, match=r"missing column.*gyro_z"):
        load_recording(p)


def test_nan_and_unreadable_samples_name_the_line(tmp_path):
    t, w, f = synthetic()
    w[10, 1] = np.nan
    p = write_csv(tmp_path / "a.csv", t, w, f)
    # the file is named too (a folder's run or evaluation must say which one is bad)
    with pytest.raises(ValueError, match=r"^a\.csv: angular rate.*line 12"):
        load_recording(p)
    w[10, 1] = 0.0
    p = write_csv(tmp_path / "b.csv", t, w, f)
    lines = p.read_text().splitlines()
    fields = lines[5].split(",")
    fields[4] = "oops"
    lines[5] = ",".join(fields)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"line 6, column 'accel_x': 'oops' is not a number"):
        load_recording(p)
    w[3, 0] = np.inf
    p = write_csv(tmp_path / "c.csv", t, w, f)
    with pytest.raises(ValueError, match="line 5"):
        load_recording(p)


def test_time_going_backwards_names_the_line(tmp_path):
    t, w, f = synthetic()
    t[50] = t[48]
    p = write_csv(tmp_path / "a.csv", t, w, f)
    with pytest.raises(ValueError, match=r"time goes backwards: line 52"):
        load_recording(p)
    t, w, f = synthetic()
    t[250] = t[249]  # same time, different values (the foot moves)
    p = write_csv(tmp_path / "b.csv", t, w, f)
    with pytest.raises(ValueError, match=r"line 252 repeats"):
        load_recording(p)


def test_duplicate_rows_are_dropped_and_reported_or_refused(tmp_path):
    t, w, f = synthetic()
    idx = np.insert(np.arange(len(t)), 30, 29)
    p = write_csv(tmp_path / "a.csv", t[idx], w[idx], f[idx])
    rec = load_recording(p)
    assert rec.num_samples == len(t)
    issue = rec.issues[0]
    assert issue.kind == "duplicate_rows_removed" and issue.rows == ("line 32",)
    with pytest.raises(ValueError, match=r"duplicate rows.*line 32"):
        load_recording(p, options=LoadOptions(duplicates="error"))


def test_long_gap_is_an_error_and_short_gaps_are_filled(tmp_path):
    t, w, f = synthetic()
    t2 = t.copy()
    t2[200:] += 0.5
    with pytest.raises(ValueError, match=r"gap of 0.505 s before line 202"):
        load_recording(write_csv(tmp_path / "a.csv", t2, w, f))
    keep = np.ones(len(t), dtype=bool)
    keep[[100, 101, 250]] = False  # two gaps: 2 and 1 samples missing
    rec = load_recording(write_csv(tmp_path / "b.csv", t[keep], w[keep], f[keep]))
    gap = next(i for i in rec.issues if i.kind == "gap_filled")
    assert gap.count == 3 and gap.rows == ("line 102", "line 250")
    u = to_uniform(rec)
    assert u.num_samples == len(t) and u.filled.sum() == 3
    np.testing.assert_allclose(u.omega_b[~u.filled], rec.omega_b)
    # jitter that compensates itself is not a gap
    tj = t.copy()
    tj[100] += 0.0035
    rec = load_recording(write_csv(tmp_path / "c.csv", tj, w, f))
    assert to_uniform(rec).num_samples == len(t)
    assert any(i.kind == "time_jitter" for i in rec.issues)


def test_unit_mistakes_are_named(tmp_path):
    t, w, f = synthetic()
    p = write_csv(tmp_path / "g.csv", t, w, f / STANDARD_GRAVITY)  # g declared as m/s²
    with pytest.raises(ValueError, match="looks like g"):
        load_recording(p)
    header = HEADER.replace("accel_x", "accel_x (g)")
    p = write_csv(tmp_path / "m.csv", t, w, f, header=header)  # m/s² declared as g
    with pytest.raises(ValueError, match="looks like m/s"):
        load_recording(p)
    p = write_csv(tmp_path / "d.csv", t, np.degrees(w) * 20, f)  # deg/s declared as rad/s
    with pytest.raises(ValueError, match="look like deg/s"):
        load_recording(p)
    rec = load_recording(p, options=LoadOptions(check_units=False))
    assert rec.num_samples == len(t)
    with pytest.raises(ValueError, match="time column in seconds"):
        load_recording(write_csv(tmp_path / "ms.csv", t * 1e3, w, f))


def test_saturation_flagged_bridged_or_refused(tmp_path):
    t, w, f = synthetic(800)
    true_w = w.copy()
    limit = 2.5
    w[:, 1] = np.clip(w[:, 1], -limit, limit)
    p = write_csv(tmp_path / "s.csv", t, w, f)
    rec = load_recording(p)  # plateaus detected without a declared range
    sat = next(i for i in rec.issues if i.kind == "saturated")
    assert sat.count > 10 and sat.rows[0].startswith("line ")
    with pytest.raises(ValueError, match="saturated"):
        load_recording(p, options=LoadOptions(saturation="error"))
    rec = load_recording(p, options=LoadOptions(saturation="bridge", gyro_range=limit))
    assert any(i.kind == "saturation_bridged" for i in rec.issues)
    mask = np.abs(w[:, 1]) >= limit
    err_clipped = np.abs(w[mask, 1] - true_w[mask, 1]).max()
    err_bridged = np.abs(rec.omega_b[mask, 1] - true_w[mask, 1]).max()
    assert rec.omega_b[mask, 1].__abs__().max() > limit  # the bridge overshoots the range
    assert err_bridged < 0.3 * err_clipped


def test_quintic_bridge_is_c2_at_the_joins():
    d0, d1 = (1.0, -2.0, 3.0), (0.5, 1.0, -4.0)
    s = np.array([0.0, 1.0])
    y = quintic_bridge(0.0, d0, 1.0, d1, s)
    assert y[0] == pytest.approx(1.0) and y[1] == pytest.approx(0.5)
    h = 1e-5
    for t0, d in ((0.0, d0), (1.0, d1)):
        yp = quintic_bridge(0.0, d0, 1.0, d1, np.array([t0 - h, t0, t0 + h]))
        assert (yp[2] - yp[0]) / (2 * h) == pytest.approx(d[1], rel=1e-4)
        assert (yp[2] - 2 * yp[1] + yp[0]) / h**2 == pytest.approx(d[2], rel=1e-3)


def test_bridging_a_run_at_the_edge_is_refused():
    x = np.zeros((10, 3))
    x[:4, 0] = 5.0
    mask = saturation_mask(x, 5.0)
    with pytest.raises(ValueError, match="cannot be bridged"):
        bridge_saturated(np.arange(10.0), x, mask)


def test_pyshoe_missing_variable_and_nan_truth(tmp_path):
    p = tmp_path / "bad.mat"
    scipy.io.savemat(p, {"imu": np.zeros((10, 6))})
    with pytest.raises(ValueError, match="missing variable 'ts'"):
        load_recording(p)
    d = scipy.io.loadmat(PYSHOE)
    d["gt"][100:110] = np.nan
    p = tmp_path / "gap.mat"
    scipy.io.savemat(p, {k: v for k, v in d.items() if not k.startswith("__")})
    rec = load_recording(p)
    miss = next(i for i in rec.issues if i.kind == "truth_missing")
    assert miss.count == 10 and miss.rows[0] == "sample 100"
    assert math.isnan(rec.truth_pos[105, 0])


def test_unknown_format_and_file(tmp_path):
    with pytest.raises(ValueError, match="unknown format"):
        load_recording(XIO, format="bin")
    with pytest.raises(ValueError, match="no such file"):
        load_recording(tmp_path / "nope.csv")
