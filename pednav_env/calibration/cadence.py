"""Recorded strides' cycle and speed, and the walking cadence law fitted to them
(docs/SIM_TO_REAL_CANDIDATES.md, "The walking cadence").

A **stride** runs from one footfall of the instrumented foot to its next:

- walks with footprints (the hallway walks' ``strideIndex`` / GCP): footprint to
  footprint;
- walks with stance labels and truth positions (PyShoe's ``zv_vicon_opt`` and
  VICON): the starts of the stance runs of the labels cleaned as
  :func:`pednav_env.calibration.stats.walk_stats` cleans them (gaps and runs
  shorter than :data:`~pednav_env.calibration.stats.LABEL_MIN_RUN_S` closed and
  dropped), with two stance runs merged when the foot moves less than
  :data:`~pednav_env.calibration.strides.MIN_SWING_M` horizontally between them,
  however short the gap (the gap's length,
  :data:`~pednav_env.calibration.strides.MIN_SWING_S`, decides only where a
  truth position is missing: PyShoe's labels also split a stance by gaps of
  0.05–0.1 s in which the foot does not move; a real swing moves it 0.15 m or
  more), and a run starting less than
  :data:`~pednav_env.calibration.strides.MIN_STRIDE_S` after the run before it
  joined to it (no human stride is shorter;
  :func:`pednav_env.calibration.strides.stride_stances`, which ``walk_stats``'
  strides use too).

A stride is kept when it does not overlap a stand (stance ≥
:data:`~pednav_env.calibration.stats.STAND_MIN_S`) or a truth glitch (a frozen
truth position then a jump, :func:`pednav_env.calibration.strides.truth_glitches`;
these are counted in ``RecordedStrides.glitch_left_out_s``), lasts at most
:data:`MAX_CYCLE_S` and its speed (footfall-to-footfall horizontal distance over
its duration, the speed :func:`pednav_env.gait.speed_route.speed_route` gives its
strides) lies in [:data:`MIN_SPEED_MPS`, :data:`MAX_WALK_SPEED_MPS`): below it
the foot shuffles on the spot, from it on the simulator runs.

The **law** (:func:`fit_cadence_law`): stride frequency f = a + b·v (Hz, v in
m/s), the form of the simulator's default a = 0.55, b = 0.3
(:class:`pednav_env.gait.speed_route.SpeedRouteConfig`), fitted by least squares
with every recording weighing the same (each stride 1/n of its recording), and
the walker-to-walker spread: the standard deviation over recordings of each
recording's median log10(f / (a + b·v)).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from pednav_env.calibration.stats import (
    LABEL_MIN_RUN_S,
    STAND_MIN_S,
    WalkSamples,
    clean_labels,
    long_runs,
    runs,
)
from pednav_env.calibration.strides import glitched_strides, stride_stances

Array = NDArray[np.float64]

#: A footfall-to-footfall interval longer than this (s) is not a stride.
MAX_CYCLE_S = 3.0
#: Strides slower than this (m/s) are steps on the spot, not walking.
MIN_SPEED_MPS = 0.1
#: Strides from this speed (m/s) on run in the simulator (SpeedRouteConfig.run_from_mps).
MAX_WALK_SPEED_MPS = 2.0


@dataclass(frozen=True)
class RecordedStrides:
    """One walk's kept strides: start (s), cycle (s) and speed (m/s); and the
    (start, end) times (s) of the strides left out for a truth glitch, one row each."""

    name: str
    start_s: Array
    cycle_s: Array
    speed_mps: Array
    glitch_left_out_s: Array = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def frequency_hz(self) -> Array:
        return 1.0 / self.cycle_s


@dataclass(frozen=True)
class CadenceLaw:
    """f = ``intercept_hz`` + ``slope_hz_per_mps`` · v, walker spread ``log10_std``."""

    intercept_hz: float
    slope_hz_per_mps: float
    log10_std: float
    recordings: int
    strides: int

    def frequency_hz(self, speed_mps: Array | float) -> Array:
        return self.intercept_hz + self.slope_hz_per_mps * np.asarray(speed_mps, dtype=float)


def footfalls(samples: WalkSamples) -> tuple[NDArray[np.int64], Array, NDArray[np.bool_]]:
    """Sample indices of the walk's footfalls, their horizontal positions (m), and the
    stand mask (module docstring).

    Raises
    ------
    ValueError
        ``samples`` has neither footprints nor stance labels with truth positions.
    """
    s = samples
    rate = float(s.rate_hz)
    if s.footfall_index is not None and s.footprints_m is not None:
        idx = np.asarray(s.footfall_index, dtype=np.int64)
        return idx, np.asarray(s.footprints_m, dtype=float)[:, :2], np.zeros(len(s.f_b), bool)
    if s.stance is None or s.truth_pos is None:
        raise ValueError(f"{s.name}: strides need footprints, or stance labels and truth positions")
    clean = clean_labels(np.asarray(s.stance, dtype=bool), max(1, round(LABEL_MIN_RUN_S * rate)))
    stand = long_runs(clean, max(1, round(STAND_MIN_S * rate)))
    pos = np.asarray(s.truth_pos, dtype=float)[:, :2]
    idx, _ = stride_stances(*runs(clean), rate, pos)
    return idx, pos[idx], stand


def recorded_strides(samples: WalkSamples) -> RecordedStrides:
    """The walk's kept strides (module docstring)."""
    rate = float(samples.rate_hz)
    idx, points, stand = footfalls(samples)
    glitched = glitched_strides(idx, samples.truth_pos, rate)
    rows, left_out = [], []
    for k in range(idx.size - 1):
        a, b = int(idx[k]), int(idx[k + 1])
        cycle = (b - a) / rate
        if b <= a or stand[a:b].any() or cycle > MAX_CYCLE_S:
            continue
        if glitched[k]:
            left_out.append((a / rate, b / rate))
            continue
        speed = float(np.linalg.norm(points[k + 1] - points[k])) / cycle
        if np.isfinite(speed) and MIN_SPEED_MPS <= speed < MAX_WALK_SPEED_MPS:
            rows.append((a / rate, cycle, speed))
    cols = np.array(rows, dtype=float).reshape(-1, 3).T
    left = np.array(left_out, dtype=float).reshape(-1, 2)
    return RecordedStrides(samples.name, cols[0], cols[1], cols[2], glitch_left_out_s=left)


def fit_cadence_law(walks: Sequence[RecordedStrides]) -> CadenceLaw:
    """The cadence law of ``walks`` (module docstring).

    Raises
    ------
    ValueError
        Fewer than two walks with strides, or strides all at one speed.
    """
    used = [w for w in walks if w.cycle_s.size]
    if len(used) < 2:
        raise ValueError(f"fit_cadence_law: needs ≥ 2 walks with strides, got {len(used)}")
    v = np.concatenate([w.speed_mps for w in used])
    f = np.concatenate([w.frequency_hz for w in used])
    weight = np.concatenate([np.full(w.cycle_s.size, 1.0 / w.cycle_s.size) for w in used])
    if np.ptp(v) <= 0:
        raise ValueError("fit_cadence_law: every stride at one speed; the slope is undetermined")
    design = np.column_stack([np.ones_like(v), v]) * np.sqrt(weight)[:, None]
    (a, b), *_ = np.linalg.lstsq(design, f * np.sqrt(weight), rcond=None)
    offsets = [float(np.median(np.log10(w.frequency_hz / (a + b * w.speed_mps)))) for w in used]
    return CadenceLaw(float(a), float(b), float(np.std(offsets)), len(used), int(v.size))
