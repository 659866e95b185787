"""Evaluation (pednav evaluate), the SB3 VecEnv adapter and the bench command."""

import json
import time

import gymnasium as gym
import numpy as np
import pytest
from scipy.stats import beta
from testdata import HALLWAY_DATA, REPLAY_DATA

from agents.bench.timing import bench_native_vs_reference
from agents.cli import main
from agents.evaluate import divergence_interval, evaluate, load_policy, run_episodes
from baselines import PaperPolicy
from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.gait.foot_route import RouteRandomization
from pednav_env.sb3 import NativeVecEnv

ENV_ID = "pednav/FootZupt-v0"


@pytest.mark.parametrize(("diverged", "episodes"), [(148, 200), (17, 200), (0, 10), (10, 10)])
def test_divergence_interval_is_clopper_pearson(diverged: int, episodes: int) -> None:
    # the beta-quantile form of the exact interval, written out (the code uses binomtest)
    flags = np.arange(episodes) < diverged
    lo = 0.0 if diverged == 0 else beta.ppf(0.025, diverged, episodes - diverged + 1)
    hi = 1.0 if diverged == episodes else beta.ppf(0.975, diverged + 1, episodes - diverged)
    assert divergence_interval(flags) == pytest.approx((lo, hi), abs=1e-9)


SHORT = {"config": FootZuptConfig(route=RouteRandomization(duration_s=(10.0, 15.0)))}


def scalar_rollout(seed):
    """Independent path: the scalar env, one episode, zero actions."""
    env = gym.make(ENV_ID, **SHORT)
    env.reset(seed=seed)
    total = 0.0
    while True:
        _, r, term, trunc, info = env.step(np.zeros(4, np.float32))
        total += r
        if term or trunc:
            return -total, info, term


def test_episodes_match_scalar_rollouts_seed_by_seed():
    res = run_episodes(ENV_ID, PaperPolicy(gym.make(ENV_ID).action_space), 3, 700, SHORT)
    for i, r in enumerate(res):
        err, info, term = scalar_rollout(700 + i)
        assert r.seed == 700 + i
        assert r.mean_error == pytest.approx(err, rel=1e-6)
        assert r.final_error == pytest.approx(info["error"], rel=1e-9)
        assert r.distance == pytest.approx(info["distance"], rel=1e-9)
        assert r.diverged == term


def test_evaluate_json_has_the_contract_keys_and_paired_stats(tmp_path):
    from stable_baselines3 import PPO

    model = PPO(
        "MlpPolicy",
        gym.make(ENV_ID, **SHORT),
        n_steps=64,
        batch_size=32,
        n_epochs=1,
        seed=0,
        policy_kwargs={"net_arch": [16]},
        device="cpu",
    )
    model.learn(64)
    path = tmp_path / "tiny.zip"
    model.save(path)
    with pytest.warns(UserWarning, match="no vecnormalize.pkl beside it"):
        out = evaluate(ENV_ID, ["paper", str(path)], 3, 5000, SHORT)
    assert set(out) == {"env", "episodes", "seed", "policies"}
    assert out["env"] == ENV_ID and out["episodes"] == 3 and out["seed"] == 5000
    names = [p["name"] for p in out["policies"]]
    assert names == ["paper", str(path)]
    for p in out["policies"]:
        assert set(p) == {
            "name",
            "mean_error",
            "ci95",
            "final_error_pct",
            "divergence_rate",
            "divergence_ci95",
            "vs_paper",
            "mean_error_non_diverged",
            "episode_errors",
            "vs_tuned",
            "filter",  # the foot env's filter family the policy played on
        }
        assert p["filter"] == "paper"  # a run without meta.json: the paper family
        lo, hi = p["ci95"]
        assert lo <= p["mean_error"] <= hi
        assert 0.0 <= p["divergence_rate"] <= 1.0
        lo, hi = p["divergence_ci95"]
        assert 0.0 <= lo <= p["divergence_rate"] <= hi <= 1.0 and hi - lo > 0.3  # 3 episodes
    paper, learned = out["policies"]
    assert paper["vs_paper"] == {"mean_diff": 0.0, "p_value": None}
    assert learned["vs_paper"]["mean_diff"] == pytest.approx(
        learned["mean_error"] - paper["mean_error"], abs=1e-9
    )
    assert 0.0 <= learned["vs_paper"]["p_value"] <= 1.0


