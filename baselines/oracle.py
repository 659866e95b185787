"""The privileged oracle: a CMA-ES constant per context (the adaptation ceiling).

Not a baseline but a target. The oracle reads the simulator's truth
(``info["context"]``: the WaistStep sensor grade and the MarkerTrack UWB
condition of the episode; the FootZupt speed band of the coming decision
interval), which no deployable tuner can see, and plays the constant action
tuned for that context. Its gap to the single CMA-ES constant (``tuned``) is
what an adaptive tuner can win by recognising the context from its
observations; a learner that only matches ``tuned`` has learned nothing
adaptive, one that matches the oracle has learned all a context switch can give.

Each context's constant comes from :func:`baselines.tuned.search` on training
episodes of that context only (the env's config restricted to it, see
:data:`CONTEXTS`). The table is ``oracle_actions.json`` beside this module
(:data:`RESULTS_FILE`), written by ``pednav tune ENV --per-context --install``;
it is keyed like the tuned constants (:func:`baselines.tuned.result_key`), so
FootZupt's shoe-family table is ``pednav/FootZupt-v0:shoe`` and cannot be read
as a paper-family one.

FootZupt (shoe family): the context is the speed band of the interval the next
action governs (:data:`pednav_env.envs.foot_context.SPEED_BANDS`), so the
oracle switches every decision interval. A band's constant is searched on
calibrated-scenario walks whose every leg is drawn at a speed of that band
(``speed_route.speed_mps`` = the band, clipped to the scenario's 0.3–3 m/s; the
top band ≥ 2.6 m/s is searched on 2.6–3 m/s). The standing band (< 0.2 m/s) has no
walks of its own: its intervals are the 2 s stand before every walk and the
stops before legs, which occur at every speed and sit between intervals of the
other bands. No band-restricted search targets them, so the oracle plays there
the CMA-ES constant of the whole scenario (``tuned``), the one constant tuned on
stops next to every speed (:data:`UNSEARCHED`).

Policies that need the context declare ``needs_context = True``; the
evaluation passes ``context=`` (the ``(N, K)`` array of ``info["context"]``) to
their ``predict`` and to no other policy's.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from baselines.tuned import result_key
from pednav_env.envs.foot_context import CONTEXT_FIELDS as FOOT_CONTEXT_FIELDS
from pednav_env.envs.foot_context import SPEED_BANDS
from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.marker_config import CONTEXT_FIELDS as MARKER_CONTEXT_FIELDS
from pednav_env.envs.marker_config import MarkerTrackConfig
from pednav_env.envs.waist_config import CONTEXT_FIELDS as WAIST_CONTEXT_FIELDS
from pednav_env.envs.waist_config import WaistStepConfig
from pednav_env.files import writing

#: The shipped per-context table (one entry per env id).
RESULTS_FILE = Path(__file__).parent / "oracle_actions.json"
#: File name of a per-context search result in a run directory.
RESULT_NAME = "oracle_actions.json"
#: How the oracle is labelled in tables and docs: it reads the simulator's truth.
LABEL = "oracle (privileged)"
#: What a context without a search of its own plays (``restrict`` returns None).
UNSEARCHED = "the CMA-ES constant of all contexts (tuned)"


@dataclass(frozen=True)
class ContextSplit:
    """How an env's episodes split into the contexts the oracle switches between.

    ``field``: the entry of ``info["context"]`` holding the context's index into
    ``labels`` (the default config's order); ``restrict(label)``: env keyword
    arguments that draw episodes of that context only (the rest of the episode
    distribution unchanged), or None for a context that has no episodes of its
    own (it plays :data:`UNSEARCHED`); ``family``: the filter family the table
    is for (None: an env without families).
    """

    field: str
    field_index: int
    labels: tuple[str, ...]
    restrict: Callable[[str], dict[str, Any] | None]
    family: str | None = None

    @property
    def searched(self) -> tuple[str, ...]:
        """The labels that get a search of their own."""
        return tuple(label for label in self.labels if self.restrict(label) is not None)


def _waist_only(grade: str) -> dict[str, Any]:
    return {"config": WaistStepConfig(sensor_grades=(grade,), sensor_grade_weights=(1.0,))}


def _marker_only(condition: str) -> dict[str, Any]:
    return {"config": MarkerTrackConfig(uwb_conditions=(condition,), uwb_condition_weights=(1.0,))}


#: FootZupt's speed-band labels (SPEED_BANDS order) and the speeds (m/s) their
#: walks are drawn at; the standing band has none (module docstring).
FOOT_STANDING = "standing"
_FOOT_SPEEDS = FootZuptConfig(filter_family="shoe").speed_route.speed_mps
FOOT_BAND_SPEEDS: dict[str, tuple[float, float]] = {
    (f"{lo:g}+" if hi == float("inf") else f"{lo:g}-{hi:g}"): (
        max(lo, _FOOT_SPEEDS[0]),
        min(hi, _FOOT_SPEEDS[1]),
    )
    for lo, hi in SPEED_BANDS[1:]
}


def _foot_band_only(label: str) -> dict[str, Any] | None:
    """Calibrated shoe-family walks whose every leg is at a speed of band ``label``."""
    if label == FOOT_STANDING:
        return None
    base = FootZuptConfig(filter_family="shoe")
    speeds = FOOT_BAND_SPEEDS[label]
    return {"config": replace(base, speed_route=replace(base.speed_route, speed_mps=speeds))}


#: The context split of each env with an oracle, keyed like the tables
#: (:func:`baselines.tuned.result_key`: the env id, ``:shoe`` for that family).
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
    "pednav/FootZupt-v0:shoe": ContextSplit(
        "speed_band",
        FOOT_CONTEXT_FIELDS.index("speed_band"),
        (FOOT_STANDING, *FOOT_BAND_SPEEDS),
        _foot_band_only,
        "shoe",
    ),
}


def context_split(env_id: str, filter_family: str | None = None) -> ContextSplit:
    """The context split of ``env_id`` (and filter family); ValueError naming them
    when there is none."""
    key = result_key(env_id, filter_family)
    if key not in CONTEXTS:
        what = env_id if filter_family is None else f"{env_id} (filter family {filter_family})"
        raise ValueError(f"no oracle context for {what}; known: {', '.join(sorted(CONTEXTS))}")
    return CONTEXTS[key]


class OraclePolicy:
    """The constant tuned for each context, chosen by the episode's true context.

    ``predict`` has SB3's signature plus ``context`` (the ``(N, K)`` array of
    ``info["context"]``), which it requires.
    """

    name = "oracle"
    needs_context = True

    def __init__(
        self,
        actions: np.ndarray,
        field_index: int,
        action_space: spaces.Box,
        filter_family: str | None = None,
    ) -> None:
        self.filter_family = filter_family
        a = np.asarray(actions, dtype=np.float32)
        if a.ndim != 2 or a.shape[1:] != action_space.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"oracle actions of shape {a.shape} do not fit {action_space}")
        self.actions = np.clip(a, action_space.low, action_space.high)
        self.field_index = int(field_index)
        self.action_space = action_space

    @classmethod
    def from_table(
        cls,
        table: dict[str, Any],
        env_id: str,
        action_space: spaces.Box,
        source: str,
        filter_family: str | None = None,
    ) -> OraclePolicy:
        """The entry of ``env_id`` (and filter family) in a per-context table
        (``source`` names it in errors)."""
        split = context_split(env_id, filter_family)
        key = result_key(env_id, filter_family)
        if key not in table:
            flag = f" --filter {filter_family}" if filter_family else ""
            raise ValueError(
                f"{source}: no oracle table for {key!r}: run `pednav tune {env_id}{flag} "
                "--per-context --install`"
            )
        entry = table[key]
        if tuple(entry["labels"]) != split.labels:
            raise ValueError(
                f"{source}: the {key} table's contexts {entry['labels']} are not "
                f"the env's {list(split.labels)}"
            )
        try:
            actions = [entry["contexts"][label]["action"] for label in split.labels]
            return cls(
                np.array(actions, dtype=float), split.field_index, action_space, split.family
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f"{source}: the {key} table has no usable action per context ({exc})"
            ) from None

    @classmethod
    def for_env(
        cls, env_id: str, action_space: spaces.Box, filter_family: str | None = None
    ) -> OraclePolicy:
        """The shipped table's oracle for ``env_id`` (and filter family)."""
        table = read_table(RESULTS_FILE) if RESULTS_FILE.exists() else {}
        return cls.from_table(table, env_id, action_space, str(RESULTS_FILE), filter_family)

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
    filter_family: str | None = None,
    unsearched_action: Sequence[float] | None = None,
    **search_kwargs: Any,
) -> dict[str, Any]:
    """One CMA-ES constant per context: ``search(env_id, action_dim, env_kwargs=...,
    **search_kwargs)`` (:func:`baselines.tuned.search`) on episodes of each context
    in turn. A context without episodes of its own plays ``unsearched_action`` (the
    shipped ``tuned`` constant; required then). Returns the table entry
    ``{"field", "labels", "contexts": {label: result}}``."""
    split = context_split(env_id, filter_family)
    if len(split.searched) < len(split.labels) and unsearched_action is None:
        raise ValueError(
            f"{result_key(env_id, filter_family)}: contexts "
            f"{sorted(set(split.labels) - set(split.searched))} play the CMA-ES constant "
            "(tuned); tune it first"
        )
    contexts = {}
    for label in split.labels:
        env_kwargs = split.restrict(label)
        if env_kwargs is None:
            contexts[label] = {
                "action": [float(v) for v in np.asarray(unsearched_action, dtype=float)],
                "searched": False,
                "from": UNSEARCHED,
                "env_kwargs": {"context": label},
            }
            continue
        result = search(env_id, action_dim, env_kwargs=env_kwargs, **search_kwargs)
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
    with writing(path):
        path.write_text(json.dumps(table, indent=2) + "\n")
    return path
