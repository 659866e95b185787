"""The command line as a user meets it: --version, --help defaults, progress bars, the
evaluation table and figures."""

import argparse
import io

import numpy as np
import pytest
from testdata import DATA

from agents.cli import build_parser, main
from agents.evaluate import EpisodeResult
from agents.evaluate_report import format_table, log_limits, short_name, write_plots
from agents.progress import progress_bar, wanted
from pednav_env import __version__


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"pednav {__version__}"


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


@pytest.mark.parametrize("command", sorted(_subparsers(build_parser())))
def test_every_help_shows_the_defaults(command):
    """Each option that has a default says it in --help (argparse's own "(default: …)"
    or a help text naming it)."""
    sub = _subparsers(build_parser())[command]
    text = " ".join(sub.format_help().split())
    for action in sub._actions:
        default = action.default
        if not action.option_strings or default is None or default is False or default == []:
            continue
        if default == argparse.SUPPRESS:
            continue
        help_text = " ".join((action.help or "").split())
        assert help_text in text
        after = text[text.index(help_text) + len(help_text) :].lstrip()
        assert "default" in help_text or after.startswith("(default:"), (command, action.dest)


def test_progress_only_on_a_terminal_and_never_with_json():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    assert wanted(False, Tty())
    assert not wanted(True, Tty())  # --json
    assert not wanted(False, io.StringIO())  # piped
    with progress_bar("x", 3, enabled=False) as advance:
        advance(1)  # a no-op, and no rich import needed


def _result(env_id: str, name: str = "paper") -> dict:
    pol = {
        "name": name,
        "mean_error": 1.5,
        "ci95": [1.0, 2.0],
        "final_error_pct": 12.34,
        "divergence_rate": 0.36,
        "vs_paper": {"mean_diff": -0.25, "p_value": 0.01},
    }
    paper = {**pol, "name": "paper", "vs_paper": {"mean_diff": 0.0, "p_value": None}}
    return {"env": env_id, "episodes": 100, "seed": 5000, "policies": [paper, pol]}


def test_table_prints_divergence_in_percent_and_shortens_paths():
    long = "/home/someone/experiments/2026-11-25/runs/FootZupt-v0/ppo_seed0"
    text = format_table(_result("pednav/FootZupt-v0", long))
    lines = text.splitlines()
    assert "36 %" in lines[-1] and "0.36" not in text
    assert "12.3" in lines[-1]  # final % of distance
    name = lines[-1].split()[0]
    assert long not in text and name.startswith("…/") and name.endswith("FootZupt-v0/ppo_seed0")
    widths = {len(line) for line in lines[1:]}
    assert len(widths) == 1  # every row as wide as the header: nothing pushed out


def test_marker_table_has_no_percent_of_distance():
    text = format_table(_result("pednav/MarkerTrack-v0"))
    assert "% dist" not in text and "12.3" not in text
    assert "RMS marker error" in text


def test_short_name_keeps_short_names_and_the_tail_of_long_ones():
    assert short_name("pretrained") == "pretrained"
    assert short_name("a" * 60) == "…" + "a" * 27
    assert len(short_name("x/" * 40 + "model.zip")) <= 28


def test_log_axis_limits_hug_the_data():
    """The per-episode axes span the data (plus a 15 % margin), not decades below it."""
    lo, hi = log_limits(np.array([2.0, 7.0, 40.0, np.nan, 0.0]), margin=1.15)
    assert lo == pytest.approx(2.0 / 1.15) and hi == pytest.approx(40.0 * 1.15)
    lo, hi = log_limits(np.array([3.0, 3.0]))  # one value: still a usable range around it
    assert lo < 3.0 < hi and hi / lo < 10


def test_plots_are_written_in_seconds(tmp_path):
    rng = np.random.default_rng(0)

    def episodes(scale):
        out = []
        for i in range(6):
            trace = tuple(scale * np.linspace(0.1, 5, 20 + 3 * i) * rng.uniform(0.5, 2))
            out.append(EpisodeResult(i, float(np.mean(trace)), trace[-1], 50.0, i == 5, trace))
        return out

    files = write_plots(
        "pednav/FootZupt-v0", {"paper": episodes(1.0), "tuned": episodes(0.5)}, tmp_path, 0.5
    )
    assert [f.name for f in files] == ["error_over_time.png", "per_episode.png"]
    assert all(f.stat().st_size > 10_000 for f in files)


