"""Where the median SHOE sample sits, by phase of the gait cycle: recordings beside
the calibrated simulator at the same walking speed (docs/SIM_TO_REAL.md, "Slow
walkers: the mechanism").

    PYTHONPATH=. .venv/bin/python benchmarks/slow_walk_phases.py \
        [--shared DIR] [--fits JSON] [--walks 60] [--seed 21200] [--json FILE] \
        [--heel-rocker] [--pitch-knot-stride M]

The walk-level p50 of log10 SHOE (``pednav sim2real``'s measure) is the level L
at which the share F(L) of walking samples below L is one half. A recording's p50
lies below the simulator's when, at its own p50, the simulated walks have fewer
samples below it; this script splits that share by phase:

- phases from a stance mask the same for recordings and simulation: the truth
  foot speed below 0.2 m/s (:func:`pednav_env.calibration.stats.truth_velocity_stance`),
  else (hallway walks, footprints only) the SHOE detector's quiet phase, cleaned
  like labels. Each gap between two stance runs is split in thirds: heel-off
  (first third: toe-off and the early swing), swing (middle), heel strike (last
  third). Stands (≥ 1 s) are removed as ``pednav sim2real`` removes them;
- per phase: its share of the walking time, the median log10 SHOE in it, and
  its contribution to F(L), L the recording's p50 (the contributions sum to 0.5
  for the recording); medians of |ω| (rad/s) and ||f| − g| (m/s²) in the swing
  third; the quiet share (:class:`pednav_env.calibration.stats.WalkStats`);
- the cycle profile: cycles from one stance start to the next (walking only,
  at most 3 s), their median length, and per tenth of the cycle (0 = stance
  start) the median log10 SHOE and the share of samples below L;
- the swing's vigour by walking speed (:func:`speed_scan`): every recording's p90
  and swing |ω| beside the all-data fit's simulated walks at 0.35–1.5 m/s;
- an exploration (:func:`explore`): the all-data fit with one value changed, at
  0.30–0.45 m/s.

Recordings: the three slowest PyShoe trials, beside the all-data fit of
``--fits`` (default ``benchmarks/results/calibrate_foot.json``, the shipped
model), then every recording a held-out fold of that file misses on p50 (its
p50 outside its band's p50 envelope in the fold's stored check), beside that
fold's model. Simulated walks: ``--walks`` walks (MicroStrain grade) with stride
speeds in 0.7–1.1× the recording's walking speed, walk i of the j-th recording
drawn from ``default_rng([seed + j, i])`` (development seeds), kept when their
measured walking speed is within ±10 % of the recording's.
"""

from __future__ import annotations

import argparse
import json
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from pednav_env.calibration.objective import GRADE
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.sources import load_walk, samples_from_simulation
from pednav_env.calibration.stats import (
    DETECTOR_STAND_LOG10,
    LABEL_MIN_RUN_S,
    STAND_MIN_S,
    WalkSamples,
    clean_labels,
    log10_shoe,
    long_runs,
    quiet_threshold,
    runs,
    truth_velocity_stance,
    walk_stats,
)
from pednav_env.gait.stance_motion import StanceRandomization

ROOT = Path(__file__).resolve().parents[1]
PHASES = ("stance", "heel_off", "swing", "heel_strike")
#: The three slowest PyShoe development trials (0.35–0.44 m/s).
SLOW = ("2017-11-22-11-28-39", "2017-11-22-11-27-30", "2017-11-22-11-28-03")
#: Speed range of the simulated walks around a recording's walking speed.
SPEED_SPAN = 0.10
#: A cycle (stance start to stance start) longer than this (s) is not a stride.
MAX_CYCLE_S = 3.0
#: Stride speeds of the simulated walks, relative to the recording's walking speed:
#: a simulated walk's measured speed (its foot's path) runs above the strides'
#: nominal speed when slow, so walks are drawn over this range and kept when
#: their measured speed is within SPEED_SPAN of the recording's.
NOMINAL_SPAN = (0.7, 1.1)
#: Walking speeds (m/s) of the swing-vigour scan (:func:`speed_scan`).
SCAN_SPEEDS = (0.35, 0.45, 0.6, 0.75, 0.9, 1.1, 1.3, 1.5)
#: The level L of :func:`explore` (between the slowest trials' p50s, 7.81–7.93).
EXPLORE_LEVEL = 7.88
#: Bins of the cycle profile (stance start = 0).
PROFILE_BINS = 10


