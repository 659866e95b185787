"""``--speed LO HI`` of `pednav tune` / `pednav evaluate`: the calibrated walks of
pednav/FootZupt-v0 in a stride-speed range (agents.cli_options.speed_config)."""

import json

import gymnasium as gym
import numpy as np
import pytest

import pednav_env  # noqa: F401  (registers the environments)
from agents.cli import build_parser, main
from agents.cli_options import env_kwargs_from_args
from pednav_env.envs.foot_context import CONTEXT_FIELDS

ENV_ID = "pednav/FootZupt-v0"
SPEED = CONTEXT_FIELDS.index("speed_mps")


def _kwargs(*argv: str) -> dict:
    return env_kwargs_from_args(build_parser().parse_args(["tune", ENV_ID, *argv]))


def _walked_speeds(env_kwargs: dict, seed: int, steps: int = 40) -> np.ndarray:
    """The truth speed of each decision interval (privileged context) over the first
    ``steps`` intervals of one episode at action 0; standing intervals left out."""
    env = gym.make(ENV_ID, **env_kwargs)
    _, info = env.reset(seed=seed)
    speeds = [info["context"][SPEED]]
    for _ in range(steps):
        _, _, term, trunc, info = env.step(np.zeros(env.action_space.shape, np.float32))
        speeds.append(info["context"][SPEED])
        if term or trunc:
            break
    s = np.asarray(speeds)
    return s[s > 0.2]


def test_speed_draws_the_calibrated_walks_in_that_range():
    """Walks drawn with --speed 0.4 0.7 and --speed 2.5 3.0 (same seed) are walked at
    those speeds: the fast walk's median interval speed (truth distance the foot
    covers over about a stride) lies in its range, the slow walk's stays below 1 m/s
    (over a window shorter than a slow stride the foot's path reads above the
    walking speed), and nine in ten slow intervals are slower than nine in ten fast
    ones. The rest of the calibrated scenario stays."""
    slow_kw, fast_kw = _kwargs("--speed", "0.4", "0.7"), _kwargs("--speed", "2.5", "3.0")
    slow, fast = _walked_speeds(slow_kw, 20_000), _walked_speeds(fast_kw, 20_000)
    assert 2.5 <= np.median(fast) <= 3.0
    assert np.median(slow) < 1.0
    assert np.percentile(slow, 90) < np.percentile(fast, 10)
    default = gym.make(ENV_ID, filter="shoe").unwrapped.config
    config = gym.make(ENV_ID, **fast_kw).unwrapped.config
    assert config.speed_route.speed_mps == (2.5, 3.0)
    assert config.scenario == "calibrated" and config.filter_family == "shoe"
    assert config.filter == default.filter  # action 0 is still real-fixed
    assert config.speed_route.duration_s == default.speed_route.duration_s
    assert config.speed_route.stop_s == default.speed_route.stop_s
    assert config.calibrated_imu_grades == default.calibrated_imu_grades


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["tune", ENV_ID, "--speed", "2", "1"], "--speed 2 1: need 0.1 ≤ LO ≤ HI ≤ 4"),
        (["tune", ENV_ID, "--speed", "1", "5"], "--speed 1 5: need"),
        (["tune", "pednav/WaistStep-v0", "--speed", "1", "2"], "--speed: only pednav/FootZupt"),
        (["tune", ENV_ID, "--filter", "paper", "--speed", "1", "2"], "not scenario 'random'"),
        (["evaluate", ENV_ID, "--policy", "paper", "--speed", "1", "9"], "--speed 1 9: need"),
        (["tune", ENV_ID, "--per-context", "--speed", "1", "2"], "no env options but --filter"),
    ],
)
def test_bad_speed_is_a_one_line_error(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_tune_with_speed_searches_those_walks_and_records_the_range(tmp_path, capsys):
    """`pednav tune --speed` hands the range to the search (its env config) and writes
    it in the result."""
    args = ["tune", ENV_ID, "--speed", "2.5", "3.0", "--episodes", "1", "--generations", "1"]
    args += ["--popsize", "2", "--run-dir", str(tmp_path / "run")]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["speed_mps"] == [2.5, 3.0]
    assert "speed_mps=(2.5, 3.0)" in result["env_kwargs"]["config"]
    written = json.loads((tmp_path / "run" / "tuned_actions.json").read_text())
    assert written[f"{ENV_ID}:shoe"] == result
