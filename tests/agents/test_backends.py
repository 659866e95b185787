"""The Ray backend gives the serial backend's results, on a local Ray instance (2 CPUs)."""

import json

import numba
import pytest
import torch

from agents.backends import RayBackend, SerialBackend, make_backend
from agents.cli import main
from agents.train import train_seeds
from baselines import tuned as tuned_module
from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.gait.foot_route import RouteRandomization
from pednav_env.seeds import training_seed

ENV_ID = "pednav/FootZupt-v0"
SHORT = FootZuptConfig(route=RouteRandomization(duration_s=(10.0, 14.0)))


@pytest.fixture(scope="module")
def ray_backend():
    import ray

    backend = RayBackend(num_cpus=2)
    yield backend
    ray.shutdown()


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory):
    """A saved PPO model with its VecNormalize statistics (trained on 2 lanes)."""
    from stable_baselines3 import PPO

    from pednav_env.sb3 import make_vec_env

    out = tmp_path_factory.mktemp("model")
    vec = make_vec_env(ENV_ID, n_envs=2, seed=1, normalize=True, config=SHORT)
    kwargs = {"n_steps": 32, "batch_size": 32, "n_epochs": 1, "policy_kwargs": {"net_arch": [16]}}
    model = PPO("MlpPolicy", vec, seed=1, device="cpu", **kwargs).learn(64)
    model.save(out / "model.zip")
    vec.save(str(out / "vecnormalize.pkl"))
    return out


def test_backends_map_in_item_order_and_raise_a_task_error(ray_backend):
    done = []
    assert SerialBackend().map(training_seed, [2, 1], on_done=done.append) == [
        training_seed(2),
        training_seed(1),
    ]
    assert done == [0, 1]
    done.clear()
    seeds = list(range(7))
    assert ray_backend.map(training_seed, seeds, on_done=done.append) == [
        training_seed(s) for s in seeds
    ]
    assert sorted(done) == seeds
    assert ray_backend.workers == 2
    # a task reserves one CPU: the foot kernel runs on one numba thread there
    assert ray_backend.map(lambda _: numba.get_num_threads(), [0, 1]) == [1, 1]
    with pytest.raises(ValueError, match="seed must be in"):  # the task's own ValueError
        ray_backend.map(training_seed, [1, -1])
    with pytest.raises(ValueError, match="backend must be one of"):
        make_backend("dask")


def test_evaluate_on_ray_equals_serial(ray_backend, tiny_model, capsys):
    """Same seeds, same JSON to the last bit: a batch is the unit of work of both."""
    args = ["evaluate", ENV_ID, "--policy", "paper", "tuned", "adaptive", str(tiny_model)]
    args += ["--episodes", "5", "--seed", "300", "--scenario", "paper", "--lanes", "2", "--json"]
    assert main(args) == 0
    serial = json.loads(capsys.readouterr().out)
    assert main([*args, "--backend", "ray"]) == 0
    assert json.loads(capsys.readouterr().out) == serial
    assert {p["vs_paper"]["mean_diff"] != 0 for p in serial["policies"][1:]} == {True}


def test_tune_on_ray_equals_serial(ray_backend):
    kwargs = {"episodes": 2, "generations": 2, "popsize": 4, "env_kwargs": {"config": SHORT}}
    serial = tuned_module.search(ENV_ID, 4, **kwargs)
    ray = tuned_module.search(ENV_ID, 4, map_fn=ray_backend.map, n_tasks=3, **kwargs)
    serial.pop("seconds"), ray.pop("seconds")
    assert ray == serial


def test_train_seeds_on_ray_equals_serial(ray_backend, tmp_path):
    # A network and batch big enough for PyTorch's kernel choice to matter: with the
    # workers' default OMP_NUM_THREADS=1 these weights differ in the last bits.
    hp = {"n_steps": 64, "batch_size": 128, "n_epochs": 2, "policy_kwargs": {"net_arch": [64, 64]}}
    hp |= {"env_kwargs": {"config": SHORT}, "checkpoint_steps": 10_000}
    kwargs = {"timesteps": 256, "n_envs": 2, "hyperparams": hp}
    serial = train_seeds(ENV_ID, "ppo", [4, 5], tmp_path / "serial", **kwargs)
    ray = train_seeds(ENV_ID, "ppo", [4, 5], tmp_path / "ray", backend=ray_backend, **kwargs)
    assert [p.name for p in ray] == [p.name for p in serial] == ["ppo_seed4", "ppo_seed5"]
    from stable_baselines3 import PPO

    weights = []
    for a, b in zip(serial, ray, strict=True):
        pa = PPO.load(a / "model.zip", device="cpu").policy.state_dict()
        pb = PPO.load(b / "model.zip", device="cpu").policy.state_dict()
        assert pa.keys() == pb.keys()
        for key in pa:
            assert torch.equal(pa[key], pb[key]), key
        weights.append(pa["mlp_extractor.policy_net.0.weight"])
        meta_a, meta_b = (json.loads((d / "meta.json").read_text()) for d in (a, b))
        assert meta_a["lane_seeds"] == meta_b["lane_seeds"]
    assert not torch.equal(*weights)  # two seeds, two different runs