@dataclass(frozen=True)
class Phases:
    """Per walking sample of one walk: log10 SHOE, |ω|, ||f| − g| and the phase index."""

    log_shoe: np.ndarray
    gyro: np.ndarray
    accel_dev: np.ndarray
    phase: np.ndarray  # index into PHASES
    cycle_phase: np.ndarray  # position in the cycle, stance start to stance start, [0, 1) or NaN
    cycle_s: np.ndarray  # durations of the cycles (s)


def phases_of(s: WalkSamples) -> tuple[Phases, str]:
    """The walking samples of ``s`` with their phase (module docstring) and the
    phase mask's source."""
    rate = s.rate_hz
    log_t = log10_shoe(s.omega_b, s.f_b, rate, s.g)
    n_clean = max(1, int(round(LABEL_MIN_RUN_S * rate)))
    if s.stance is not None:
        stand_src = np.asarray(s.stance, dtype=bool)
    elif s.truth_pos is not None and np.isfinite(s.truth_pos).all(axis=1).mean() > 0.9:
        stand_src = truth_velocity_stance(s.truth_pos, rate)
    else:
        stand_src = log_t < DETECTOR_STAND_LOG10
    stand = long_runs(clean_labels(stand_src, n_clean), max(1, int(round(STAND_MIN_S * rate))))
    walking = ~stand
    if s.footfall_index is not None and len(s.footfall_index) >= 2:
        walking[: s.footfall_index[0]] = False
        walking[s.footfall_index[-1] + 1 :] = False
    if s.truth_pos is not None and np.isfinite(s.truth_pos).all(axis=1).mean() > 0.9:
        source, stance = "truth velocity", truth_velocity_stance(s.truth_pos, rate)
    else:
        source, stance = "detector", log_t < quiet_threshold(log_t[walking])
    stance = clean_labels(stance | stand, n_clean)
    phase = np.zeros(stance.size, dtype=np.int64)
    cycle_phase = np.full(stance.size, np.nan)
    cycles = []
    starts, ends = runs(stance)
    for s0, e, nxt in zip(starts[:-1], ends[:-1], starts[1:], strict=True):
        a, b = e + (nxt - e) // 3, e + 2 * (nxt - e) // 3
        phase[e:a], phase[a:b], phase[b:nxt] = 1, 2, 3
        if walking[s0:nxt].all() and nxt - s0 <= MAX_CYCLE_S * rate:
            cycle_phase[s0:nxt] = np.arange(nxt - s0) / (nxt - s0)
            cycles.append((nxt - s0) / rate)
    gyro = np.linalg.norm(s.omega_b, axis=1)
    accel = np.abs(np.linalg.norm(s.f_b, axis=1) - s.g)
    w = walking & np.isfinite(log_t)
    return (
        Phases(log_t[w], gyro[w], accel[w], phase[w], cycle_phase[w], np.array(cycles)),
        source,
    )


