"""The calibration fit's objective: a distance between summary statistics of
recorded and simulated walks (:func:`distance`), minimised by
:mod:`pednav_env.calibration.fit` over the values of
:mod:`pednav_env.calibration.parameters`.

The distance (:func:`band_distance`), per speed band holding recordings,
weighted by the band's share of the recordings and summed: the
1-Wasserstein distances (W1) between the recordings' and the simulated walks'
values of

- p10, p50 and p90 of log10 SHOE (decades): mid-stance quietness, the
  stance/swing edge, swing vigour;
- the quiet share of the walking time and the median quiet-run length
  (:mod:`pednav_env.calibration.stats`; divided by 0.1 and 0.1 s, so that a
  tenth of the cycle weighs as a decade);

plus half the W1 between the pooled log10 SHOE samples; and two terms over
all bands (:func:`stride_distance`, :func:`coverage_distance`):

- **per stride**, the W1 between the recordings' and the simulated strides'
  quietness (5th percentile of log10 SHOE over the stride,
  :class:`pednav_env.calibration.stats.StrideStats`), binned by the stride's own
  speed, averaged over the bins holding at least :data:`MIN_STRIDES_PER_BIN`
  recorded strides with equal weight: a walk's median speed hides its fast
  strides (the hallway walks' fast and running bursts), and a stance detector
  has to work at every speed, so the fast bins count as much as the many
  walking strides;
- **coverage**, per recording, how far (decades) its p10 and its p50 lie
  outside the simulated walks' 5–95 % range in its band, averaged over the
  recordings: the walker-to-walker spread must cover the recorded spread
  (what ``pednav sim2real`` checks), which a distance between distributions
  alone does not ask for.

Two opt-in changes to the distance (off by default; the shipped fit's
distance is unchanged, candidate v7 of docs/SIM_TO_REAL_CANDIDATES.md):

- **swing** (``swing=True``, :func:`swing_distance`), per stride-speed bin of
  the stride term (:func:`stride_bins`), the W1 (decades of rad/s) between the
  recorded and the simulated strides' swing vigour, log10 of the median |ω|
  over the stride's swing samples
  (:attr:`pednav_env.calibration.stats.StrideStats.swing_gyro_median`), averaged
  over the bins with equal weight (a bin without a simulated stride counts
  :data:`MISSING_BIN_DECADES`), weight :data:`SWING_WEIGHT`, term
  ``stride_swing``: the only term that sees the swing's pitch knots
  (``pitch_knot_stride_m``), which act on the stance measures only through the
  swing's end;
- **coverage on separate walks** (``coverage_walks`` N > 0): per band holding
  recordings, N more simulated walks (seeds :func:`coverage_seed`, never those
  of the W1 terms' walks) for the coverage term alone, so that a spread that
  collapses on the W1 walks' few walkers is seen on other walkers.

The simulated walks of a fit use the same seeds at every evaluation (common
random numbers), so the distance is a deterministic function of the
parameters.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.stats import wasserstein_distance

from pednav_env.calibration.compare import (
    SPEED_BANDS,
    band_of,
    band_turns,
    stride_quietness_by_bin,
    stride_swing_by_bin,
)
from pednav_env.calibration.parameters import randomization
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.stats import WalkStats

Array = NDArray[np.float64]

#: The recordings' IMU grade, used in every fit.
GRADE = "microstrain_gx5"
#: Simulated walks in a fit are shorter than sim2real's (s; the cost of a fit).
FIT_DURATION_S = (20.0, 30.0)
#: Scales of the per-walk statistics in the distance (module docstring).
STAT_SCALES = {
    "log_shoe_p10": 1.0,
    "log_shoe_p50": 1.0,
    "log_shoe_p90": 1.0,
    "quiet_fraction": 0.1,
    "quiet_s_median": 0.1,
}
#: Weight of the pooled log10 SHOE W1.
POOLED_WEIGHT = 0.5
#: Weights of the per-stride quietness term and of the coverage term (decades,
#: like the W1 of p10).
STRIDE_WEIGHT = 1.0
COVERAGE_WEIGHT = 1.0
#: A stride-speed bin enters the stride term with at least this many recorded
#: strides.
MIN_STRIDES_PER_BIN = 10
#: The coverage term's range over simulated walks (%), as ``pednav sim2real``'s.
COVERAGE_PERCENT = (5.0, 95.0)
#: The stride term's value for a bin the simulator has no stride in (decades).
MISSING_BIN_DECADES = 2.0
#: Weight of the opt-in swing term (decades of rad/s; like the stride term).
SWING_WEIGHT = 1.0
#: The opt-in coverage walks of band k use seed ``seed · 100 + 50 + k``
#: (:func:`coverage_seed`); the W1 walks use ``seed · 100 + k``.
COVERAGE_SEED_OFFSET = 50
#: Probabilities at which the pooled W1 compares quantile functions.
_POOLED_P = (np.arange(400) + 0.5) / 400


def pooled_w1(real: Array, sim: Array) -> float:
    """W1 between two samples as the mean absolute difference of their quantile
    functions on a 400-point grid (the integral ∫|F⁻¹ − G⁻¹| dp by the midpoint
    rule; within 1e-3 decades of the exact value on walks, at a fraction of the
    cost of sorting both pooled samples together)."""
    return float(np.mean(np.abs(np.quantile(real, _POOLED_P) - np.quantile(sim, _POOLED_P))))


def band_distance(real: Sequence[WalkStats], sim: Sequence[WalkStats]) -> dict[str, float]:
    """The distance's terms for one band (module docstring), each already scaled."""
    out = {}
    for attr, scale in STAT_SCALES.items():
        r = np.array([getattr(s, attr) for s in real])
        m = np.array([getattr(s, attr) for s in sim])
        r, m = r[np.isfinite(r)], m[np.isfinite(m)]
        out[attr] = wasserstein_distance(r, m) / scale if r.size and m.size else 0.0
    pooled_real = np.concatenate([s.log_shoe for s in real])
    pooled_sim = np.concatenate([s.log_shoe for s in sim])
    out["pooled_log_shoe"] = POOLED_WEIGHT * pooled_w1(pooled_real, pooled_sim)
    return out


