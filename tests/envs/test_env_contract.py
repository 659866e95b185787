"""The contract every registered ``pednav/`` environment keeps, scalar and vector.

Parametrised over the ids in Gymnasium's registry (as Gymnasium's own
``tests/envs/test_envs.py`` does), so a newly registered env is checked too:
Gymnasium's and SB3's env checkers without warnings; same seed ⇒ same episode;
the vector env's spaces, shapes, dtypes, seeding and SAME_STEP autoreset; lane i
of a vector env reset with seed s equals, bit for bit, a scalar env reset with
seed s + i (observations, rewards, flags and every info entry, over two episodes
per lane); bad actions raise a ValueError naming the env; random and extreme
actions over whole episodes stay finite and inside the observation space;
rendering, pickling and a PPO smoke run. Env-specific behaviour (rewards against
an independent computation, knobs, configuration errors) is in each env's own file
beside this one (test_foot_zupt.py, test_waist_step.py, test_marker_track.py,
test_foot_replay.py).
"""

from __future__ import annotations

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from env_rollout import ENV_IDS, FAST_KWARGS, rollout
from gymnasium.utils.env_checker import check_env as gym_check_env
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import pednav_env  # noqa: F401  (registers the environments)
from pednav_env.envs.foot_filters import FILTER_FAMILIES

#: Envs whose test data hold a single episode (the replay env's one shipped trial),
#: so that another seed cannot give another episode.
SINGLE_EPISODE = {"pednav/FootZuptReplay-v0"}

#: Envs with filter families: each family is a case of its own ("id:family").
FAMILIES = {"pednav/FootZupt-v0": FILTER_FAMILIES, "pednav/FootZuptReplay-v0": FILTER_FAMILIES}
CASES = [
    f"{env_id}:{family}" if env_id in FAMILIES else env_id
    for env_id in ENV_IDS
    for family in FAMILIES.get(env_id, ("",))
]

pytestmark = pytest.mark.parametrize("env_id", CASES)


def case_kwargs(case: str) -> tuple[str, dict]:
    """(env id, constructor arguments) of a case."""
    env_id, _, family = case.partition(":")
    kwargs = dict(FAST_KWARGS.get(env_id, {}))
    if family:
        kwargs["filter"] = family
    return env_id, kwargs


def make(case: str, **kwargs) -> gym.Env:
    env_id, fast = case_kwargs(case)
    return gym.make(env_id, **fast, **kwargs)


def make_vec(case: str, n: int) -> gym.vector.VectorEnv:
    env_id, kwargs = case_kwargs(case)
    return gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)


def test_gymnasium_and_sb3_checkers_pass_without_warnings(env_id):
    env = make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(env.unwrapped)
        sb3_check_env(env, warn=True)
    env.close()


def test_same_seed_same_episode(env_id):
    env = make(env_id).unwrapped
    a, b, c = rollout(env, 3), rollout(env, 3), rollout(env, 4)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert data_equivalence(a[2], b[2], exact=True)  # the last infos
    if env_id.partition(":")[0] not in SINGLE_EPISODE:
        assert a[0].shape != c[0].shape or not np.array_equal(a[0], c[0])


def test_vector_env_spaces_shapes_dtypes_and_seeding(env_id):
    n = 3
    venv = make_vec(env_id, n)
    env = make(env_id).unwrapped
    assert venv.num_envs == n
    assert venv.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    assert venv.single_action_space == env.action_space
    assert venv.single_observation_space == env.observation_space
    assert venv.action_space == batch_space(env.action_space, n)
    assert venv.observation_space == batch_space(env.observation_space, n)

    def play(seed):
        """Observations of 6 steps; every lane gets the same actions, so lanes that
        share a seed share a trajectory."""
        obs, info = venv.reset(seed=seed)
        assert obs.dtype == np.float32 and venv.observation_space.contains(obs)
        assert all(len(v) == n for v in info.values())
        env.action_space.seed(0)
        out = [obs]
        for _ in range(6):
            a = np.tile(env.action_space.sample(), (n, 1))
            obs, r, term, trunc, info = venv.step(a)
            assert venv.observation_space.contains(obs)
            assert r.shape == term.shape == trunc.shape == (n,)
            assert r.dtype == np.float64 and term.dtype == trunc.dtype == np.bool_
            assert all(len(v) == n for v in info.values())
            out.append(obs)
        return np.array(out)

    first = play(11)
    np.testing.assert_array_equal(play(11), first)
    # lane i plays the scalar env's seed + i: lanes 0, 1 with seed 12 are lanes 1, 2 with 11
    shifted = play(12)
    np.testing.assert_array_equal(shifted[:, :2], first[:, 1:])
    if env_id.partition(":")[0] not in SINGLE_EPISODE:
        assert not np.array_equal(shifted, first)
    venv.close()


