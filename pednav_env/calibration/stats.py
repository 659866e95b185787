"""Summary statistics of a foot-IMU walk, recorded or simulated.

What the simulator is compared on (docs/SIM_TO_REAL.md):

- the **label-free quietness measure**: over the walking part of a walk
  (stands longer than :data:`STAND_MIN_S` removed), the 10th and 50th
  percentiles of log10 of the SHOE statistic (Skog et al. 2010, eq 11;
  :func:`pednav_env.nav.detectors.shoe_statistic`) with PyShoe's settings: a
  window of 5 samples at 200 Hz, σ_a = 0.00098 m/s², σ_ω = 8.7266e-5 rad/s.
  p10 measures how quiet mid-stance is; p50 sits at the stance/swing edge;
- the **walking speed**: horizontal path length over the time not spent
  standing (truth positions), or the footprint path length over the walking
  time between the first and the last footprint;
- **per stride**: speed, stance duration, the medians of |ω| (rad/s) and
  ||f| − g| (m/s²) in stance and in swing, and the 5th percentile of log10
  SHOE over the stride (the threshold a detector needs to see its stance);
- the **quiet phase**, measured the same way on every walk whatever its
  labels: the runs of the walking part whose log10 SHOE lies below the
  midpoint between the walk's own p10 and p50 (the detector rule below),
  as a share of the walking time and as the median run length (s). PyShoe's
  stored labels are each trial's optimised detector output (their stance
  share ranges 0.1–0.6 of the cycle between trials), so stance durations from
  labels do not compare with the simulator's truth; the quiet phase does.

Stands are the runs of stance at least :data:`STAND_MIN_S` long after the
labels are cleaned (gaps and runs shorter than :data:`LABEL_MIN_RUN_S`
closed and dropped): PyShoe's labels flicker, and a pause split by a
one-sample flicker would otherwise stay in the walking part (on the slow
trials it moved p50 by up to a decade).

Strides without footprints start at the stance runs of the cleaned labels,
split stances merged and runs closer than a minimum stride joined
(:func:`pednav_env.calibration.strides.stride_stances`): the labels also split
stances by short gaps in which the foot stays put, which would make a short
false stride. Stands are found before the merge, on the cleaned labels alone.
With truth positions, strides overlapping a truth glitch (a frozen position
then a jump; :func:`pednav_env.calibration.strides.truth_glitches`) are left
out of the per-stride arrays and counted (``StrideStats.glitch_left_out_s``).

Stance comes, in this order of preference, from labels stored with the walk
(PyShoe's ``zv_vicon_opt``, the simulator's truth), from the truth velocity
(|v| below :data:`TRUTH_STANCE_SPEED_MPS`), or from the SHOE detector
(:data:`DETECTOR_STAND_LOG10` for stands; inside the walking part, the
midpoint in log between the walk's own p10 and p50). :class:`WalkStats`
records which (``stance_source``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from pednav_env.calibration.strides import glitched_strides, stride_stances
from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.detectors import ShoeDetectorConfig, shoe_statistic

Array = NDArray[np.float64]
Flags = NDArray[np.bool_]

#: PyShoe's SHOE noise σ's (m/s², rad/s) and window (5 samples at 200 Hz).
SHOE_ACCEL_SIGMA = 0.00098
SHOE_GYRO_SIGMA = 8.7266e-5
SHOE_WINDOW_S = 5 / 200.0
#: A stance run at least this long (s) is a stand, removed from the walking part.
STAND_MIN_S = 1.0
#: Truth-velocity stance: horizontal-and-vertical foot speed below this (m/s),
#: the velocity by central differences smoothed over 0.05 s.
TRUTH_STANCE_SPEED_MPS = 0.2
#: Detector stands: log10 SHOE below this for at least STAND_MIN_S (a still
#: foot reads 3.5–5 with a MicroStrain 3DM-GX5-25; walking p10 is ≥ 4.5).
DETECTOR_STAND_LOG10 = 6.0
#: Label cleaning for stance durations: gaps and runs shorter than this (s) are
#: closed / dropped (PyShoe's VICON labels flicker at mid-stance edges).
LABEL_MIN_RUN_S = 0.05
#: Per stride, the percentile of log10 SHOE reported as its quietness (%).
STRIDE_QUIET_PERCENT = 5.0


class StanceSource(StrEnum):
    """Where a walk's stance labels came from."""

    LABELS = "labels"
    TRUTH_VELOCITY = "truth_velocity"
    DETECTOR = "detector"


