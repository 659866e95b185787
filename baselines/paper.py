"""The papers' fixed filters as a policy."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces


class PaperPolicy:
    """Always action 0: each knob at its paper value (``base · span**0``).

    In ``pednav/FootZupt-v0`` this is paper 003's ZUPT-UKF with its
    thresholds and noise model, unchanged for the whole walk.

    Parameters
    ----------
    action_space : the single-environment ``Box`` action space.
    """

    name = "paper"
    #: The filter family the policy is made for (pednav_env.envs.foot_filters).
    filter_family = "paper"

    def __init__(self, action_space: spaces.Box) -> None:
        if not isinstance(action_space, spaces.Box):
            raise ValueError(f"action_space must be a gymnasium Box, got {action_space!r}")
        self.action_space = action_space

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Zeros shaped like the action space, with the batch axes of ``observation``."""
        obs = np.asarray(observation)
        batch = obs.shape[:-1]
        return np.zeros(batch + self.action_space.shape, dtype=self.action_space.dtype), state


class RealFixedPolicy(PaperPolicy):
    """Action 0 of the foot envs' ``shoe`` filter family: the ``real-fixed``
    filter (SHOE detector, a ZUPT at every stance sample), unchanged for the
    whole walk."""

    name = "real-fixed"
    filter_family = "shoe"
