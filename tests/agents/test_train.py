"""Training (agents.train), saved tuners, loading policies and the seed split."""

import json

import gymnasium as gym
import numpy as np
import pytest

from agents.evaluate import evaluate, load_policy
from agents.policies import load_run
from agents.train import load_hyperparams, train
from baselines import tuned as tuned_module
from pednav_env.envs.foot_core import FootZuptConfig
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
    # the learned tuners' default filter family, carried by the run
    assert meta["filter"] == "shoe" and load_run(run_dir).filter_family == "shoe"


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


def test_load_policy_names(run_dir):
    space = gym.make(ENV_ID).action_space
    assert load_policy("adaptive", space, ENV_ID).name == "adaptive"
    assert load_policy(str(run_dir), space, ENV_ID) is not None
    with pytest.raises(ValueError, match="no pretrained tuner"):
        load_policy("pretrained", space, "pednav/Other-v0")