def test_vector_lanes_equal_scalar_envs_bit_for_bit(env_id):
    """Lane i of a vector env reset with ``seed`` plays, bit for bit, the episodes of
    a scalar env reset with ``seed + i`` (two episodes per lane, so the SAME_STEP
    autoreset is crossed): observations, rewards, flags and every info entry; a
    finished lane reports its last observation and info in ``final_obs`` /
    ``final_info`` and already returns the next episode's first observation; its
    top-level step entries (``error``, ``distance``, …) stay the finished step's,
    its episode descriptors (``context``, the sensor grade, …) are the new
    episode's."""
    n, seed = 3, 20
    venv = make_vec(env_id, n)
    k = venv.single_action_space.shape[0]
    obs, info = venv.reset(seed=seed)
    lanes = [
        {"obs": [obs[i]], "steps": [], "resets": [{key: v[i] for key, v in info.items()}]}
        for i in range(n)
    ]
    episodes = np.zeros(n, dtype=int)
    rng = np.random.default_rng(0)
    actions = []
    while episodes.min() < 2:
        a = rng.uniform(-1.0, 1.0, (n, k)).astype(np.float32)
        actions.append(a)
        obs, r, term, trunc, info = venv.step(a)
        done = term | trunc
        np.testing.assert_array_equal(info.get("_final_obs", np.zeros(n, bool)), done)
        for i in range(n):
            if done[i]:
                step_info = info["final_info"][i]
                # top level after an autoreset: the step's entries are the finished
                # episode's (as in final_info), the descriptors (the reset info's
                # keys) the new episode's
                for key, value in step_info.items():
                    if key not in lanes[i]["resets"][0]:
                        np.testing.assert_array_equal(info[key][i], value, err_msg=key)
                lanes[i]["obs"].append(info["final_obs"][i])
                assert venv.single_observation_space.contains(info["final_obs"][i])
            else:
                step_info = {
                    key: v[i] for key, v in info.items() if not key.startswith(("_", "final_"))
                }
            lanes[i]["steps"].append((r[i], term[i], trunc[i], step_info))
            if done[i]:
                episodes[i] += 1
                lane_info = {k: info[k][i] for k in lanes[i]["resets"][0]}
                lanes[i]["resets"].append(lane_info)
            lanes[i]["obs"].append(obs[i])
    for i in range(n):
        env = make(env_id).unwrapped
        o, reset_info = env.reset(seed=seed + i)
        got_obs, resets = [o], [reset_info]
        for a, (r, term, trunc, lane_step_info) in zip(actions, lanes[i]["steps"], strict=True):
            o, r_s, term_s, trunc_s, step_info = env.step(a[i])
            got_obs.append(o)
            assert (r_s, term_s, trunc_s) == (r, term, trunc)
            assert set(step_info) == set(lane_step_info) | {"knobs"}
            for key, value in lane_step_info.items():
                np.testing.assert_array_equal(step_info[key], value, err_msg=key)
            if term_s or trunc_s:
                o, reset_info = env.reset()  # next episode from the same generator
                got_obs.append(o)
                resets.append(reset_info)
        np.testing.assert_array_equal(np.array(got_obs), np.array(lanes[i]["obs"]))
        for got, lane_reset in zip(resets, lanes[i]["resets"], strict=True):
            assert set(lane_reset) <= set(got)
            for key, value in lane_reset.items():  # arrays (the context) entry by entry
                np.testing.assert_array_equal(got[key], value, err_msg=key)
    venv.close()


