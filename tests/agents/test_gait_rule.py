"""The gait-adaptive SHOE rule: its mapping, its parameter file, its names in
`pednav evaluate` / `pednav run`, and the search's rollouts."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
from testdata import DATA

from agents import gait_rule_search
from agents.cli import main
from agents.evaluate import evaluate
from agents.gait_rule import PARAMS_FILE, GaitRuleParams, GaitRulePolicy, read_params
from agents.gait_rule_search import main as search_main
from agents.gait_rule_search import rule_errors, search, to_params, tuned_start
from agents.policies import load_policy
from baselines.tuned import constant_action_errors
from pednav_env.envs.foot_core import OBS_FEATURES, FootZuptConfig
from pednav_env.gait.foot_route import RouteRandomization
from pednav_env.seeds import (
    FINAL_EVALUATION_SEEDS,
    REEVALUATION_SEED,
    TRAIN_SEED_BASE,
    search_seeds,
)

ENV_ID = "pednav/FootZupt-v0"
NAMES = [f.name for f in OBS_FEATURES]
PYSHOE = DATA / "replay" / "pyshoe_2017-11-22-11-48-35_first7s.mat"
SPACE = gym.spaces.Box(-1.0, 1.0, (4,), np.float32)


def obs_row(feature: float, gyro_mean: float = 2.0) -> np.ndarray:
    row = np.zeros(len(NAMES) + 4, np.float32)
    row[NAMES.index("accel_excess_absmax")] = feature
    row[NAMES.index("gyro_norm_mean")] = gyro_mean
    return row


def write(tmp_path, **overrides) -> str:
    data = {"env_id": ENV_ID, "filter": "shoe", "feature": "accel_excess_absmax"}
    data.update({"feature_ref": 25.0, "c": [0.1, 0.5, 0.2, -0.3, 0.4], **overrides})
    data = {k: v for k, v in data.items() if v is not None}
    path = tmp_path / "rule.json"
    path.write_text(json.dumps(data))
    return str(path)


def test_mapping_against_hand_computed_actions():
    """a0 = c0 + c1 · log10(x / 25) while moving, c0 while still, clipped to ±1;
    the other knobs are c2, c3, c4."""
    pol = GaitRulePolicy(GaitRuleParams(c=(0.1, 0.5, 0.2, -0.3, 0.4)))
    obs = np.stack([obs_row(250.0), obs_row(2.5), obs_row(250.0, gyro_mean=0.1), obs_row(0.0)])
    a, _ = pol.predict(obs)
    # log10(250/25) = 1 → 0.6; log10(2.5/25) = −1 → −0.4; still → 0.1;
    # x = 0 → ε = 0.1: 0.1 + 0.5 · log10(0.004) = −1.099 → clipped to −1
    np.testing.assert_allclose(a[:, 0], [0.6, -0.4, 0.1, -1.0], atol=1e-6)
    np.testing.assert_allclose(a[:, 1:], [[0.2, -0.3, 0.4]] * 4, atol=1e-6)
    single, _ = pol.predict(obs_row(250.0))
    assert single.shape == (4,) and single[0] == pytest.approx(0.6, abs=1e-6)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"filter": "paper"}, r"key 'filter' must be 'shoe'"),
        ({"env_id": "pednav/WaistStep-v0"}, r"key 'env_id' must be"),
        ({"c": None}, r"missing key 'c'"),
        ({"c": [0.1, 0.2]}, r"c: expected 5 finite numbers"),
        ({"c": [0.1, True, 0, 0, 0]}, r"key 'c' must be a list of 5 numbers"),
        ({"feature": "speed_mps"}, r"feature: 'speed_mps' is not an observation feature"),
        ({"feature_ref": -1.0}, r"feature_ref: must be a finite number > 0"),
    ],
)
def test_parameter_file_errors_name_the_file_and_key(tmp_path, overrides, message):
    path = write(tmp_path, **overrides)
    with pytest.raises(ValueError, match=message) as exc:
        read_params(path)
    assert "rule.json" in str(exc.value)


def test_unreadable_parameter_file(tmp_path):
    p = tmp_path / "broken.json"
    p.write_text("{not json")
    with pytest.raises(ValueError, match=r"broken.json: not a readable gait-rule JSON file"):
        read_params(p)


def test_the_name_is_shoe_family_only_and_the_shipped_file_is_valid():
    pol = load_policy("gait-rule", SPACE, ENV_ID)
    assert isinstance(pol, GaitRulePolicy) and pol.filter_family == "shoe"
    assert read_params(PARAMS_FILE) == pol.params
    replay = load_policy("gait-rule", SPACE, "pednav/FootZuptReplay-v0")
    assert replay.filter_family == "shoe"
    with pytest.raises(ValueError, match="cannot run filter 'paper'"):
        load_policy("gait-rule:paper", SPACE, ENV_ID)
    with pytest.raises(ValueError, match="shoe filter family"):
        load_policy(
            "gait-rule", gym.make("pednav/WaistStep-v0").action_space, "pednav/WaistStep-v0"
        )


def constant_rule_file(tmp_path) -> str:
    """A rule with slope 0 at the shipped tuned constant: the tuned policy itself."""
    return write(tmp_path, c=tuned_start().tolist())


def test_evaluate_plays_the_rule_on_the_shoe_family(tmp_path):
    """With slope 0 the rule is the tuned constant: evaluate pairs it with tuned on
    the same shoe episodes and finds no difference; the shipped rule plays too."""
    route = RouteRandomization(duration_s=(10.0, 15.0))
    kwargs = {"config": FootZuptConfig(route=route)}
    out = evaluate(ENV_ID, [constant_rule_file(tmp_path), "gait-rule"], 2, 5200, kwargs)
    rows = out["policies"]
    rule = next(p for p in rows if p["name"].endswith("rule.json"))
    assert rule["filter"] == "shoe"
    assert rule["vs_tuned"]["mean_diff"] == pytest.approx(0.0, abs=1e-9)
    shipped = next(p for p in rows if p["name"] == "gait-rule")
    assert shipped["filter"] == "shoe" and len(shipped["episode_errors"]) == 2


def test_pednav_run_accepts_the_rule(capsys, tmp_path):
    assert main(["run", str(PYSHOE), "--json", "--policy", constant_rule_file(tmp_path)]) == 0
    constant = json.loads(capsys.readouterr().out)
    assert main(["run", str(PYSHOE), "--json", "--policy", "tuned"]) == 0
    assert json.loads(capsys.readouterr().out) == constant
    assert main(["run", str(PYSHOE), "--json", "--policy", "gait-rule"]) == 0
    assert "armse_m" in json.loads(capsys.readouterr().out)


def test_search_rollout_with_slope_zero_is_the_constant_and_writes_a_file(tmp_path, capsys):
    seeds = [900_000_000]
    x0 = tuned_start()
    c = np.array([x0[0], 0.0, *x0[2:]])
    base = GaitRuleParams(c=(0.0,) * 5)
    ours = rule_errors(c[None], seeds, base)
    const = constant_action_errors(ENV_ID, np.array([[c[0], *c[2:]]]), seeds, {"filter": "shoe"})
    np.testing.assert_allclose(ours, const, rtol=1e-6)
    args = ["--episodes", "1", "--generations", "1", "--popsize", "2", "--reevaluate", "1"]
    assert search_main(["--out", str(tmp_path / "run"), *args, "--episode-set", "3"]) == 0
    params = read_params(tmp_path / "run" / "gait_rule.json")
    assert params.feature == "accel_excess_absmax"
    record = json.loads((tmp_path / "run" / "gait_rule.json").read_text())
    # set 3: SEARCH_SEED + 3 · 100 000; re-evaluated on the shared fresh episodes
    assert record["episode_set"] == 3 and record["episode_seeds"] == [900_300_000] * 2
    assert record["reevaluation"]["episode_seeds"] == [910_000_000] * 2
    assert search_main(["--out", str(tmp_path / "run" / "gait_rule.json"), *args]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_search_episode_sets_are_disjoint_training_seeds():
    """Set 0 is the shipped search's episodes (900 000 000 …); every set lies on
    the training side, below the re-evaluation episodes, apart from the others."""
    assert search_seeds(0, 16) == list(range(900_000_000, 900_000_016))
    sets = [set(search_seeds(k, 100_000)) for k in (0, 1, 2, 99)]
    assert all(not (a & b) for i, a in enumerate(sets) for b in sets[i + 1 :])
    every = set().union(*sets)
    assert min(every) >= TRAIN_SEED_BASE and max(every) < REEVALUATION_SEED
    assert not every & set(FINAL_EVALUATION_SEEDS)
    for bad, match in (((100, 16), "episode_set"), ((-1, 16), "episode_set")):
        with pytest.raises(ValueError, match=match):
            search_seeds(*bad)
    with pytest.raises(ValueError, match="episodes"):
        search_seeds(1, 100_001)


def test_search_cli_refuses_an_episode_set_out_of_range(tmp_path, capsys):
    args = ["--out", str(tmp_path / "run"), "--episodes", "1", "--episode-set", "100"]
    assert search_main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: episode_set must be in [0, 100)") and err.count("\n") == 1


def _bowl(centre):
    """A stand-in for the rule's errors: each parameter row's squared distance to
    ``centre``, the same on every episode."""

    def errors(cs, seeds, base):
        d = np.sum((np.atleast_2d(cs) - np.asarray(centre)) ** 2, axis=1)
        return np.repeat(d[:, None], len(seeds), axis=1)

    return errors


def test_search_keeps_its_start_when_no_candidate_beats_it(monkeypatch):
    start = to_params(tuned_start())  # the bowl's minimum: no candidate reaches 0
    monkeypatch.setattr(gait_rule_search, "rule_errors", _bowl(start))
    params, record = search(episodes=2, generations=2, popsize=4, reevaluate_episodes=0)
    assert record["kept_start"] is True
    np.testing.assert_array_equal(params.c, start)
    assert record["objective_m"] == 0.0 == record["start_objective_m"]
    assert min(record["best_per_generation_m"]) > 0.0


def test_search_returns_its_best_when_it_beats_the_start(monkeypatch):
    centre = to_params(np.clip(tuned_start() + 0.3, -1, 1))
    monkeypatch.setattr(gait_rule_search, "rule_errors", _bowl(centre))
    params, record = search(episodes=2, generations=6, popsize=6, sigma0=0.3, reevaluate_episodes=0)
    assert record["kept_start"] is False
    start_distance = float(np.sum((to_params(tuned_start()) - centre) ** 2))
    assert record["start_objective_m"] == pytest.approx(start_distance)
    assert record["objective_m"] == min(record["best_per_generation_m"]) < start_distance
    assert np.sum((np.asarray(params.c) - centre) ** 2) == pytest.approx(record["objective_m"])
