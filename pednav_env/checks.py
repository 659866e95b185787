"""Checks of scalar settings shared by the model configs of every layer.

Each raises ``ValueError`` naming the setting (``name``, e.g.
``"UwbSpec.drop_prob"``) and the value it was given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np


def require_finite(name: str, value: Any) -> None:
    """``value`` is a finite real number."""
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")


def require_positive(name: str, value: Any) -> None:
    """``value`` is a finite number > 0."""
    require_finite(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")


def require_nonnegative(name: str, value: Any) -> None:
    """``value`` is a finite number ≥ 0."""
    require_finite(name, value)
    if value < 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")


def require_probability(name: str, value: Any) -> None:
    """``value`` is a probability in [0, 1]."""
    require_finite(name, value)
    if not 0 <= value <= 1:
        raise ValueError(f"{name} must be a probability in [0, 1], got {value!r}")


def require_range(
    name: str,
    value: Any,
    *,
    positive: bool = False,
    within: tuple[float, float] | None = None,
) -> None:
    """``value`` is a pair ``(low, high)`` of finite numbers with low ≤ high (and
    low > 0 when ``positive``; ``within[0]`` ≤ low and high ≤ ``within[1]`` when given)."""
    try:
        low, high = value
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a (low, high) pair, got {value!r}") from None
    require_finite(f"{name} low", low)
    require_finite(f"{name} high", high)
    if low > high or (positive and low <= 0):
        bound = "0 < low <= high" if positive else "low <= high"
        raise ValueError(f"{name} must be a range with {bound}, got {value!r}")
    if within is not None and not within[0] <= low <= high <= within[1]:
        raise ValueError(f"{name} must lie within {within}, got {value!r}")


def require_weights(name: str, weights: Sequence[float], count: int) -> None:
    """``weights`` are ``count`` finite non-negative numbers with a positive sum."""
    w = np.asarray(weights, dtype=float)
    if w.shape != (count,) or not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
        raise ValueError(
            f"{name} must be {count} non-negative weights with a positive sum, got {weights!r}"
        )


def require_choice(name: str, value: Any, choices: Sequence[Any]) -> None:
    """``value`` is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name} must be one of {tuple(choices)}, got {value!r}")
