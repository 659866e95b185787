"""Checks of scalar settings shared by the model configs of every layer.

Each raises ``ValueError`` naming the setting (``name``, e.g.
``"UwbSpec.drop_prob"``) and the value it was given.
"""

from __future__ import annotations

import math
from typing import Any


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
