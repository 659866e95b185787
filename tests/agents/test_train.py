"""Training, saved tuners, the seed split, and the tuned/adaptive baselines."""

import json

import gymnasium as gym
import numpy as np
import pytest

from agents.cli import main
from agents.evaluate import evaluate, load_policy
from agents.policies import load_run
from agents.train import load_hyperparams, train
from baselines import InnovationAdaptivePolicy, TunedFixedPolicy
from baselines import tuned as tuned_module
from pednav_env.envs.foot_core import OBS_FEATURES, FootZuptConfig
from pednav_env.gait.foot_route import RouteRandomization
from pednav_env.seeds import TRAIN_SEED_BASE, check_evaluation_seeds, training_seed

ENV_ID = "pednav/FootZupt-v0"
SHORT = FootZuptConfig(route=RouteRandomization(duration_s=(10.0, 14.0)))
TINY = {
    "n_steps": 64,
    "batch_size": 64,
    "n_epochs": 1,
    "env_kwargs": {"config": SHORT},
    "policy_kwargs": {"net_arch": [16]},
    "checkpoint_steps": 256,
}


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    return train(
        ENV_ID,
        "ppo",
        timesteps=512,
        seed=3,
        n_envs=4,
        run_dir=out,
        progress_bar=False,
        hyperparams=TINY,
    )


def test_training_saves_a_loadable_model_with_stats_and_meta(run_dir):
    assert (run_dir / "model.zip").exists() and (run_dir / "vecnormalize.pkl").exists()
    assert list((run_dir / "checkpoints").glob("model_*_steps.zip"))
    assert list((run_dir / "tb").iterdir())  # TensorBoard logs
    meta = json.loads((run_dir / "meta.json").read_text())
    assert meta["env_id"] == ENV_ID and meta["algo"] == "ppo" and meta["timesteps"] >= 512
    assert meta["training_seeds_from"] == training_seed(3) >= TRAIN_SEED_BASE
    assert meta["lane_seeds"] == [[training_seed(3), training_seed(3) + 3]]


def test_loaded_policy_acts_like_the_trained_one(run_dir):
    import pickle

    from stable_baselines3 import PPO

    policy = load_run(run_dir)
    obs = np.stack([gym.make(ENV_ID, config=SHORT).reset(seed=s)[0] for s in range(5)])
    model = PPO.load(run_dir / "model.zip", device="cpu")
    with (run_dir / "vecnormalize.pkl").open("rb") as fh:
        stats = pickle.load(fh)
    expected, _ = model.predict(stats.normalize_obs(obs), deterministic=True)
    got, _ = policy.predict(obs)
    np.testing.assert_allclose(got, expected, atol=1e-6)
    assert not np.allclose(policy.normalize(obs), obs)  # statistics really applied


def test_resume_continues_from_the_checkpoint(run_dir):
    out = train(
        ENV_ID,
        "ppo",
        timesteps=768,
        seed=3,
        n_envs=4,
        run_dir=run_dir,
        resume=True,
        progress_bar=False,
        hyperparams=TINY,
    )
    meta = json.loads((out / "meta.json").read_text())
    assert meta["timesteps"] >= 768 and meta["resumes"] == 1
    # the first part played lane seeds training_seed(3) + 0…3, the resumed part the next
    # four of the run's block: no replay of the first episodes, no evaluation seed
    first = training_seed(3)
    assert meta["lane_seeds"] == [[first, first + 3], [first + 4, first + 7]]


def test_sac_trains_and_saves(tmp_path):
    hp = {
        "learning_starts": 64,
        "buffer_size": 2000,
        "batch_size": 32,
        "train_freq": 1,
        "gradient_steps": 1,
        "env_kwargs": {"config": SHORT},
        "policy_kwargs": {"net_arch": [16]},
        "checkpoint_steps": 10_000,
    }
    out = train(
        ENV_ID,
        "sac",
        timesteps=256,
        seed=1,
        n_envs=2,
        run_dir=tmp_path,
        progress_bar=False,
        hyperparams=hp,
    )
    assert json.loads((out / "meta.json").read_text())["algo"] == "sac"
    a, _ = load_run(out).predict(np.zeros((3, 20), np.float32))
    assert a.shape == (3, 4) and np.all(np.abs(a) <= 1)