def test_evaluate_scores_against_separate_scalar_episodes():
    """episode_errors in seed order (episode i = a scalar env reset with seed S+i),
    and the summary fields recomputed from those episodes and their end flags
    with numpy / scipy. A 4 m divergence bound (no distance term) makes some
    episodes diverge and others not."""
    from dataclasses import replace

    from scipy import stats

    from baselines import InnovationAdaptivePolicy, TunedFixedPolicy

    config = replace(SHORT["config"], divergence_error_m=4.0, divergence_error_fraction=0.0)
    seed, n = 5100, 4
    # the paper filter family for the adaptive rule too (its default family is shoe)
    out = evaluate(ENV_ID, ["paper", "adaptive:paper"], n, seed, {"config": config})
    space = gym.make(ENV_ID).action_space
    policies = {
        "paper": PaperPolicy(space),
        "adaptive:paper": InnovationAdaptivePolicy(space, ENV_ID),
        "tuned": TunedFixedPolicy.for_env(ENV_ID, space),
    }
    errors, diverged = {}, {}
    for name, pol in policies.items():
        env = gym.make(ENV_ID, config=config)
        errors[name], diverged[name] = [], []
        for i in range(n):
            obs, _ = env.reset(seed=seed + i)
            total = 0.0
            while True:
                obs, r, term, trunc, _ = env.step(pol.predict(obs)[0])
                total += r
                if term or trunc:
                    break
            errors[name].append(-total)
            diverged[name].append(term)
    flags = np.array([diverged[k] for k in ("paper", "adaptive:paper")])
    assert flags.any() and not flags.all(), "the bound should split the episodes"
    by_name = {p["name"]: p for p in out["policies"]}
    assert list(by_name) == ["paper", "adaptive:paper"]  # tuned is played, not listed
    for name, p in by_name.items():
        err, div = np.array(errors[name]), np.array(diverged[name])
        # the vector env's rewards reach SB3 as float32: relative 1e-6
        np.testing.assert_allclose(p["episode_errors"], err, rtol=1e-6)
        assert p["mean_error"] == pytest.approx(err.mean(), rel=1e-6)
        assert p["divergence_rate"] == div.mean()
        if div.all():
            assert p["mean_error_non_diverged"] is None
        else:
            assert p["mean_error_non_diverged"] == pytest.approx(err[~div].mean(), rel=1e-6)
        tuned = np.array(errors["tuned"])
        assert p["vs_tuned"]["mean_diff"] == pytest.approx((err - tuned).mean(), abs=1e-5)
        # the p-value of the same differences; abs 1e-4: float32 rewards move t slightly
        want = stats.ttest_rel(err, tuned).pvalue if np.any(err != tuned) else 1.0
        assert p["vs_tuned"]["p_value"] == pytest.approx(want, abs=1e-4)


def test_vs_tuned_is_null_without_a_tuned_constant():
    config = FootZuptConfig(
        route=RouteRandomization(duration_s=(10.0, 12.0)), tune_min_stance=True
    )  # five knobs: the shipped constant has four
    out = evaluate(ENV_ID, ["paper"], 2, 5000, {"config": config})
    assert out["policies"][0]["vs_tuned"] is None
    out = evaluate(ENV_ID, ["tuned"], 2, 5000, SHORT)
    assert out["policies"][0]["vs_tuned"] == {"mean_diff": 0.0, "p_value": None}


