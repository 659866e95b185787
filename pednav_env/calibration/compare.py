"""The foot simulator beside recorded walks, per speed band (``pednav sim2real``).

For each speed band (:data:`SPEED_BANDS`): the recordings whose walking speed
falls in it (:mod:`pednav_env.calibration.stats`), ``walks_per_band``
simulated walks of that band's speeds (:func:`pednav_env.gait.speed_route.speed_route`,
one walker's stance dynamics and IMU errors per walk: domain
randomisation), and

- the simulator's **envelope**: the 5–95 % range over the simulated walks of
  their p10 and of their p50 of log10 SHOE;
- **coverage**: whether a recording's p10 and p50 both fall inside its band's
  envelopes;
- the **width check**: how much wider (decades) each envelope is than the
  real spread (max − min over the band's recordings);
- a **distance**: the 1-Wasserstein distance between the pooled log10 SHOE
  samples of the recordings and of the simulated walks.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.stats import binomtest, wasserstein_distance

from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.stats import WalkStats
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.gait.walker_checks import WALKER_FLAGS
from pednav_env.sensors.imu import IMU_GRADES

#: Speed bands (m/s), lower bound included.
SPEED_BANDS = ((0.3, 0.8), (0.8, 1.3), (1.3, 1.8), (1.8, 2.6), (2.6, math.inf))
#: Simulated walks per band by default: the 5–95 % envelope of 20 walks moved a
#: recording count by ±5 of 31 between seeds; of 60 by ±2 (docs/SIM_TO_REAL.md).
DEFAULT_WALKS_PER_BAND = 60
#: Envelope quantiles over simulated walks (%).
ENVELOPE_PERCENT = (5.0, 95.0)
#: Per-walk shape measures reported beside the envelopes (medians over walks):
#: quiet share of the walking time, median quiet run (s), p90 of log10 SHOE.
WALK_SHAPE = ("quiet_fraction", "quiet_s_median", "log_shoe_p90")


def band_label(band: tuple[float, float]) -> str:
    lo, hi = band
    return f">{lo:g}" if math.isinf(hi) else f"{lo:g}-{hi:g}"


def band_of(speed_mps: float) -> tuple[float, float] | None:
    """The band holding ``speed_mps`` (None below the first or for NaN)."""
    for lo, hi in SPEED_BANDS:
        if lo <= speed_mps < hi:
            return (lo, hi)
    return None


@dataclass(frozen=True)
class BandComparison:
    """One speed band: recordings, simulated envelope, coverage, distance."""

    band: tuple[float, float]
    real: list[WalkStats]
    sim: list[WalkStats]

    def _q(self, attr: str) -> tuple[float, float]:
        values = [getattr(s, attr) for s in self.sim]
        lo, hi = np.percentile(values, ENVELOPE_PERCENT)
        return float(lo), float(hi)

    @property
    def p10_envelope(self) -> tuple[float, float]:
        return self._q("log_shoe_p10")

    @property
    def p50_envelope(self) -> tuple[float, float]:
        return self._q("log_shoe_p50")

    def covered(self, stats: WalkStats) -> bool:
        (a, b), (c, d) = self.p10_envelope, self.p50_envelope
        return a <= stats.log_shoe_p10 <= b and c <= stats.log_shoe_p50 <= d

    def excess_width(self) -> float | None:
        """Largest envelope width minus real spread (decades), None without recordings."""
        if not self.real:
            return None
        out = -math.inf
        for attr, env in (("log_shoe_p10", self.p10_envelope), ("log_shoe_p50", self.p50_envelope)):
            values = [getattr(s, attr) for s in self.real]
            out = max(out, (env[1] - env[0]) - (max(values) - min(values)))
        return float(out)

    def distance(self) -> float | None:
        """W1 between pooled log10 SHOE of recordings and simulated walks (decades)."""
        if not self.real:
            return None
        real = np.concatenate([s.log_shoe for s in self.real])
        sim = np.concatenate([s.log_shoe for s in self.sim])
        return float(wasserstein_distance(real, sim))

    def to_json(self) -> dict[str, Any]:
        r3 = lambda x: None if x is None else round(float(x), 3)  # noqa: E731
        return {
            "band_mps": band_label(self.band),
            "recordings": [{**s.summary(), "covered": self.covered(s)} for s in self.real],
            "sim_walks": len(self.sim),
            "sim_p10_envelope": [r3(x) for x in self.p10_envelope],
            "sim_p50_envelope": [r3(x) for x in self.p50_envelope],
            "sim_stance_s_median": r3(_median_of(self.sim, "stance_s")),
            "real_stance_s_median": r3(_median_of(self.real, "stance_s")),
            **{
                f"{side}_{attr}_median": r3(_walk_median(walks, attr))
                for attr in WALK_SHAPE
                for side, walks in (("real", self.real), ("sim", self.sim))
            },
            "envelope_excess_decades": r3(self.excess_width()),
            "wasserstein_log_shoe": r3(self.distance()),
        }


def stride_values_by_bin(
    walks: Sequence[WalkStats], attr: str = "log_shoe_p5"
) -> dict[int, NDArray[np.float64]]:
    """The walks' per-stride values of the :class:`pednav_env.calibration.stats.StrideStats`
    field ``attr`` by index into :data:`SPEED_BANDS` of the stride's own speed
    (strides without a finite speed or value dropped; bins without a stride left out)."""
    speed = np.concatenate([w.strides.speed_mps for w in walks]) if walks else np.zeros(0)
    value = np.concatenate([getattr(w.strides, attr) for w in walks]) if walks else np.zeros(0)
    keep = np.isfinite(speed) & np.isfinite(value)
    out = {}
    for k, (lo, hi) in enumerate(SPEED_BANDS):
        m = keep & (speed >= lo) & (speed < hi)
        if m.any():
            out[k] = value[m]
    return out


def stride_quietness_by_bin(walks: Sequence[WalkStats]) -> dict[int, NDArray[np.float64]]:
    """The walks' per-stride quietness (5th percentile of log10 SHOE) by index
    into :data:`SPEED_BANDS` of the stride's own speed (strides without a
    speed or a quietness dropped)."""
    return stride_values_by_bin(walks, "log_shoe_p5")


def stride_swing_by_bin(walks: Sequence[WalkStats]) -> dict[int, NDArray[np.float64]]:
    """The walks' per-stride swing vigour, log10 of the median |ω| (rad/s) over the
    stride's swing samples (``StrideStats.swing_gyro_median``), by index into
    :data:`SPEED_BANDS` of the stride's own speed (strides without a speed, without
    swing samples or with a zero median dropped)."""
    out = {}
    for k, v in stride_values_by_bin(walks, "swing_gyro_median").items():
        v = v[v > 0]
        if v.size:
            out[k] = np.log10(v)
    return out


def _cell(value: float | None) -> str:
    return "  -  " if value is None else f"{value:5.2f}"


def _walk_median(stats: Sequence[WalkStats], attr: str) -> float | None:
    values = np.array([getattr(s, attr) for s in stats], dtype=float)
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else None


def _median_of(stats: Sequence[WalkStats], stride_attr: str) -> float | None:
    values = np.concatenate([getattr(s.strides, stride_attr) for s in stats]) if stats else []
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else None


def coverage_interval(covered: int, total: int, confidence: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper–Pearson) interval of the share of recordings covered,
    ``covered`` of ``total``: where the share for recordings of the same kind,
    not only these, lies (scipy's ``binomtest(...).proportion_ci``)."""
    if not 0 <= covered <= total or total < 1:
        raise ValueError(
            f"coverage_interval: need 0 ≤ covered ≤ total, total ≥ 1; got {covered}/{total}"
        )
    ci = binomtest(int(covered), int(total)).proportion_ci(confidence, method="exact")
    return float(ci.low), float(ci.high)


