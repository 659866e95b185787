"""``pednav train`` into a run directory that holds an earlier run: refused in one line
naming what is there, unless ``--overwrite`` (which removes it first) or ``--resume``
(which continues it); with ``--seeds``, ``ALGO_seedS`` directories of seeds not in the
list are refused (or removed) too, so a run directory holds one run per seed given."""

from __future__ import annotations

import json

from testdata import tiny_train_argv

from agents.cli import main


def test_fewer_seeds_into_the_same_run_dir_are_refused_then_overwritten(tmp_path, capsys):
    runs = tmp_path / "runs"
    assert (
        main(tiny_train_argv(tmp_path, runs, "--seeds", "0", "1", "2", "--timesteps", "256")) == 0
    )
    capsys.readouterr()
    assert main(tiny_train_argv(tmp_path, runs, "--seeds", "0", "1", "--timesteps", "64")) == 2
    assert capsys.readouterr().err == (
        f"pednav: error: --run-dir {runs}: earlier runs in ppo_seed0, ppo_seed1; runs of "
        "seeds not in --seeds: ppo_seed2; give --overwrite to remove them first\n"
    )
    assert sorted(p.name for p in runs.iterdir()) == ["ppo_seed0", "ppo_seed1", "ppo_seed2"]

    argv = tiny_train_argv(tmp_path, runs, "--seeds", "0", "1", "--overwrite")
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"removed {runs / 'ppo_seed2'}\n" in err
    assert f"removed {runs / 'ppo_seed0' / 'checkpoints'}\n" in err
    assert sorted(p.name for p in runs.iterdir()) == ["ppo_seed0", "ppo_seed1"]
    for seed in (0, 1):
        run = runs / f"ppo_seed{seed}"
        # only the new 128-step run's checkpoints: --resume cannot pick the old run's 256
        assert sorted(p.name for p in (run / "checkpoints").glob("*.zip")) == [
            "model_128_steps.zip",
            "model_64_steps.zip",
        ]
        assert len(list((run / "tb").iterdir())) == 1
        assert json.loads((run / "meta.json").read_text())["timesteps"] == 128


def test_resume_keeps_its_runs_but_not_other_seeds(tmp_path, capsys):
    runs = tmp_path / "runs"
    assert main(tiny_train_argv(tmp_path, runs, "--seeds", "0", "1")) == 0
    assert main(tiny_train_argv(tmp_path, runs, "--seeds", "0", "1")) == 2
    assert capsys.readouterr().err.endswith(
        "earlier runs in ppo_seed0, ppo_seed1; give --resume to continue them or "
        "--overwrite to remove them first\n"
    )
    assert main(tiny_train_argv(tmp_path, runs, "--seeds", "0", "--resume")) == 2
    assert capsys.readouterr().err.endswith(
        "runs of seeds not in --seeds: ppo_seed1; give --overwrite to remove them first\n"
    )
    argv = tiny_train_argv(tmp_path, runs, "--seeds", "0", "--resume", "--overwrite", "--timesteps")
    assert main([*argv, "192"]) == 0
    assert [p.name for p in runs.iterdir()] == ["ppo_seed0"]
    meta = json.loads((runs / "ppo_seed0" / "meta.json").read_text())
    assert meta["resumes"] == 1 and meta["timesteps"] >= 192


def test_a_single_run_dir_with_an_earlier_run(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(tiny_train_argv(tmp_path, run, "--timesteps", "256")) == 0
    (run / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert main(tiny_train_argv(tmp_path, run)) == 2
    assert capsys.readouterr().err == (
        f"pednav: error: --run-dir {run}: holds an earlier run (checkpoints, meta.json, "
        "model.zip, tb, vecnormalize.pkl); give --resume to continue it or --overwrite to "
        "remove it first\n"
    )
    assert main(tiny_train_argv(tmp_path, run, "--overwrite")) == 0
    assert sorted(p.name for p in (run / "checkpoints").glob("*.zip")) == [
        "model_128_steps.zip",
        "model_64_steps.zip",
    ]
    assert (run / "notes.txt").read_text() == "mine"  # only the run's own outputs go


def test_an_empty_or_new_run_dir_trains_without_overwrite(tmp_path):
    (tmp_path / "empty").mkdir()
    assert main(tiny_train_argv(tmp_path, tmp_path / "empty", "--timesteps", "64")) == 0
    assert (
        main(tiny_train_argv(tmp_path, tmp_path / "runs", "--seeds", "3", "--timesteps", "64")) == 0
    )
    assert (tmp_path / "runs" / "ppo_seed3" / "model.zip").exists()


def test_resume_with_overwrite_checks_the_checkpoints_before_removing(tmp_path, capsys):
    runs = tmp_path / "runs"
    assert main(tiny_train_argv(tmp_path, runs, "--seeds", "0", "--timesteps", "64")) == 0
    capsys.readouterr()
    # ppo_seed1 has no checkpoint to resume: refused before ppo_seed0 (not in --seeds) goes
    argv = tiny_train_argv(tmp_path, runs, "--seeds", "1", "--resume", "--overwrite")
    assert main(argv) == 2
    assert capsys.readouterr().err == (
        f"pednav: error: --resume: no checkpoint in {runs / 'ppo_seed1' / 'checkpoints'}\n"
    )
    assert [p.name for p in runs.iterdir()] == ["ppo_seed0"]
    assert (runs / "ppo_seed0" / "model.zip").exists()


def test_seeds_beside_a_single_run_are_refused(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(tiny_train_argv(tmp_path, run, "--timesteps", "64")) == 0
    capsys.readouterr()
    assert main(tiny_train_argv(tmp_path, run, "--seeds", "0", "--timesteps", "64")) == 2
    assert capsys.readouterr().err == (
        f"pednav: error: --run-dir {run}: an earlier single run (checkpoints, meta.json, "
        "model.zip, tb, vecnormalize.pkl); give --overwrite to remove them first\n"
    )
    assert not (run / "ppo_seed0").exists()
    argv = tiny_train_argv(tmp_path, run, "--seeds", "0", "--timesteps", "64", "--overwrite")
    assert main(argv) == 0
    assert [p.name for p in run.iterdir()] == ["ppo_seed0"]