def test_seed_split_is_enforced():
    check_evaluation_seeds(5000, 100)
    with pytest.raises(ValueError, match="reserved for training"):
        check_evaluation_seeds(TRAIN_SEED_BASE - 5, 10)
    with pytest.raises(ValueError, match="reserved for training"):
        evaluate(ENV_ID, ["paper"], 3, TRAIN_SEED_BASE, {"config": SHORT})
    assert training_seed(0) >= TRAIN_SEED_BASE
    assert tuned_module.SEARCH_SEED >= TRAIN_SEED_BASE
    with pytest.raises(ValueError, match="seed"):
        training_seed(-1)


def test_hyperparameter_files_and_bad_names():
    hp = load_hyperparams("ppo", ENV_ID)
    assert hp["n_envs"] >= 1 and "policy" in hp
    assert load_hyperparams("sac", ENV_ID)["n_timesteps"] > 0
    with pytest.raises(ValueError, match="algo"):
        load_hyperparams("dqn", ENV_ID)
    with pytest.raises(ValueError, match="no hyperparameters"):
        load_hyperparams("ppo", "pednav/Nope-v0")


def _mean_error_of_constant_action(action, seeds) -> float:
    """Independent path: the scalar env, one episode per seed, the same action."""
    env = gym.make(ENV_ID, config=SHORT)
    errors = []
    for seed in seeds:
        env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            _, r, term, trunc, _ = env.step(np.asarray(action, np.float32))
            total += r
            done = term or trunc
        errors.append(-total)
    return float(np.mean(errors))


def test_tuned_search_beats_action_zero_and_saves_its_policy(tmp_path):
    """A small CMA-ES run (4 training episodes, 3 generations of 6) finds a constant
    action better than action 0 on its training episodes, and reports both objectives
    as the scalar env measures them. Action 0 is the paper's filter, which loses
    stances on fast random walks and diverges (docs/ENV_FOOT.md: 17.5 m mean error on
    the random scenario, 62 % diverged); widening the thresholds a little already
    roughly halves that, so the search must at least halve it."""
    res = tuned_module.search(
        ENV_ID, 4, episodes=4, generations=3, popsize=6, env_kwargs={"config": SHORT}
    )
    assert len(res["action"]) == 4 and all(-1 <= a <= 1 for a in res["action"])
    assert res["evaluations"] == 18
    seeds = [tuned_module.SEARCH_SEED + i for i in range(4)]
    best = _mean_error_of_constant_action(res["action"], seeds)
    paper = _mean_error_of_constant_action(np.zeros(4), seeds)
    # same episodes and actions on another code path: equal up to summation order
    assert res["objective_m"] == pytest.approx(best, rel=1e-9)
    assert res["paper_objective_m"] == pytest.approx(paper, rel=1e-9)
    assert best < 0.5 * paper
    path = tuned_module.save_result(ENV_ID, res, tmp_path / "tuned.json")
    space = gym.make(ENV_ID).action_space
    pol = TunedFixedPolicy.from_file(path, ENV_ID, space)
    a, _ = pol.predict(np.zeros((3, 20), np.float32))
    np.testing.assert_allclose(a, np.tile(res["action"], (3, 1)), atol=1e-6)
    with pytest.raises(ValueError, match="no tuned-fixed action"):
        TunedFixedPolicy.for_env("pednav/Other-v0", space)
    with pytest.raises(ValueError, match="no tuned-fixed action for 'pednav/Other-v0'"):
        TunedFixedPolicy.from_file(path, "pednav/Other-v0", space)
    (tmp_path / "bad.json").write_text("[1, 2]")
    with pytest.raises(ValueError, match=r"bad\.json"):
        TunedFixedPolicy.from_file(tmp_path / "bad.json", ENV_ID, space)