@dataclass(frozen=True)
class Sim2RealReport:
    """The comparison over all bands, and the recordings left out (no speed)."""

    model: str
    bands: list[BandComparison]
    unbanded: list[WalkStats] = field(default_factory=list)

    @property
    def coverage(self) -> tuple[int, int]:
        """(covered, total) recordings with a band."""
        pairs = [(b.covered(s), 1) for b in self.bands for s in b.real]
        return sum(c for c, _ in pairs), len(pairs)

    def to_json(self) -> dict[str, Any]:
        covered, total = self.coverage
        excess = [b.excess_width() for b in self.bands if b.real]
        return {
            "model": self.model,
            "covered": covered,
            "recordings": total,
            "coverage_fraction": round(covered / total, 4) if total else None,
            "coverage_ci95": (
                [round(v, 4) for v in coverage_interval(covered, total)] if total else None
            ),
            "max_envelope_excess_decades": round(max(excess), 3) if excess else None,
            "bands": [b.to_json() for b in self.bands],
            "unbanded": [s.summary() for s in self.unbanded],
            "strides": self.stride_rows(),
        }

    def stride_rows(self) -> list[dict[str, Any]]:
        """Per stride-speed bin holding recorded strides: counts, median and
        10–90 % of the strides' quietness, recordings and simulator, and the W1
        between them (decades)."""
        real = stride_quietness_by_bin([s for b in self.bands for s in b.real])
        sim = stride_quietness_by_bin([s for b in self.bands for s in b.sim])
        rows = []
        for k, r in real.items():
            m = sim.get(k, np.zeros(0))
            q = lambda a, p: round(float(np.percentile(a, p)), 3) if a.size else None  # noqa: E731
            rows.append(
                {
                    "band_mps": band_label(SPEED_BANDS[k]),
                    "real_strides": int(r.size),
                    "real_median": q(r, 50),
                    "real_p10_p90": [q(r, 10), q(r, 90)],
                    "sim_strides": int(m.size),
                    "sim_median": q(m, 50),
                    "sim_p10_p90": [q(m, 10), q(m, 90)],
                    "w1": round(float(wasserstein_distance(r, m)), 3) if m.size else None,
                }
            )
        return rows

    def format_text(self) -> str:
        lines = [f"simulator model: {self.model}"]
        lines.append(
            "band (m/s)  rec  p10 real          p10 sim 5-95%    "
            "p50 real          p50 sim 5-95%    covered  excess  W1"
        )
        for b in self.bands:
            real10 = [s.log_shoe_p10 for s in b.real]
            real50 = [s.log_shoe_p50 for s in b.real]
            span = lambda v: f"{min(v):5.2f}-{max(v):5.2f}" if v else "    -      "  # noqa: E731
            e10, e50 = b.p10_envelope, b.p50_envelope
            cov = sum(b.covered(s) for s in b.real)
            ex, w = b.excess_width(), b.distance()
            lines.append(
                f"{band_label(b.band):10s}  {len(b.real):3d}  {span(real10):16s}  "
                f"{e10[0]:5.2f}-{e10[1]:5.2f}      {span(real50):16s}  {e50[0]:5.2f}-{e50[1]:5.2f}"
                f"      {cov:2d}/{len(b.real):<2d}   "
                f"{'  -  ' if ex is None else f'{ex:+5.2f}'}  {'  -' if w is None else f'{w:.2f}'}"
            )
        covered, total = self.coverage
        if total:
            lo, hi = coverage_interval(covered, total)
            lines.append(
                f"covered: {covered}/{total} recordings ({100 * covered / total:.0f} %; "
                f"exact 95 % interval {100 * lo:.0f}-{100 * hi:.0f} %)"
            )
        lines.append("medians over walks, real / sim: quiet share, quiet run (s), p90")
        for b in self.bands:
            if b.real:
                cells = [
                    " / ".join(_cell(_walk_median(side, a)) for side in (b.real, b.sim))
                    for a in WALK_SHAPE
                ]
                lines.append(f"{band_label(b.band):10s}  " + "   ".join(cells))
        rows = self.stride_rows()
        if rows:
            lines.append(
                "per stride, by stride speed: quietness (p5 of log10 SHOE), real / sim: "
                "strides, median, 10-90 %, W1"
            )
            for r in rows:
                span = lambda a: "    -      " if a[0] is None else f"{a[0]:5.2f}-{a[1]:5.2f}"  # noqa: E731
                med = lambda v: "  -  " if v is None else f"{v:5.2f}"  # noqa: E731
                lines.append(
                    f"{r['band_mps']:10s}  {r['real_strides']:4d} / {r['sim_strides']:<5d} "
                    f"{med(r['real_median'])} / {med(r['sim_median'])}   "
                    f"{span(r['real_p10_p90'])} / {span(r['sim_p10_p90'])}   "
                    f"{'  -' if r['w1'] is None else format(r['w1'], '.2f')}"
                )
        for s in self.unbanded:
            lines.append(f"{s.name}: no walking speed in a band (speed source {s.speed_source})")
        return "\n".join(lines)


