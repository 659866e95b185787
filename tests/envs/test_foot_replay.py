"""``pednav/FootZuptReplay-v0`` on the shipped PyShoe excerpt: the FootZupt spaces, the
episode and its return, bad data directories, and the policy-driven `pednav run` path
replaying the same filter (the contract every env keeps is in tests/envs/test_env_contract.py)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from env_rollout import rollout
from testdata import HALLWAY_DATA, REPLAY_DATA

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.envs.foot_replay_core import FootReplayConfig, FootReplayCore
from pednav_env.io import load_recording

ENV_ID = "pednav/FootZuptReplay-v0"


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID, data_dir=str(REPLAY_DATA))
    yield e
    e.close()


@pytest.mark.parametrize("family", ["paper", "shoe"])
def test_same_spaces_as_the_simulated_env(family):
    """Per filter family, a policy made in simulation fits the replay env."""
    replay = gym.make(ENV_ID, data_dir=str(REPLAY_DATA), filter=family)
    sim = gym.make("pednav/FootZupt-v0", filter=family)
    assert replay.action_space == sim.action_space
    assert replay.observation_space == sim.observation_space
    assert replay.unwrapped.core.knobs == sim.unwrapped.core.knobs


def test_episode_is_the_trial_and_the_return_is_minus_the_mean_error(env):
    _, rewards, info = rollout(env, 0)
    assert info["trial"] == "pyshoe_2017-11-22-11-48-35_first7s"
    assert info["imu_grade"] == "recorded"
    assert len(rewards) == 12  # (1400 − alignment) samples / 100 per step
    assert np.all(rewards <= 0)
    assert info["distance"] > 5.0  # 5.8 m walked in the 6 s after the still start
    # A ZUPT-aided foot INS drifts about 1 % of the distance walked (0.06 m here);
    # PyShoe's own filter, tuned for this trial, reaches 0.04 m in this metric over the
    # whole 21 s trial (docs/REAL_DATA.md, PyShoe's 0.029 m × √2). Without working
    # ZUPTs this 6 s walk drifts about 1 m (mean) and 2 m (final).
    assert -rewards.sum() < 0.1  # the return is minus the time-averaged error
    assert info["error"] < 0.25  # the final error


def test_bad_data_directories():
    with pytest.raises(ValueError, match="data_dir is required"):
        gym.make(ENV_ID)
    with pytest.raises(ValueError, match="not a directory"):
        gym.make(ENV_ID, data_dir=str(REPLAY_DATA / "nope"))
    # footprint-only walks: refused at construction, naming the first such file
    with pytest.raises(ValueError, match=r"first5s\.csv: no truth track \(it has footprints"):
        gym.make(ENV_ID, data_dir=str(HALLWAY_DATA))
    with pytest.raises(ValueError, match="trial_order must be one of"):
        gym.make(ENV_ID, data_dir=str(REPLAY_DATA), trial_order="shuffled")


def test_recordings_whose_intervals_differ_in_samples_are_refused(tmp_path):
    """200 Hz and 100 Hz walks: a 0.5 s decision interval is 100 and 50 samples, and the
    lanes step together, so the folder is refused naming both files and rates."""
    from pednav_env.replay.simulate import SimulateConfig, simulate_walk, write_recording_csv

    for name, rate in (("a200", 200.0), ("b100", 100.0)):
        walk = simulate_walk(SimulateConfig(duration_s=5.0, rate_hz=rate))
        write_recording_csv(walk, tmp_path / f"{name}.csv")
    with pytest.raises(ValueError, match=r"a200\.csv 200\.0 Hz, b100\.csv 100\.0 Hz") as exc:
        gym.make(ENV_ID, data_dir=str(tmp_path))
    assert "100 and 50 samples" in str(exc.value)


def test_each_recording_plays_at_its_own_rate(tmp_path):
    """A recording whose clock runs 0.03 % slow (as PyShoe trials differ: 200.009 to
    200.151 Hz) plays at its own rate beside one at the original rate: each episode
    equals that recording replayed alone (the filter's sample interval is per lane)."""
    import scipy.io

    src = next(REPLAY_DATA.glob("*.mat"))
    data = scipy.io.loadmat(src)
    (tmp_path / "a.mat").write_bytes(src.read_bytes())
    data["ts"] = data["ts"] * (1.0 + 3e-4)
    scipy.io.savemat(tmp_path / "b.mat", {k: v for k, v in data.items() if k[0] != "_"})

    def errors(folder, n):
        env = gym.make_vec(
            ENV_ID,
            n,
            vectorization_mode="vector_entry_point",
            data_dir=str(folder),
            trial_order="sequential",
        )
        env.reset(seed=0)
        total, done = np.zeros(n), np.zeros(n, dtype=bool)
        while not done.all():
            _, r, term, trunc, _ = env.step(np.zeros((n, 4), np.float32))
            total += np.where(done, 0.0, r)
            done |= term | trunc
        return -total

    both = errors(tmp_path, 2)
    assert abs(both[0] - both[1]) > 1e-4  # the clocks differ enough to tell
    for i, name in enumerate(("a", "b")):
        alone = tmp_path / name
        alone.mkdir()
        (alone / f"{name}.mat").write_bytes((tmp_path / f"{name}.mat").read_bytes())
        np.testing.assert_allclose(errors(alone, 1)[0], both[i], rtol=1e-9)


def test_sequential_order_plays_every_recording_once_in_name_order(three_recordings):
    """trial_order="sequential": seed s plays recording (s − first_trial_seed) mod n of the
    sorted names, a lane's next episode the next one; lane i of a vector env seeded s
    plays what the scalar env seeded s + i plays."""
    kwargs = {"data_dir": str(three_recordings), "trial_order": "sequential"}
    env = gym.make(ENV_ID, first_trial_seed=100, **kwargs)
    trials = [env.reset(seed=101)[1]["trial"]] + [env.reset()[1]["trial"] for _ in range(3)]
    assert trials == ["b", "c", "a", "b"]
    assert env.reset(seed=100)[1]["trial"] == "a"
    venv = gym.make_vec(
        ENV_ID, num_envs=4, vectorization_mode="vector_entry_point", first_trial_seed=7, **kwargs
    )
    _, info = venv.reset(seed=7)
    assert list(info["trial"]) == ["a", "b", "c", "a"]
    lengths = {"a": 7.0, "b": 6.0, "c": 5.0}
    while True:  # c (5 s) ends first; lane 2 then starts its next trial, a
        _, _, term, trunc, info = venv.step(np.zeros((4, 4), np.float32))
        if (term | trunc).any():
            break
    assert list(np.flatnonzero(term | trunc)) == [2]
    assert info["final_info"][2]["trial"] == "c" and info["trial"][2] == "a"
    assert min(lengths, key=lengths.get) == "c"
    # random order (the default, training) draws: not every 3 seeds cover the three
    draws = [
        gym.make(ENV_ID, data_dir=str(three_recordings)).reset(seed=s)[1]["trial"] for s in range(6)
    ]
    assert len(set(draws[:3])) < 3 or len(set(draws[3:])) < 3


@pytest.mark.parametrize("family", ["paper", "shoe"])
def test_policy_schedule_replays_the_core_exactly(family):
    """`pednav run` with a policy: the knob schedule recorded in the replay core,
    replayed by the runner, gives the core's own estimate at every interval end
    (shoe family: the window knob too, the statistic per interval)."""
    rec = load_recording(REPLAY_DATA / "pyshoe_2017-11-22-11-48-35_first7s.mat")
    config = FootReplayConfig(filter_family=family)
    core = FootReplayCore(config, 1, "test", recordings=[rec])
    core.reset_lanes(np.array([0]), [np.random.default_rng(0)])
    rng = np.random.default_rng(1)
    from pednav_env.replay.runner import run_prepared

    ends, knobs = [], {}
    while core.cursor[0] < core.length[0]:
        _, _, _, _, info = core.step(rng.uniform(-1, 1, (1, 4)))
        ends.append((int(core.cursor[0]), info["pos_est"][0].copy()))
        for k, v in core.knob_values().items():
            knobs.setdefault(k, []).append(v.copy())
    run = run_prepared(core._trial(0).prepared, schedule={k: np.array(v) for k, v in knobs.items()})
    for cursor, pos in ends:
        np.testing.assert_allclose(run.pos[0, cursor - 1], pos, atol=1e-12)
