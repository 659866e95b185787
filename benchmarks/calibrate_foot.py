"""Fit the calibrated foot simulator to the development recordings (CMA-ES).

The parameters: the distribution over walkers of the stance dynamics
(:class:`pednav_env.gait.stance_motion.StanceRandomization`: log10 mean and
spread of the mid-stance quiet amplitude, its speed exponent, the edge
amplitude and its speed exponent, the heel-strike and heel-off time
constants, the roll-over amplitude), with the MicroStrain 3DM-GX5-25 grade.

The distance, per speed band holding training recordings, summed over bands:
W1 between the recordings' p10 values and the simulated walks' p10 values
(log10 SHOE, :mod:`pednav_env.calibration.stats`), the same for p50, and half
the W1 between the pooled log10 SHOE samples. The simulated walks use the
same seeds at every evaluation (common random numbers), so the distance is a
deterministic function of the parameters.

Cross-validation: three groups — the PyShoe trials before 11:35 and after
(two sessions of one day), and the hallway walks (another walker, place and
day). Each fold fits on two groups and reports the coverage of the held-out
group by ``pednav sim2real``'s envelope (20 walks per band); then a fit on all
recordings gives the shipped values. Run (about 10 min on 2 cores):

    PYTHONPATH=. .venv/bin/python benchmarks/calibrate_foot.py \\
        --pyshoe ../shared/data/pyshoe-vicon-dev --hallway ../shared/data/hallway-gcp-dev \\
        --out benchmarks/results/calibrate_foot.json
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict
from pathlib import Path

import cma
import numpy as np
from scipy.stats import wasserstein_distance

from pednav_env.calibration.compare import SimModel, band_of, compare
from pednav_env.calibration.sources import load_walk
from pednav_env.calibration.stats import WalkStats, walk_stats
from pednav_env.gait.stance_motion import StanceRandomization

NAMES = (
    "quiet_log10_mean",
    "quiet_log10_std",
    "quiet_speed_exponent",
    "edge_log10_mean",
    "edge_speed_exponent",
    "log10_tau_hs_s",
    "log10_tau_ho_s",
    "log10_roll_rad",
)
X0 = np.array([-2.5, 0.3, 0.5, -2.0, 1.0, -1.4, -1.4, -2.0])
LOWER = np.array([-4.5, 0.02, -1.0, -4.0, -1.0, -2.0, -2.0, -4.0])
UPPER = np.array([-1.2, 1.0, 3.0, -0.8, 3.0, -0.7, -0.7, -0.8])
SCALE = UPPER - LOWER
GRADE = "microstrain_gx5"
#: Simulated walks in the fit are shorter than sim2real's (speed of the fit).
FIT_DURATION_S = (20.0, 30.0)


def randomization(x: np.ndarray) -> StanceRandomization:
    """The parameter vector (NAMES order) as a StanceRandomization."""
    x = np.clip(x, LOWER, UPPER)
    return StanceRandomization(
        quiet_log10_mean=float(x[0]),
        quiet_log10_std=float(x[1]),
        quiet_speed_exponent=float(x[2]),
        edge_log10_mean=float(x[3]),
        edge_speed_exponent=float(x[4]),
        tau_hs_s=float(10 ** x[5]),
        tau_ho_s=float(10 ** x[6]),
        roll_rad=float(10 ** x[7]),
    )


def distance(x: np.ndarray, real: list[WalkStats], walks: int, seed: int) -> float:
    """The summed per-band distance (module docstring)."""
    model = SimModel("fit", GRADE, randomization(x))
    by_band: dict[tuple[float, float], list[WalkStats]] = {}
    for s in real:
        by_band.setdefault(band_of(s.speed_mps), []).append(s)
    total = 0.0
    for k, (band, rec) in enumerate(sorted(by_band.items())):
        sim = model.simulate(band, walks, seed * 100 + k, FIT_DURATION_S)
        for attr in ("log_shoe_p10", "log_shoe_p50"):
            total += wasserstein_distance(
                [getattr(s, attr) for s in rec], [getattr(s, attr) for s in sim]
            )
        pooled_real = np.concatenate([s.log_shoe for s in rec])
        pooled_sim = np.concatenate([s.log_shoe for s in sim])
        total += 0.5 * wasserstein_distance(pooled_real, pooled_sim)
    return float(total)


def fit(real: list[WalkStats], walks: int, iterations: int, seed: int) -> tuple[np.ndarray, float]:
    """CMA-ES in the box LOWER..UPPER scaled to [0, 1]; returns (x, distance)."""
    z0 = (X0 - LOWER) / SCALE
    es = cma.CMAEvolutionStrategy(
        z0,
        0.2,
        {
            "bounds": [0.0, 1.0],
            "popsize": 8,
            "maxiter": iterations,
            "seed": seed + 1,
            "verbose": -9,
        },
    )
    while not es.stop():
        zs = es.ask()
        es.tell(zs, [distance(LOWER + SCALE * np.asarray(z), real, walks, seed) for z in zs])
    z = es.result.xbest
    return LOWER + SCALE * np.asarray(z), float(es.result.fbest)


def groups(stats: list[WalkStats]) -> dict[str, list[WalkStats]]:
    """PyShoe before 11:35, PyShoe after, hallway (by file name)."""
    out: dict[str, list[WalkStats]] = {"pyshoe_early": [], "pyshoe_late": [], "hallway": []}
    for s in stats:
        if s.name.startswith("2017-"):
            hhmm = s.name[11:13] + s.name[14:16]
            out["pyshoe_early" if hhmm < "1135" else "pyshoe_late"].append(s)
        else:
            out["hallway"].append(s)
    return out


def coverage(real: list[WalkStats], x: np.ndarray, walks: int) -> dict:
    report = compare(real, SimModel("calibrated", GRADE, randomization(x)), walks, seed=0)
    covered, total = report.coverage
    return {"covered": covered, "total": total, "report": report.to_json()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pyshoe", required=True, help="directory of PyShoe .mat trials")
    ap.add_argument("--hallway", required=True, help="directory of hallway _LLIO.mat walks")
    ap.add_argument("--walks", type=int, default=8, help="simulated walks per band in the fit")
    ap.add_argument("--iterations", type=int, default=10, help="CMA-ES generations")
    ap.add_argument("--seed", type=int, default=7, help="fit seed (not sim2real's)")
    ap.add_argument("--no-cv", action="store_true", help="skip the cross-validation folds")
    ap.add_argument("--out", default=None, help="write the results as JSON here")
    args = ap.parse_args()
    paths = sorted(Path(args.pyshoe).glob("*.mat")) + sorted(Path(args.hallway).glob("*_LLIO.mat"))
    stats = [walk_stats(load_walk(p)) for p in paths]
    result: dict = {"names": NAMES, "folds": {}}

    def save() -> None:
        if args.out:
            Path(args.out).parent.mkdir(parents=True, exist_ok=True)
            Path(args.out).write_text(json.dumps(result, indent=1))

    t0 = time.perf_counter()
    x, d = fit(stats, args.walks, args.iterations, args.seed)
    cov = coverage(stats, x, 20)
    print(
        f"all recordings: distance {d:.3f}, covered {cov['covered']}/{cov['total']} "
        f"({time.perf_counter() - t0:.0f} s)",
        flush=True,
    )
    result["all"] = {"x": x.tolist(), "distance": d, **cov}
    result["randomization"] = asdict(randomization(x))
    print(json.dumps(result["randomization"], indent=1), flush=True)
    save()
    folds = {} if args.no_cv else groups(stats)
    for held_out, test in folds.items():
        train = [s for s in stats if all(s is not t for t in test)]
        t0 = time.perf_counter()
        x, d = fit(train, args.walks, args.iterations, args.seed)
        cov = coverage(test, x, 20)
        print(
            f"fold held-out {held_out}: distance {d:.3f}, held-out covered "
            f"{cov['covered']}/{cov['total']} ({time.perf_counter() - t0:.0f} s)",
            flush=True,
        )
        result["folds"][held_out] = {"x": x.tolist(), "distance": d, **cov}
        save()


if __name__ == "__main__":
    main()