def band_turns(
    recordings: Sequence[WalkStats], walks: int
) -> list[tuple[float, float] | None] | None:
    """The turn per stride of each of ``walks`` simulated walks compared with
    ``recordings`` (one band): None (the scenario's legs) unless a recording carries
    its :attr:`~pednav_env.calibration.stats.WalkStats.turn_per_stride_rad`; then walk i
    walks the circles of recording ⌊i·n/walks⌋ (n recordings, in the order given;
    None for a recording without one)."""
    if not any(r.turn_per_stride_rad is not None for r in recordings):
        return None
    n = len(recordings)
    return [recordings[i * n // walks].turn_per_stride_rad for i in range(walks)]


def compare(
    real: Sequence[WalkStats],
    model: SimModel,
    walks_per_band: int = DEFAULT_WALKS_PER_BAND,
    seed: int = 0,
) -> Sim2RealReport:
    """Recordings beside ``walks_per_band`` simulated walks per band (module docstring).

    Every band is simulated, with recordings or not; band k's walks use seed
    ``[seed, k]`` streams, so bands and models are comparable run to run. Recordings
    that carry their turn per stride get simulated walks on the same circles
    (:func:`band_turns`); :func:`~pednav_env.calibration.stats.walk_stats` leaves it
    unset, so by default every walk keeps the scenario's legs.
    """
    if walks_per_band < 2:
        raise ValueError(f"walks_per_band must be ≥ 2, got {walks_per_band}")
    by_band: dict[tuple[float, float], list[WalkStats]] = {b: [] for b in SPEED_BANDS}
    unbanded = []
    for s in real:
        band = band_of(s.speed_mps)
        (unbanded if band is None else by_band[band]).append(s)
    bands = [
        BandComparison(
            b,
            by_band[b],
            model.simulate(
                b,
                walks_per_band,
                seed * 100 + k,
                turns_per_walk=band_turns(by_band[b], walks_per_band),
            ),
        )
        for k, b in enumerate(SPEED_BANDS)
    ]
    return Sim2RealReport(model.name, bands, unbanded)


#: Named simulator models: today's (ADIS16470-like grade, realistic stance terms)
#: and the one calibrated to the development recordings.
MODELS = {
    "today": SimModel("today", "adis16470"),
    "calibrated": SimModel("calibrated", "microstrain_gx5", StanceRandomization.calibrated()),
}
#: Keys a fitted-parameter file may hold beside the StanceRandomization fields.
_MODEL_FILE_KEYS = ("imu_grade",)
#: StanceRandomization fields a fitted-parameter file gives as true or false.
_MODEL_FILE_FLAGS = WALKER_FLAGS


def model_from_json(path: str | Path) -> SimModel:
    """A simulator model from a fitted-parameter JSON file (``pednav sim2real
    --model PATH``): an object of :class:`StanceRandomization` fields (numbers;
    ``flat_fraction`` and ``cadence_intercept_hz`` may be null; ``heel_rocker``,
    ``monotone_pitch`` and ``mid_pitch_midpoint`` true or false), optionally
    ``imu_grade`` (default the recordings' ``microstrain_gx5``), or a
    ``benchmarks/calibrate_foot.py`` output,
    whose top-level ``randomization`` is that object. Fields left out take
    StanceRandomization's defaults. The model is named after the file's stem.

    Raises
    ------
    ValueError
        A missing or unreadable file, invalid JSON, an unknown key, a value that is
        not a number, or a value StanceRandomization rejects; the message names
        the file and the key.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as e:
        raise ValueError(f"{path}: cannot read the model file ({e.strerror})") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not a JSON file ({e})") from None
    if isinstance(data, dict) and isinstance(data.get("randomization"), dict):
        data = {**data["randomization"], **{k: data[k] for k in _MODEL_FILE_KEYS if k in data}}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object of model parameters")
    known = {f.name for f in fields(StanceRandomization)}
    values: dict[str, float | bool | None] = {}
    for key, value in data.items():
        if key in _MODEL_FILE_KEYS:
            continue
        if key not in known:
            raise ValueError(f"{path}: unknown key {key!r}; known: {', '.join(sorted(known))}")
        if value is None and key in ("flat_fraction", "cadence_intercept_hz"):
            values[key] = None
        elif key in _MODEL_FILE_FLAGS:
            if not isinstance(value, bool):
                raise ValueError(f"{path}: key {key!r} must be true or false, got {value!r}")
            values[key] = value
        elif isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{path}: key {key!r} must be a number, got {value!r}")
        else:
            values[key] = float(value)
    grade = data.get("imu_grade", "microstrain_gx5")
    if grade not in IMU_GRADES:
        raise ValueError(
            f"{path}: key 'imu_grade' {grade!r} unknown; known: {', '.join(sorted(IMU_GRADES))}"
        )
    try:
        stance = StanceRandomization(**values)
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None
    return SimModel(path.stem, grade, stance)