class SpeedSource(StrEnum):
    """Where a walk's speeds came from."""

    TRUTH = "truth"
    FOOTPRINTS = "footprints"
    NONE = "none"


@dataclass(frozen=True)
class WalkSamples:
    """The samples a :func:`walk_stats` needs, from any source.

    Parameters
    ----------
    omega_b, f_b : (T, 3) rad/s and m/s², any axes (the statistics use norms).
    rate_hz : sample rate (Hz).
    name : for messages and reports.
    stance : (T,) bool labels or None.
    truth_pos : (T, 3) m or None (NaN rows allowed: no reference there).
    footfall_index : (K,) sample index of each footprint, increasing, or None.
    footprints_m : (K, 2) footprint positions (m) or None.
    g : gravity (m/s²) for ||f| − g| and the SHOE statistic.
    """

    omega_b: Array
    f_b: Array
    rate_hz: float
    name: str = "walk"
    stance: Flags | None = None
    truth_pos: Array | None = None
    footfall_index: NDArray[np.int64] | None = None
    footprints_m: Array | None = None
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        w = np.asarray(self.omega_b, dtype=float)
        f = np.asarray(self.f_b, dtype=float)
        if w.ndim != 2 or w.shape[1] != 3 or w.shape != f.shape or w.shape[0] < 2:
            raise ValueError(
                f"{self.name}: omega_b and f_b must both be (T, 3) with T ≥ 2, "
                f"got {w.shape} and {f.shape}"
            )
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"{self.name}: rate_hz must be > 0, got {self.rate_hz!r}")
        n = w.shape[0]
        if self.stance is not None and np.shape(self.stance) != (n,):
            raise ValueError(f"{self.name}: stance must be ({n},), got {np.shape(self.stance)}")
        if self.truth_pos is not None and np.shape(self.truth_pos) != (n, 3):
            raise ValueError(
                f"{self.name}: truth_pos must be ({n}, 3), got {np.shape(self.truth_pos)}"
            )
        if (self.footfall_index is None) != (self.footprints_m is None):
            raise ValueError(f"{self.name}: footfall_index and footprints_m go together")
        if self.footfall_index is not None:
            idx = np.asarray(self.footfall_index)
            if np.shape(self.footprints_m) != (idx.size, 2):
                raise ValueError(
                    f"{self.name}: footprints_m must be ({idx.size}, 2), "
                    f"got {np.shape(self.footprints_m)}"
                )
            if idx.size and (idx.min() < 0 or idx.max() >= n or np.any(np.diff(idx) <= 0)):
                raise ValueError(
                    f"{self.name}: footfall_index must increase strictly within [0, {n})"
                )
        object.__setattr__(self, "omega_b", w)
        object.__setattr__(self, "f_b", f)


