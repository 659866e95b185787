"""FootZupt's privileged oracle (shoe family): one constant per speed band of the
coming decision interval."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import pednav_env  # noqa: F401  (registers the environments)
from agents.cli import main
from agents.evaluate import EpisodeBatch, evaluate, load_policy, play_batch
from agents.evaluate_report import format_table
from baselines import oracle as oracle_module
from baselines.oracle import (
    CONTEXTS,
    FOOT_BAND_SPEEDS,
    FOOT_STANDING,
    UNSEARCHED,
    OraclePolicy,
    context_split,
    read_table,
    save_table_entry,
    search_per_context,
)
from baselines.tuned import TunedFixedPolicy
from pednav_env.envs.foot_context import SPEED_BANDS
from pednav_env.envs.foot_core import FootZuptConfig

ENV_ID = "pednav/FootZupt-v0"
KEY = "pednav/FootZupt-v0:shoe"
SPLIT = CONTEXTS[KEY]
SPACE = gym.make(ENV_ID, filter="shoe").action_space
#: Six distinct rows, one per speed band.
ROWS = np.linspace(-0.8, 0.8, len(SPEED_BANDS))[:, None] * np.ones(4)


def test_split_is_the_speed_band_of_the_context_for_the_shoe_family_only():
    assert SPLIT.family == "shoe"
    assert len(SPLIT.labels) == len(SPEED_BANDS)
    assert SPLIT.field == "speed_band" and SPLIT.field_index == 0
    assert SPLIT.labels[0] == FOOT_STANDING and SPLIT.searched == SPLIT.labels[1:]
    assert context_split(ENV_ID, "shoe") is SPLIT
    for family in (None, "paper"):
        with pytest.raises(ValueError, match="no oracle context for pednav/FootZupt-v0"):
            context_split(ENV_ID, family)


@pytest.mark.parametrize("label", SPLIT.labels[1:])
def test_band_episodes_have_their_intervals_mostly_in_that_band(label):
    """Walks restricted to a band: over the intervals in which the foot moves
    (speed ≥ 0.2 m/s), the band's own share is the largest and above one half, and
    the median interval speed lies in the band's walking speeds."""
    kwargs = SPLIT.restrict(label)
    config = kwargs["config"]
    assert config.filter_family == "shoe" and config.scenario == "calibrated"
    default = FootZuptConfig(filter_family="shoe")
    lo, hi = FOOT_BAND_SPEEDS[label]
    assert config.speed_route.speed_mps == (lo, hi)
    assert config.speed_route.stop_probability == default.speed_route.stop_probability
    band = SPLIT.labels.index(label)
    n = 8
    venv = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    _, info = venv.reset(seed=1_500_000)  # training side
    action = np.zeros((n, 4), np.float32)
    contexts = [info["context"]]
    for _ in range(60):
        _, _, _, _, info = venv.step(action)
        contexts.append(info["context"])
    ctx = np.concatenate(contexts)
    moving = ctx[ctx[:, 0] >= 1]
    share = np.bincount(moving[:, 0].astype(int), minlength=len(SPEED_BANDS)) / len(moving)
    assert share.argmax() == band and share[band] > 0.5, share
    assert lo <= np.median(moving[:, 2]) <= hi


def _fake_search(calls):
    def search(env_id, action_dim, env_kwargs=None, **kwargs):
        calls.append((env_id, env_kwargs, kwargs))
        k = len(calls)
        return {"action": ROWS[k].tolist(), "objective_m": float(k)}

    return search


def test_table_round_trip_plays_each_band_its_row_and_standing_the_constant(tmp_path):
    """search_per_context → table file → OraclePolicy: the searched bands' rows in
    band order, the standing band the unsearched constant, shoe family; each
    search saw the walks of its own band."""
    calls = []
    constant = [0.5, -0.25, -0.6, -0.5]
    entry = search_per_context(
        ENV_ID, 4, _fake_search(calls), None, "shoe", constant, episodes=3, seed=7
    )
    assert [c[1]["config"].speed_route.speed_mps for c in calls] == list(FOOT_BAND_SPEEDS.values())
    assert all(c[2] == {"episodes": 3, "seed": 7} for c in calls)
    standing = entry["contexts"][FOOT_STANDING]
    assert standing["searched"] is False and standing["from"] == UNSEARCHED
    path = save_table_entry(KEY, entry, tmp_path / "oracle_actions.json")
    table = read_table(path)
    assert list(table) == [KEY]
    policy = OraclePolicy.from_table(table, ENV_ID, SPACE, str(path), "shoe")
    assert policy.filter_family == "shoe"
    np.testing.assert_allclose(policy.actions[0], constant, atol=1e-7)
    np.testing.assert_allclose(policy.actions[1:], ROWS[1:], atol=1e-7)
    context = np.array([[5.0, 3.0, 2.9], [0.0, 3.0, 0.0], [2.0, 3.0, 1.0]])
    action, _ = policy.predict(np.zeros((3, 20)), context=context)
    np.testing.assert_allclose(action, policy.actions[[5, 0, 2]])