@pytest.mark.parametrize(
    "bad", ["short", "batched", "nan", "inf", "-inf", "text"], ids=lambda b: f"action_{b}"
)
def test_bad_actions_raise_with_the_env_name(env_id, bad):
    """Wrong shape, non-finite or non-numeric actions are refused, by the scalar env
    and by the vector env, with a ValueError naming the env."""
    env = make(env_id).unwrapped
    k = env.action_space.shape[0]
    value = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf}
    action = {
        "short": np.zeros(k - 1),
        "batched": np.zeros((1, k)),
        "text": np.array(["a"] * k, dtype=object),
    }.get(bad, np.where(np.arange(k) == 1, value.get(bad, 0.0), 0.0))
    env.reset(seed=0)
    with pytest.raises(ValueError, match=env_id.partition(":")[0]):
        env.step(action)
    venv = make_vec(env_id, 2)
    venv.reset(seed=0)
    batch = {"short": np.zeros((2, k - 1)), "batched": np.zeros((3, k))}.get(bad)
    with pytest.raises(ValueError, match=env_id.partition(":")[0]):
        venv.step(np.stack([action, np.zeros(k)]) if batch is None else batch)
    venv.close()


def test_bad_common_settings_are_refused_naming_them(env_id):
    """The settings every env shares (scenario, decision interval and rate, checked by
    envs.spec.EnvConfig; the replay env takes its rate from the recordings and has no
    scenario), a render mode and the lane count: a bad value given to the constructor
    is a ValueError naming it."""
    bad = {"scenario": "moon", "decision_interval_s": 0.0, "rate_hz": -10.0}
    takes = set(bad) & set(make(env_id).unwrapped.arguments)
    replay = env_id.partition(":")[0] == "pednav/FootZuptReplay-v0"
    assert takes == ({"decision_interval_s"} if replay else set(bad))
    for name in sorted(takes):
        with pytest.raises(ValueError, match=name):
            make(env_id, **{name: bad[name]})
    # gymnasium's make warns first; the env then refuses with a ValueError
    with (
        pytest.warns(UserWarning, match="render_mode"),
        pytest.raises(ValueError, match="render_mode"),
    ):
        make(env_id, render_mode="ascii")
    with pytest.raises(ValueError, match="num_envs"):
        make_vec(env_id, 0)


def test_random_and_extreme_actions_over_whole_episodes(env_id):
    """Uniform, huge (±1e6, clipped) and corner actions: observations finite and in
    the observation space, rewards finite and ≤ 0 (minus an error)."""
    env = make(env_id).unwrapped
    k = env.action_space.shape[0]
    rng = np.random.default_rng(99)
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * k)).reshape(k, -1).T
    policies = [
        lambda t: rng.uniform(-1, 1, k),
        lambda t: rng.choice([-1e6, -1.0, 1.0, 1e6], k),
        lambda t: corners[t % len(corners)],
        lambda t: corners[(t // 7) % len(corners)],  # held for 7 decisions
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        for seed, policy in enumerate(policies):
            obs, rewards, info = rollout(env, seed, policy)
            assert all(env.observation_space.contains(o) for o in obs)
            assert np.all(np.isfinite(rewards)) and np.all(rewards <= 0)
            assert np.isfinite(info["error"])


def test_render_rgb_array_and_pickling(env_id):
    env = make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(3):
        env.step(np.zeros(env.action_space.shape, np.float32))
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    assert frame.std() > 0  # something is drawn
    env.close()
    env = make(env_id).unwrapped
    env.reset(seed=5)
    env.step(np.zeros(env.action_space.shape))
    clone = pickle.loads(pickle.dumps(env))  # mid-episode
    action = np.full(env.action_space.shape, 0.3)
    assert data_equivalence(env.step(action), clone.step(action), exact=True)
    assert data_equivalence(env.reset(seed=1), clone.reset(seed=1), exact=True)


def test_ppo_trains_for_2000_steps(env_id):
    """SB3 PPO learns on the scalar env and predicts actions of the right shape."""
    from stable_baselines3 import PPO

    env = make(env_id)
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=256,
        batch_size=64,
        n_epochs=2,
        seed=0,
        policy_kwargs={"net_arch": [32, 32]},
        device="cpu",
    )
    model.learn(2000)
    assert model.num_timesteps >= 2000
    action, _ = model.predict(env.reset(seed=1)[0], deterministic=True)
    assert action.shape == env.action_space.shape
