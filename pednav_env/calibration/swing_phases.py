"""Where in the swing the foot moves fast without rotating (docs/SIM_TO_REAL.md, "The
error level and where it comes from").

The SHOE statistic (Skog et al. 2010, eq 11) of a moving foot is dominated by its
angular rate (PyShoe's σ_ω = 8.7·10⁻⁵ rad/s): a swing sample that moves fast but hardly
rotates can fall below a high threshold γ, and a zero-velocity update there wipes a
velocity of metres per second. This module places every swing sample at its phase in
the swing and summarises, per phase bin, how fast the foot moves and how fast it
rotates.

A swing is a non-stance run of the walk's walking part
(:func:`pednav_env.calibration.stats.walking_part`; stance from the walk's labels or
the simulator's truth, cleaned as the statistics clean labels) lasting
:data:`MIN_SWING_S` to :data:`MAX_SWING_S`; its n samples sit at phases (k + 0.5)/n,
0 at the end of one stance and 1 at the start of the next. Per phase bin, over the
swings of all walks given: the median truth foot speed
(:func:`pednav_env.calibration.stats.truth_speed`), the median and 10th percentile of
|ω|, the median of the signed sagittal rate, and the share of samples that are *fast
and still*: foot speed above :data:`FAST_MPS` and |ω| below :data:`STILL_RAD_S`. The
sagittal rate is, per walk, ω along the principal direction of its swings' angular
rates (the unit vector of largest variance, whatever the sensor's mounting), signed so
that its median over the middle of the swing (phases 0.4–0.6, where the foot swings
forward) is positive; the off-sagittal rate is the magnitude of the rest,
√(|ω|² − sagittal²), the foot's turning about the other two axes. Samples without a truth speed
(no reference, or inside a truth glitch,
:func:`pednav_env.calibration.strides.truth_glitches`) are left out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from pednav_env.calibration.stats import (
    StanceSource,
    WalkSamples,
    log10_shoe,
    runs,
    truth_speed,
    walking_stance,
)
from pednav_env.calibration.strides import truth_glitches

#: Shortest and longest swing kept (s): shorter runs are label flicker, longer ones
#: shuffles or turns on the spot.
MIN_SWING_S, MAX_SWING_S = 0.25, 1.5
#: A fast-and-still sample: truth foot speed above FAST_MPS (m/s) and |ω| below
#: STILL_RAD_S (rad/s).
FAST_MPS, STILL_RAD_S = 1.0, 1.0


class SwingSamples(NamedTuple):
    """A walk's swing samples (module docstring), each ``(K,)``."""

    phase: np.ndarray
    speed_mps: np.ndarray
    rate_rad_s: np.ndarray  # |ω|
    sagittal_rad_s: np.ndarray  # signed, along the principal direction
    log_shoe: np.ndarray  # log10 of the SHOE statistic (PyShoe's settings)


def swing_samples(samples: WalkSamples) -> SwingSamples:
    """The walk's swing samples (module docstring); ValueError when the walk has no
    truth positions or its stance comes from the detector rule (no labels, no truth
    stance)."""
    s = samples
    if s.truth_pos is None:
        raise ValueError(f"{s.name}: swing phases need truth positions (the foot speed)")
    rate = float(s.rate_hz)
    log_t = log10_shoe(s.omega_b, s.f_b, rate, s.g)
    source, stance, walking = walking_stance(s, log_t)
    if source == StanceSource.DETECTOR:
        raise ValueError(f"{s.name}: swing phases need stance labels or truth stance")
    speed = truth_speed(s.truth_pos, rate)
    for a, b in truth_glitches(s.truth_pos, rate):
        speed[a : b + 1] = np.nan
    rate_norm = np.linalg.norm(s.omega_b, axis=1)
    phases, speeds, rates, axes, shoe = [], [], [], [], []
    for a, b in zip(*runs(walking & ~stance), strict=True):
        n = int(b - a)
        if not (MIN_SWING_S * rate <= n <= MAX_SWING_S * rate):
            continue
        ok = np.isfinite(speed[a:b])
        phases.append(((np.arange(n) + 0.5) / n)[ok])
        speeds.append(speed[a:b][ok])
        rates.append(rate_norm[a:b][ok])
        axes.append(s.omega_b[a:b][ok])
        shoe.append(log_t[a:b][ok])
    if not phases:
        return SwingSamples(*(np.zeros(0) for _ in range(5)))
    phase, omega = np.concatenate(phases), np.concatenate(axes)
    _, _, principal = np.linalg.svd(omega - omega.mean(axis=0), full_matrices=False)
    sagittal = omega @ principal[0]
    middle = (phase > 0.4) & (phase < 0.6)
    if middle.any() and np.median(sagittal[middle]) < 0:
        sagittal = -sagittal
    return SwingSamples(
        phase, np.concatenate(speeds), np.concatenate(rates), sagittal, np.concatenate(shoe)
    )


