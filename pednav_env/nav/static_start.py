"""Find the still span at the start of a recording (for paper 003's eq 4).

Alignment and the gyro-bias calibration need the IMU at rest. A recording's
initial still span ends where the causal 0.05 s means leave either bound:
mean |ω| ≤ ``gyro_max`` and | mean |f| − g₀ | ≤ ``accel_max``, with g₀ the
median |f| over the first 0.05 s. The alignment window is that span, less
one averaging window (the means react late), capped at ``max_s``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.nav.detectors import causal_moving_mean, window_samples

Array = NDArray[np.float64]

#: Averaging window of the stillness test (s).
STILL_WINDOW_S = 0.05


def initial_still_samples(
    omega_b: Array,
    f_b: Array,
    rate_hz: float,
    max_s: float = 1.0,
    min_s: float = 0.1,
    gyro_max: float = 0.1,
    accel_max: float = 0.5,
) -> int:
    """Number of samples of the alignment window at the start of ``(T, 3)`` records.

    Raises
    ------
    ValueError
        When the IMU is not still for ``min_s`` at the start (the sample where
        motion is detected is named).
    """
    n = window_samples(STILL_WINDOW_S, rate_hz)
    wn = np.linalg.norm(omega_b, axis=-1)[None, :]
    fn = np.linalg.norm(f_b, axis=-1)
    g0 = float(np.median(fn[:n]))
    w = causal_moving_mean(wn, n)[0]
    a = causal_moving_mean(fn[None, :], n)[0]
    moving = (w > gyro_max) | (np.abs(a - g0) > accel_max)
    first = int(np.argmax(moving)) if moving.any() else len(wn[0])
    still = max(0, first - n) if moving.any() else first
    n_max = max(1, int(round(max_s * rate_hz)))
    n_min = max(1, int(round(min_s * rate_hz)))
    if still < n_min:
        raise ValueError(
            f"the IMU must be still for at least {min_s} s at the start of the recording for "
            f"the alignment (paper 003 eq 4); it moves at sample {first} "
            f"(t = {first / rate_hz:.3f} s: mean |ω| {w[first]:.3f} rad/s, "
            f"| |f| − g | {abs(a[first] - g0):.3f} m/s²)"
        )
    return min(still, n_max)
