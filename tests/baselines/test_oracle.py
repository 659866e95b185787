"""The privileged episode context and the oracle that reads it."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import pednav_env  # noqa: F401  (registers the environments)
from agents.cli import main
from agents.evaluate import EpisodeBatch, evaluate, play_batch
from agents.evaluate_report import format_table
from baselines import oracle as oracle_module
from baselines.oracle import CONTEXTS, RESULTS_FILE, OraclePolicy, read_table
from baselines.tuned import TunedFixedPolicy
from pednav_env.envs.marker_config import MarkerTrackConfig
from pednav_env.envs.waist_config import WaistRandomization, WaistStepConfig
from pednav_env.seeds import REEVALUATION_SEED

SHORT = {
    "pednav/WaistStep-v0": {
        "config": WaistStepConfig(randomization=WaistRandomization(duration_s=(4.0, 6.0)))
    },
    "pednav/MarkerTrack-v0": {"config": MarkerTrackConfig(duration_s=(3.0, 4.0))},
}
#: info entry naming the context the index must point at.
LABEL_KEY = {"pednav/WaistStep-v0": "sensor_grade", "pednav/MarkerTrack-v0": "uwb_condition"}


@pytest.mark.parametrize("env_id", sorted(SHORT))
def test_context_index_names_the_episode_condition(env_id):
    """The context's index field points at the grade / condition the info names,
    in the vector env (reset and after an autoreset) and the scalar env alike."""
    split = CONTEXTS[env_id]
    venv = gym.make_vec(
        env_id, num_envs=6, vectorization_mode="vector_entry_point", **SHORT[env_id]
    )
    _, info = venv.reset(seed=20000)
    labels = [split.labels[int(i)] for i in info["context"][:, split.field_index]]
    assert labels == list(info[LABEL_KEY[env_id]])
    resets = 0
    for _ in range(20):  # past the end of the short walks (≤ 6 s = 12 steps): autoresets
        _, _, term, trunc, info = venv.step(np.zeros(venv.action_space.shape, np.float32))
        resets += int((term | trunc).sum())
        labels = [split.labels[int(i)] for i in info["context"][:, split.field_index]]
        assert labels == list(info[LABEL_KEY[env_id]])
    assert resets >= 6
    env = gym.make(env_id, **SHORT[env_id])
    for lane in range(3):
        _, scalar_info = env.reset(seed=20000 + lane)
        _, vinfo = venv.reset(seed=20000)
        np.testing.assert_array_equal(scalar_info["context"], vinfo["context"][lane])


def test_waist_context_scales_are_drawn_in_the_grade_scale_range():
    """σ_a and σ_n factors lie in the configured range and differ between episodes
    (a context stuck at 1 would be the paper scenario's)."""
    cfg = WaistStepConfig(randomization=WaistRandomization(duration_s=(4.0, 6.0)))
    venv = gym.make_vec(
        "pednav/WaistStep-v0", num_envs=16, vectorization_mode="vector_entry_point", config=cfg
    )
    _, info = venv.reset(seed=20000)
    lo, hi = cfg.randomization.grade_scale
    scales = info["context"][:, 1:3]
    assert np.all((scales >= lo) & (scales <= hi))
    assert np.unique(scales).size == scales.size


def _oracle(env_id: str) -> OraclePolicy:
    space = gym.make(env_id, **SHORT[env_id]).action_space
    n = len(CONTEXTS[env_id].labels)
    actions = np.linspace(-0.9, 0.9, n)[:, None] * np.ones(space.shape)
    return OraclePolicy(actions, CONTEXTS[env_id].field_index, space)


def test_oracle_plays_the_row_of_the_context():
    env_id = "pednav/MarkerTrack-v0"
    oracle = _oracle(env_id)
    context = np.array([[2.0, 1.1], [0.0, 0.8], [5.0, 1.4]])
    action, _ = oracle.predict(np.zeros((3, 5)), context=context)
    np.testing.assert_array_equal(action, oracle.actions[[2, 0, 5]])
    with pytest.raises(ValueError, match="context"):
        oracle.predict(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="outside"):
        oracle.predict(np.zeros((1, 5)), context=np.array([[-1.0, 1.0]]))


class RecordingPolicy:
    """Zero actions; records the contexts it is handed (or that it got none)."""

    def __init__(self, needs_context: bool) -> None:
        self.needs_context = needs_context
        self.seen: list[np.ndarray] = []

    def predict(self, observation, state=None, episode_start=None, deterministic=True, **kw):
        self.seen.append(kw.get("context"))
        return np.zeros((len(observation), 4), np.float32), state


@pytest.mark.parametrize("needs_context", [True, False])
def test_evaluation_hands_the_context_only_to_policies_that_declare_it(needs_context):
    env_id = "pednav/MarkerTrack-v0"
    policy = RecordingPolicy(needs_context)
    play_batch(EpisodeBatch(env_id, policy, 20000, 4, SHORT[env_id]))
    if not needs_context:
        assert all(c is None for c in policy.seen)
        return
    _, info = gym.make_vec(
        env_id, num_envs=4, vectorization_mode="vector_entry_point", **SHORT[env_id]
    ).reset(seed=20000)
    np.testing.assert_array_equal(policy.seen[0], info["context"])


def test_oracle_on_its_own_contexts_equals_the_constants_per_context():
    """Evaluated through `evaluate`, each episode scores what its context's constant
    scores on it (the table row is applied to the right episodes)."""
    env_id = "pednav/MarkerTrack-v0"
    oracle = _oracle(env_id)
    kwargs = SHORT[env_id]
    out = play_batch(EpisodeBatch(env_id, oracle, 20000, 6, kwargs))
    _, info = gym.make_vec(
        env_id, num_envs=6, vectorization_mode="vector_entry_point", **kwargs
    ).reset(seed=20000)
    rows = info["context"][:, 0].astype(int)
    for lane, row in enumerate(rows):
        const = TunedFixedPolicy(oracle.actions[row], gym.make(env_id, **kwargs).action_space)
        alone = play_batch(EpisodeBatch(env_id, const, 20000 + lane, 1, kwargs))
        assert out[lane].mean_error == alone[0].mean_error


def test_shipped_oracle_table_covers_the_env_contexts():
    if not RESULTS_FILE.exists():
        pytest.skip("no oracle table shipped")
    table = read_table(RESULTS_FILE)
    for key, entry in table.items():
        assert tuple(entry["labels"]) == CONTEXTS[key].labels
        env_id, _, family = key.partition(":")
        family = family or None
        space = gym.make(env_id, **({"filter": family} if family else {})).action_space
        assert OraclePolicy.for_env(env_id, space, family).filter_family == family


def test_evaluate_labels_and_plays_the_oracle(monkeypatch):
    env_id = "pednav/MarkerTrack-v0"
    monkeypatch.setattr(
        oracle_module.OraclePolicy,
        "for_env",
        classmethod(lambda cls, e, s, f=None: _oracle(env_id)),
    )
    result = evaluate(env_id, ["oracle"], 3, 20000, SHORT[env_id])
    assert result["policies"][0]["name"] == "oracle"
    assert "oracle (privileged)" in format_table(result)


def _scalar_mean_error(env_id, action, seeds, env_kwargs):
    """Independent path: the scalar env, one episode per seed, a constant action."""
    env = gym.make(env_id, **env_kwargs)
    errors, labels = [], []
    for seed in seeds:
        _, info = env.reset(seed=seed)
        labels.append(info[LABEL_KEY[env_id]])
        total, done = 0.0, False
        while not done:
            _, r, term, trunc, _ = env.step(np.asarray(action, np.float32))
            total += r
            done = term or trunc
        errors.append(-total)
    return float(np.mean(errors)), labels


def test_tune_per_context_searches_each_context_on_its_own_episodes(tmp_path, monkeypatch, capsys):
    """`pednav tune --per-context` writes one search per UWB condition; each was
    re-evaluated on fresh training episodes of that condition only (the scalar env
    replays them), and --install makes the table `--policy oracle` reads."""
    env_id = "pednav/MarkerTrack-v0"
    installed = tmp_path / "installed.json"
    monkeypatch.setattr(oracle_module, "RESULTS_FILE", installed)
    args = ["tune", env_id, "--per-context", "--episodes", "2", "--generations", "1"]
    args += ["--popsize", "2", "--reevaluate", "1", "--run-dir", str(tmp_path / "run"), "--install"]
    assert main(args) == 0
    printed = json.loads(capsys.readouterr().out)
    entry = read_table(tmp_path / "run" / "oracle_actions.json")[env_id]
    assert entry == printed and read_table(installed)[env_id] == entry
    split = CONTEXTS[env_id]
    assert entry["labels"] == list(split.labels)
    for label in split.labels[1:3]:  # two conditions keep the test short
        result = entry["contexts"][label]
        seeds = [REEVALUATION_SEED]
        mean, labels = _scalar_mean_error(env_id, result["action"], seeds, split.restrict(label))
        assert labels == [label]
        # same episodes and action through the vector env: equal up to summation order
        assert result["reevaluation"]["mean_m"] == pytest.approx(mean, rel=1e-9)
    space = gym.make(env_id).action_space
    oracle = OraclePolicy.for_env(env_id, space)
    np.testing.assert_allclose(
        oracle.actions[1], np.clip(entry["contexts"][split.labels[1]]["action"], -1, 1), atol=1e-6
    )
