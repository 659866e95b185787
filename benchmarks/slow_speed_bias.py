"""Why a slow simulated walk's measured speed runs above its strides' nominal speed
(docs/SIM_TO_REAL.md, "What is left").

    PYTHONPATH=. .venv/bin/python benchmarks/slow_speed_bias.py \\
        [--walks 40] [--seed 21400] [--shared ../shared/data] [--json FILE] [--heel-rocker]

**Simulated walks** of the shipped calibrated model
(``StanceRandomization.calibrated()``, MicroStrain grade, 30–60 s, turns and stops,
as ``pednav sim2real`` walks them) with every stride's nominal speed in each band
of :data:`BANDS`; walk i of band j from ``default_rng([seed + j, i])``
(development seeds). Per walk:

- **nominal**: Σ stride length / Σ cycle over the route's strides;
- **measured**: ``pednav sim2real``'s walking speed
  (:func:`pednav_env.calibration.stats.walk_stats`): the horizontal path length of
  the truth position (the IMU, at its lever arm from the heel) over the time not
  spent standing (stands ≥ 1 s of the cleaned truth stance labels removed);
- measured = nominal × **path factor** × **time factor**: the IMU's horizontal
  path over the walking samples / Σ stride length, and Σ cycle / walking time;
- **footfall speed**: the horizontal distance between successive stance starts
  (footfall to footfall, as the hallway walks' footprints measure it) over the
  walking time (:func:`footfall_speed`);
- per straight stride (no heading change, no stop), from the same routes
  simulated with the IMU at the heel (lever arm 0): the **heel's path** over the
  stride / its stride length, how far the heel runs **past its footfall** before
  it comes to rest there (m, and as a share of the stride length), and how far it
  dips **below the ground** (mm); the same path factor for the IMU.

**Recordings** (``--shared``, the 23 PyShoe development trials with their VICON
truth and stance labels): the same path speed (sim2real's) and footfall speed,
and their ratio. Then ``pednav sim2real``'s in-sample check of the shipped model
(60 walks per band, seed 0) three times: the recordings binned by their path
speed and the simulated walks by their nominal band (the shipped check); the
recordings binned by their footfall speed (the simulated walks' nominal speed is
within 1–2 % of their footfall speed); and recordings and simulated walks both
binned by their path speed (the same simulated walks, each moved to the band of
its own measured speed; a band keeps its own walks if fewer than 2 arrive). The
hallway walks' speed is their footprints' in all three.

Prints tables; ``--json`` writes every walk. ``--heel-rocker`` runs all of it with
the shipped model's walkers landing the heel at rest on its footfall
(``StanceRandomization.heel_rocker``).
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from pednav_env.calibration.compare import BandComparison, Sim2RealReport, band_of, compare
from pednav_env.calibration.objective import GRADE
from pednav_env.calibration.sim_model import SIM_DURATION_S, SimModel
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import (
    LABEL_MIN_RUN_S,
    STAND_MIN_S,
    SpeedSource,
    WalkSamples,
    WalkStats,
    clean_labels,
    long_runs,
    runs,
    walk_stats,
)
from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import Route
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.sensors.imu import IMU_GRADES, simulate_imu

#: Nominal stride-speed bands (m/s): the slow walks in question, two faster for scale.
BANDS = ((0.3, 0.35), (0.35, 0.4), (0.4, 0.45), (0.45, 0.5), (0.8, 1.0), (1.3, 1.5))
RATE_HZ = 200.0
CHECK_WALKS, CHECK_SEED = 60, 0


def stand_and_starts(s: WalkSamples) -> tuple[np.ndarray, np.ndarray]:
    """The stands (≥ 1 s of cleaned stance labels, as walk_stats finds them) and
    the sample indices of the cleaned labels' stance starts."""
    clean = clean_labels(
        np.asarray(s.stance, dtype=bool), max(1, round(LABEL_MIN_RUN_S * s.rate_hz))
    )
    stand = long_runs(clean, max(1, round(STAND_MIN_S * s.rate_hz)))
    return stand, runs(clean)[0]


def footfall_speed(s: WalkSamples) -> float:
    """Horizontal distance between successive stance starts (truth positions) over
    the time not spent standing."""
    stand, starts = stand_and_starts(s)
    foot = np.asarray(s.truth_pos, dtype=float)[starts, :2]
    step = np.linalg.norm(np.diff(foot, axis=0), axis=1)
    return float(step[np.isfinite(step)].sum()) / (float((~stand).sum()) / s.rate_hz)


