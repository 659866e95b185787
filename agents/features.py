"""Episode-history features: what a memoryless network needs to recognise the context.

The envs' observations describe one decision interval. The context a tuner
should adapt to (a sensor grade, a UWB condition) is fixed for the episode and
shows in the statistics of the filter's own signals over many intervals
(innovation size, NIS, covariance, detector counts). :class:`HistoryFeatures`
appends, per lane, the running mean and running RMS of every sensor and filter
entry since the episode started:

    x_t = [o_t, mean(o_0 … o_t), sqrt(mean(o_0² … o_t²))]

computed from observations only (so a policy using it is as honest as the
observation). The trailing entries of every observation, the action in force
(docs/CONTRACTS.md), are left out: a student fitted on a teacher's rollouts
would otherwise learn to repeat the action in force, which is the teacher's
own action there, and keep its first action once it drives. A run directory
whose ``meta.json`` says ``"features": "history"`` is loaded with these
features in front of its network (:func:`agents.policies.load_run`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: ``meta.json`` value of ``"features"`` for :class:`HistoryFeatures`.
HISTORY = "history"
#: Feature sets a run directory may name.
FEATURE_SETS = (HISTORY,)


def feature_dim(obs_dim: int, features: str | None, action_dim: int) -> int:
    """Length of the network input for observations of length ``obs_dim`` (the
    last ``action_dim`` entries being the action in force)."""
    if features is None:
        return obs_dim
    if features == HISTORY:
        return 3 * (obs_dim - action_dim)
    raise ValueError(f"features must be one of {FEATURE_SETS} or None, got {features!r}")


class HistoryFeatures:
    """Per-lane running mean and RMS of the observations (without their last
    ``action_dim`` entries, the action in force) since each episode start."""

    def __init__(self, action_dim: int) -> None:
        if action_dim < 0:
            raise ValueError(f"action_dim must be ≥ 0, got {action_dim}")
        self.action_dim = int(action_dim)
        self.count: np.ndarray | None = None
        self.mean: np.ndarray | None = None
        self.mean_sq: np.ndarray | None = None

    def __call__(self, obs: np.ndarray, episode_start: np.ndarray | None) -> np.ndarray:
        """Features of a batch of observations ``(N, d)``; ``episode_start[i]`` true
        when ``obs[i]`` is the first of an episode (None: only on the first call)."""
        obs = np.asarray(obs, dtype=np.float64)
        if obs.ndim != 2 or obs.shape[1] <= self.action_dim:
            raise ValueError(
                f"observations must be (lanes, dim > {self.action_dim}), got shape {obs.shape}"
            )
        obs = obs[:, : obs.shape[1] - self.action_dim]
        n = obs.shape[0]
        if self.count is None or self.count.shape[0] != n or self.mean.shape[1] != obs.shape[1]:
            self.count = np.zeros(n)
            self.mean = np.zeros(obs.shape)
            self.mean_sq = np.zeros(obs.shape)
            start = np.ones(n, dtype=bool)
        elif episode_start is None:
            start = np.zeros(n, dtype=bool)
        else:
            start = np.asarray(episode_start, dtype=bool).reshape(n)
        self.count[start] = 0.0
        self.mean[start] = 0.0
        self.mean_sq[start] = 0.0
        self.count += 1.0
        w = (1.0 / self.count)[:, None]
        self.mean += w * (obs - self.mean)
        self.mean_sq += w * (obs * obs - self.mean_sq)
        return np.concatenate((obs, self.mean, np.sqrt(self.mean_sq)), axis=1).astype(np.float32)


class FeaturePolicy:
    """A policy over feature vectors, fed raw observations (SB3 ``predict`` signature)."""

    def __init__(self, policy: Any, features: str, action_dim: int) -> None:
        feature_dim(action_dim + 1, features, action_dim)  # checks the name
        self.policy = policy
        self.features = HistoryFeatures(action_dim)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(observation, dtype=np.float32)
        single = obs.ndim == 1
        batch = obs[None, :] if single else obs
        start = None if episode_start is None else np.atleast_1d(episode_start)
        x = self.features(batch, start)
        action, state = self.policy.predict(
            x, state=state, episode_start=episode_start, deterministic=deterministic
        )
        return (action[0] if single else action), state
