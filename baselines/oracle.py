"""The privileged oracle: a CMA-ES constant per episode context (the adaptation ceiling).

Not a baseline but a target. The oracle reads the simulator's truth about the
episode (``info["context"]``: the WaistStep sensor grade, the MarkerTrack UWB
condition), which no deployable tuner can see, and plays the constant action
tuned for that context. Its gap to the single CMA-ES constant (``tuned``) is
what an adaptive tuner can win by recognising the context from its
observations; a learner that only matches ``tuned`` has learned nothing
adaptive, one that matches the oracle has learned all a context switch can give.

Each context's constant comes from :func:`baselines.tuned.search` on training
episodes of that context only (the env's config restricted to it, see
:data:`CONTEXTS`). The table is ``oracle_actions.json`` beside this module
(:data:`RESULTS_FILE`), written by ``pednav tune ENV --per-context --install``.

Policies that need the context declare ``needs_context = True``; the
evaluation passes ``context=`` (the ``(N, K)`` array of ``info["context"]``) to
their ``predict`` and to no other policy's.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from pednav_env.envs.marker_config import CONTEXT_FIELDS as MARKER_CONTEXT_FIELDS
from pednav_env.envs.marker_config import MarkerTrackConfig
from pednav_env.envs.waist_config import CONTEXT_FIELDS as WAIST_CONTEXT_FIELDS
from pednav_env.envs.waist_config import WaistStepConfig

#: The shipped per-context table (one entry per env id).
RESULTS_FILE = Path(__file__).parent / "oracle_actions.json"
#: File name of a per-context search result in a run directory.
RESULT_NAME = "oracle_actions.json"
#: How the oracle is labelled in tables and docs: it reads the simulator's truth.
LABEL = "oracle (privileged)"


@dataclass(frozen=True)
class ContextSplit:
    """How an env's episodes split into the contexts the oracle switches between.

    ``field``: the entry of ``info["context"]`` holding the context's index into
    ``labels`` (the default config's order); ``restrict(label)``: env keyword
    arguments that draw episodes of that context only (the rest of the episode
    distribution unchanged).
    """

    field: str
    field_index: int
    labels: tuple[str, ...]
    restrict: Callable[[str], dict[str, Any]]


def _waist_only(grade: str) -> dict[str, Any]:
    return {"config": WaistStepConfig(sensor_grades=(grade,), sensor_grade_weights=(1.0,))}


def _marker_only(condition: str) -> dict[str, Any]:
    return {"config": MarkerTrackConfig(uwb_conditions=(condition,), uwb_condition_weights=(1.0,))}


#: The context split of each env with an oracle.
CONTEXTS: dict[str, ContextSplit] = {
    "pednav/WaistStep-v0": ContextSplit(
        "sensor_grade_index",
        WAIST_CONTEXT_FIELDS.index("sensor_grade_index"),
        WaistStepConfig().sensor_grades,
        _waist_only,
    ),
    "pednav/MarkerTrack-v0": ContextSplit(
        "uwb_condition_index",
        MARKER_CONTEXT_FIELDS.index("uwb_condition_index"),
        MarkerTrackConfig().uwb_conditions,
        _marker_only,
    ),
}


def context_split(env_id: str) -> ContextSplit:
    """The context split of ``env_id``; ValueError naming it when it has none."""
    if env_id not in CONTEXTS:
        raise ValueError(f"no oracle context for {env_id!r}; known: {', '.join(sorted(CONTEXTS))}")
    return CONTEXTS[env_id]


class OraclePolicy:
    """The constant tuned for each context, chosen by the episode's true context.

    ``predict`` has SB3's signature plus ``context`` (the ``(N, K)`` array of
    ``info["context"]``), which it requires.
    """

    name = "oracle"
    needs_context = True
    filter_family = None  # the envs with an oracle have no filter families

    def __init__(self, actions: np.ndarray, field_index: int, action_space: spaces.Box) -> None:
        a = np.asarray(actions, dtype=np.float32)
        if a.ndim != 2 or a.shape[1:] != action_space.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"oracle actions of shape {a.shape} do not fit {action_space}")
        self.actions = np.clip(a, action_space.low, action_space.high)
        self.field_index = int(field_index)
        self.action_space = action_space

    @classmethod
    def from_table(
        cls, table: dict[str, Any], env_id: str, action_space: spaces.Box, source: str
    ) -> OraclePolicy:
        """The entry of ``env_id`` in a per-context table (``source`` names it in errors)."""
        if env_id not in table:
            raise ValueError(
                f"{source}: no oracle table for {env_id!r}: run `pednav tune {env_id} "
                "--per-context --install`"
            )
        entry = table[env_id]
        split = context_split(env_id)
        if tuple(entry["labels"]) != split.labels:
            raise ValueError(
                f"{source}: the {env_id} table's contexts {entry['labels']} are not "
                f"the env's {list(split.labels)}"
            )
        actions = [entry["contexts"][label]["action"] for label in split.labels]
        return cls(np.array(actions), split.field_index, action_space)

    @classmethod
    def for_env(cls, env_id: str, action_space: spaces.Box) -> OraclePolicy:
        """The shipped table's oracle for ``env_id``."""
        table = read_table(RESULTS_FILE) if RESULTS_FILE.exists() else {}
        return cls.from_table(table, env_id, action_space, str(RESULTS_FILE))

    def predict(
        self, observation, state=None, episode_start=None, deterministic=True, context=None
    ):
        if context is None:
            raise ValueError("the oracle needs the episode context (info['context'])")
        index = np.asarray(context)[..., self.field_index]
        k = np.rint(index).astype(np.int64)
        if np.any((k < 0) | (k >= len(self.actions))):
            raise ValueError(
                f"oracle: context index {index.tolist()} outside its {len(self.actions)} contexts "
                "(the oracle covers the default config's contexts only)"
            )
        return self.actions[k].copy(), state


def read_table(path: Path) -> dict[str, Any]:
    """A per-context table ``{env_id: {"labels": [...], "contexts": {label: result}}}``;
    ValueError naming the file when it is not one."""
    try:
        table = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a readable oracle-actions JSON file ({exc})") from None
    ok = isinstance(table, dict) and all(
        isinstance(v, dict) and "labels" in v and "contexts" in v for v in table.values()
    )
    if not ok:
        raise ValueError(f"{path}: expected {{env_id: {{'labels': [...], 'contexts': {{...}}}}}}")
    return table


def search_per_context(
    env_id: str,
    action_dim: int,
    search: Callable[..., dict[str, Any]],
    on_context: Callable[[str], None] | None = None,
    **search_kwargs: Any,
) -> dict[str, Any]:
    """One CMA-ES constant per context: ``search(env_id, action_dim, env_kwargs=...,
    **search_kwargs)`` (:func:`baselines.tuned.search`) on episodes of each context
    in turn. Returns the table entry ``{"field", "labels", "contexts": {label: result}}``."""
    split = context_split(env_id)
    contexts = {}
    for label in split.labels:
        result = search(env_id, action_dim, env_kwargs=split.restrict(label), **search_kwargs)
        result["env_kwargs"] = {"context": label}
        contexts[label] = result
        if on_context is not None:
            on_context(label)
    return {"field": split.field, "labels": list(split.labels), "contexts": contexts}


def save_table_entry(env_id: str, entry: dict[str, Any], path: Path) -> Path:
    """Write ``entry`` as ``env_id``'s in the table at ``path`` (other entries kept)."""
    table = read_table(path) if path.exists() else {}
    table[env_id] = entry
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(table, indent=2) + "\n")
    return path
