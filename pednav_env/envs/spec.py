"""The contract every pednav environment core keeps, and the specs it is built from.

- :class:`Knob`: one action component ``a`` ∈ [−1, 1] and the physical value it
  sets (log or linear mapping, with a unit); action 0 is always the paper's value.
- :class:`ObsFeature`: one observation entry, its bounds and unit.
- :class:`Core`: what :mod:`pednav_env.envs.native` needs of a batched episode
  core (N lanes stepped in one call).
- :func:`validate_action`: the one action check of every core.
- :class:`EnvConfig`: the settings every env config has (scenario, decision
  interval, sample rate, divergence bound) and their checks; the rest of a
  config uses the shared validators of :mod:`pednav_env.checks` (re-exported
  here: ``require_positive``, ``require_probability``, ``require_range``,
  ``require_weights`` ...).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from pednav_env.checks import (
    require_choice,
    require_finite,
    require_nonnegative,
    require_positive,
    require_probability,
    require_range,
    require_weights,
)

Array = NDArray[np.float64]

#: ``(obs, reward, terminated, truncated, info)`` of all lanes.
StepResult = tuple[NDArray[np.float32], Array, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]
KNOB_MAPPINGS = ("log", "linear", "linear_positive")


@dataclass(frozen=True)
class Knob:
    """One action component: ``a`` ∈ [−1, 1] → physical value in ``unit``.

    ``mapping="log"``: ``base · span ** a`` (a multiplicative range of
    span⁻¹ … span around the paper's ``base``). ``"linear"``: ``base + span · a``;
    ``"linear_positive"``: ``base + span · max(a, 0)`` (a ≤ 0 keeps the paper's
    ``base``, e.g. "no minimum duration", which a log scale cannot reach).
    In every case ``a = 0`` gives ``base``.
    """

    name: str
    mapping: str
    base: float
    span: float
    unit: str

    def __post_init__(self) -> None:
        if self.mapping not in KNOB_MAPPINGS:
            raise ValueError(
                f"Knob {self.name!r}: mapping must be one of {KNOB_MAPPINGS}, got {self.mapping!r}"
            )
        require_finite(f"Knob {self.name!r}: base", self.base)
        require_positive(f"Knob {self.name!r}: span", self.span)
        if self.mapping == "log" and self.base <= 0:
            raise ValueError(f"Knob {self.name!r}: a log knob needs base > 0, got {self.base!r}")

    def value(self, a: Any) -> Any:
        """Physical value(s) for action component(s) ``a``."""
        if self.mapping == "log":
            return self.base * self.span**a
        if self.mapping == "linear":
            return self.base + self.span * a
        return self.base + self.span * np.maximum(a, 0.0)

    def action(self, value: Any) -> Any:
        """The action component(s) giving physical ``value`` (log knobs:
        ``log(value / base) / log(span)``, the inverse of :meth:`value`)."""
        if self.mapping != "log":
            raise ValueError(f"Knob {self.name!r}: action() is defined for log knobs only")
        return np.log(value / self.base) / np.log(self.span)


@dataclass(frozen=True)
class ObsFeature:
    """One observation entry: its name, the bounds it is clipped to, its unit."""

    name: str
    low: float
    high: float
    unit: str = "1"

    def __post_init__(self) -> None:
        require_range(f"ObsFeature {self.name!r}", (self.low, self.high))


def obs_bounds(
    features: Sequence[ObsFeature], action_dim: int = 0
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """The observation space bounds (low, high), float32: ``features`` in order,
    then ``action_dim`` entries in [−1, 1] (the action in force)."""
    low = np.array([f.low for f in features] + [-1.0] * action_dim, dtype=np.float32)
    high = np.array([f.high for f in features] + [1.0] * action_dim, dtype=np.float32)
    return low, high


class Core(Protocol):
    """A batched episode core: ``n`` lanes, each an episode of one env, stepped
    together. ``obs`` is ``(n, obs_dim)``; ``step`` returns ``(obs, reward,
    terminated, truncated, info)`` with one row per lane (info values are arrays
    with the lanes first); ``reset_lanes`` starts new episodes on some lanes,
    each drawn from its generator; ``knob_values`` gives the physical value of
    every knob per lane."""

    n: int
    env_name: str
    obs: NDArray[np.float32]
    obs_low: NDArray[np.float32]
    obs_high: NDArray[np.float32]

    def reset_lanes(
        self, lanes: NDArray[np.integer], rngs: Sequence[np.random.Generator]
    ) -> None: ...

    def step(self, actions: Any) -> StepResult: ...

    def knob_values(self) -> dict[str, Array]: ...

    def validate_action(self, action: Any) -> Array: ...


def validate_action(action: Any, shape: tuple[int, ...], env_name: str) -> Array:
    """``action`` as float64 of ``shape`` with finite entries, or a ValueError
    naming ``env_name`` (non-numeric input, wrong shape, NaN or inf)."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{env_name}: action is not numeric: {action!r}") from None
    if a.shape != shape:
        raise ValueError(f"{env_name}: actions must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{env_name}: action contains NaN or inf: {a.tolist()}")
    return a


class EnvConfig:
    """Mixin of the frozen env configs: the settings every environment has.

    A config dataclass declares ``scenario``, ``decision_interval_s``,
    ``rate_hz``, ``divergence_error_m`` and, when the bound grows with the
    distance walked, ``divergence_error_fraction`` (with its own defaults), and
    calls :meth:`check_env_settings` from its ``__post_init__``. Divergence is a
    horizontal error above ``divergence_error_m + divergence_error_fraction × distance walked``.
    """

    SCENARIOS: ClassVar[tuple[str, ...]] = ("random", "paper")
    scenario: str
    decision_interval_s: float
    rate_hz: float
    divergence_error_m: float

    def check_env_settings(self, sample: str = "sample") -> None:
        """Scenario known, rate and interval finite and > 0 with at least one
        ``sample`` per interval, divergence bound > 0 (fraction ≥ 0)."""
        require_choice("scenario", self.scenario, self.SCENARIOS)
        require_positive("rate_hz", self.rate_hz)
        require_positive("decision_interval_s", self.decision_interval_s)
        if round(self.decision_interval_s * self.rate_hz) < 1:
            raise ValueError(
                f"decision_interval_s={self.decision_interval_s!r} is shorter than one {sample}"
            )
        require_positive("divergence_error_m", self.divergence_error_m)
        # an env whose bound does not grow with the distance has no fraction
        require_nonnegative(
            "divergence_error_fraction", getattr(self, "divergence_error_fraction", 0.0)
        )

    @property
    def interval_samples(self) -> int:
        """Samples per decision interval."""
        return int(round(self.decision_interval_s * self.rate_hz))


__all__ = [
    "Core",
    "EnvConfig",
    "Knob",
    "ObsFeature",
    "StepResult",
    "obs_bounds",
    "require_choice",
    "require_finite",
    "require_nonnegative",
    "require_positive",
    "require_probability",
    "require_range",
    "require_weights",
    "validate_action",
]