def stride_bins(real: Sequence[WalkStats]) -> list[int]:
    """The bins of the stride term: those with ≥ :data:`MIN_STRIDES_PER_BIN`
    recorded strides."""
    return [k for k, v in stride_quietness_by_bin(real).items() if v.size >= MIN_STRIDES_PER_BIN]


def stride_distance(real: Sequence[WalkStats], sim: Sequence[WalkStats]) -> dict[int, float]:
    """Per stride-speed bin of :func:`stride_bins`, the W1 (decades) between the
    recorded and the simulated strides' quietness; a bin without simulated
    strides counts :data:`MISSING_BIN_DECADES` (the simulator has no stride
    there to compare)."""
    return binned_w1(stride_quietness_by_bin(real), stride_quietness_by_bin(sim), stride_bins(real))


def swing_distance(real: Sequence[WalkStats], sim: Sequence[WalkStats]) -> dict[int, float]:
    """Per stride-speed bin of :func:`stride_bins` holding recorded swing values,
    the W1 (decades of rad/s) between the recorded and the simulated strides'
    log10 swing |ω| median (:func:`pednav_env.calibration.compare.stride_swing_by_bin`);
    a bin without simulated strides counts :data:`MISSING_BIN_DECADES`, as in
    :func:`stride_distance`."""
    return binned_w1(stride_swing_by_bin(real), stride_swing_by_bin(sim), stride_bins(real))


def binned_w1(
    recorded: Mapping[int, Array], simulated: Mapping[int, Array], bins: Sequence[int]
) -> dict[int, float]:
    """Per bin of ``bins`` holding recorded values, the W1 between the recorded and
    the simulated values of that bin (per-bin arrays keyed by bin index);
    :data:`MISSING_BIN_DECADES` where the simulator has none."""
    return {
        k: float(wasserstein_distance(recorded[k], simulated[k]))
        if k in simulated
        else MISSING_BIN_DECADES
        for k in bins
        if k in recorded
    }


def coverage_seed(seed: int, band: int, bands: int = len(SPEED_BANDS)) -> int:
    """The seed of the opt-in coverage walks of band index ``band`` (of ``bands``):
    ``seed · 100 + 50 + band``. The W1 walks of the same fit use ``seed · 100 + k``
    with k < ``bands``, so the two sets cannot meet while ``bands`` ≤
    :data:`COVERAGE_SEED_OFFSET` (50); more bands are refused (ValueError naming
    ``bands``) rather than given colliding seeds."""
    if bands > COVERAGE_SEED_OFFSET:
        raise ValueError(
            f"coverage_seed: bands = {bands} > {COVERAGE_SEED_OFFSET}; the coverage walks' "
            "seeds would meet the W1 walks' seeds"
        )
    if not 0 <= band < bands:
        raise ValueError(f"coverage_seed: band = {band} outside 0..{bands - 1}")
    return seed * 100 + COVERAGE_SEED_OFFSET + band