def decompose(p: Phases, level: float) -> dict[str, float]:
    """Shares, medians and F(level) contributions by phase (module docstring)."""
    out: dict[str, float] = {}
    n = p.log_shoe.size
    for k, name in enumerate(PHASES):
        m = p.phase == k
        out[f"{name}_share"] = float(m.mean())
        out[f"{name}_median"] = float(np.median(p.log_shoe[m])) if m.any() else float("nan")
        out[f"{name}_below"] = float((m & (p.log_shoe < level)).sum() / n)
    swing = p.phase == 2
    out["swing_gyro"] = float(np.median(p.gyro[swing])) if swing.any() else float("nan")
    out["swing_accel_dev"] = float(np.median(p.accel_dev[swing])) if swing.any() else float("nan")
    out["below"] = float((p.log_shoe < level).mean())
    out["cycle_s"] = float(np.median(p.cycle_s)) if p.cycle_s.size else float("nan")
    k = np.floor(p.cycle_phase * PROFILE_BINS)
    for b in range(PROFILE_BINS):
        m = k == b
        out[f"profile{b}"] = float(np.median(p.log_shoe[m])) if m.any() else float("nan")
        out[f"profile_below{b}"] = float((p.log_shoe[m] < level).mean()) if m.any() else np.nan
    return out


def walk_row(s: WalkSamples, level: float | None) -> dict[str, float]:
    """One walk's figures at ``level`` (its own p50 if None)."""
    st = walk_stats(s)
    ph, _ = phases_of(s)
    lev = st.log_shoe_p50 if level is None else level
    return {
        "speed": st.speed_mps,
        "p10": st.log_shoe_p10,
        "p50": st.log_shoe_p50,
        "p90": st.log_shoe_p90,
        "quiet_share": st.quiet_fraction,
        **decompose(ph, lev),
    }


def held_out_p50_misses(
    results: dict, p50: dict[str, tuple[float, float]]
) -> list[tuple[str, str]]:
    """(recording, fold) for each held-out recording whose p50 lies outside its
    band's p50 envelope in that fold's check of ``results``
    (``benchmarks/results/calibrate_foot.json``, the text table's envelopes);
    ``p50`` maps a recording to (walking speed, p50)."""
    out = []
    for part, res in results["parts"].items():
        if "held_out" not in res:
            continue
        envelopes = {}
        for line in res["held_out"]["text"].splitlines():
            pairs = re.findall(r"(\d+\.\d+)-\s*(\d+\.\d+)", line)
            band = re.match(r"^>?(\d+(?:\.\d+)?)", line)
            if band and len(pairs) == 5:  # the band, then p10 real, p10 sim, p50 real, p50 sim
                envelopes[float(band.group(1))] = (float(pairs[4][0]), float(pairs[4][1]))
        for name in sorted(set(p50) - set(res["train"])):
            speed, value = p50[name]
            lows = [lo for lo in envelopes if lo <= speed]
            if lows:
                a, b = envelopes[max(lows)]
                if not a <= value <= b:
                    out.append((name, part))
    return sorted(out, key=lambda x: (x[1], x[0]))


def summarize(rows: list[dict[str, float]]) -> dict[str, float]:
    keys = rows[0].keys()
    return {k: float(np.nanmedian([r[k] for r in rows])) for k in keys}