def test_tune_writes_a_run_dir_and_installs_only_when_asked(tmp_path, monkeypatch, capsys):
    """`pednav tune` leaves the shipped baseline alone unless --install; its output
    is a policy for `pednav evaluate` (the file or its directory)."""
    env_id = "pednav/MarkerTrack-v0"
    installed = tmp_path / "installed.json"
    installed.write_text(json.dumps({"pednav/FootZupt-v0": {"action": [0.0] * 4}}))
    monkeypatch.setattr(tuned_module, "RESULTS_FILE", installed)
    args = ["tune", env_id, "--episodes", "2", "--generations", "1", "--popsize", "2"]
    args += ["--scenario", "paper", "--run-dir", str(tmp_path / "run")]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    written = tmp_path / "run" / "tuned_actions.json"
    assert json.loads(written.read_text())[env_id] == result
    assert set(json.loads(installed.read_text())) == {"pednav/FootZupt-v0"}  # untouched
    env = gym.make(env_id)
    obs = np.zeros((1, *env.observation_space.shape), np.float32)
    for policy in (written, written.parent):
        a, _ = load_policy(str(policy), env.action_space, env_id).predict(obs)
        np.testing.assert_allclose(a[0], result["action"], atol=1e-6)
    assert main([*args, "--install"]) == 0
    capsys.readouterr()
    table = json.loads(installed.read_text())
    assert set(table) == {"pednav/FootZupt-v0", env_id}  # other envs' entries kept
    assert table[env_id]["action"] == result["action"]  # same seed, same search


def test_adaptive_rule_reacts_to_innovations_and_motion():
    space = gym.make(ENV_ID).action_space
    pol = InnovationAdaptivePolicy(space)
    idx = {f.name: i for i, f in enumerate(OBS_FEATURES)}
    obs = np.zeros((3, 20), np.float32)
    obs[:, idx["log_nis_interval"]] = np.log1p([40.0, 4.0, 0.4])  # NIS 10x, 1x, 0.1x expected
    obs[:, idx["gyro_norm_mean"]] = [0.05, 2.0, 6.0]  # still, walking, running
    obs[:, idx["accel_excess_std"]] = [0.01, 5.0, 20.0]
    a, _ = pol.predict(obs)
    assert a[0, 2] > 0 and a[1, 2] == pytest.approx(0.0, abs=1e-6) and a[2, 2] < 0
    assert a[0, 0] == 0.0 and a[0, 1] == 0.0  # still: paper thresholds
    assert a[2, 0] > a[1, 0] and a[2, 1] > a[1, 1]  # faster gait: wider thresholds
    with pytest.raises(ValueError, match="no innovation-adaptive rule"):
        InnovationAdaptivePolicy(space, "pednav/Other-v0")


@pytest.mark.parametrize(
    ("env_id", "feature", "knob"),
    [("pednav/WaistStep-v0", "log_nis_interval", 3), ("pednav/MarkerTrack-v0", "log_nis_mean", 0)],
)
def test_adaptive_rules_of_the_other_envs_follow_the_nis(env_id, feature, knob):
    """Too-large innovations raise the adapted noise scale, too-small ones lower it,
    and no update leaves it alone; all other knobs stay at the paper's values."""
    from pednav_env.envs import marker_core, waist_config

    core = waist_config if "Waist" in env_id else marker_core
    names = [f.name if hasattr(f, "name") else f[0] for f in core.OBS_FEATURES]
    space = gym.make(env_id).action_space
    obs = np.zeros((3, len(names) + space.shape[0]), np.float32)
    obs[:, names.index(feature)] = np.log1p([40.0, 0.04, 0.0])  # NIS ≫ m, ≪ m, none
    a, _ = InnovationAdaptivePolicy(space, env_id).predict(obs)
    assert a[0, knob] > 0 > a[1, knob] and a[2, knob] == 0
    others = np.delete(a, knob, axis=1)
    assert not others.any()


def test_load_policy_names(run_dir):
    space = gym.make(ENV_ID).action_space
    assert load_policy("adaptive", space, ENV_ID).name == "adaptive"
    assert load_policy(str(run_dir), space, ENV_ID) is not None
    with pytest.raises(ValueError, match="no pretrained tuner"):
        load_policy("pretrained", space, "pednav/Other-v0")