def straight_strides(
    route: Route, heel_pos: np.ndarray, imu_pos: np.ndarray, gait_step: np.ndarray
) -> list[dict]:
    """Per straight stride: heel and IMU path / stride length, the heel's overshoot
    past its footfall and its dip below the ground."""
    out = []
    for k, stride in enumerate(route.strides):
        if stride.heading_change != 0 or stride.stop_s != 0:
            continue
        idx = np.flatnonzero(gait_step == k)
        if idx.size < 3:
            continue
        idx = np.append(idx, idx[-1] + 1)  # the stride's last sample reaches the next stance
        heel = heel_pos[idx]
        d = heel[-1, :2] - heel[0, :2]
        length = stride.shape.stride_length_m
        along = (heel[:, :2] - heel[0, :2]) @ (d / np.linalg.norm(d))
        path = lambda p: float(np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1).sum())  # noqa: E731
        out.append(
            {
                "length_m": length,
                "heel_path_factor": path(heel) / length,
                "imu_path_factor": path(imu_pos[idx]) / length,
                "heel_overshoot_m": float(along.max() - along[-1]),
                "heel_below_ground_mm": float(1e3 * max(0.0, heel[0, 2] - heel[:, 2].min())),
            }
        )
    return out


def stance_model(heel_rocker: bool) -> StanceRandomization:
    """The shipped calibrated model, with ``heel_rocker`` set as asked."""
    return replace(StanceRandomization.calibrated(), heel_rocker=heel_rocker)


def band_walks(
    band: tuple[float, float], walks: int, seed: int, heel_rocker: bool = False
) -> tuple[list[dict], list[dict]]:
    """The walks of one band (nominal, measured, factors) and their straight strides."""
    rngs = [np.random.default_rng([seed, i]) for i in range(walks)]
    stance_rand = stance_model(heel_rocker)
    routes = []
    for rng in rngs:
        motion = stance_rand.draw(rng)
        cfg = SpeedRouteConfig(speed_mps=band, duration_s=SIM_DURATION_S, stance_motion=motion)
        routes.append(speed_route(rng, cfg))
    truth = simulate_foot(routes, FootSimConfig(rate_hz=RATE_HZ), full_state=False)
    heel = simulate_foot(
        routes, FootSimConfig(rate_hz=RATE_HZ, lever_arm_m=(0.0, 0.0, 0.0)), full_state=False
    )
    imu = simulate_imu(
        truth.omega_b,
        truth.f_b,
        RATE_HZ,
        IMU_GRADES[GRADE](),
        rngs,
        gait_step_index=truth.gait_step,
    )
    out, strides = [], []
    for i, route in enumerate(routes):
        s = samples_from_simulation(truth, imu, i)
        stats = walk_stats(s, per_stride=False)
        lengths = np.array([st.shape.stride_length_m for st in route.strides])
        cycles = np.array([st.shape.cycle_s for st in route.strides])
        stand, _ = stand_and_starts(s)
        walking = ~stand
        step = np.linalg.norm(np.diff(np.asarray(s.truth_pos)[:, :2], axis=0), axis=1)
        path = float(step[walking[1:] & walking[:-1]].sum())
        walking_s = float(walking.sum()) / RATE_HZ
        out.append(
            {
                "nominal_mps": float(lengths.sum() / cycles.sum()),
                "measured_mps": float(stats.speed_mps),
                "path_factor": path / float(lengths.sum()),
                "time_factor": float(cycles.sum()) / walking_s,
                "footfall_mps": footfall_speed(s),
                "stride_length_median_m": float(np.median(lengths)),
                "cycle_median_s": float(np.median(cycles)),
            }
        )
        strides += straight_strides(route, heel.pos_n[i], truth.pos_n[i], truth.gait_step[i])
    return out, strides


def simulated(args: argparse.Namespace) -> dict:
    print(
        "nominal band  walks  nominal  measured  ratio  path f.  time f.  footfall   "
        "| straight strides  heel path f.  IMU path f.  heel overshoot m (share)  below ground mm"
    )
    result = {}
    for j, band in enumerate(BANDS):
        rows, strides = band_walks(band, args.walks, args.seed + j, args.heel_rocker)
        med = {k: float(np.median([r[k] for r in rows])) for k in rows[0]}
        ratio = float(np.median([r["measured_mps"] / r["nominal_mps"] for r in rows]))
        smed = {k: float(np.median([r[k] for r in strides])) for k in strides[0]}
        share = float(np.median([r["heel_overshoot_m"] / r["length_m"] for r in strides]))
        print(
            f"{band[0]:.2f}-{band[1]:.2f}    {len(rows):5d}  {med['nominal_mps']:7.3f}  "
            f"{med['measured_mps']:8.3f}  {ratio:5.3f}  {med['path_factor']:7.3f}  "
            f"{med['time_factor']:7.3f}  {med['footfall_mps']:8.3f}   | {len(strides):16d}  "
            f"{smed['heel_path_factor']:12.3f}  {smed['imu_path_factor']:11.3f}  "
            f"{smed['heel_overshoot_m']:14.3f} ({share:.3f})  {smed['heel_below_ground_mm']:15.1f}",
            flush=True,
        )
        result[f"{band[0]:g}-{band[1]:g}"] = {
            "median": med,
            "ratio_median": ratio,
            "straight_strides_median": smed,
            "heel_overshoot_share_median": share,
            "walks": rows,
        }
    return result


