"""`pednav simulate`: a simulated foot walk written as a recording, read back by the
loaders and filtered by `pednav run` (round trip)."""

from __future__ import annotations

import json
from dataclasses import asdict

import numpy as np
import pytest

from agents.cli import main
from pednav_env.gait.foot_route import Gait
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.io import load_recording
from pednav_env.io.saturation import runs
from pednav_env.replay.simulate import (
    CSV_COLUMNS,
    DEFAULT_MODEL,
    GAIT_NAMES,
    GAIT_SPEEDS_MPS,
    SimulateConfig,
    simulate_walk,
    write_recording_csv,
)


def read_back(path):
    """The written columns as a dict of arrays (names without units)."""
    header = path.read_text().splitlines()[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return {h.split(" ")[0]: data[:, i] for i, h in enumerate(header)}


def stride_speeds(cols: dict) -> np.ndarray:
    """Speed of each full stride from the truth: distance between consecutive stance
    starts over the time between them (no stops: one gait cycle)."""
    stance = cols["stance"].astype(bool)
    starts = np.array([s for s, _ in runs(stance)])
    pos = np.column_stack((cols["pos_x"], cols["pos_y"]))
    t = cols["time"]
    inner = starts[1:-1]  # the first start is the initial stand, the last the final one
    return np.linalg.norm(np.diff(pos[inner], axis=0), axis=1) / np.diff(t[inner])


def test_round_trip_simulate_then_run(tmp_path, capsys):
    out = tmp_path / "walk.csv"
    assert main(["simulate", "--out", str(out), "--duration", "20", "--seed", "0"]) == 0
    assert "wrote" in capsys.readouterr().out
    assert out.read_text().splitlines()[0] == ",".join(CSV_COLUMNS)
    rec = load_recording(out)
    assert rec.metadata["format"] == "csv" and not rec.issues
    assert rec.rate_hz == pytest.approx(200.0)
    cols = read_back(out)
    np.testing.assert_allclose(rec.truth_pos[:, 0], cols["pos_x"])
    assert main(["run", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    truth_m = np.sum(np.hypot(np.diff(cols["pos_x"]), np.diff(cols["pos_y"])))
    # 20 s of the calibrated model at 0.8-1.3 m/s, seed 0: a walker whose mid-stance
    # is quieter than real-fixed's threshold, ARMSE 0.021 m (path 2.8 % long). Over
    # seeds 0-7 the calibrated walkers give 0.02-0.68 m: louder walkers' stances
    # cross real-fixed's γ (docs/SIM_TO_REAL.md). A broken round trip (units, axes,
    # time) gives metres
    assert summary["armse_m"] < 0.1
    assert summary["distance_m"] == pytest.approx(truth_m, rel=0.1)


def test_each_stride_speed_lies_in_the_range_and_sets_the_gait():
    for lo, hi, gaits in ((1.0, 1.2, {Gait.WALK}), (2.2, 2.6, {Gait.RUN})):
        walk = simulate_walk(SimulateConfig(speed_mps=(lo, hi), duration_s=25, stops=False))
        cols = {
            "stance": walk.stance,
            "pos_x": walk.pos_n[:, 0],
            "pos_y": walk.pos_n[:, 1],
            "time": walk.time,
        }
        v = stride_speeds(cols)
        assert len(v) >= 10
        # the range is the heel's speed; this is the IMU's, 0.10 m ahead of the heel,
        # whose displacement changes by up to ~5 % when the foot turns by up to 60°
        # between footfalls (and stance starts fall on the 5 ms grid)
        assert v.min() > lo * 0.95 and v.max() < hi * 1.05
        assert np.median(v) == pytest.approx((lo + hi) / 2, rel=0.1)
        moving = set(np.unique(walk.gait).tolist()) - {Gait.STANDING}
        assert moving == gaits


def test_gait_option_and_no_stops():
    """``--gait G``: every stride of class G, at the class's speeds (GAIT_SPEEDS_MPS)."""
    for name, gait in GAIT_NAMES.items():
        walk = simulate_walk(SimulateConfig(gait=name, duration_s=20, stops=False))
        assert set(np.unique(walk.gait).tolist()) == {Gait.STANDING, gait}
        lo, hi = GAIT_SPEEDS_MPS[name]
        cols = {"stance": walk.stance, "time": walk.time}
        cols.update(pos_x=walk.pos_n[:, 0], pos_y=walk.pos_n[:, 1])
        v = stride_speeds(cols)  # the IMU's, within ~5 % of the heel's (test above)
        assert len(v) >= 5 and v.min() > lo * 0.95 and v.max() < hi * 1.05
        if name == "slow_walk":
            stands = [(e - s) / 200.0 for s, e in runs(walk.stance)][1:-1]
            assert max(stands) < 1.0  # slow-walk stances are < 1 s; a stop would be ≥ 1 s


def test_gait_option_walks_the_models_walker(tmp_path, capsys):
    """``--gait`` applies the model's walker as ``--speed`` does (it used to draw the
    strides without it): a model file whose cadence law is f = 1.2 Hz (b = 0) walks
    0.83 s cycles (±7 %) with ``--gait slow_walk``, where a slow walk without the law
    takes 1.2 s or more; and ``--gait walk`` is ``--speed 0.75 1.2``, byte for byte."""
    model = tmp_path / "quick.json"
    law = {"cadence_intercept_hz": 1.2, "cadence_slope_hz_per_mps": 0.0}
    model.write_text(json.dumps({**asdict(StanceRandomization.calibrated()), **law}))
    out = tmp_path / "quick.csv"
    argv = ["simulate", "--out", str(out), "--duration", "30", "--gait", "slow_walk"]
    assert main([*argv, "--no-stops", "--seed", "3", "--model", str(model)]) == 0
    cols = read_back(out)
    assert set(np.unique(cols["gait"]).tolist()) == {Gait.STANDING, Gait.SLOW_WALK}
    starts = np.array([s for s, _ in runs(cols["stance"].astype(bool))])
    cycles = np.diff(cols["time"][starts[1:-1]])
    assert len(cycles) >= 20
    assert np.all((cycles > 0.93 / 1.2) & (cycles < 1.07 / 1.2))
    paths = {}
    for name, args in (("gait", ["--gait", "walk"]), ("speed", ["--speed", "0.75", "1.2"])):
        paths[name] = tmp_path / f"{name}.csv"
        assert main(["simulate", "--out", str(paths[name]), "--duration", "10", *args]) == 0
    capsys.readouterr()
    assert paths["gait"].read_bytes() == paths["speed"].read_bytes()


def test_seeds_and_options_are_honoured(tmp_path):
    a = write_recording_csv(simulate_walk(SimulateConfig(duration_s=10, seed=5)), tmp_path / "a")
    b = write_recording_csv(simulate_walk(SimulateConfig(duration_s=10, seed=5)), tmp_path / "b")
    c = write_recording_csv(simulate_walk(SimulateConfig(duration_s=10, seed=6)), tmp_path / "c")
    assert a.read_bytes() == b.read_bytes() != c.read_bytes()
    w = simulate_walk(SimulateConfig(duration_s=10, rate_hz=400.0, imu_grade="ideal"))
    assert np.diff(w.time).max() == pytest.approx(1 / 400)
    assert w.time[-1] <= 10.0
    with pytest.raises(ValueError, match="not both"):
        SimulateConfig(speed_mps=(1.0, 1.2), gait="walk")
    with pytest.raises(ValueError, match="unknown IMU grade"):
        SimulateConfig(imu_grade="nope")
    with pytest.raises(ValueError, match="unknown gait"):
        SimulateConfig(gait="hop")


def test_default_model_is_sim2reals_calibrated_one():
    from pednav_env.calibration.compare import MODELS

    calibrated = MODELS["calibrated"]
    assert DEFAULT_MODEL.imu_grade == calibrated.imu_grade
    assert DEFAULT_MODEL.stance() == calibrated.stance


def test_simulate_errors_are_one_line(tmp_path, capsys):
    argv = ["simulate", "--out", str(tmp_path / "x.csv"), "--speed", "1.2", "0.8"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: speed range") and err.count("\n") == 1
    assert main(["simulate", "--out", str(tmp_path / "no" / "x.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_simulate_refuses_what_it_cannot_write_or_read_back(tmp_path, capsys, monkeypatch):
    """An output that is a directory (or in a missing one) is refused in one line before
    anything is simulated; rates the loaders refuse (90–1100 Hz) and walks too long to
    hold in memory are refused by the config."""
    import pednav_env.replay.simulate as simulate

    def no_simulation(config):
        raise AssertionError("simulated before the output path was checked")

    monkeypatch.setattr(simulate, "simulate_walk", no_simulation)
    for out, why in ((tmp_path, "is a directory"), (tmp_path / "no" / "x.csv", "does not exist")):
        assert main(["simulate", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"pednav: error: {out}: ") and err.count("\n") == 1
        assert why in err
    for rate in (60.0, 1500.0):  # pednav run refuses both (median rate outside 90–1100 Hz)
        with pytest.raises(ValueError, match="rate must be in 90…1100 Hz"):
            SimulateConfig(rate_hz=rate)
    for rate in (90.0, 1100.0):
        SimulateConfig(rate_hz=rate)
    with pytest.raises(ValueError, match="duration must be 5…7200 s"):
        SimulateConfig(duration_s=1e9)


def test_simulate_model_option(tmp_path, capsys):
    """``--model`` takes sim2real's named models and fitted-parameter files: a file
    with ``heel_rocker`` simulates the same walker and route as the calibrated model
    (the flag draws nothing), its heel landing at rest instead of running on."""
    from dataclasses import asdict, replace

    from pednav_env.gait.stance_motion import StanceRandomization

    model = tmp_path / "rocker.json"
    rocker = replace(StanceRandomization.calibrated(), heel_rocker=True)
    model.write_text(json.dumps(asdict(rocker)))
    walks = {}
    for name in ("calibrated", str(model)):
        out = tmp_path / f"{len(walks)}.csv"
        argv = ["simulate", "--out", str(out), "--duration", "10", "--model", name]
        assert main(argv) == 0
        assert f"model {'rocker' if name.endswith('json') else 'calibrated'}," in (
            capsys.readouterr().out
        )
        walks[name] = read_back(out)
    base, other = walks["calibrated"], walks[str(model)]
    np.testing.assert_array_equal(base["stance"], other["stance"])  # same route and timing
    assert not np.array_equal(base["pos_x"], other["pos_x"])  # another heel strike
    assert main(["simulate", "--out", str(tmp_path / "x.csv"), "--model", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: --model 'nope'") and err.count("\n") == 1


def test_simulate_model_file_sets_the_walkers_cadence(tmp_path, capsys):
    """``--model FILE`` walks the file's model: a cadence law of f = 1.2 Hz (b = 0) gives
    0.83 s cycles (±7 %) at 0.4–0.5 m/s, where the calibrated default walks 1.39–1.52 s;
    a bad file or name is one line."""
    model = tmp_path / "quick.json"
    law = {"cadence_intercept_hz": 1.2, "cadence_slope_hz_per_mps": 0.0}
    fields = {**asdict(StanceRandomization.calibrated()), **law}
    model.write_text(json.dumps({"randomization": fields}))
    cycles = {}
    for name, extra in (("quick", ["--model", str(model)]), ("default", [])):
        out = tmp_path / f"{name}.csv"
        argv = ["simulate", "--out", str(out), "--duration", "30", "--speed", "0.4", "0.5"]
        assert main([*argv, "--no-stops", "--seed", "3", *extra]) == 0
        assert f"model {'quick' if extra else 'calibrated'}" in capsys.readouterr().out
        cols = read_back(out)
        starts = np.array([s for s, _ in runs(cols["stance"].astype(bool))])
        cycles[name] = np.diff(cols["time"][starts[1:-1]])
    assert np.all((cycles["quick"] > 0.93 / 1.2) & (cycles["quick"] < 1.07 / 1.2))
    assert np.all(cycles["default"] > 0.93 / (0.55 + 0.3 * 0.5))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"cadence_intercept_hz": 5.0}))
    for arg in (str(bad), "nonsense"):
        assert main(["simulate", "--out", str(tmp_path / "x.csv"), "--model", arg]) == 2
        err = capsys.readouterr().err
        assert err.startswith("pednav: error:") and err.count("\n") == 1
        assert ("cadence_intercept_hz" if arg != "nonsense" else "--model 'nonsense'") in err
