"""A ``pednav`` command that fails after its output directory was made: the directories
it created and left empty are removed, others are not; a failed write is one line."""

from __future__ import annotations

import pytest

from agents.cli import main
from agents.cli_types import output_dir, removing_created_dirs_on_failure

TUNE = ["tune", "pednav/WaistStep-v0", "--episodes", "1", "--generations", "1", "--popsize", "2"]


def fail_search(monkeypatch, exc: BaseException, put_file_in=None) -> None:
    """``pednav tune``'s CMA-ES search raises ``exc`` (after writing a file to
    ``put_file_in``, when given)."""

    def search(*args, **kwargs):
        if put_file_in is not None:
            (put_file_in / "partial.json").write_text("{}")
        raise exc

    monkeypatch.setattr("baselines.tuned.search", search)


def test_a_failed_tune_removes_the_run_directory_it_created(tmp_path, monkeypatch, capsys):
    fail_search(monkeypatch, ValueError("no episodes left"))
    run_dir = tmp_path / "new" / "run"
    assert main([*TUNE, "--run-dir", str(run_dir)]) == 2
    assert capsys.readouterr().err == "pednav: error: no episodes left\n"
    assert not (tmp_path / "new").exists()  # the run directory and its created parent
    assert list(tmp_path.iterdir()) == []


def test_a_failed_tune_leaves_a_directory_that_existed(tmp_path, monkeypatch):
    fail_search(monkeypatch, ValueError("no episodes left"))
    run_dir = tmp_path / "old"
    run_dir.mkdir()
    assert main([*TUNE, "--run-dir", str(run_dir / "new")]) == 2
    assert run_dir.is_dir() and list(run_dir.iterdir()) == []
    assert main([*TUNE, "--run-dir", str(run_dir)]) == 2
    assert run_dir.is_dir()


def test_a_failed_tune_leaves_a_directory_with_a_file(tmp_path, monkeypatch):
    run_dir = tmp_path / "new" / "run"
    fail_search(monkeypatch, ValueError("no episodes left"), put_file_in=run_dir)
    assert main([*TUNE, "--run-dir", str(run_dir)]) == 2
    assert [p.name for p in run_dir.iterdir()] == ["partial.json"]


def test_ctrl_c_propagates_and_removes_the_run_directory(tmp_path, monkeypatch):
    fail_search(monkeypatch, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        main([*TUNE, "--run-dir", str(tmp_path / "new" / "run")])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("error", "message"),
    [
        (
            lambda out: PermissionError(13, "Permission denied", str(out)),
            "{out}: Permission denied",
        ),
        (lambda out: OSError(28, "No space left on device"), "[Errno 28] No space left on device"),
    ],
)
def test_a_failed_write_is_one_line_and_exit_code_1(error, message, tmp_path, monkeypatch, capsys):
    """An OSError after the up-front checks (as root ``os.access`` allows /proc; a full
    disk): one line naming the file when the error names it, no traceback."""
    out = tmp_path / "walk.csv"

    def write_recording_csv(walk, path):
        raise error(out)

    monkeypatch.setattr("pednav_env.replay.simulate.write_recording_csv", write_recording_csv)
    assert main(["simulate", "--out", str(out), "--duration", "5"]) == 1
    captured = capsys.readouterr()
    assert captured.err == f"pednav: error: {message.format(out=out)}\n"
    assert captured.out == ""


def test_only_directories_made_inside_the_context_are_removed(tmp_path):
    """Deepest first, each only when empty; one made before the context stays, and so
    does everything when the block succeeds."""
    before = output_dir(tmp_path / "before", "--out")
    with pytest.raises(RuntimeError), removing_created_dirs_on_failure():
        output_dir(tmp_path / "a" / "b", "--plot")
        output_dir(tmp_path / "a" / "c" / "d", "--out")
        (tmp_path / "a" / "c" / "keep.txt").write_text("")
        output_dir(before, "--out")
        raise RuntimeError
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a", "before", "c", "keep.txt"]
    with removing_created_dirs_on_failure():
        output_dir(tmp_path / "ok" / "run", "--run-dir")
    assert (tmp_path / "ok" / "run").is_dir()


def test_output_dir_removes_the_parents_it_made_when_the_directory_cannot_be_made(tmp_path):
    target = tmp_path / "new" / ("x" * 300)  # longer than a file name may be
    with pytest.raises(ValueError, match="cannot create the directory"):
        output_dir(target, "--out")
    assert list(tmp_path.iterdir()) == []


def test_a_run_that_fails_by_its_exit_code_removes_its_empty_directories(tmp_path, capsys):
    # pednav run DIR exits 1 when recordings fail; with every one failing, the --plot and
    # --out directories it made hold nothing and go
    recordings = tmp_path / "recs"
    recordings.mkdir()
    (recordings / "broken.csv").write_text("time,gyro_x\n0,oops\n")
    plots, out = tmp_path / "new" / "figs", tmp_path / "made" / "out"
    code = main(["run", str(recordings), "--plot", str(plots), "--out", str(out)])
    assert code == 1
    assert "broken.csv" in capsys.readouterr().out
    assert not (tmp_path / "new").exists() and not (tmp_path / "made").exists()
    assert recordings.exists()