def one_line_usage_error(capsys, argv: list[str], message: str) -> None:
    """argparse's refusal: exit code 2, one stderr line naming the option, no usage block."""
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "usage:" not in err, err
    assert message in err and "--help" in err, err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["evaluate", "pednav/MarkerTrack-v0", "--policy", "paper", "--episodes", "0"],
            "--episodes: must be ≥ 1",
        ),
        (
            ["evaluate", "pednav/MarkerTrack-v0", "--policy", "paper", "--episodes", "x"],
            "--episodes: not an integer: 'x'",
        ),
        (
            ["evaluate", "pednav/FootZupt-v0", "--policy", "paper", "--filter", "bogus"],
            "--filter: invalid choice",
        ),
        (
            ["evaluate", "pednav/FootZupt-v0", "--policy", "paper", "--speed", "0", "5"],
            "--speed: must be a finite number > 0",
        ),
        (["reproduce", "003", "--seed", "-1"], "--seed: must be ≥ 0, got -1"),
        (["simulate", "--out", "x.csv", "--seed", "-1"], "--seed: must be ≥ 0"),
        (["simulate", "--out", "x.csv", "--rate", "0"], "--rate: must be a finite number > 0"),
        (["simulate", "--out", "x.csv", "--duration", "-3"], "--duration: must be"),
        (["sim2real", "x.mat", "--seed", "-1"], "--seed: must be ≥ 0"),
        (["tune", "pednav/WaistStep-v0", "--seed", "-1"], "--seed: must be ≥ 0"),
        (["tune", "pednav/WaistStep-v0", "--reevaluate", "-1"], "--reevaluate: must be ≥ 0"),
        (["distill", "pednav/MarkerTrack-v0", "--seeds", "0", "-1"], "--seeds: must be ≥ 0"),
        (["fit-rule", "x.mat", "--out", "o", "--seed", "-1"], "--seed: must be ≥ 0"),
        (["bench", "foot", "--seconds", "-1"], "--seconds: must be a finite number > 0"),
        (["run", "x.csv", "--rate", "0"], "--rate: must be a finite number > 0"),
        (["evaluate"], "the following arguments are required"),
    ],
)
def test_bad_options_are_one_line_errors(argv, message, capsys):
    one_line_usage_error(capsys, argv, message)


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (
            ["evaluate", "pednav/MarkerTrack-v0", "--policy", "paper", "--episodes", "1", "--plot"],
            "--plot",
        ),
        (["reproduce", "003", "--plots"], "--plots"),
        (["train", "pednav/WaistStep-v0", "--timesteps", "1", "--run-dir"], "--run-dir"),
        (["tune", "pednav/WaistStep-v0", "--run-dir"], "--run-dir"),
        (["distill", "pednav/MarkerTrack-v0", "--run-dir"], "--run-dir"),
        (["fit-rule", "x.mat", "--out"], "--out"),
        (["run", str(DATA / "replay"), "--plot"], "--plot"),
        (["run", str(DATA / "replay"), "--out"], "--out"),
        (["sim2real", str(DATA / "replay"), "--plot"], "--plot"),
    ],
)
def test_output_directories_are_checked_before_the_run(argv, option, tmp_path, capsys, monkeypatch):
    """An output directory in the way of a file, under a file or not writable is a one-line
    error naming its option, before any work (not a traceback after it)."""
    blocker = tmp_path / "afile"
    blocker.write_text("")
    for target, message in (
        (blocker, "is a file; give a directory"),
        (blocker / "sub", "cannot create the directory"),
    ):
        assert main([*argv, str(target)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"pednav: error: {option} {target}: {message}"), err
        assert err.count("\n") == 1, err
    monkeypatch.setattr("agents.cli_types.os.access", lambda *_: False)
    assert main([*argv, str(tmp_path / "new")]) == 2
    assert (
        capsys.readouterr().err
        == f"pednav: error: {option} {tmp_path / 'new'}: directory not writable\n"
    )


def test_unreadable_run_files_name_the_file(tmp_path, capsys):
    """A hyperparameter file that is not YAML, a run whose meta.json is not JSON, an
    unknown env id for distill and --filter on an env without families: one line each."""
    bad = tmp_path / "bad.yml"
    bad.write_text("x: [1, 2\n")
    argv = ["train", "pednav/WaistStep-v0", "--timesteps", "1", "--config", str(bad)]
    assert main([*argv, "--run-dir", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err == f"pednav: error: config file {str(bad)!r}: not valid YAML at line 2\n"
    assert not (tmp_path / "r").exists()  # refused before the run directory is made
    run = tmp_path / "run"
    run.mkdir()
    (run / "model.zip").write_bytes(b"")
    (run / "meta.json").write_text("{oops")
    assert main(["evaluate", "pednav/MarkerTrack-v0", "--policy", str(run), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(
        f"pednav: error: policy {str(run)!r}: {run / 'meta.json'} is not valid JSON"
    )
    assert err.count("\n") == 1
    assert main(["distill", "bogus", "--run-dir", str(tmp_path / "d")]) == 2
    assert capsys.readouterr().err.startswith("pednav: error: unknown environment 'bogus'; known:")
    assert main(["distill", "pednav/FootZuptReplay-v0", "--run-dir", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: pednav/FootZuptReplay-v0 plays recordings")
    assert err.count("\n") == 1
    assert not (tmp_path / "d").exists()  # refused before the run directory is made
    assert main(["train", "pednav/WaistStep-v0", "--filter", "shoe"]) == 2
    assert (
        capsys.readouterr().err
        == "pednav: error: --filter: pednav/WaistStep-v0 has no filter families\n"
    )