def fmt(name: str, r: dict[str, float]) -> str:
    parts = [
        f"{name:<24} v {r['speed']:.2f}  p10 {r['p10']:.2f} "
        f"p50 {r['p50']:.2f} p90 {r['p90']:.2f}  quiet {r['quiet_share']:.2f}  "
        f"swing |w| {r['swing_gyro']:.2f} ||f|-g| {r['swing_accel_dev']:.2f}"
    ]
    parts.append(
        "    share  "
        + "  ".join(f"{p} {r[f'{p}_share']:.2f}" for p in PHASES)
        + "\n    median "
        + "  ".join(f"{p} {r[f'{p}_median']:.2f}" for p in PHASES)
        + f"\n    below L={r.get('level', r['p50']):.2f}: {r['below']:.3f} = "
        + " + ".join(f"{p} {r[f'{p}_below']:.3f}" for p in PHASES)
        + f"\n    cycle {r['cycle_s']:.2f} s; median log SHOE by tenth of the cycle: "
        + " ".join(f"{r[f'profile{b}']:.1f}" for b in range(PROFILE_BINS))
        + "\n    share below L by tenth: "
        + " ".join(f"{r[f'profile_below{b}']:.2f}" for b in range(PROFILE_BINS))
    )
    return "\n".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shared", default=str(ROOT.parent / "shared" / "data"))
    ap.add_argument("--fits", default=str(ROOT / "benchmarks" / "results" / "calibrate_foot.json"))
    ap.add_argument("--walks", type=int, default=60)
    ap.add_argument("--seed", type=int, default=21200)
    ap.add_argument("--scan-walks", type=int, default=24, help="simulated walks per scan speed")
    ap.add_argument("--explore-walks", type=int, default=40, help="walks per explored variant")
    ap.add_argument("--json", default=None)
    ap.add_argument(
        "--heel-rocker",
        action="store_true",
        help="every model of --fits with its walkers landing the heel at rest on its "
        "footfall (StanceRandomization.heel_rocker)",
    )
    ap.add_argument(
        "--pitch-knot-stride",
        type=float,
        default=None,
        metavar="M",
        help="every model of --fits with its swing pitch knots shrinking below this "
        "stride length (m; StanceRandomization.pitch_knot_stride_m)",
    )
    args = ap.parse_args()
    shared = Path(args.shared)
    paths = sorted((shared / "pyshoe-vicon-dev").glob("*.mat"))
    paths += sorted((shared / "hallway-gcp-dev").glob("*_LLIO.mat"))
    recs = {}
    for path in paths:
        rec = load_walk(path)
        recs[rec.name] = rec
    rows = {name: walk_row(rec, None) for name, rec in recs.items()}
    fits = json.loads(Path(args.fits).read_text())
    if args.heel_rocker:
        for part in fits["parts"].values():
            part["randomization"]["heel_rocker"] = True
    if args.pitch_knot_stride is not None:
        for part in fits["parts"].values():
            part["randomization"]["pitch_knot_stride_m"] = args.pitch_knot_stride
    misses = held_out_p50_misses(fits, {n: (r["speed"], r["p50"]) for n, r in rows.items()})
    cases = [(name, "all") for name in SLOW] + misses
    out = []
    for j, (name, part) in enumerate(cases):
        real = rows[name]
        real["level"] = real["p50"]
        model = SimModel(part, GRADE, StanceRandomization(**fits["parts"][part]["randomization"]))
        v = real["speed"]
        nominal = (max(0.1, v * NOMINAL_SPAN[0]), v * NOMINAL_SPAN[1])
        truth, imu = model.batch(nominal, args.walks, args.seed + j)
        sim_rows = [
            row
            for i in range(args.walks)
            if abs(
                (row := walk_row(samples_from_simulation(truth, imu, i), real["p50"]))["speed"] - v
            )
            <= SPEED_SPAN * v
        ]
        sim = summarize(sim_rows)
        sim["level"] = real["p50"]
        p50s = np.array([r["p50"] for r in sim_rows])
        label = "all-data fit" if part == "all" else f"held out of fold {part}"
        print(fmt(f"{name} ({label})", real))
        print(fmt(f"  sim, median of {len(sim_rows)} walks within 10 % of its speed", sim))
        print(
            f"    sim p50 5-95 %: {np.percentile(p50s, 5):.2f}-{np.percentile(p50s, 95):.2f}; "
            f"walks with p50 <= the recording's: {(p50s <= real['p50']).sum()}/{p50s.size}",
            flush=True,
        )
        out.append(
            {
                "name": name,
                "fit": part,
                "real": real,
                "sim_median": sim,
                "sim_p50": p50s.round(3).tolist(),
            }
        )
    scan = speed_scan(rows, fits, args.scan_walks, args.seed + len(cases))
    explored = explore(fits, args.explore_walks, args.seed + 100)
    if args.json:
        Path(args.json).write_text(
            json.dumps({"cases": out, "speed_scan": scan, "exploration": explored}, indent=1)
        )


