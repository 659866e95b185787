"""A write that fails during a ``pednav`` command (a full disk, a permission lost after
the up-front checks) is one line naming the file, ``pednav: error: FILE: reason``, with
exit status 1 and no traceback (docs/CONVENTIONS.md, Configuration and bad input).

The failure is simulated where the bytes are written: numpy's ``savetxt``, matplotlib's
``savefig``, ``Path.write_text``, Stable-Baselines3's ``save`` and ``VecNormalize.save``
raise ``OSError(ENOSPC)`` *without* a file name for the one target file, as a full disk
does part-way through a write; every other file is written as usual."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest
from testdata import DATA, PYSHOE_SAMPLE, tiny_train_argv

from agents.cli import main
from pednav_env.files import save_figure, writing

DISK_FULL = os.strerror(errno.ENOSPC)


def fail_writes_to(monkeypatch, name: str) -> None:
    """Writes to a file called ``name`` raise ENOSPC without naming it; others succeed."""
    import matplotlib.figure
    import numpy as np
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.vec_env import VecNormalize

    def failing(original, path_arg):
        def wrapper(*args, **kwargs):
            target = path_arg(*args, **kwargs)
            if Path(os.fspath(target)).name == name:
                raise OSError(errno.ENOSPC, DISK_FULL)
            return original(*args, **kwargs)

        return wrapper

    patches = [
        (np, "savetxt", lambda fname, *a, **k: fname),
        (matplotlib.figure.Figure, "savefig", lambda self, fname, *a, **k: fname),
        (Path, "write_text", lambda self, *a, **k: self),
        (BaseAlgorithm, "save", lambda self, path, *a, **k: path),
        (VecNormalize, "save", lambda self, save_path, *a, **k: save_path),
    ]
    for owner, attr, path_arg in patches:
        monkeypatch.setattr(owner, attr, failing(getattr(owner, attr), path_arg))


def assert_one_line_naming(capsys, path: Path) -> None:
    err = capsys.readouterr().err
    assert err == f"pednav: error: {path}: {DISK_FULL}\n"


def test_writing_names_the_file_only_when_the_error_does_not():
    with pytest.raises(OSError) as caught, writing("out/a.csv"):
        raise OSError(errno.ENOSPC, DISK_FULL)
    assert (caught.value.errno, caught.value.filename) == (errno.ENOSPC, "out/a.csv")
    assert isinstance(caught.value.__cause__, OSError)
    with pytest.raises(PermissionError) as caught, writing("out/a.csv"):
        raise PermissionError(errno.EACCES, "Permission denied")
    assert caught.value.filename == "out/a.csv"  # the same errno, so the same subclass
    with pytest.raises(OSError) as caught, writing("out/a.csv"):
        raise OSError(errno.EACCES, "Permission denied", "elsewhere.csv")
    assert caught.value.filename == "elsewhere.csv"  # an error naming its file is kept
    with pytest.raises(KeyError), writing("out/a.csv"):
        raise KeyError("x")


def test_save_figure_names_the_file_on_a_full_disk(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure()
    fail_writes_to(monkeypatch, "f.png")
    with pytest.raises(OSError) as caught:
        save_figure(fig, tmp_path / "f.png")
    plt.close(fig)
    assert caught.value.filename == str(tmp_path / "f.png")
    assert caught.value.strerror == DISK_FULL


def test_simulate_out(tmp_path, monkeypatch, capsys):
    out = tmp_path / "walk.csv"
    fail_writes_to(monkeypatch, out.name)
    assert main(["simulate", "--out", str(out), "--duration", "5"]) == 1
    assert_one_line_naming(capsys, out)


@pytest.mark.parametrize(("option", "name"), [("--out", "track.csv"), ("--plot", "top.png")])
def test_run_out_and_plot(option, name, tmp_path, monkeypatch, capsys):
    target = tmp_path / name
    fail_writes_to(monkeypatch, name)
    assert main(["run", str(PYSHOE_SAMPLE), option, str(target)]) == 1
    assert_one_line_naming(capsys, target)


def test_run_folder_out(tmp_path, monkeypatch, capsys):
    target = tmp_path / "tracks" / f"{PYSHOE_SAMPLE.stem}_track.csv"
    fail_writes_to(monkeypatch, target.name)
    assert main(["run", str(DATA / "replay"), "--out", str(tmp_path / "tracks")]) == 1
    assert_one_line_naming(capsys, target)


def test_evaluate_plot(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "per_episode.png")
    argv = ["evaluate", "pednav/WaistStep-v0", "--policy", "paper", "--episodes", "1"]
    assert main([*argv, "--plot", str(tmp_path / "figs")]) == 1
    assert_one_line_naming(capsys, tmp_path / "figs" / "per_episode.png")


def test_tune_run_dir(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "tuned_actions.json")
    argv = ["tune", "pednav/WaistStep-v0", "--episodes", "1", "--generations", "1"]
    assert main([*argv, "--popsize", "2", "--run-dir", str(tmp_path / "run")]) == 1
    assert_one_line_naming(capsys, tmp_path / "run" / "tuned_actions.json")


def test_reproduce_plots(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "paper000_step.png")
    assert main(["reproduce", "000", "--runs", "1", "--plots", str(tmp_path / "figs")]) == 1
    assert_one_line_naming(capsys, tmp_path / "figs" / "paper000_step.png")


def test_fit_rule_out(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "gait_rule.json")
    argv = ["fit-rule", str(PYSHOE_SAMPLE), "--out", str(tmp_path / "fit")]
    assert main([*argv, "--generations", "1", "--popsize", "2"]) == 1
    assert_one_line_naming(capsys, tmp_path / "fit" / "gait_rule.json")


def test_sim2real_plot(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "sim2real_calibrated_strides.png")
    argv = ["sim2real", str(PYSHOE_SAMPLE), "--walks", "2", "--plot", str(tmp_path / "figs")]
    assert main(argv) == 1
    assert_one_line_naming(capsys, tmp_path / "figs" / "sim2real_calibrated_strides.png")


@pytest.mark.parametrize("name", ["model.zip", "vecnormalize.pkl", "meta.json"])
def test_train_run_dir(name, tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, name)
    run_dir = tmp_path / "run"
    assert main(tiny_train_argv(tmp_path, run_dir)) == 1
    assert_one_line_naming(capsys, run_dir / name)


def test_train_checkpoint_during_learning_names_the_run_directory(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "model_64_steps.zip")
    run_dir = tmp_path / "run"
    assert main(tiny_train_argv(tmp_path, run_dir)) == 1
    assert_one_line_naming(capsys, run_dir)


def test_distill_run_dir(tmp_path, monkeypatch, capsys):
    fail_writes_to(monkeypatch, "model.zip")
    argv = ["distill", "pednav/MarkerTrack-v0", "--iterations", "1", "--steps", "2"]
    assert main([*argv, "--lanes", "2", "--run-dir", str(tmp_path / "d")]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines[:-1] == ["iteration 0: loss " + lines[0].rpartition(" ")[2]]  # progress
    assert lines[-1] == f"pednav: error: {tmp_path / 'd' / 'model.zip'}: {DISK_FULL}"
