"""Fit the calibrated foot simulator to recorded walks: CMA-ES on a distance
between summary statistics (``benchmarks/calibrate_foot.py``, docs/SIM_TO_REAL.md).

The parameters (:data:`PARAMETERS`) are those of the distribution over
walkers :class:`pednav_env.gait.stance_motion.StanceRandomization`: the
mid-stance quiet amplitude (log10 mean and spread over walkers, speed
exponent), the edge amplitude (the same), the heel-strike and heel-off time
constants, the roll-over amplitude, the walker's foot-flat share of the
walking cycle (mean at 1 m/s, spread over walkers, change per unit ln speed),
the heel-off/heel-strike share, and the swing vigour (log10 mean and spread of
the scale of the swing's pitch knots). Optionally (:data:`SWING_SPEED`, a
16th value) the swing vigour's speed exponent,
:attr:`pednav_env.gait.stance_motion.StanceRandomization.swing_speed_exponent`,
which the shipped fit holds at 0. Optionally (:data:`PITCH_KNOTS`, one value
more, last) the stride length below which the swing's pitch knots shrink,
:attr:`pednav_env.gait.stance_motion.StanceRandomization.pitch_knot_stride_m`
(0, off, in the shipped fit). Model options that are not fitted (such as
``heel_rocker``, :attr:`pednav_env.gait.stance_motion.StanceRandomization.heel_rocker`,
or a walking cadence law regressed on the training recordings,
:mod:`pednav_env.calibration.cadence`) are held fixed by ``options``. The IMU
grade is the recordings' (``microstrain_gx5``).

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
distance is unchanged, candidate v7 of docs/SIM_TO_REAL.md):

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

``pednav sim2real``'s check is measured afterwards on other simulated walks
(other seeds, longer walks), and on recordings the fit did not see
(``benchmarks/calibrate_foot.py``'s leave-one-group-out folds).

The simulated walks of a fit use the same seeds at every evaluation (common
random numbers), so the distance is a deterministic function of the
parameters. A fit scores its start point first and returns it when the search
finds nothing better (:func:`minimize_in_box`): CMA-ES never evaluates its own
mean, and a warm-started search on a small budget can end above its start.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import cma
import numpy as np
from numpy.typing import NDArray
from scipy.stats import wasserstein_distance

from pednav_env.calibration.compare import (
    SPEED_BANDS,
    SimModel,
    band_of,
    stride_quietness_by_bin,
    stride_swing_by_bin,
)
from pednav_env.calibration.stats import WalkStats
from pednav_env.gait.stance_motion import StanceRandomization

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


@dataclass(frozen=True)
class Parameter:
    """One fitted value: its name, start point and box (the fit's units)."""

    name: str
    start: float
    lower: float
    upper: float


#: The fitted values in vector order. Start points: today's stance timing
#: (foot flat 0.34 of the cycle, heel-off and heel-strike 0.16 each, unscaled
#: swing) and round guesses for the stance dynamics, not a previous fit.
PARAMETERS = (
    Parameter("quiet_log10_mean", -2.5, -4.5, -1.2),
    Parameter("quiet_log10_std", 0.3, 0.02, 1.0),
    Parameter("quiet_speed_exponent", 0.5, -1.0, 3.0),
    Parameter("edge_log10_mean", -2.0, -5.0, -0.8),
    Parameter("edge_log10_std", 0.2, 0.02, 1.0),
    Parameter("edge_speed_exponent", 1.0, -1.0, 4.0),
    Parameter("log10_tau_hs_s", -1.4, -2.0, -0.7),
    Parameter("log10_tau_ho_s", -1.4, -2.0, -0.7),
    Parameter("log10_roll_rad", -2.0, -4.0, -0.8),
    Parameter("flat_fraction", 0.34, 0.15, 0.6),
    Parameter("flat_fraction_std", 0.03, 0.0, 0.15),
    Parameter("flat_speed_slope", 0.0, -0.3, 0.1),
    Parameter("heel_fraction", 0.16, 0.05, 0.2),
    Parameter("log10_swing_pitch_scale", 0.0, -0.15, 0.35),
    Parameter("swing_pitch_log10_std", 0.05, 0.0, 0.2),
)
NAMES = tuple(p.name for p in PARAMETERS)
START = np.array([p.start for p in PARAMETERS])
LOWER = np.array([p.lower for p in PARAMETERS])
UPPER = np.array([p.upper for p in PARAMETERS])
#: The optional 16th value: the swing vigour's speed exponent (k ∝ v^p), start 0
#: (the shipped model's speed-independent scale).
SWING_SPEED = Parameter("swing_speed_exponent", 0.0, -0.5, 1.5)
EXTENDED = (*PARAMETERS, SWING_SPEED)
#: The optional last value with ``knots``: the stride length (m) below which the
#: swing's pitch knots shrink (StanceRandomization.pitch_knot_stride_m), start 0
#: (off: today's knots at every length), box up to 1.2 m (about the route's
#: default stride at 1 m/s, 1.18 m).
PITCH_KNOTS = Parameter("pitch_knot_stride_m", 0.0, 0.0, 1.2)


def parameter_set(size: int, knots: bool = False) -> tuple[Parameter, ...]:
    """The parameters of a vector of ``size`` values: :data:`PARAMETERS` (15) or
    :data:`EXTENDED` (16), followed by :data:`PITCH_KNOTS` when ``knots`` (one
    value more)."""
    base = size - 1 if knots else size
    extra = (PITCH_KNOTS,) if knots else ()
    if base == len(PARAMETERS):
        return (*PARAMETERS, *extra)
    if base == len(EXTENDED):
        return (*EXTENDED, *extra)
    raise ValueError(
        f"a parameter vector{' with the pitch knots' if knots else ''} has "
        f"{len(PARAMETERS) + len(extra)} or {len(EXTENDED) + len(extra)} values, got {size}"
    )


def box(size: int, knots: bool = False) -> tuple[Array, Array]:
    """Lower and upper bounds of a vector of ``size`` values (:func:`parameter_set`)."""
    ps = parameter_set(size, knots)
    return np.array([p.lower for p in ps]), np.array([p.upper for p in ps])


def randomization(
    x: Sequence[float],
    options: Mapping[str, float | bool] | None = None,
    knots: bool = False,
) -> StanceRandomization:
    """The parameter vector (:data:`NAMES` order, then optionally
    :data:`SWING_SPEED`, then with ``knots`` :data:`PITCH_KNOTS`; clipped to the
    box) as a StanceRandomization, with the fixed model ``options``
    (StanceRandomization fields, e.g. ``heel_rocker`` or the ``cadence_*`` law of
    :func:`pednav_env.calibration.cadence.fit_cadence_law`)."""
    x = np.asarray(x, dtype=float)
    lower, upper = box(x.size, knots)
    x = np.clip(x, lower, upper)
    v = dict(zip([p.name for p in parameter_set(x.size, knots)], x.tolist(), strict=True))
    if knots:
        options = {**(options or {}), "pitch_knot_stride_m": v["pitch_knot_stride_m"]}
    return StanceRandomization(
        quiet_log10_mean=v["quiet_log10_mean"],
        quiet_log10_std=v["quiet_log10_std"],
        quiet_speed_exponent=v["quiet_speed_exponent"],
        edge_log10_mean=v["edge_log10_mean"],
        edge_log10_std=v["edge_log10_std"],
        edge_speed_exponent=v["edge_speed_exponent"],
        tau_hs_s=10 ** v["log10_tau_hs_s"],
        tau_ho_s=10 ** v["log10_tau_ho_s"],
        roll_rad=10 ** v["log10_roll_rad"],
        flat_fraction=v["flat_fraction"],
        flat_fraction_std=v["flat_fraction_std"],
        flat_speed_slope=v["flat_speed_slope"],
        heel_fraction=v["heel_fraction"],
        swing_pitch_scale=10 ** v["log10_swing_pitch_scale"],
        swing_pitch_log10_std=v["swing_pitch_log10_std"],
        swing_speed_exponent=v.get("swing_speed_exponent", 0.0),
        **(options or {}),
    )


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
    rec, mod = stride_quietness_by_bin(real), stride_quietness_by_bin(sim)
    return {
        k: float(wasserstein_distance(rec[k], mod[k])) if k in mod else MISSING_BIN_DECADES
        for k in stride_bins(real)
    }


def swing_distance(real: Sequence[WalkStats], sim: Sequence[WalkStats]) -> dict[int, float]:
    """Per stride-speed bin of :func:`stride_bins` holding recorded swing values,
    the W1 (decades of rad/s) between the recorded and the simulated strides'
    log10 swing |ω| median (:func:`pednav_env.calibration.compare.stride_swing_by_bin`);
    a bin without simulated strides counts :data:`MISSING_BIN_DECADES`, as in
    :func:`stride_distance`."""
    rec, mod = stride_swing_by_bin(real), stride_swing_by_bin(sim)
    return {
        k: float(wasserstein_distance(rec[k], mod[k])) if k in mod else MISSING_BIN_DECADES
        for k in stride_bins(real)
        if k in rec
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
    :func:`coverage_seed`, no per-stride statistics) instead of the W1 walks."""
    if coverage_walks < 0:
        raise ValueError(f"distance: coverage_walks must be ≥ 0, got {coverage_walks}")
    model = SimModel("fit", GRADE, randomization(x, options, knots))
    bands = by_band(real)
    total_recordings = sum(len(v) for v in bands.values())
    simulate = sorted(set(bands) | set(stride_bins(real)))
    parts: dict[str, float] = {}
    all_sim: list[WalkStats] = []
    for k in simulate:
        sim = model.simulate(SPEED_BANDS[k], walks, seed * 100 + k, FIT_DURATION_S, True)
        all_sim += sim
        rec = bands.get(k, [])
        if not rec:
            continue
        weight = len(rec) / total_recordings
        for name, value in band_distance(rec, sim).items():
            parts[name] = parts.get(name, 0.0) + weight * value
        if coverage_walks:
            cover_seed = coverage_seed(seed, k)
            sim = model.simulate(SPEED_BANDS[k], coverage_walks, cover_seed, FIT_DURATION_S, False)
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


@dataclass
class FitResult:
    """The returned parameters and their distance, the start point's distance,
    whether the start was kept (the search found nothing better), and the
    search's best distance after each generation (the convergence record)."""

    x: Array
    distance: float
    evaluations: int
    cpu_s: float
    stop: dict[str, float]
    best_by_generation: list[float] = field(default_factory=list)
    start_distance: float = float("nan")
    search_distance: float = float("nan")
    kept_start: bool = False

    def to_json(self) -> dict:
        return {
            "x": [round(float(v), 5) for v in self.x],
            "distance": round(self.distance, 5),
            "start_distance": round(self.start_distance, 5),
            "search_distance": round(self.search_distance, 5),
            "kept_start": self.kept_start,
            "evaluations": self.evaluations,
            "generations": len(self.best_by_generation),
            "cpu_s": round(self.cpu_s, 1),
            "stop": {k: float(v) for k, v in self.stop.items()},
            "best_by_generation": [round(v, 5) for v in self.best_by_generation],
        }


def minimize_in_box(
    objective: Callable[[Array], float],
    x0: Sequence[float],
    lower: Array,
    upper: Array,
    max_evaluations: int,
    seed: int,
    popsize: int = 12,
    sigma0: float = 0.2,
    progress: Callable[[int, float], None] | None = None,
) -> FitResult:
    """CMA-ES (Hansen's ``cma``) on ``objective`` in the box [lower, upper]
    scaled to [0, 1]^n, from ``x0`` (clipped to the box), step ``sigma0`` in the
    scaled box, until ``max_evaluations`` or its own convergence tests (a
    best-value change below 1e-3 over the recent generations).

    The start point is scored first and returned when no candidate of the
    search beats it (``kept_start``): CMA-ES samples around its mean but never
    evaluates the mean itself, so a warm-started search with a small budget can
    otherwise end above where it started. The search itself (its candidates and
    ``best_by_generation``) does not depend on the start's score.
    ``progress(generation, best)`` is called after each generation with the
    search's best so far."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    scale = upper - lower
    start = np.clip(np.asarray(x0, dtype=float), lower, upper)
    t0 = time.process_time()
    start_distance = float(objective(start))
    es = cma.CMAEvolutionStrategy(
        (start - lower) / scale,
        sigma0,
        {
            "bounds": [0.0, 1.0],
            "popsize": popsize,
            "maxfevals": max_evaluations,
            "tolfun": 1e-3,
            "tolfunhist": 1e-3,
            "seed": seed + 1,
            "verbose": -9,
        },
    )
    history: list[float] = []
    while not es.stop():
        zs = es.ask()
        es.tell(zs, [objective(lower + scale * np.asarray(z)) for z in zs])
        history.append(float(es.result.fbest))
        if progress is not None:
            progress(len(history), history[-1])
    searched = float(es.result.fbest)
    kept_start = not searched < start_distance
    x = start if kept_start else lower + scale * np.asarray(es.result.xbest)
    return FitResult(
        x,
        start_distance if kept_start else searched,
        int(es.result.evaluations) + 1,
        time.process_time() - t0,
        dict(es.stop()),
        history,
        start_distance,
        searched,
        kept_start,
    )


def fit(
    real: Sequence[WalkStats],
    walks: int,
    max_evaluations: int,
    seed: int,
    popsize: int = 12,
    progress: Callable[[int, float], None] | None = None,
    x0: Sequence[float] | None = None,
    sigma0: float = 0.2,
    options: Mapping[str, float | bool] | None = None,
    knots: bool = False,
    swing: bool = False,
    coverage_walks: int = 0,
) -> FitResult:
    """:func:`distance` to ``real`` minimised by :func:`minimize_in_box` from
    ``x0`` (default :data:`START`; clipped to the box; 16 values fit
    :data:`EXTENDED`; fixed model ``options`` and ``knots``, the last value
    :data:`PITCH_KNOTS`, as in :func:`randomization`; ``swing`` and
    ``coverage_walks`` as in :func:`distance`): the better of the start and
    the search's best."""
    if not real:
        raise ValueError("fit: no recordings with a walking speed in a band")
    x0 = START if x0 is None else np.asarray(x0, dtype=float)
    lower, upper = box(x0.size, knots)
    return minimize_in_box(
        lambda x: distance(
            x,
            real,
            walks,
            seed,
            options=options,
            knots=knots,
            swing=swing,
            coverage_walks=coverage_walks,
        ),
        x0,
        lower,
        upper,
        max_evaluations,
        seed,
        popsize,
        sigma0,
        progress,
    )


def groups(stats: Sequence[WalkStats]) -> dict[str, list[WalkStats]]:
    """The cross-validation groups: PyShoe trials before 11:35 and after (two
    sessions of one day; file names ``2017-11-22-HH-MM-SS``) and the hallway walks
    (another walker, place and day)."""
    out: dict[str, list[WalkStats]] = {"pyshoe_early": [], "pyshoe_late": [], "hallway": []}
    for s in stats:
        if s.name.startswith("2017-") and len(s.name) >= 16:
            hhmm = s.name[11:13] + s.name[14:16]
            out["pyshoe_early" if hhmm < "1135" else "pyshoe_late"].append(s)
        else:
            out["hallway"].append(s)
    return out
