"""Hand-built labelled walks for the calibration tests (tests/calibration)."""

from __future__ import annotations

import numpy as np

from pednav_env.calibration.stats import WalkSamples
from pednav_env.constants import STANDARD_GRAVITY


def labelled_walk(
    stances: list[tuple[float, float]],
    positions: list[float],
    rate_hz: float,
    freeze: tuple[float, float] | None = None,
    truth: bool = True,
) -> WalkSamples:
    """A walk along x: the foot at ``positions[k]`` during stance k (start, end in s),
    moving linearly between stances; still IMU readings (the strides need none).
    ``freeze`` (t0, t1): the truth position held at its t0 value until t1, where it
    jumps back (a tracking dropout); ``truth`` False: no truth positions."""
    n = int(round((stances[-1][1] + 0.5) * rate_hz))
    t = np.arange(n) / rate_hz
    stance = np.zeros(n, bool)
    knots_t, knots_x = [], []
    for (a, b), x in zip(stances, positions, strict=True):
        stance[int(round(a * rate_hz)) : int(round(b * rate_hz))] = True
        knots_t += [a, b]
        knots_x += [x, x]
    pos = np.zeros((n, 3))
    pos[:, 0] = np.interp(t, knots_t, knots_x)
    if freeze is not None:
        a, b = (int(round(x * rate_hz)) for x in freeze)
        pos[a:b] = pos[a]
    still = np.zeros((n, 3))
    return WalkSamples(still, still, rate_hz, "w", stance=stance, truth_pos=pos if truth else None)


def phase_walk(
    phases: list[tuple[int, float, bool, float]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(omega_b, f_b, stance, truth_pos)`` of a walk along x built from
    ``(samples, |ω| rad/s, stance, metres moved)`` phases: ω about x, |f| = g, the
    foot moving linearly over each phase (sample k at the distance reached before
    it)."""
    omega, stance, x = [], [], [0.0]
    for n, w, st, dist in phases:
        omega += [w] * n
        stance += [st] * n
        x += list(x[-1] + dist * np.arange(1, n + 1) / n)
    omega_b = np.zeros((len(omega), 3))
    omega_b[:, 0] = omega
    f_b = np.tile([0.0, 0.0, STANDARD_GRAVITY], (len(omega), 1))
    pos = np.zeros((len(omega), 3))
    pos[:, 0] = x[:-1]
    return omega_b, f_b, np.array(stance), pos