def test_standing_needs_the_constant():
    with pytest.raises(ValueError, match=r"standing.*tune it first"):
        search_per_context(ENV_ID, 4, _fake_search([]), None, "shoe", None)


def _entry(**changes):
    entry = {
        "field": "speed_band",
        "labels": list(SPLIT.labels),
        "contexts": {label: {"action": [0.0] * 4} for label in SPLIT.labels},
    }
    entry.update(changes)
    return entry


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({ENV_ID: _entry()}, "no oracle table for 'pednav/FootZupt-v0:shoe'"),
        ({KEY: _entry(labels=list(SPLIT.labels[:-1]))}, "contexts .* are not the env's"),
        ({KEY: _entry(contexts={FOOT_STANDING: {"action": [0.0] * 4}})}, "no usable action"),
        ({KEY: _entry(contexts={b: {"action": [0.0] * 3} for b in SPLIT.labels})}, "do not fit"),
        ({KEY: _entry(contexts={b: {"action": "x"} for b in SPLIT.labels})}, "no usable action"),
    ],
)
def test_bad_table_raises_naming_the_file(tmp_path, table, match):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(table))
    with pytest.raises(ValueError, match=match) as err:
        OraclePolicy.from_table(read_table(path), ENV_ID, SPACE, str(path), "shoe")
    assert str(path) in str(err.value)


def test_a_paper_keyed_table_is_not_the_shoe_oracle_and_vice_versa(tmp_path):
    """A table under the bare env id (how paper-family results are keyed) is not
    read for the shoe family, and the paper family has no oracle."""
    with pytest.raises(ValueError, match="no oracle table for 'pednav/FootZupt-v0:shoe'"):
        OraclePolicy.from_table({ENV_ID: _entry()}, ENV_ID, SPACE, "t.json", "shoe")
    with pytest.raises(ValueError, match="filter family paper"):
        OraclePolicy.from_table({KEY: _entry()}, ENV_ID, SPACE, "t.json", "paper")
    with pytest.raises(ValueError, match="filter family paper"):
        load_policy("oracle:paper", SPACE, ENV_ID)


def test_not_a_table_raises_naming_the_file(tmp_path):
    path = tmp_path / "x.json"
    path.write_text("[1, 2]")
    with pytest.raises(ValueError, match=r"x\.json"):
        read_table(path)


def _oracle(rows=ROWS) -> OraclePolicy:
    return OraclePolicy(rows, SPLIT.field_index, SPACE, "shoe")


class Spy:
    """An oracle that records the bands it was handed."""

    needs_context = True
    filter_family = "shoe"

    def __init__(self) -> None:
        self.oracle = _oracle()
        self.bands: list[np.ndarray] = []

    def predict(self, observation, state=None, episode_start=None, deterministic=True, **kw):
        self.bands.append(kw["context"][:, 0].copy())
        return self.oracle.predict(observation, state, context=kw["context"])


def test_oracle_switches_within_an_episode_and_equals_tuned_when_its_rows_do():
    """Evaluated on shoe-family episodes, the oracle sees several bands within
    each walk (it switches per interval, not per episode); with every row the
    tuned constant it scores exactly what the constant scores."""
    kwargs = {"filter": "shoe"}
    spy = Spy()
    play_batch(EpisodeBatch(ENV_ID, spy, 20000, 2, kwargs))
    bands = np.array(spy.bands)  # steps × lanes
    for lane in range(2):
        assert len(np.unique(bands[:, lane])) >= 3
    tuned = TunedFixedPolicy.for_env(ENV_ID, SPACE, "shoe")
    same = _oracle(np.tile(tuned.action, (len(SPLIT.labels), 1)))
    a = play_batch(EpisodeBatch(ENV_ID, same, 20000, 2, kwargs))
    b = play_batch(EpisodeBatch(ENV_ID, tuned, 20000, 2, kwargs))
    assert [r.mean_error for r in a] == [r.mean_error for r in b]


