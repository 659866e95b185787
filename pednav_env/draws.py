"""Draws of numpy's ``Generator`` written out as it makes them, without its argument handling.

``Generator.choice(n, p=p)`` checks and converts its arguments at every call
(about 35 µs), far longer than the draw. For weights fixed ahead of time the
same number comes from :func:`choice_index` on :func:`choice_cdf`: numpy takes
the cumulative sum of ``p``, divides it by its last entry, draws one
``Generator.random()`` and returns the index where that number would be
inserted to the right (``searchsorted(..., side="right")``). Same stream, same
index (``tests/test_draws.py`` compares them draw by draw).
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence

import numpy as np


def choice_cdf(p: Sequence[float] | np.ndarray) -> list[float]:
    """The cumulative probabilities ``Generator.choice(len(p), p=p)`` searches:
    ``cumsum(p) / cumsum(p)[-1]``. ``p`` as given to ``choice`` (checked there:
    here only that it is a non-empty 1-D array of finite numbers ≥ 0 with a
    positive sum)."""
    probs = np.asarray(p, dtype=float)
    if probs.ndim != 1 or probs.size == 0 or not np.all(np.isfinite(probs)):
        raise ValueError(f"p must be a non-empty 1-D array of finite numbers, got {p!r}")
    if np.any(probs < 0) or not probs.sum() > 0:
        raise ValueError(f"p must be ≥ 0 with a positive sum, got {p!r}")
    cdf = probs.cumsum()
    cdf /= cdf[-1]
    return cdf.tolist()


def choice_index(rng: np.random.Generator, cdf: list[float]) -> int:
    """``int(rng.choice(len(p), p=p))`` for ``cdf = choice_cdf(p)``: one ``rng.random()``."""
    return bisect.bisect_right(cdf, rng.random())
