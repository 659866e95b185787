"""Where navigation can start: the still span for the alignment (paper 003 eq 4).

The still span at the start of a recording comes from
:func:`pednav_env.nav.static_start.initial_still_samples`. When the IMU moves
at the very start (a foot still settling), the first still span that begins
within :data:`STILL_SEARCH_S` is used instead, searched in steps of the
stillness window; the samples before it are left out.

:func:`find_still_start` decides on a whole record; with ``final=False`` it
decides on the samples seen so far of a stream and returns None while more
samples could change the answer (the streaming filter,
:mod:`pednav_env.replay.stream`, then waits). Both give the same answer on
the same samples.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.nav.detectors import window_samples
from pednav_env.nav.static_start import STILL_WINDOW_S, initial_still_samples

Array = NDArray[np.float64]

#: How far into a recording (s) the still span for the alignment is looked for
#: when the IMU is not still at the very start.
STILL_SEARCH_S = 5.0


def find_still_start(
    omega_b: Array,
    f_b: Array,
    rate_hz: float,
    max_s: float,
    min_s: float,
    final: bool = True,
) -> tuple[int, int] | None:
    """(samples skipped, alignment samples) for ``(T, 3)`` records (module docstring).

    ``final=False``: the records are the first T samples of a longer stream;
    None means "not decided yet". Each test looks at the stillness window
    (0.05 s) beyond the longest alignment, so a decision taken on a long
    enough prefix is the decision on the whole record.

    Raises
    ------
    ValueError
        No still span of ``min_s`` begins within :data:`STILL_SEARCH_S` (the
        sample where the IMU moves at the start is named).
    """
    t = len(omega_b)
    step = window_samples(STILL_WINDOW_S, rate_hz)
    n_max = max(1, int(round(max_s * rate_hz)))
    # enough samples for the stillness means to reach past the longest window
    decided = n_max + 2 * step
    if not final and t < decided:
        return None
    try:
        return 0, initial_still_samples(omega_b, f_b, rate_hz, max_s, min_s)
    except ValueError as exc:
        first_error = exc
    span = int(round((max_s + 2 * STILL_WINDOW_S) * rate_hz)) + step
    horizon = int(STILL_SEARCH_S * rate_hz)
    for skip in range(step, min(horizon, t) if final else horizon, step):
        stop = skip + span
        if not final and stop > t:
            return None
        try:
            return skip, initial_still_samples(
                omega_b[skip:stop], f_b[skip:stop], rate_hz, max_s, min_s
            )
        except ValueError:
            continue
    raise ValueError(
        f"{first_error}; no still span of {min_s} s begins in the first {STILL_SEARCH_S} s either"
    )
