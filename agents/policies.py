"""Policies by name or from disk, all with SB3's ``predict`` signature.

Names: ``paper`` (action 0), ``tuned`` (the shipped best constant action),
``adaptive`` (the innovation-based rule), ``pretrained`` (the shipped tuner
under ``agents/pretrained/``; for the foot envs' shoe family, which has no trained
network shipped, the gait-adaptive rule ``gait-rule-real``), ``gait-rule`` (foot envs,
shoe family only: the SHOE threshold follows a gait feature of the sensors,
:mod:`agents.gait_rule`, parameters in ``agents/pretrained/gait_rule.json``),
``gait-rule-real`` (the same rule fitted on recordings, :mod:`agents.gait_rule_real`,
parameters in ``agents/pretrained/gait_rule_real.json``), ``oracle`` (privileged:
the constant tuned for the true context, the episode's on WaistStep and
MarkerTrack, the interval's speed band on FootZupt's shoe family;
:mod:`baselines.oracle`; a target, not a baseline), and for the foot envs
``real-fixed`` (action 0 of the shoe filter family).

Filter families (foot envs, :mod:`pednav_env.envs.foot_filters`): every policy
carries the family it is made for as ``filter_family`` (None on the other
envs). ``paper`` is always the paper family and ``real-fixed`` the shoe
family; ``tuned``, ``adaptive`` and ``pretrained`` take the family asked for
(``NAME:FAMILY``, e.g. ``tuned:paper``, or the caller's ``filter_family``),
by default :data:`~pednav_env.envs.foot_filters.LEARNED_FAMILY` (shoe); a
training run carries its family in ``meta.json`` (``"filter"``, paper for
runs that have none) and a tuned-actions file in its keys
(:func:`baselines.tuned.result_key`). Paths: a run directory of ``pednav train``
or ``pednav distill`` (``model.zip``, ``vecnormalize.pkl``, ``meta.json``), a saved SB3 model
(``.zip``), a tuned-actions JSON file written by ``pednav tune``, or a tune run
directory holding one, or a gait-rule parameter file (JSON with keys ``c`` and
``feature``, written by :mod:`agents.gait_rule_search`).

:class:`NormalizedModelPolicy` applies a run's observation statistics itself,
so a learned model takes raw observations and goes through the same evaluation
as the baselines.
"""

from __future__ import annotations

import json
import pickle
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from agents.features import FeaturePolicy
from agents.gait_rule import PARAMS_FILE, REAL_PARAMS_FILE, GaitRulePolicy, is_params_file
from baselines import InnovationAdaptivePolicy, PaperPolicy, RealFixedPolicy, TunedFixedPolicy
from baselines.oracle import OraclePolicy
from baselines.tuned import RESULT_NAME
from pednav_env.envs.foot_filters import FILTER_FAMILIES, LEARNED_FAMILY, require_family

#: Shipped tuners: agents/pretrained/<env name>/.
PRETRAINED_DIR = Path(__file__).parent / "pretrained"
#: Policy names understood besides a path.
BUILTIN_POLICIES = (
    "paper",
    "tuned",
    "adaptive",
    "pretrained",
    "gait-rule",
    "gait-rule-real",
    "oracle",
)
#: Observation statistics saved beside a model trained under VecNormalize.
STATS_NAME = "vecnormalize.pkl"
#: Envs that play another env's named policies (same spaces and knobs): the replay
#: env runs the tuners made in simulation.
POLICY_SOURCE_ENV = {"pednav/FootZuptReplay-v0": "pednav/FootZupt-v0"}
#: Envs with filter families (the ``filter`` constructor argument).
FAMILY_ENVS = ("pednav/FootZupt-v0", "pednav/FootZuptReplay-v0")
#: The policy that is action 0 of each filter family.
ZERO_ACTION = {"paper": "paper", "shoe": "real-fixed"}


def split_name(name: str) -> tuple[str, str | None]:
    """``"tuned:shoe"`` → ``("tuned", "shoe")``; a name without a family suffix → (name, None)."""
    base, sep, family = name.rpartition(":")
    if sep and family in FILTER_FAMILIES and base:
        return base, family
    return name, None