def explore(fits: dict, walks: int, seed: int) -> dict:
    """One value of the all-data fit changed at a time, walks at 0.30–0.45 m/s (an
    exploration of the mechanism, not a fit; :data:`EXPLORE_LEVEL` the level L):
    the swing scale k × 0.6 and × 0.4, and a heel-off/heel-strike share of 0.10
    with the time given to the flat phase or to the swing."""
    base = StanceRandomization(**fits["parts"]["all"]["randomization"])
    variants = {
        "all-data fit": base,
        "k x 0.6": replace(base, swing_pitch_scale=base.swing_pitch_scale * 0.6),
        "k x 0.4": replace(base, swing_pitch_scale=base.swing_pitch_scale * 0.4),
        "heel 0.10, flat longer": replace(
            base,
            heel_fraction=0.10,
            flat_fraction=base.flat_fraction + 2 * (base.heel_fraction - 0.10),
        ),
        "heel 0.10, swing longer": replace(base, heel_fraction=0.10),
    }
    print(f"exploration at 0.30-0.45 m/s, {walks} walks, L = {EXPLORE_LEVEL}")
    out = {}
    for name, stance in variants.items():
        truth, imu = SimModel(name, GRADE, stance).batch((0.30, 0.45), walks, seed)
        rows = [
            walk_row(samples_from_simulation(truth, imu, i), EXPLORE_LEVEL) for i in range(walks)
        ]
        r = summarize(rows)
        p50 = np.array([x["p50"] for x in rows])
        lo, hi = np.percentile(p50, (5, 95))
        print(
            f"  {name:<24} p50 {r['p50']:.2f} (5-95 % {lo:.2f}-{hi:.2f})  p90 {r['p90']:.2f}  "
            f"swing |w| {r['swing_gyro']:.2f}  first tenth {r['profile0']:.2f}  "
            f"quiet {r['quiet_share']:.2f}"
        )
        out[name] = {**r, "p50_5": float(lo), "p50_95": float(hi)}
    return out


def speed_scan(rows: dict[str, dict[str, float]], fits: dict, walks: int, seed: int) -> dict:
    """Swing vigour by walking speed: each recording's p90 and swing |ω|, and the
    all-data fit's simulated walks at :data:`SCAN_SPEEDS` (``walks`` each, kept
    within ±10 % of the speed as above; walk i of speed k from
    ``default_rng([seed + k, i])``)."""
    print("swing vigour by walking speed: p90 of log10 SHOE, swing-third |w| median (rad/s)")
    for name, r in sorted(rows.items(), key=lambda kv: kv[1]["speed"]):
        print(
            f"  {name:<28} v {r['speed']:.2f}  p90 {r['p90']:.2f}  swing |w| {r['swing_gyro']:.2f}"
        )
    model = SimModel("all", GRADE, StanceRandomization(**fits["parts"]["all"]["randomization"]))
    sim = {}
    for k, v in enumerate(SCAN_SPEEDS):
        truth, imu = model.batch((v * NOMINAL_SPAN[0], v * NOMINAL_SPAN[1]), walks, seed + k)
        kept = [
            row
            for i in range(walks)
            if abs((row := walk_row(samples_from_simulation(truth, imu, i), None))["speed"] - v)
            <= SPEED_SPAN * v
        ]
        p90 = float(np.median([r["p90"] for r in kept]))
        gyro = float(np.median([r["swing_gyro"] for r in kept]))
        sim[f"{v:g}"] = {"walks": len(kept), "p90": round(p90, 3), "swing_gyro": round(gyro, 3)}
        print(
            f"  simulated at {v:.2f} m/s ({len(kept)} walks)  p90 {p90:.2f}  swing |w| {gyro:.2f}"
        )
    return {
        "recordings": {
            n: {k: r[k] for k in ("speed", "p90", "swing_gyro")} for n, r in rows.items()
        },
        "simulated": sim,
    }


if __name__ == "__main__":
    main()