@dataclass(frozen=True)
class StrideStats:
    """Per-stride arrays, one entry per stride (strides overlapping a stand dropped).

    A stride runs from one footprint to the next or, without footprints, from one
    stance start to the next, the stance runs cleaned, split stances merged and
    runs closer than a minimum stride joined
    (:func:`pednav_env.calibration.strides.stride_stances`). ``speed_mps`` is NaN
    without truth or footprints (the stride's path over its duration);
    ``stance_s`` is the first stance run starting in the stride (a merged run
    with its gaps); the medians are over the stride's stance and swing samples
    (NaN if there are none); ``log_shoe_p5`` is its quietest 5 %. Strides
    overlapping a truth glitch are not in the arrays: ``glitch_left_out_s`` holds
    their (start, end) times (s), one row each.
    """

    start_s: Array
    duration_s: Array
    speed_mps: Array
    stance_s: Array
    stance_gyro_median: Array  # |ω|, rad/s
    stance_accel_dev_median: Array  # ||f| − g|, m/s²
    swing_gyro_median: Array
    swing_accel_dev_median: Array
    #: 5th percentile of log10 SHOE over the stride's samples (NaN under 10
    #: finite samples): the SHOE threshold log10 γ must exceed it for 5 % of the
    #: stride to be detected as stance; it needs no labels.
    log_shoe_p5: Array
    #: (K, 2) start and end (s) of the strides left out for a truth glitch
    #: (:func:`pednav_env.calibration.strides.truth_glitches`; strides through a
    #: stand are dropped before and not counted here).
    glitch_left_out_s: Array = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def count(self) -> int:
        return int(self.start_s.size)


@dataclass(frozen=True)
class WalkStats:
    """Statistics of one walk (module docstring)."""

    name: str
    rate_hz: float
    stance_source: StanceSource
    speed_source: SpeedSource
    speed_mps: float  # NaN without truth or footprints
    walking_s: float
    standing_s: float
    log_shoe: Array  # log10 SHOE over the walking part
    strides: StrideStats
    #: The walk's 25th–75th percentile of |turn per stride| (rad), when the caller
    #: measured it (:func:`pednav_env.calibration.path_turns.turn_range`): simulated
    #: walks compared with this one then walk circles of that turn
    #: (:func:`pednav_env.calibration.compare.band_turns`). ``walk_stats`` leaves it None.
    turn_per_stride_rad: tuple[float, float] | None = None

    @property
    def log_shoe_p10(self) -> float:
        return float(np.percentile(self.log_shoe, 10)) if self.log_shoe.size else float("nan")

    @property
    def log_shoe_p50(self) -> float:
        return float(np.percentile(self.log_shoe, 50)) if self.log_shoe.size else float("nan")

    @property
    def log_shoe_p90(self) -> float:
        """90th percentile of log10 SHOE: how vigorous the swing is."""
        return float(np.percentile(self.log_shoe, 90)) if self.log_shoe.size else float("nan")

    @cached_property
    def quiet(self) -> Flags:
        """The quiet phase of the walking part, per sample of ``log_shoe``
        (module docstring)."""
        if self.log_shoe.size < 2:
            return np.zeros(self.log_shoe.size, dtype=bool)
        return quiet_phase(self.log_shoe, self.rate_hz)

    @property
    def quiet_runs_s(self) -> Array:
        """Lengths (s) of the quiet runs of the walking part."""
        starts, ends = runs(self.quiet)
        return (ends - starts) / self.rate_hz

    @property
    def quiet_fraction(self) -> float:
        """Share of the walking time in quiet runs, NaN without a walking part."""
        return float(self.quiet.mean()) if self.quiet.size else float("nan")

    @property
    def quiet_s_median(self) -> float:
        """Median quiet-run length (s), NaN without runs."""
        return _median(self.quiet_runs_s)

    def summary(self) -> dict[str, Any]:
        """Scalars for JSON: the measure, the speeds and the stride medians."""
        st = self.strides

        def med(a: Array) -> float | None:
            a = a[np.isfinite(a)]
            return round(float(np.median(a)), 6) if a.size else None

        return {
            "name": self.name,
            "stance_source": str(self.stance_source),
            "speed_source": str(self.speed_source),
            "speed_mps": None if np.isnan(self.speed_mps) else round(self.speed_mps, 4),
            "walking_s": round(self.walking_s, 3),
            "standing_s": round(self.standing_s, 3),
            "log_shoe_p10": round(self.log_shoe_p10, 4),
            "log_shoe_p50": round(self.log_shoe_p50, 4),
            "log_shoe_p90": round(self.log_shoe_p90, 4),
            "quiet_fraction": round(self.quiet_fraction, 4),
            "quiet_s_median": med(self.quiet_runs_s),
            "strides": st.count,
            "strides_left_out_truth_glitch": int(st.glitch_left_out_s.shape[0]),
            "truth_glitch_strides_s": np.round(st.glitch_left_out_s, 3).tolist(),
            "stride_speed_median_mps": med(st.speed_mps),
            "stance_s_median": med(st.stance_s),
            "stance_gyro_median_rad_s": med(st.stance_gyro_median),
            "stance_accel_dev_median_m_s2": med(st.stance_accel_dev_median),
            "swing_gyro_median_rad_s": med(st.swing_gyro_median),
            "swing_accel_dev_median_m_s2": med(st.swing_accel_dev_median),
            "stride_log_shoe_p5_median": med(st.log_shoe_p5),
        }