class NormalizedModelPolicy:
    """An SB3 model with frozen observation normalisation."""

    #: The filter family of the run (from its meta.json), None when it has none.
    filter_family: str | None = None

    def __init__(self, model: Any, obs_rms: Any | None, clip_obs: float, epsilon: float) -> None:
        self.model = model
        self.obs_rms = obs_rms
        self.clip_obs = clip_obs
        self.epsilon = epsilon

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        if self.obs_rms is None:
            return obs
        z = (obs - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        return np.clip(z, -self.clip_obs, self.clip_obs).astype(np.float32)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = self.normalize(np.asarray(observation, dtype=np.float32))
        return self.model.predict(
            obs, state=state, episode_start=episode_start, deterministic=deterministic
        )


def load_run(path: str | Path) -> Any:
    """Load a run directory, or a ``model.zip`` with ``vecnormalize.pkl`` beside it.

    A run whose ``meta.json`` names ``"features"`` (e.g. ``"history"``, written by
    :mod:`agents.distill`) gets those features computed in front of its network
    (:class:`agents.features.FeaturePolicy`).

    Without ``vecnormalize.pkl`` the model sees raw observations; a
    ``UserWarning`` says so (a model trained under ``VecNormalize`` then acts on
    inputs it has never seen).
    """
    from stable_baselines3 import PPO, SAC

    path = Path(path)
    model_file = path / "model.zip" if path.is_dir() else path
    if not model_file.exists():
        raise ValueError(f"policy {str(path)!r}: no such model file ({model_file})")
    meta_file = model_file.parent / "meta.json"
    try:
        meta = json.loads(meta_file.read_text()) if meta_file.exists() else {}
    except json.JSONDecodeError as exc:
        raise ValueError(f"policy {str(path)!r}: {meta_file} is not valid JSON ({exc})") from None
    algo = meta.get("algo")
    classes = {"ppo": PPO, "sac": SAC}
    candidates = [classes[algo]] if algo in classes else [PPO, SAC]
    model = None
    for cls in candidates:
        try:
            model = cls.load(model_file, device="cpu")
            break
        except (ValueError, KeyError, RuntimeError, TypeError):
            continue
    if model is None:
        raise ValueError(f"policy {str(path)!r}: not a PPO or SAC model")
    stats_file = model_file.parent / STATS_NAME
    family = meta.get("filter", "paper" if meta.get("env_id") in FAMILY_ENVS else None)
    features = meta.get("features")
    if stats_file.exists():
        with stats_file.open("rb") as fh:
            vn = pickle.load(fh)
        policy = NormalizedModelPolicy(model, vn.obs_rms, vn.clip_obs, vn.epsilon)
        policy.filter_family = family
        return _with_features(policy, features, model)
    normalized = (meta.get("hyperparams") or {}).get("normalize", {}).get("norm_obs")
    known = " (its meta.json says it was trained with VecNormalize)" if normalized else ""
    warnings.warn(
        f"{model_file}: no {STATS_NAME} beside it, so the model is evaluated on raw "
        f"observations{known}; if it was trained under VecNormalize, save the statistics "
        f"(vec.save('{STATS_NAME}')) next to the model",
        UserWarning,
        stacklevel=2,
    )
    policy = NormalizedModelPolicy(model, None, 10.0, 1e-8)
    policy.filter_family = family
    return _with_features(policy, features, model)


def _gait_rule(
    path: Path,
    action_space: spaces.Box,
    env_id: str,
    families: bool,
    family: str | None,
    name: str = "",
) -> GaitRulePolicy:
    """The gait rule from ``path``; ValueError off the foot envs or for another family."""
    if not families:
        raise ValueError(
            f"policy gait-rule: a rule of the foot envs' shoe filter family {FAMILY_ENVS}, "
            f"not of {env_id!r}"
        )
    if family not in (None, GaitRulePolicy.filter_family):
        raise ValueError(
            f"policy gait-rule sets the shoe filter family's knobs; it cannot run filter {family!r}"
        )
    return GaitRulePolicy.from_file(path, int(np.prod(action_space.shape)), name)


def _with_features(policy: NormalizedModelPolicy, features: str | None, model: Any) -> Any:
    """``policy``, behind the run's feature computation when its meta.json names one."""
    if not features:
        return policy
    wrapped = FeaturePolicy(policy, features, int(np.prod(model.action_space.shape)))
    wrapped.filter_family = policy.filter_family
    return wrapped


def pretrained_dir(env_id: str, filter_family: str | None = None) -> Path:
    """Directory of the shipped tuner for ``env_id`` (e.g. pednav/FootZupt-v0;
    ``FootZupt-v0-shoe`` for a filter family other than the paper's)."""
    name = env_id.split("/")[-1]
    return PRETRAINED_DIR / (
        name if filter_family in (None, "paper") else f"{name}-{filter_family}"
    )


def load_policy(
    name: str,
    action_space: spaces.Box,
    env_id: str = "",
    other_names: Sequence[str] = (),
    filter_family: str | None = None,
) -> Any:
    """A policy by name, or from a path (see the module docstring).

    ``other_names``: names the caller handles itself (e.g. ``real-fixed`` in
    ``pednav run``), listed in the error for an unknown name. The named policies
    of an env in :data:`POLICY_SOURCE_ENV` are those of its source env.
    ``filter_family``: the family of ``tuned``/``adaptive``/``pretrained`` and of
    a path on an env with families (None: the name's suffix, the run's own, or
    :data:`LEARNED_FAMILY`).
    """
    families = env_id in FAMILY_ENVS
    replayed = env_id in POLICY_SOURCE_ENV  # recordings: no privileged policy
    env_id = POLICY_SOURCE_ENV.get(env_id, env_id)
    name, suffix = split_name(name)
    if filter_family is not None:
        require_family(filter_family)
    family = (suffix or filter_family) if families else None
    learned = (family or LEARNED_FAMILY) if families else None
    if name == "paper":
        return PaperPolicy(action_space)
    if name == "real-fixed" and families and "real-fixed" not in other_names:
        return RealFixedPolicy(action_space)
    if name == "tuned":
        return TunedFixedPolicy.for_env(env_id, action_space, learned)
    if name == "adaptive":
        return InnovationAdaptivePolicy(action_space, env_id, learned)
    if name == "gait-rule":
        return _gait_rule(PARAMS_FILE, action_space, env_id, families, family)
    if name == "gait-rule-real":
        return _gait_rule(REAL_PARAMS_FILE, action_space, env_id, families, family, name)
    if name == "oracle":
        return OraclePolicy.for_env(env_id, action_space, learned)
    if name == "pretrained":
        path = pretrained_dir(env_id, learned)
        if families and learned == GaitRulePolicy.filter_family and not path.exists():
            # The shoe family's shipped tuner is the gait-adaptive rule fitted on
            # recordings and simulated walks (docs/REAL_DATA.md, docs/RESULTS.md).
            return _gait_rule(REAL_PARAMS_FILE, action_space, env_id, families, family, name)
        if not (path / "model.zip").exists():
            what = env_id if learned is None else f"{env_id} (filter family {learned})"
            hint = ""
            if learned not in (None, "paper") and (pretrained_dir(env_id) / "model.zip").exists():
                hint = "; the shipped one is the paper family's: pretrained:paper or --filter paper"
            raise ValueError(f"no pretrained tuner shipped for {what} (looked in {path}){hint}")
        return load_run(path)
    path = Path(name)
    if path.suffix == ".json":
        if not path.is_file():
            raise ValueError(f"policy {name!r}: no such tuned-actions file")
        if is_params_file(path):
            return _gait_rule(path, action_space, env_id, families, family)
        return TunedFixedPolicy.from_file(path, env_id, action_space, family)
    if path.is_dir() and not (path / "model.zip").exists() and (path / RESULT_NAME).exists():
        return TunedFixedPolicy.from_file(path / RESULT_NAME, env_id, action_space, family)
    if path.suffix == ".zip" or path.exists():
        policy = load_run(path)
        if family is not None and policy.filter_family not in (None, family):
            raise ValueError(
                f"policy {name!r} was trained with filter {policy.filter_family!r}, not {family!r}"
            )
        return policy
    known = [n for n in BUILTIN_POLICIES if not (replayed and n == "oracle")]
    if families and "real-fixed" not in other_names:
        known.append("real-fixed")
    names = ", ".join((*known, *other_names))
    raise ValueError(
        f"unknown policy {name!r}: use one of {names}, or a path to a training run directory, "
        f"a saved SB3 model (.zip), or a tuned-actions file ({RESULT_NAME}) or its directory"
    )