def pooled(walks: Sequence[WalkSamples]) -> SwingSamples:
    """The swing samples of ``walks`` end to end."""
    parts = [swing_samples(w) for w in walks]
    return SwingSamples(
        *(np.concatenate([p[i] for p in parts]) if parts else np.zeros(0) for i in range(5))
    )


def fast_below(walks: Sequence[WalkSamples], thresholds: Sequence[float]) -> list[float | None]:
    """Per SHOE threshold γ: the share of the fast swing samples (foot speed above
    :data:`FAST_MPS`) whose SHOE statistic is below γ, i.e. that a detector with that γ
    calls stance while the foot moves at more than 1 m/s (None without fast samples)."""
    every = pooled(walks)
    fast = every.speed_mps > FAST_MPS
    if not fast.any():
        return [None for _ in thresholds]
    return [float(np.mean(every.log_shoe[fast] < math.log10(g))) for g in thresholds]


def swing_phase_profile(walks: Sequence[WalkSamples], bins: int = 10) -> dict[str, Any]:
    """Per phase bin (``bins`` equal bins of [0, 1)) over the swings of ``walks``:
    ``samples``, ``speed_median_mps``, ``rate_median_rad_s``, ``rate_p10_rad_s``,
    ``sagittal_rate_median_rad_s``, ``off_sagittal_rate_median_rad_s`` and
    ``fast_still_share`` (lists, None where a bin is empty), with ``bin_edges`` and
    ``swing_samples`` (the total)."""
    if bins < 1:
        raise ValueError(f"bins must be ≥ 1, got {bins}")
    every = pooled(walks)
    phase, speed, rate, sagittal = (
        every.phase,
        every.speed_mps,
        every.rate_rad_s,
        every.sagittal_rad_s,
    )
    off = np.sqrt(np.maximum(rate**2 - sagittal**2, 0.0))
    index = np.minimum((phase * bins).astype(int), bins - 1)
    out: dict[str, Any] = {
        "bin_edges": np.linspace(0.0, 1.0, bins + 1).tolist(),
        "swing_samples": int(phase.size),
        "samples": [],
        "speed_median_mps": [],
        "rate_median_rad_s": [],
        "rate_p10_rad_s": [],
        "sagittal_rate_median_rad_s": [],
        "off_sagittal_rate_median_rad_s": [],
        "fast_still_share": [],
    }
    for k in range(bins):
        m = index == k
        empty = not m.any()
        out["samples"].append(int(m.sum()))
        out["speed_median_mps"].append(None if empty else float(np.median(speed[m])))
        out["rate_median_rad_s"].append(None if empty else float(np.median(rate[m])))
        out["rate_p10_rad_s"].append(None if empty else float(np.percentile(rate[m], 10)))
        out["sagittal_rate_median_rad_s"].append(None if empty else float(np.median(sagittal[m])))
        out["off_sagittal_rate_median_rad_s"].append(None if empty else float(np.median(off[m])))
        still = (speed[m] > FAST_MPS) & (rate[m] < STILL_RAD_S)
        out["fast_still_share"].append(None if empty else float(still.mean()))
    return out
