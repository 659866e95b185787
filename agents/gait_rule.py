"""Gait-adaptive SHOE policy: the SHOE threshold γ follows the gait seen in the sensors.

On the calibrated foot walks the best SHOE threshold grows with walking speed
(docs/RESULTS.md, the FootZupt speed-band oracle; docs/SIM_TO_REAL.md), so a
constant γ must choose between slow walks and running. This rule, for the foot
env's ``shoe`` filter family (Skog et al. 2010 eq 11 detector), sets after each
decision interval

    a0 = clip(c0 + c1 · log10(max(x, ε) / x_ref), −1, 1)    (x = the gait feature)
    a0 = c0                                                  while the foot is still
    a1, a2, a3 = c2, c3, c4                                  (window, Q and R scales)

where x is one observation feature of the interval just played (sensors only,
:data:`pednav_env.envs.foot_core.OBS_FEATURES`; no truth) and a0 is log γ over
the knob's span of 100 (γ = γ_real-fixed · 100^a0). "Still" is
``gyro_norm_mean`` below ``still_gyro_rad_s``. With c1 = 0 the rule is a
constant action.

The feature is ``accel_excess_absmax`` (max |‖f‖ − g| over the interval): among
the observation features it has the largest correlation with the truth speed of
the interval (log–log Pearson r = 0.88 over 2408 moving intervals of 16
calibrated training walks, seed 1 070 000; ``accel_excess_std`` 0.87,
``gyro_norm_mean`` 0.69, ``gyro_norm_max`` 0.69, ``stance_duration_avg`` −0.35;
docs/RESULTS.md gives the command).

Parameter file (JSON object; :func:`read_params` checks it and names the file and
key on error)::

    {"env_id": "pednav/FootZupt-v0", "filter": "shoe",
     "feature": "accel_excess_absmax", "feature_ref": 25.0, "feature_eps": 0.1,
     "still_gyro_rad_s": 0.3, "c": [c0, c1, c2, c3, c4], ...}

Other keys (the search's record) are kept and ignored. The parameters are found
by CMA-ES on training episodes: :mod:`agents.gait_rule_search`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.envs.foot_core import OBS_FEATURES
from pednav_env.files import writing

#: The shipped parameters (found on simulated training walks only): ``gait-rule``.
PARAMS_FILE = Path(__file__).parent / "pretrained" / "gait_rule.json"
#: The shipped parameters fitted on recordings (:mod:`agents.gait_rule_real`):
#: ``gait-rule-real``.
REAL_PARAMS_FILE = Path(__file__).parent / "pretrained" / "gait_rule_real.json"
#: The env and filter family the rule is made for.
ENV_ID = "pednav/FootZupt-v0"
FAMILY = "shoe"
#: Number of rule parameters c0 … c4.
N_PARAMS = 5
_NAMES = tuple(f.name for f in OBS_FEATURES)


@dataclass(frozen=True)
class GaitRuleParams:
    """The rule's parameters (module docstring): ``c`` = (c0, c1, c2, c3, c4)."""

    c: tuple[float, ...]
    feature: str = "accel_excess_absmax"
    feature_ref: float = 25.0
    feature_eps: float = 0.1
    still_gyro_rad_s: float = 0.3

    def __post_init__(self) -> None:
        if len(self.c) != N_PARAMS or not all(math.isfinite(float(v)) for v in self.c):
            raise ValueError(f"c: expected {N_PARAMS} finite numbers, got {list(self.c)!r}")
        if self.feature not in _NAMES:
            raise ValueError(f"feature: {self.feature!r} is not an observation feature {_NAMES}")
        for key in ("feature_ref", "feature_eps"):
            v = getattr(self, key)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{key}: must be a finite number > 0, got {v!r}")
        if not (math.isfinite(self.still_gyro_rad_s) and self.still_gyro_rad_s >= 0):
            raise ValueError(f"still_gyro_rad_s: must be ≥ 0, got {self.still_gyro_rad_s!r}")


def rule_actions(obs: np.ndarray, c: np.ndarray, p: GaitRuleParams) -> np.ndarray:
    """The rule's action for each row of ``obs`` (N, d) with per-row parameters
    ``c`` (N, 5) or shared ones (5,); the feature settings from ``p``."""
    obs = np.atleast_2d(np.asarray(obs, dtype=np.float64))
    c = np.broadcast_to(np.asarray(c, dtype=np.float64), (obs.shape[0], N_PARAMS))
    x = obs[:, _NAMES.index(p.feature)]
    still = obs[:, _NAMES.index("gyro_norm_mean")] < p.still_gyro_rad_s
    log_x = np.log10(np.maximum(x, p.feature_eps) / p.feature_ref)
    a0 = np.where(still, c[:, 0], c[:, 0] + c[:, 1] * log_x)
    return np.clip(np.column_stack([a0, c[:, 2:]]), -1.0, 1.0).astype(np.float32)


class GaitRulePolicy:
    """The gait-adaptive SHOE rule with SB3's ``predict`` signature (shoe family)."""

    name = "gait-rule"
    filter_family = FAMILY

    def __init__(self, params: GaitRuleParams, action_dim: int = 4, name: str = "") -> None:
        if action_dim != 4:
            raise ValueError(f"gait-rule sets 4 knobs; the env's action has {action_dim}")
        self.params = params
        if name:
            self.name = name

    @classmethod
    def from_file(
        cls, path: str | Path = PARAMS_FILE, action_dim: int = 4, name: str = ""
    ) -> GaitRulePolicy:
        return cls(read_params(path), action_dim, name)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        out = rule_actions(observation, np.asarray(self.params.c), self.params)
        return (out[0] if np.ndim(observation) == 1 else out), state


def read_params(path: str | Path) -> GaitRuleParams:
    """The parameters in a gait-rule JSON file; ValueError naming the file (and key)."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a readable gait-rule JSON file ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object with keys env_id, filter, c, ...")
    for key, want in (("env_id", ENV_ID), ("filter", FAMILY)):
        if data.get(key) != want:
            raise ValueError(f"{path}: key {key!r} must be {want!r}, got {data.get(key)!r}")
    if "c" not in data:
        raise ValueError(f"{path}: missing key 'c' (the {N_PARAMS} rule parameters)")
    c = data["c"]
    if not isinstance(c, list) or not all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in c
    ):
        raise ValueError(f"{path}: key 'c' must be a list of {N_PARAMS} numbers, got {c!r}")
    kwargs: dict[str, Any] = {"c": tuple(float(v) for v in c)}
    for key in ("feature", "feature_ref", "feature_eps", "still_gyro_rad_s"):
        if key in data:
            kwargs[key] = data[key]
    try:
        return GaitRuleParams(**kwargs)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{path}: {exc}") from None


def is_params_file(path: str | Path) -> bool:
    """Whether ``path`` holds a JSON object with the gait rule's keys ``c`` and
    ``feature`` (a tuned-actions table has neither); False when unreadable."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return False
    return isinstance(data, dict) and "c" in data and "feature" in data


def write_params(params: GaitRuleParams, path: str | Path, record: dict[str, Any]) -> Path:
    """Write ``params`` (and the search's ``record``) as a gait-rule JSON file."""
    path = Path(path)
    data = {
        "env_id": ENV_ID,
        "filter": FAMILY,
        "feature": params.feature,
        "feature_ref": params.feature_ref,
        "feature_eps": params.feature_eps,
        "still_gyro_rad_s": params.still_gyro_rad_s,
        "c": list(params.c),
        **record,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    with writing(path):
        path.write_text(json.dumps(data, indent=2) + "\n")
    return path