def log10_shoe(omega_b: Array, f_b: Array, rate_hz: float, g: float = STANDARD_GRAVITY) -> Array:
    """log10 of the SHOE statistic (T,) with PyShoe's σ's and window (module docstring)."""
    cfg = ShoeDetectorConfig(
        threshold=1.0,
        window_s=SHOE_WINDOW_S,
        accel_noise_std=SHOE_ACCEL_SIGMA,
        gyro_noise_std=SHOE_GYRO_SIGMA,
        g=g,
    )
    t = shoe_statistic(np.asarray(omega_b)[None], np.asarray(f_b)[None], cfg, rate_hz)[0]
    return np.log10(np.maximum(t, 1e-300))


def runs(flags: Flags) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Start and end (exclusive) indices of the runs of True in ``flags``."""
    d = np.diff(np.concatenate(([0], np.asarray(flags, dtype=np.int8), [0])))
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1)


def long_runs(flags: Flags, min_samples: int) -> Flags:
    """The runs of True in ``flags`` of at least ``min_samples`` samples."""
    out = np.zeros(len(flags), dtype=bool)
    for a, b in zip(*runs(flags), strict=True):
        if b - a >= min_samples:
            out[a:b] = True
    return out


def clean_labels(flags: Flags, min_samples: int) -> Flags:
    """Close gaps shorter than ``min_samples`` between True runs, then drop runs
    shorter than ``min_samples``."""
    out = np.asarray(flags, dtype=bool).copy()
    starts, ends = runs(out)
    for e, s in zip(ends[:-1], starts[1:], strict=True):
        if s - e < min_samples:
            out[e:s] = True
    return long_runs(out, min_samples)


def truth_speed(truth_pos: Array, rate_hz: float) -> Array:
    """Foot speed (m/s, 3-D, (T,)) from truth positions by central differences
    (one-sided at the ends); NaN next to a missing position."""
    vel = np.gradient(np.asarray(truth_pos, dtype=float), 1.0 / rate_hz, axis=0)
    return np.linalg.norm(vel, axis=1)


def truth_velocity_stance(truth_pos: Array, rate_hz: float) -> Flags:
    """Stance where the smoothed truth speed is below :data:`TRUTH_STANCE_SPEED_MPS`
    (samples without a reference are not stance)."""
    n = max(1, int(round(0.05 * rate_hz)))
    speed = truth_speed(truth_pos, rate_hz)
    ok = np.isfinite(speed)
    smooth = np.convolve(np.where(ok, speed, np.inf), np.ones(n) / n, mode="same")
    return ok & (smooth < TRUTH_STANCE_SPEED_MPS)


def quiet_threshold(log_shoe: Array) -> float:
    """The detector's level inside the walking part: the midpoint in log between
    the p10 and p50 of ``log_shoe``."""
    p10, p50 = np.percentile(log_shoe, (10, 50))
    return float(0.5 * (p10 + p50))


def quiet_phase(log_shoe: Array, rate_hz: float) -> Flags:
    """Samples of ``log_shoe`` (a walking part) below :func:`quiet_threshold`, runs
    and gaps shorter than :data:`LABEL_MIN_RUN_S` cleaned as labels are."""
    quiet = log_shoe < quiet_threshold(log_shoe)
    return clean_stance(quiet, rate_hz)


def _path_length(pos: Array, mask: Flags) -> float:
    """Horizontal path length over the steps k → k+1 with both samples in ``mask``."""
    step = np.linalg.norm(np.diff(pos[:, :2], axis=0), axis=1)
    keep = mask[1:] & mask[:-1] & np.isfinite(step)
    return float(step[keep].sum())


def _median(x: Array) -> float:
    return float(np.median(x)) if x.size else float("nan")


def clean_stance(stance: Flags, rate_hz: float) -> Flags:
    """Stance flags cleaned as every statistic here cleans labels: gaps and runs shorter
    than :data:`LABEL_MIN_RUN_S` closed and dropped (:func:`clean_labels`)."""
    return clean_labels(stance, max(1, int(round(LABEL_MIN_RUN_S * rate_hz))))


def walking_stance(samples: WalkSamples, log_shoe: Array) -> tuple[StanceSource, Flags, Flags]:
    """:func:`walking_part`'s stance source, its stance flags cleaned
    (:func:`clean_stance`) and its walking part."""
    source, stance, _, walking = walking_part(samples, log_shoe)
    return source, clean_stance(stance, float(samples.rate_hz)), walking


def walking_part(samples: WalkSamples, log_shoe: Array) -> tuple[StanceSource, Flags, Flags, Flags]:
    """Per sample of ``samples``: where its stance came from, the stance flags
    (labels, truth velocity or detector; module docstring), the stands (cleaned
    stance runs of at least :data:`STAND_MIN_S`) and the walking part (not a stand
    and, with footprints, between the first and the last footprint), as
    :func:`walk_stats` uses them. ``log_shoe`` is :func:`log10_shoe` of the walk."""
    s = samples
    rate = float(s.rate_hz)
    log_t = np.asarray(log_shoe, dtype=float)
    if log_t.shape != (len(s.omega_b),):
        raise ValueError(f"{s.name}: log_shoe must be ({len(s.omega_b)},), got {log_t.shape}")
    stand_min = max(1, int(round(STAND_MIN_S * rate)))
    if s.stance is not None:
        source, stance = StanceSource.LABELS, np.asarray(s.stance, dtype=bool)
    elif s.truth_pos is not None and np.isfinite(s.truth_pos).all(axis=1).mean() > 0.9:
        source, stance = StanceSource.TRUTH_VELOCITY, truth_velocity_stance(s.truth_pos, rate)
    else:
        source, stance = StanceSource.DETECTOR, log_t < DETECTOR_STAND_LOG10
    # stands from the cleaned labels: a pause split by a one-sample flicker of the
    # labels (PyShoe's VICON labels flicker) is still a stand
    stand = long_runs(clean_stance(stance, rate), stand_min)
    walking = ~stand
    if source is StanceSource.DETECTOR and walking.any():
        stance = stand | (log_t < quiet_threshold(log_t[walking]))
    if s.footfall_index is not None and len(s.footfall_index) >= 2:
        idx = np.asarray(s.footfall_index, dtype=np.int64)
        walking[: idx[0]] = False  # the walk is between the first and last footprint
        walking[idx[-1] + 1 :] = False
    return source, stance, stand, walking


def walk_stats(samples: WalkSamples, per_stride: bool = True) -> WalkStats:
    """The statistics of one walk (module docstring); ``per_stride`` False leaves
    the per-stride arrays empty (the cost of a fit's many simulated walks)."""
    s = samples
    rate = float(s.rate_hz)
    log_t = log10_shoe(s.omega_b, s.f_b, rate, s.g)
    source, stance, stand, walking = walking_part(s, log_t)
    walking_s = float(walking.sum()) / rate
    speed_source, speed = SpeedSource.NONE, float("nan")
    if s.footfall_index is not None and len(s.footfall_index) >= 2 and walking_s > 0:
        fp = np.asarray(s.footprints_m, dtype=float)
        speed_source = SpeedSource.FOOTPRINTS
        speed = float(np.linalg.norm(np.diff(fp, axis=0), axis=1).sum()) / walking_s
    elif s.truth_pos is not None and walking_s > 0:
        speed_source = SpeedSource.TRUTH
        speed = _path_length(np.asarray(s.truth_pos, dtype=float), walking) / walking_s
    strides = _stride_stats(s, stance, stand, log_t, rate) if per_stride else _no_strides()
    return WalkStats(
        name=s.name,
        rate_hz=rate,
        stance_source=source,
        speed_source=speed_source,
        speed_mps=speed,
        walking_s=walking_s,
        standing_s=float(stand.sum()) / rate,
        log_shoe=log_t[walking],
        strides=strides,
    )


def _no_strides() -> StrideStats:
    return StrideStats(*np.zeros((9, 0)))


def _stride_stats(
    s: WalkSamples, stance: Flags, stand: Flags, log_t: Array, rate: float
) -> StrideStats:
    """Per-stride statistics; strides from footprints, or from the starts of the
    clean stance runs as :func:`pednav_env.calibration.strides.stride_stances`
    joins them (a merged run, its gaps included, is the stride's stance); with
    truth positions, strides overlapping a truth glitch left out and recorded."""
    n = stance.size
    clean = clean_stance(stance, rate)
    starts, ends = runs(clean)
    if s.footfall_index is not None:
        bounds = np.asarray(s.footfall_index, dtype=np.int64)
        points = np.asarray(s.footprints_m, dtype=float)
    else:
        starts, ends = stride_stances(starts, ends, rate, s.truth_pos)
        for a, b in zip(starts, ends, strict=True):
            clean[a:b] = True
        bounds = starts
        points = None
        if s.truth_pos is not None:
            points = np.asarray(s.truth_pos, dtype=float)[bounds, :2]
    gyro = np.linalg.norm(s.omega_b, axis=1)
    accel_dev = np.abs(np.linalg.norm(s.f_b, axis=1) - s.g)
    glitched = glitched_strides(bounds, s.truth_pos, rate)
    rows, left_out = [], []
    for k in range(bounds.size - 1):
        a, b = int(bounds[k]), int(bounds[k + 1])
        if b <= a or stand[a:b].any() or b > n:
            continue
        if glitched[k]:
            left_out.append((a / rate, b / rate))
            continue
        speed = float("nan")
        if points is not None:
            d = np.linalg.norm(points[k + 1, :2] - points[k, :2])
            speed = float(d) * rate / (b - a) if np.isfinite(d) else float("nan")
        first = np.flatnonzero((starts >= a) & (starts < b))
        stance_s = float(ends[first[0]] - starts[first[0]]) / rate if first.size else float("nan")
        st = clean[a:b]
        quiet = log_t[a:b][np.isfinite(log_t[a:b])]
        p5 = float(np.percentile(quiet, STRIDE_QUIET_PERCENT)) if quiet.size >= 10 else np.nan
        rows.append(
            (
                a / rate,
                (b - a) / rate,
                speed,
                stance_s,
                _median(gyro[a:b][st]),
                _median(accel_dev[a:b][st]),
                _median(gyro[a:b][~st]),
                _median(accel_dev[a:b][~st]),
                p5,
            )
        )
    cols = np.array(rows, dtype=float).reshape(-1, 9).T
    left = np.array(left_out, dtype=float).reshape(-1, 2)
    return StrideStats(*cols, glitch_left_out_s=left)