def test_cli_evaluate_and_errors(capsys, tmp_path):
    assert (
        main(
            [
                "evaluate",
                ENV_ID,
                "--policy",
                "paper",
                "adaptive",
                "--episodes",
                "2",
                "--scenario",
                "paper",
                "--json",
                "--plot",
                str(tmp_path),
            ]
        )
        == 0
    )
    for name in ("error_over_time.png", "per_episode.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    out = json.loads(capsys.readouterr().out)
    assert out["policies"][0]["name"] == "paper" and out["episodes"] == 2
    assert main(["evaluate", ENV_ID, "--policy", "soothsayer", "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert "unknown policy 'soothsayer'" in err and err.count("\n") == 1
    # every name the foot env accepts, real-fixed (its shoe family's action 0) among them
    names = ("paper", "tuned", "adaptive", "pretrained", "gait-rule", "gait-rule-real", "oracle")
    for name in (*names, "real-fixed"):
        assert name in err
    replay = "pednav/FootZuptReplay-v0"
    with pytest.raises(ValueError, match="unknown policy 'soothsayer'") as exc:
        load_policy("soothsayer", gym.make(ENV_ID).action_space, replay)
    assert "real-fixed" in str(exc.value) and "oracle" not in str(exc.value)  # not on recordings
    with pytest.raises(ValueError, match="no such model"):
        load_policy("missing.zip", gym.make(ENV_ID).action_space)


def test_unknown_policy_in_pednav_run_lists_real_fixed():
    from agents.policies import load_policy as load
    from pednav_env.replay.setup import SETUP_NAMES

    space = gym.make(ENV_ID).action_space
    with pytest.raises(ValueError, match="unknown policy") as exc:
        load("bogus", space, ENV_ID, other_names=SETUP_NAMES)
    for name in ("paper", "tuned", "adaptive", "pretrained", "real-fixed"):
        assert name in str(exc.value)


def test_replay_evaluation_plays_each_recording_once_paired_by_recording(
    three_recordings, tmp_path, capsys
):
    """`pednav evaluate` over a folder: one episode per recording by default, in name
    order from the first seed, for every policy; each episode's error is that of its
    recording evaluated alone; the text table names each recording."""
    replay = "pednav/FootZuptReplay-v0"
    args = ["evaluate", replay, "--policy", "paper", "real-fixed", "--seed", "20000"]
    assert main([*args, "--recordings", str(three_recordings), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["episodes"] == 3 and out["episode_recordings"] == ["a", "b", "c"]
    by_name = {p["name"]: p for p in out["policies"]}
    assert all(len(p["episode_errors"]) == 3 for p in out["policies"])
    for k, name in enumerate(["a", "b", "c"]):
        alone = tmp_path / name
        alone.mkdir()
        (alone / f"{name}.mat").write_bytes((three_recordings / f"{name}.mat").read_bytes())
        assert main([*args, "--recordings", str(alone), "--json"]) == 0
        single = json.loads(capsys.readouterr().out)
        assert single["episodes"] == 1 and single["episode_recordings"] == [name]
        for p in single["policies"]:
            # each recording at its own rate (a.mat 200.1230 Hz, b.mat 200.1236 Hz),
            # whatever else is in the folder; to rounding: the process-noise basis is
            # computed at the folder's first rate (1e-20 apart; 3e-8 of b's error;
            # at the first rate for all, before, 8.6e-5; docs/REAL_DATA.md)
            np.testing.assert_allclose(
                by_name[p["name"]]["episode_errors"][k], p["episode_errors"][0], rtol=1e-6
            )
    # the recordings differ, so the check above can tell them apart
    assert len(set(by_name["real-fixed"]["episode_errors"])) == 3
    assert main([*args, "--recordings", str(three_recordings)]) == 0
    text = capsys.readouterr().out
    assert "error (m) per recording, by seed:" in text
    for k, name in enumerate(["a", "b", "c"]):
        row = next(line for line in text.splitlines() if line.split()[:2] == [str(20000 + k), name])
        err = by_name["paper"]["episode_errors"][k]
        assert f"{err:.3f}" in row


def test_replay_evaluation_refuses_footprint_walks_in_one_line(capsys):
    """Hallway walks (footprints only) cannot be replay episodes: one line naming the file."""
    args = ["evaluate", "pednav/FootZuptReplay-v0", "--policy", "real-fixed"]
    assert main([*args, "--recordings", str(HALLWAY_DATA)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: pednav/FootZuptReplay-v0: ") and err.count("\n") == 1
    assert "SensorConnectData_31_first5s.csv: no truth track" in err and "pednav run" in err


def test_replay_evaluation_names_the_bad_recording_of_a_folder(tmp_path, capsys):
    """A recording with a NaN sample in a folder: one line naming the file and its line."""
    (tmp_path / "good.mat").write_bytes(next(REPLAY_DATA.glob("*.mat")).read_bytes())
    rows = [f"{0.005 * k:.3f},0,0,0,0,0,9.81,0,0,0" for k in range(1, 9)]
    rows[4] = rows[4].replace(",0,0,0,0,0,9.81", ",0,nan,0,0,0,9.81")
    header = "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z,pos_x,pos_y,pos_z"
    (tmp_path / "bad.csv").write_text("\n".join([header, *rows]) + "\n")
    args = ["evaluate", "pednav/FootZuptReplay-v0", "--policy", "real-fixed"]
    assert main([*args, "--recordings", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: ") and err.count("\n") == 1
    assert "bad.csv: angular rate" in err and "line 6" in err


def test_privileged_oracle_is_refused_on_recordings(capsys):
    """The oracle reads info['context'], which on recordings comes from the truth track:
    `pednav evaluate` on the replay env refuses it in one line (whatever other policies
    are named), the API with a ValueError, also for a loaded oracle given to
    run_episodes directly."""
    from baselines.oracle import OraclePolicy

    replay = "pednav/FootZuptReplay-v0"
    for policies in (["oracle"], ["real-fixed", "oracle:shoe"]):
        args = ["evaluate", replay, "--policy", *policies, "--recordings", str(REPLAY_DATA)]
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"pednav: error: {replay}: policy oracle") and err.count("\n") == 1
        assert "privileged" in err and "truth" in err
    with pytest.raises(ValueError, match="privileged"):
        evaluate(replay, ["oracle"], 1, 20000, {"data_dir": str(REPLAY_DATA)})
    space = gym.make(replay, data_dir=str(REPLAY_DATA)).action_space
    oracle = OraclePolicy.for_env(ENV_ID, space, "shoe")
    kwargs = {"data_dir": str(REPLAY_DATA), "filter": "shoe"}
    with pytest.raises(ValueError, match="privileged"):
        run_episodes(replay, oracle, 1, 20000, kwargs)


def test_replay_env_evaluates_with_recordings_and_rejects_a_scenario(capsys):
    """The documented `pednav evaluate pednav/FootZuptReplay-v0 --policy paper` works
    with --recordings DIR; --scenario (an option the replay env lacks) is one line."""
    replay = "pednav/FootZuptReplay-v0"
    args = ["evaluate", replay, "--policy", "paper", "tuned", "--episodes", "2", "--json"]
    assert main([*args, "--recordings", str(REPLAY_DATA)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["env"] == replay and [p["name"] for p in out["policies"]] == ["paper", "tuned"]
    # the simulated env's tuned action is played (same knobs), so it differs from paper
    assert out["policies"][1]["vs_paper"]["mean_diff"] != 0.0
    assert main([*args, "--env-kwarg", f"data_dir={REPLAY_DATA}"]) == 0
    assert json.loads(capsys.readouterr().out) == out
    assert main([*args, "--scenario", str(REPLAY_DATA)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pednav: error: pednav/FootZuptReplay-v0 has no option 'scenario'")
    assert "data_dir" in err and err.count("\n") == 1
    assert main([*args[:-1], "--recordings", str(REPLAY_DATA / "nope")]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert main([*args, "--env-kwarg", "data_dir"]) == 2
    assert "KEY=VALUE" in capsys.readouterr().err


def test_paper_policy_shapes():
    space = gym.make(ENV_ID).action_space
    pol = PaperPolicy(space)
    a, state = pol.predict(np.zeros(20, np.float32))
    assert a.shape == (4,) and not a.any() and state is None
    a, _ = pol.predict(np.zeros((7, 20), np.float32))
    assert a.shape == (7, 4)
    with pytest.raises(ValueError, match="Box"):
        PaperPolicy(gym.spaces.Discrete(3))


def test_sb3_adapter_autoreset_and_ppo():
    from stable_baselines3 import PPO

    venv = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode="vector_entry_point", **SHORT)
    vec = NativeVecEnv(venv)
    vec.seed(11)
    obs = vec.reset()
    assert obs.shape == (3, 20)
    seen_done = False
    for _ in range(40):
        obs, rew, dones, infos = vec.step(np.zeros((3, 4), np.float32))
        assert rew.dtype == np.float32 and len(infos) == 3
        for d, info in zip(dones, infos, strict=True):
            if d:
                seen_done = True
                assert info["terminal_observation"].shape == (20,)
                assert isinstance(info["TimeLimit.truncated"], bool)
    assert seen_done
    model = PPO(
        "MlpPolicy",
        vec,
        n_steps=32,
        batch_size=48,
        n_epochs=1,
        seed=0,
        policy_kwargs={"net_arch": [16]},
        device="cpu",
    )
    model.learn(192)
    assert model.num_timesteps >= 192


class _TimedVectorEnv:
    """A vector env whose step takes at least ``STEP_S`` of wall time."""

    STEP_S = 0.01

    def __init__(self, num_envs: int) -> None:
        self.num_envs = num_envs

    def reset(self, seed: int) -> None:
        pass

    def step(self, actions) -> None:
        assert actions.shape == (self.num_envs, 1)
        time.sleep(self.STEP_S)

    def close(self) -> None:
        pass


class _TimedReference:
    """A scalar reference env whose step takes at least ``STEP_S``."""

    STEP_S = 0.02

    def step(self) -> None:
        time.sleep(self.STEP_S)


@pytest.mark.parametrize("interleave", [False, True])
def test_bench_counts_env_steps_per_wall_second(interleave):
    """The timing loop on envs whose steps take a known time: 4 lanes per 10 ms call
    are 400 env steps/s; 4 references of 20 ms each, one after another, are 50."""

    def reference(seed):
        return _TimedReference()

    out = bench_native_vs_reference(
        "timed", _TimedVectorEnv, reference, 1, (4,), 0.2, 0.2, interleave=interleave
    )
    (row,) = out["rows"]
    assert row["num_envs"] == 4
    # sleep() never returns early, so the rates cannot exceed 400 and 50; a loaded
    # machine wakes the sleepers late, by well under a step here (bounds: half).
    assert 200 < row["steps_per_s"] <= 400
    assert 25 < row["reference_steps_per_s"] <= 50


def test_bench_command_json_and_errors(capsys):
    """`pednav bench foot --json`: the contract's keys, and the native env faster than
    the filterpy loop (by about 100× and more, docs/PERFORMANCE.md)."""
    assert main(["bench", "foot", "--sizes", "1", "--seconds", "0.05", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"bench", "rows", "peak_rss_mb"} and out["bench"] == "foot"
    assert [row["filter"] for row in out["rows"]] == ["paper", "shoe"]  # both families
    for row in out["rows"]:
        assert set(row) == {"filter", "num_envs", "steps_per_s", "reference_steps_per_s", "ratio"}
        assert row["num_envs"] == 1 and row["ratio"] > 1
    assert main(["bench", "legs"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_each_policy_plays_on_its_filter_family_against_its_action_zero():
    """Per-family evaluation: `tuned` and `adaptive` (shoe by default) are paired with
    `real-fixed` on the shoe family, `paper` with itself on the paper family; the
    pairs are checked against episodes played separately with each policy."""
    from baselines import RealFixedPolicy, TunedFixedPolicy

    route = RouteRandomization(duration_s=(10.0, 15.0))
    out = evaluate(ENV_ID, ["paper", "tuned"], 3, 5200, {"config": FootZuptConfig(route=route)})
    by_name = {p["name"]: p for p in out["policies"]}
    assert by_name["paper"]["filter"] == "paper" and by_name["tuned"]["filter"] == "shoe"
    space = gym.make(ENV_ID).action_space
    shoe = {"config": FootZuptConfig(filter_family="shoe", scenario="random", route=route)}
    zero = run_episodes(ENV_ID, RealFixedPolicy(space), 3, 5200, shoe)
    tuned = run_episodes(ENV_ID, TunedFixedPolicy.for_env(ENV_ID, space, "shoe"), 3, 5200, shoe)
    diff = np.array([t.mean_error - z.mean_error for t, z in zip(tuned, zero, strict=True)])
    # float32 rewards through SB3's evaluation loop: relative 1e-6
    assert by_name["tuned"]["vs_paper"]["mean_diff"] == pytest.approx(diff.mean(), rel=1e-5)
    assert by_name["tuned"]["vs_tuned"]["mean_diff"] == 0.0
    paper = run_episodes(
        ENV_ID, PaperPolicy(space), 3, 5200, {"config": FootZuptConfig(route=route)}
    )
    np.testing.assert_allclose(
        by_name["paper"]["episode_errors"], [r.mean_error for r in paper], rtol=1e-6
    )