def test_evaluate_plays_the_oracle_on_the_shoe_family(monkeypatch):
    """`--policy oracle` on the foot env: the shoe family's table (asked for with
    the shoe family by default), played in the shoe block beside tuned."""
    asked = []

    def for_env(cls, env_id, space, family=None):
        asked.append((env_id, family))
        return _oracle()

    monkeypatch.setattr(oracle_module.OraclePolicy, "for_env", classmethod(for_env))
    result = evaluate(ENV_ID, ["real-fixed", "tuned", "oracle"], 2, 20000)
    assert asked == [(ENV_ID, "shoe")]
    entries = {p["name"]: p for p in result["policies"]}
    assert {p["filter"] for p in result["policies"]} == {"shoe"}
    assert entries["oracle"]["vs_tuned"]["p_value"] is not None
    assert entries["oracle"]["episode_errors"] != entries["tuned"]["episode_errors"]
    assert "oracle (privileged)" in format_table(result)


def test_tune_per_context_for_the_paper_family_is_a_one_line_error(capsys):
    code = main(["tune", ENV_ID, "--per-context", "--filter", "paper", "--episodes", "1"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "filter family paper" in err
    code = main(["tune", ENV_ID, "--per-context", "--scenario", "random", "--episodes", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "no env options but --filter" in err


def test_tune_per_context_writes_the_shoe_keyed_table(tmp_path, monkeypatch, capsys):
    """`pednav tune pednav/FootZupt-v0 --per-context` (shoe by default) writes the
    table under the shoe key, standing from the shipped constant, and --install
    makes what `--policy oracle` reads."""
    installed = tmp_path / "installed.json"
    monkeypatch.setattr(oracle_module, "RESULTS_FILE", installed)
    monkeypatch.setattr(oracle_module, "CONTEXTS", {KEY: _two_bands()})
    args = ["tune", ENV_ID, "--per-context", "--episodes", "1", "--generations", "1"]
    args += ["--popsize", "2", "--run-dir", str(tmp_path / "run"), "--install"]
    assert main(args) == 0
    printed = json.loads(capsys.readouterr().out)
    table = read_table(tmp_path / "run" / "oracle_actions.json")
    assert list(table) == [KEY] and table[KEY] == printed == read_table(installed)[KEY]
    tuned = TunedFixedPolicy.for_env(ENV_ID, SPACE, "shoe")
    standing = printed["contexts"][FOOT_STANDING]
    np.testing.assert_allclose(standing["action"], tuned.action, atol=1e-6)
    assert printed["contexts"]["2.6+"]["initial_mean"] == pytest.approx(tuned.action, abs=1e-6)
    oracle = load_policy("oracle", SPACE, ENV_ID)
    assert oracle.filter_family == "shoe"
    np.testing.assert_allclose(oracle.actions[1], printed["contexts"]["2.6+"]["action"], atol=1e-6)


def _two_bands():
    """A two-context split (standing, the top band, whose walks diverge soonest at
    action 0) for a quick CLI run."""
    from dataclasses import replace

    return replace(SPLIT, labels=(FOOT_STANDING, "2.6+"))


def test_distilled_foot_student_runs_the_shoe_family(tmp_path):
    """A student distilled on the foot env with the shoe family records it in
    meta.json and loads as a shoe-family policy (so `pednav evaluate` plays it on
    the shoe family); asking for the paper family is refused."""
    from agents.distill import distill

    run = distill(
        ENV_ID,
        tmp_path / "run",
        lanes=2,
        iterations=1,
        steps_per_iteration=4,
        epochs=1,
        batch_size=8,
        teacher=_oracle(),
        filter_family="shoe",
    )
    meta = json.loads((run / "meta.json").read_text())
    assert meta["filter"] == "shoe" and meta["samples"] == 8
    assert load_policy(str(run), SPACE, ENV_ID).filter_family == "shoe"
    with pytest.raises(ValueError, match="trained with filter 'shoe', not 'paper'"):
        load_policy(str(run), SPACE, ENV_ID, filter_family="paper")


def test_distill_filter_on_an_env_without_families_is_a_one_line_error(tmp_path, capsys):
    code = main(
        ["distill", "pednav/MarkerTrack-v0", "--filter", "shoe", "--run-dir", str(tmp_path)]
    )
    err = capsys.readouterr().err
    assert code == 2 and "has no filter families" in err and err.count("\n") == 1
