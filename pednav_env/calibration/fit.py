"""Fit the calibrated foot simulator to recorded walks: CMA-ES
(:func:`minimize_in_box`, :func:`fit`) on the distance between summary
statistics of :mod:`pednav_env.calibration.objective`, over the values of
:mod:`pednav_env.calibration.parameters` (``benchmarks/calibrate_foot.py``,
docs/SIM_TO_REAL.md); and the recordings' cross-validation groups
(:func:`groups`).

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

from pednav_env.calibration.objective import distance
from pednav_env.calibration.parameters import START, box
from pednav_env.calibration.stats import WalkStats

Array = NDArray[np.float64]


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
    priors: bool = False,
) -> FitResult:
    """:func:`~pednav_env.calibration.objective.distance` to ``real`` minimised by
    :func:`minimize_in_box` from ``x0`` (default
    :data:`~pednav_env.calibration.parameters.START`; clipped to the box; 16 values
    fit :data:`~pednav_env.calibration.parameters.EXTENDED`; fixed model ``options``
    and ``knots``, the last value :data:`~pednav_env.calibration.parameters.PITCH_KNOTS`,
    as in :func:`~pednav_env.calibration.parameters.randomization`; ``swing`` and
    ``coverage_walks`` as in :func:`~pednav_env.calibration.objective.distance`): the
    better of the start and the search's best. ``priors`` narrows the box of the
    gait timing to :data:`~pednav_env.calibration.parameters.GAIT_PRIORS` (a start
    outside it is clipped to it)."""
    if not real:
        raise ValueError("fit: no recordings with a walking speed in a band")
    x0 = START if x0 is None else np.asarray(x0, dtype=float)
    lower, upper = box(x0.size, knots, priors)
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
