"""Walks with footprint truth: the .mat with ground control points, the SensorConnect
CSV with its footprint file, and every validation path (file and row named)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from testdata import HALLWAY_DATA

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.io import Footprints, detect_format, find_recordings, load_recording

MAT = HALLWAY_DATA / "SensorConnectData_31_first9s_LLIO.mat"
CSV = HALLWAY_DATA / "SensorConnectData_31_first5s.csv"
FOOTPRINTS = HALLWAY_DATA / "SensorConnectData_31_first5s_footprints.csv"
#: g the data set used to convert the vendor's g into the .mat's m/s².
MAT_G = 9.8029


def mat_copy(tmp_path: Path, **changes) -> Path:
    d = {k: v for k, v in scipy.io.loadmat(MAT).items() if not k.startswith("__")}
    for k, v in changes.items():
        if v is None:
            d.pop(k)
        else:
            d[k] = v
    p = tmp_path / "walk.mat"
    scipy.io.savemat(p, d)
    return p


def csv_copy(tmp_path: Path, footprint_lines: list[str] | None = None) -> Path:
    p = tmp_path / "walk.csv"
    shutil.copy(CSV, p)
    lines = FOOTPRINTS.read_text().splitlines() if footprint_lines is None else footprint_lines
    (tmp_path / "walk_footprints.csv").write_text("\n".join(lines) + "\n")
    return p


# ------------------------------------------------------------------ the shipped excerpts
def test_gcp_mat_loads_with_its_footprints_in_a_right_handed_frame():
    assert detect_format(MAT) == "gcp-mat"
    rec = load_recording(MAT)
    raw = scipy.io.loadmat(MAT)
    assert rec.num_samples == 1800 and rec.rate_hz == pytest.approx(200, rel=0.01)
    assert not rec.has_truth and rec.has_footprints
    fp = rec.footprints
    np.testing.assert_array_equal(fp.sample, raw["strideIndex"].ravel())
    np.testing.assert_array_equal(fp.pos[:, 0], raw["GCP"][:, 0])
    np.testing.assert_array_equal(fp.pos[:, 1], -raw["GCP"][:, 1])  # y negated (module docstring)
    np.testing.assert_array_equal(rec.f_b, raw["imu_data"][:, :3])
    np.testing.assert_array_equal(rec.omega_b, raw["imu_data"][:, 3:])


def test_sensorconnect_csv_equals_the_mat_and_finds_its_footprints():
    assert detect_format(CSV) == "sensorconnect"
    rec = load_recording(CSV)
    mat = load_recording(MAT)
    n = rec.num_samples
    assert n == 1000
    np.testing.assert_allclose(rec.time, mat.time[:n], atol=1e-12)
    np.testing.assert_allclose(rec.omega_b, mat.omega_b[:n], atol=1e-12)  # both rad/s
    # the CSV is in g (converted with standard g), the .mat used g = 9.8029
    np.testing.assert_allclose(rec.f_b, mat.f_b[:n] * STANDARD_GRAVITY / MAT_G, rtol=1e-9)
    np.testing.assert_array_equal(rec.footprints.sample, mat.footprints.sample[:3])
    np.testing.assert_allclose(rec.footprints.pos, mat.footprints.pos[:3])


def test_sensorconnect_filter_channels_in_m_s2_with_valid_flags(tmp_path):
    """The other SensorConnect export (the sensor's estimation filter, m/s²) and its
    validity flags; the footprints are placed by their timestamps."""
    lines = CSV.read_text().splitlines()
    head = lines[0].split(",")
    dev = head[1].split(":")[0]
    channels = ["estCompensatedAccelX", "estCompensatedAccelY", "estCompensatedAccelZ"]
    channels += ["estAngularRateX", "estAngularRateY", "estAngularRateZ"]
    header = ["Time"] + [c for ch in channels for c in (f"{dev}:{ch}", f"{dev}:{ch}:valid")]
    out = [",".join(header)]
    for line in lines[1:]:
        v = [float(x) for x in line.split(",")[:7]]
        acc = [a * STANDARD_GRAVITY for a in v[1:4]]
        cells = [f"{v[0]!r}"] + [c for x in acc + v[4:7] for c in (f"{x!r}", "1")]
        out.append(",".join(cells))
    p = tmp_path / "est.csv"
    p.write_text("\n".join(out) + "\n")
    shutil.copy(FOOTPRINTS, tmp_path / "est_footprints.csv")
    rec = load_recording(p)
    ref = load_recording(CSV)
    assert rec.metadata["format"] == "sensorconnect"
    np.testing.assert_allclose(rec.f_b, ref.f_b, atol=1e-9)
    np.testing.assert_array_equal(rec.footprints.sample, ref.footprints.sample)
    cells = out[301].split(",")
    cells[10] = "0"  # estAngularRateY:valid
    out[301] = ",".join(cells)
    p.write_text("\n".join(out) + "\n")
    with pytest.raises(ValueError, match=r"est.csv: line 302: .*estAngularRateY:valid.*not valid"):
        load_recording(p)


# ------------------------------------------------------------------ validation
def test_missing_footprint_file_is_an_error_unless_declined(tmp_path):
    p = tmp_path / "walk.csv"
    shutil.copy(CSV, p)
    with pytest.raises(ValueError, match=r"walk.csv: its footprint file walk_footprints.csv"):
        load_recording(p)
    rec = load_recording(p, footprints=None)
    assert not rec.has_footprints and rec.num_samples == 1000
    rec = load_recording(p, footprints=FOOTPRINTS)  # or named explicitly
    assert rec.footprints.count == 3


def test_footprints_outside_the_recording_name_the_line(tmp_path):
    lines = FOOTPRINTS.read_text().splitlines()
    lines.append("2000,10.0,-9.0,0.1")  # after the 5 s excerpt
    p = csv_copy(tmp_path, lines)
    with pytest.raises(ValueError, match=r"walk_footprints.csv: line 5: .*10.0000 s is outside"):
        load_recording(p)
    idx = scipy.io.loadmat(MAT)["strideIndex"].copy()
    idx[0, -1] = 1800  # one past the last sample
    with pytest.raises(ValueError, match=r"walk.mat: strideIndex\[5\]: .*1800 is outside"):
        load_recording(mat_copy(tmp_path, strideIndex=idx))


def test_bad_footprint_files_name_the_line(tmp_path):
    lines = FOOTPRINTS.read_text().splitlines()
    bad = lines.copy()
    bad[2] = bad[2].replace(bad[2].split(",")[2], "abc")
    with pytest.raises(ValueError, match=r"line 3, column 'gcpX': 'abc' is not a number"):
        load_recording(csv_copy(tmp_path, bad))
    bad = lines.copy()
    bad[3] = bad[3].replace(bad[3].split(",")[3], "nan")
    with pytest.raises(ValueError, match=r"walk_footprints.csv: line 4: NaN"):
        load_recording(csv_copy(tmp_path, bad))
    bad = [lines[0], lines[2], lines[1], lines[3]]
    with pytest.raises(ValueError, match=r"line 3: .*increase strictly"):
        load_recording(csv_copy(tmp_path, bad))
    with pytest.raises(ValueError, match=r"missing footprint column\(s\) \['gcpy'\]"):
        load_recording(csv_copy(tmp_path, [lines[0].replace("gcpY", "q")] + lines[1:]))


def test_gcp_mat_missing_or_bad_variables_are_named(tmp_path):
    with pytest.raises(ValueError, match=r"missing variable\(s\) \['GCP'\]"):
        load_recording(mat_copy(tmp_path, GCP=None))
    assert not load_recording(mat_copy(tmp_path, GCP=None), footprints=None).has_footprints
    with pytest.raises(ValueError, match=r"missing variable 'timestamps'"):
        load_recording(mat_copy(tmp_path, timestamps=None), format="gcp-mat")
    with pytest.raises(ValueError, match=r"positions must be 6×2"):
        load_recording(mat_copy(tmp_path, GCP=np.zeros((6, 3))))
    ts = scipy.io.loadmat(MAT)["timestamps"].copy()
    ts[0, 700] = ts[0, 650]
    with pytest.raises(
        ValueError, match=r"time goes backwards: sample 700 has t=3\.249969959 s, before"
    ):
        load_recording(mat_copy(tmp_path, timestamps=ts))
    imu = scipy.io.loadmat(MAT)["imu_data"].copy()
    imu[900, 4] = np.nan
    with pytest.raises(ValueError, match=r"angular rate: .*sample 900"):
        load_recording(mat_copy(tmp_path, imu_data=imu))


def test_footprints_validation():
    with pytest.raises(ValueError, match="≥ 2 footprints"):
        Footprints(np.array([3]), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="increase strictly"):
        Footprints(np.array([3, 3]), np.zeros((2, 2)))
    fp = Footprints(np.array([0, 10, 20]), np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 0.0]]))
    assert fp.count == 3 and fp.path_length_m == pytest.approx(9.0)


def test_find_recordings_skips_footprint_files():
    names = [p.name for p in find_recordings(HALLWAY_DATA)]
    assert names == [CSV.name, MAT.name]


def test_unreadable_files_are_named(tmp_path):
    p = tmp_path / "small.mat"
    p.write_text("not a MATLAB file")
    with pytest.raises(ValueError, match=r"small.mat: not a readable MATLAB .mat file"):
        load_recording(p)
    p = tmp_path / "other.mat"
    scipy.io.savemat(p, {"acc": np.zeros((3, 3))})
    with pytest.raises(ValueError, match=r"other.mat: not a known .mat layout"):
        load_recording(p)
    p = tmp_path / "binary.csv"
    p.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(ValueError, match=r"binary.csv: a binary file"):
        load_recording(p)
    p = tmp_path / "latin.csv"
    p.write_bytes("time,gyro_x (°/s)\n1,2\n".encode("latin-1"))
    with pytest.raises(ValueError, match=r"latin.csv: not UTF-8 text"):
        load_recording(p)


def test_a_footprint_file_for_a_generic_csv_is_taken_as_given(tmp_path):
    """Footprints for any format: placed by timestamp, positions not reflected."""
    rec = load_recording(MAT)
    p = tmp_path / "walk.csv"
    data = np.column_stack((rec.time, rec.omega_b, rec.f_b))
    header = "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    np.savetxt(p, data, delimiter=",", header=header, comments="", fmt="%.10g")
    fp = rec.footprints
    lines = ["strideIndex,timestamp,gcpX,gcpY"]
    for s, (x, y) in zip(fp.sample, fp.pos, strict=True):
        lines.append(f"{s},{float(rec.time[s])!r},{float(x)!r},{float(y)!r}")
    (tmp_path / "fp.csv").write_text("\n".join(lines) + "\n")
    got = load_recording(p, footprints=tmp_path / "fp.csv")
    assert got.metadata["format"] == "csv"
    np.testing.assert_array_equal(got.footprints.sample, fp.sample)
    np.testing.assert_array_equal(got.footprints.pos, fp.pos)
    assert not load_recording(p).has_footprints  # nothing beside a generic CSV by default