def rebinned(report: Sim2RealReport) -> Sim2RealReport:
    """The same recordings and simulated walks, each simulated walk moved to the
    band of its own measured (path) speed, as the recordings are binned."""
    pooled = [w for b in report.bands for w in b.sim]
    bands = []
    for b in report.bands:
        sim = [w for w in pooled if band_of(w.speed_mps) == b.band]
        bands.append(BandComparison(b.band, b.real, sim if len(sim) >= 2 else b.sim))
    return Sim2RealReport(report.model, bands, report.unbanded)


def coverage_line(
    label: str, stats: list[WalkStats], heel_rocker: bool, rebin: bool = False
) -> dict:
    model = SimModel("calibrated", GRADE, stance_model(heel_rocker))
    report = compare(stats, model, CHECK_WALKS, CHECK_SEED)
    if rebin:
        report = rebinned(report)
    covered, total = report.coverage
    slow = [s.name for b in report.bands for s in b.real if not b.covered(s)]
    print(f"{label}: covered {covered}/{total}; not covered: {', '.join(slow)}", flush=True)
    bands = {
        f"{b.band[0]:g}": {
            "recordings": len(b.real),
            "covered": sum(map(b.covered, b.real)),
            "sim_walks": len(b.sim),
            "p10_envelope": [round(v, 2) for v in b.p10_envelope],
            "p50_envelope": [round(v, 2) for v in b.p50_envelope],
        }
        for b in report.bands
    }
    print(
        "  by band (covered/recordings, simulated walks, p10 and p50 envelopes): "
        + "; ".join(
            f"{k}: {v['covered']}/{v['recordings']}, {v['sim_walks']}, "
            f"{v['p10_envelope'][0]:.2f}-{v['p10_envelope'][1]:.2f}, "
            f"{v['p50_envelope'][0]:.2f}-{v['p50_envelope'][1]:.2f}"
            for k, v in bands.items()
        )
    )
    return {"covered": covered, "total": total, "not_covered": slow, "bands": bands}


def recordings(shared: Path, heel_rocker: bool = False) -> dict:
    pyshoe = sorted((shared / "pyshoe-vicon-dev").glob("*.mat"))
    hallway = sorted((shared / "hallway-gcp-dev").glob("*_LLIO.mat"))
    stats, by_footfall, rows = [], [], []
    print("\nPyShoe trial           path speed  footfall speed  ratio")
    for p in pyshoe:
        s = load_walk(p)
        st = walk_stats(s)
        ff = footfall_speed(s)
        rows.append({"name": st.name, "path_mps": st.speed_mps, "footfall_mps": ff})
        print(f"{st.name}  {st.speed_mps:10.3f}  {ff:14.3f}  {st.speed_mps / ff:5.3f}", flush=True)
        stats.append(st)
        by_footfall.append(replace(st, speed_mps=ff))
    for p in hallway:
        st = walk_stats(load_walk(p))
        assert st.speed_source is SpeedSource.FOOTPRINTS
        stats.append(st)
        by_footfall.append(st)
    print()
    return {
        "pyshoe": rows,
        "check_path_speed": coverage_line("recordings by path speed (shipped)", stats, heel_rocker),
        "check_footfall_speed": coverage_line(
            "recordings by footfall speed", by_footfall, heel_rocker
        ),
        "check_path_speed_both": coverage_line(
            "recordings and simulated walks by path speed", stats, heel_rocker, rebin=True
        ),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--walks", type=int, default=40, help="simulated walks per band")
    ap.add_argument("--seed", type=int, default=21400, help="first band's seed (development)")
    ap.add_argument(
        "--shared", default=None, help="the data folder (../shared/data) for the recordings part"
    )
    ap.add_argument("--json", default=None, help="write everything here")
    ap.add_argument(
        "--heel-rocker",
        action="store_true",
        help="walkers land the heel at rest on its footfall (StanceRandomization.heel_rocker)",
    )
    args = ap.parse_args()
    result = {
        "seed": args.seed,
        "walks": args.walks,
        "heel_rocker": args.heel_rocker,
        "simulated": simulated(args),
    }
    if args.shared:
        result["recordings"] = recordings(Path(args.shared), args.heel_rocker)
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