def coverage_distance(real: Sequence[WalkStats], sim: Sequence[WalkStats]) -> float:
    """The mean over ``real`` of how far (decades) its p10 and its p50 lie outside
    the 5–95 % range of ``sim``'s (one band's walks), summed over the two."""
    if not real:
        return 0.0
    total = 0.0
    for attr in ("log_shoe_p10", "log_shoe_p50"):
        values = np.array([getattr(w, attr) for w in sim])
        lo, hi = np.percentile(values, COVERAGE_PERCENT)
        x = np.array([getattr(w, attr) for w in real])
        total += float(np.mean(np.maximum(0.0, lo - x) + np.maximum(0.0, x - hi)))
    return total


def by_band(real: Sequence[WalkStats]) -> dict[int, list[WalkStats]]:
    """Recordings by index into :data:`SPEED_BANDS` (those without a band dropped)."""
    out: dict[int, list[WalkStats]] = {}
    for s in real:
        band = band_of(s.speed_mps)
        if band is not None:
            out.setdefault(SPEED_BANDS.index(band), []).append(s)
    return dict(sorted(out.items()))


def distance(
    x: Sequence[float],
    real: Sequence[WalkStats],
    walks: int,
    seed: int,
    terms: dict[str, float] | None = None,
    options: Mapping[str, float | bool] | None = None,
    knots: bool = False,
    swing: bool = False,
    coverage_walks: int = 0,
) -> float:
    """The distance (module docstring) of the parameters ``x`` to ``real``:
    the weighted sum over bands of :func:`band_distance` and of
    :func:`coverage_distance`, plus the stride term. Band k simulates ``walks``
    walks from seed ``seed · 100 + k``: the bands holding recordings, and those
    holding recorded strides (:func:`stride_bins`). ``terms``, if given,
    receives the per-term sums; ``options`` and ``knots`` as in
    :func:`randomization`. Opt-in (module docstring): ``swing`` adds the swing
    term (``stride_swing``, :func:`swing_distance`); ``coverage_walks`` N > 0
    measures the coverage term on N other walks per band holding recordings (seed
    :func:`coverage_seed`, no per-stride statistics) instead of the W1 walks. A band's
    walks walk the circles of its recordings when they carry their turn per stride
    (:func:`pednav_env.calibration.compare.band_turns`); the bands holding recorded
    strides only keep the scenario's legs."""
    if coverage_walks < 0:
        raise ValueError(f"distance: coverage_walks must be ≥ 0, got {coverage_walks}")
    model = SimModel("fit", GRADE, randomization(x, options, knots))
    bands = by_band(real)
    total_recordings = sum(len(v) for v in bands.values())
    simulate = sorted(set(bands) | set(stride_bins(real)))
    parts: dict[str, float] = {}
    all_sim: list[WalkStats] = []
    for k in simulate:
        rec = bands.get(k, [])
        turns = band_turns(rec, walks) if rec else None
        sim = model.simulate(SPEED_BANDS[k], walks, seed * 100 + k, FIT_DURATION_S, True, turns)
        all_sim += sim
        if not rec:
            continue
        weight = len(rec) / total_recordings
        for name, value in band_distance(rec, sim).items():
            parts[name] = parts.get(name, 0.0) + weight * value
        if coverage_walks:
            cover_seed = coverage_seed(seed, k)
            turns = band_turns(rec, coverage_walks)
            sim = model.simulate(
                SPEED_BANDS[k], coverage_walks, cover_seed, FIT_DURATION_S, False, turns
            )
        parts["coverage"] = parts.get("coverage", 0.0) + (
            weight * COVERAGE_WEIGHT * coverage_distance(rec, sim)
        )
    strides = stride_distance(real, all_sim)
    if strides:
        parts["stride_p5"] = STRIDE_WEIGHT * float(np.mean(list(strides.values())))
    swings = swing_distance(real, all_sim) if swing else {}
    if swings:
        parts["stride_swing"] = SWING_WEIGHT * float(np.mean(list(swings.values())))
    if terms is not None:
        terms.update(parts)
    return float(sum(parts.values()))
