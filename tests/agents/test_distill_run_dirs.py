"""``pednav distill`` into a run directory that holds an earlier run: refused in one line
naming what is there unless ``--overwrite`` (which removes it first), as ``pednav train``
(tests/agents/test_train_run_dirs.py); with several ``--seeds`` the ``seedS``
directories of seeds not given go too. And ``make demo``'s distill line runs twice."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

from agents.cli import main

ENV_ID = "pednav/MarkerTrack-v0"
TINY = ("--iterations", "1", "--steps", "2", "--lanes", "2")
MAKEFILE = Path(__file__).resolve().parents[2] / "Makefile"


def distill_argv(run_dir, *extra: str) -> list[str]:
    return ["distill", ENV_ID, *TINY, "--run-dir", str(run_dir), *extra]


def test_fewer_seeds_are_refused_then_overwritten(tmp_path, capsys):
    runs = tmp_path / "runs"
    assert main(distill_argv(runs, "--seeds", "0", "1", "2")) == 0
    capsys.readouterr()
    assert main(distill_argv(runs, "--seeds", "0", "1", "--iterations", "2")) == 2
    assert capsys.readouterr().err == (
        f"pednav: error: --run-dir {runs}: earlier runs in seed0, seed1; runs of seeds not "
        "in --seeds: seed2; give --overwrite to remove them first\n"
    )
    assert sorted(p.name for p in runs.iterdir()) == ["seed0", "seed1", "seed2"]
    assert main(distill_argv(runs, "--seeds", "0", "1", "--iterations", "2", "--overwrite")) == 0
    err = capsys.readouterr().err
    assert f"removed {runs / 'seed2'}\n" in err
    assert f"removed {runs / 'seed0' / 'model.zip'}\n" in err
    assert sorted(p.name for p in runs.iterdir()) == ["seed0", "seed1"]
    for seed in (0, 1):
        assert json.loads((runs / f"seed{seed}" / "meta.json").read_text())["iterations"] == 2


def test_a_single_run_is_refused_then_overwritten_keeping_the_users_files(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(distill_argv(run)) == 0
    (run / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert main(distill_argv(run, "--iterations", "2")) == 2
    assert capsys.readouterr().err == (
        f"pednav: error: --run-dir {run}: holds an earlier run (meta.json, model.zip, "
        "vecnormalize.pkl); give --overwrite to remove it first\n"
    )
    assert json.loads((run / "meta.json").read_text())["iterations"] == 1
    assert main(distill_argv(run, "--iterations", "2", "--overwrite")) == 0
    assert json.loads((run / "meta.json").read_text())["iterations"] == 2
    assert (run / "notes.txt").read_text() == "mine"


def test_one_seed_beside_several_and_several_beside_one_are_refused(tmp_path, capsys):
    runs = tmp_path / "runs"
    assert main(distill_argv(runs, "--seeds", "0", "1")) == 0
    capsys.readouterr()
    assert main(distill_argv(runs)) == 2  # one seed writes into the directory itself
    assert capsys.readouterr().err.endswith(
        f"--run-dir {runs}: runs of other seeds: seed0, seed1; give --overwrite to remove "
        "them first\n"
    )
    assert main(distill_argv(runs, "--overwrite")) == 0
    assert sorted(p.name for p in runs.iterdir()) == ["meta.json", "model.zip", "vecnormalize.pkl"]
    capsys.readouterr()
    assert main(distill_argv(runs, "--seeds", "3", "4")) == 2
    assert capsys.readouterr().err.endswith(
        f"--run-dir {runs}: an earlier single run (meta.json, model.zip, vecnormalize.pkl); "
        "give --overwrite to remove them first\n"
    )
    assert not (runs / "seed3").exists()


def test_seeds_are_checked_before_the_run_dir_is_touched(tmp_path, capsys):
    runs = tmp_path / "runs"
    assert main(distill_argv(runs, "--seeds", "0", "0")) == 2
    assert capsys.readouterr().err == "pednav: error: seeds must be distinct, got [0, 0]\n"
    assert not runs.exists()


def make_demo_distill_argv(run_dir: Path) -> list[str]:
    """The ``pednav distill`` line of the Makefile's ``demo`` recipe as ``main``'s argv,
    its ``--run-dir`` moved to ``run_dir``."""
    text = MAKEFILE.read_text()
    env = re.search(r"^DEMO_ENV \?= (\S+)$", text, re.MULTILINE).group(1)
    (line,) = [ln for ln in text.splitlines() if "bin/pednav distill " in ln]
    words = shlex.split(line.replace("$(DEMO_ENV)", env))
    argv = words[words.index("distill") :]
    argv[argv.index("--run-dir") + 1] = str(run_dir)
    return argv


def test_make_demos_distill_line_runs_twice_into_one_dir(tmp_path, capsys):
    run = tmp_path / "runs" / "demo"
    argv = [*make_demo_distill_argv(run), *TINY]
    assert main(argv) == 0
    first = (run / "model.zip").stat().st_mtime_ns
    assert main(argv) == 0
    assert f"removed {run / 'model.zip'}\n" in capsys.readouterr().err
    assert (run / "model.zip").stat().st_mtime_ns >= first
    assert sorted(p.name for p in run.iterdir()) == ["meta.json", "model.zip", "vecnormalize.pkl"]
