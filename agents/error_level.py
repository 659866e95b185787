"""The simulator's navigation error beside the recordings' (``pednav sim2real --nav``;
docs/SIM_TO_REAL.md, "The error level and where it comes from").

The statistics of ``pednav sim2real`` compare signals; this compares what the signals
do to a filter. For every recording with a truth track (PyShoe's VICON trials, a
generic CSV with positions) or footprints (the hallway walks):

- the recording's error: ``real-fixed``'s (or another setup's) PyShoe ARMSE with
  ``pednav run``'s runner (:func:`agents.choose_shoe.lane_errors`), or with footprints
  only its mean footprint error;
- its simulated twins: ``walks`` walks of the simulator model. By default
  (``twins="footfalls"``) each twin walks the recording's own strides in order
  (:func:`pednav_env.calibration.path_turns.stride_sequence`: per stride the speed
  between its footfalls, its heading change and the stand before it, from the
  footprints or the truth at each stance; :func:`pednav_env.gait.speed_route.
  footfall_route`), its walker, stride shapes and IMU errors drawn; a recording with
  fewer than :data:`MIN_TWIN_STRIDES` strides gets the next form. ``"circles"``: every
  stride's speed within ±:data:`SPEED_SPREAD` of the recording's walking speed
  (:func:`pednav_env.calibration.stats.walk_stats`), the recording's length, every leg
  on a circle whose turn per stride is drawn between the 25th and 75th percentile of
  the recording's |turn per stride| (at most π/2;
  :func:`pednav_env.calibration.path_turns.route_turn_range`), stops as the calibrated
  scenario draws them. ``"straight"``: the same with the scenario's straight legs and
  turns. A recording's twin i draws from ``numpy.random.default_rng([seed, key, i])``,
  ``key`` the recording's :func:`twin_key` (its footfall points to the millimetre), so
  that its twins are the same whichever recordings are passed with it and in whatever
  order, and the same for a walk read from its ``.mat`` or from its vendor CSV; the
  same filter and measure against the simulated truth (for a footprint walk,
  footprints at the last sample of each simulated stance, the truth dropped, so that
  the twins are scored by the footprint error too);
- *covered*: the recording's ARMSE inside the twins' 5–95 % range (order statistics; a
  diverged walk counts as an infinite error); its percentile among them; and the ratio
  of the twins' median to the recording's ARMSE.

Summary: recordings covered (exact 95 % interval), the geometric mean of the ratios
(how many times harder, > 1, or easier the simulated walks are to navigate), and the
mean percentile (50 if the twins were the recordings' own distribution; a uniform
percentile's mean over n recordings has a standard deviation of 28.9/√n).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from agents.choose_shoe import lane_errors
from pednav_env.calibration.compare import ENVELOPE_PERCENT, coverage_interval
from pednav_env.calibration.path_turns import (
    StrideSequence,
    footfall_points,
    route_turn_range,
    stride_sequence,
)
from pednav_env.calibration.sim_model import SimModel, walk_entropy
from pednav_env.calibration.sources import recording_from_simulation, samples_from_recording
from pednav_env.calibration.stats import WalkSamples, walk_stats
from pednav_env.files import save_figure
from pednav_env.gait.foot import FootTrajectory
from pednav_env.io import Footprints, Recording
from pednav_env.replay.setup import RealFilterSetup, real_fixed_setup
from pednav_env.sensors.imu import ImuMeasurements

Array = NDArray[np.float64]

#: Twins' stride speeds: the recording's walking speed × (1 ± SPEED_SPREAD).
SPEED_SPREAD = 0.1
#: Twins' speed limits (m/s): the walk generator's.
SPEED_LIMITS_MPS = (0.1, 3.8)
#: Shortest twin (s): a 2 s stand, strides and a 1 s stand.
MIN_DURATION_S = 10.0
#: Simulated twins per recording unless told otherwise.
DEFAULT_WALKS = 20
#: How twins walk (module docstring): the recording's own strides (the default; circles
#: when the recording has fewer than :data:`MIN_TWIN_STRIDES` strides), circles of its
#: turn per stride at its speed, or the scenario's straight legs at its speed.
TWIN_FORMS = ("footfalls", "circles", "straight")
#: Fewest recorded strides the twins walk as they are.
MIN_TWIN_STRIDES = 3
#: A recording's :func:`twin_key` takes its footfall points rounded to this (m).
TWIN_KEY_RESOLUTION_M = 1e-3


@dataclass(frozen=True)
class RecordingLevel:
    """One recording's error beside its twins' (m; inf where the filter diverged)."""

    name: str
    speed_mps: float
    duration_s: float
    error_m: float
    twins_m: Array
    measure: str = "PyShoe ARMSE"
    #: The twins' turn per stride range (rad), None for the scenario's straight legs.
    turn_rad: tuple[float, float] | None = None
    #: How the twins walk (:data:`TWIN_FORMS`): the recording's own strides, circles of
    #: its turn per stride, or the scenario's straight legs.
    form: str = "straight"
    #: The recording's :func:`twin_key` (its twins' seed is ``[seed, key]``).
    key: int | None = None

    @property
    def envelope_m(self) -> tuple[float, float]:
        lo, hi = (p / 100.0 for p in ENVELOPE_PERCENT)
        return (
            float(np.quantile(self.twins_m, lo, method="inverted_cdf")),
            float(np.quantile(self.twins_m, hi, method="inverted_cdf")),
        )

    @property
    def median_m(self) -> float:
        return float(np.quantile(self.twins_m, 0.5, method="inverted_cdf"))

    @property
    def covered(self) -> bool:
        lo, hi = self.envelope_m
        return lo <= self.error_m <= hi

    @property
    def percentile(self) -> float:
        """Share of twins (%) with a smaller error than the recording (ties half)."""
        below = np.sum(self.twins_m < self.error_m) + 0.5 * np.sum(self.twins_m == self.error_m)
        return float(100.0 * below / self.twins_m.size)

    @property
    def ratio(self) -> float:
        """Twins' median over the recording's error."""
        return self.median_m / self.error_m

    def to_json(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        lo, hi = self.envelope_m
        return {
            "name": self.name,
            "measure": self.measure,
            "speed_mps": self.speed_mps,
            "duration_s": self.duration_s,
            "error_m": num(self.error_m),
            "twins": int(self.twins_m.size),
            "twins_walk": self.form,
            "twin_key": self.key,
            "twin_turn_per_stride_rad": None if self.turn_rad is None else list(self.turn_rad),
            "twins_diverged": int(np.sum(~np.isfinite(self.twins_m))),
            "twin_median_m": num(self.median_m),
            "twin_envelope_m": [num(lo), num(hi)],
            "percentile": self.percentile,
            "covered": self.covered,
            "ratio": num(self.ratio),
        }


@dataclass(frozen=True)
class ErrorLevelReport:
    model: str
    walks: int
    seed: int
    rows: list[RecordingLevel]
    not_checked: list[str]
    setup: str = "real-fixed"

    @property
    def twins_text(self) -> str:
        """How the twins walked, in words."""
        forms = {r.form for r in self.rows}
        parts = []
        if "footfalls" in forms:
            parts.append("walking each recording's own strides")
        if "circles" in forms:
            parts.append(f"same speed ±{SPEED_SPREAD:.0%}, length and turn per stride")
        if "straight" in forms or not forms:
            parts.append(f"same speed ±{SPEED_SPREAD:.0%} and length, straight legs")
        return "; ".join(parts)

    @property
    def coverage(self) -> tuple[int, int]:
        return sum(r.covered for r in self.rows), len(self.rows)

    @property
    def mean_percentile(self) -> float | None:
        """Mean of the recordings' percentiles among their twins: 50 for a simulator
        whose twins are the recordings' own distribution (± 29/√n)."""
        return float(np.mean([r.percentile for r in self.rows])) if self.rows else None

    @property
    def ratio_geomean(self) -> float | None:
        ratios = [r.ratio for r in self.rows if math.isfinite(r.ratio) and r.ratio > 0]
        return float(np.exp(np.mean(np.log(ratios)))) if ratios else None

    def to_json(self) -> dict[str, Any]:
        k, n = self.coverage
        lo, hi = coverage_interval(k, n) if n else (None, None)
        return {
            "model": self.model,
            "setup": self.setup,
            "walks": self.walks,
            "seed": self.seed,
            "covered": k,
            "recordings": n,
            "covered_interval": [lo, hi],
            "ratio_geomean": self.ratio_geomean,
            "mean_percentile": self.mean_percentile,
            "not_checked": self.not_checked,
            "rows": [r.to_json() for r in self.rows],
        }

    def format_text(self) -> str:
        lines = [
            f"error level: {self.setup}'s PyShoe ARMSE (footprint error for footprint walks), "
            f"each recording against {self.walks} "
            f"simulated twins ({self.model}; {self.twins_text})",
            f"{'recording':28s} {'m/s':>5s} {'s':>5s} {'error m':>8s} "
            f"{'twins: median [5–95 %] m':>28s} {'pct':>5s}  covered",
        ]

        def cell(v: float) -> str:
            return f"{v:.3f}" if math.isfinite(v) else "div."

        for r in self.rows:
            lo, hi = r.envelope_m
            twins = f"{cell(r.median_m)} [{cell(lo)}, {cell(hi)}]"
            lines.append(
                f"{r.name[:28]:28s} {r.speed_mps:5.2f} {r.duration_s:5.1f} "
                f"{cell(r.error_m):>8s} {twins:>28s} {r.percentile:5.1f}  "
                f"{'yes' if r.covered else 'no'}"
            )
        k, n = self.coverage
        if n:
            lo, hi = coverage_interval(k, n)
            geo = self.ratio_geomean
            lines.append(
                f"covered {k}/{n} (exact 95 %: {100 * lo:.0f}–{100 * hi:.0f} %); twins' median "
                f"/ recording: geometric mean {'n/a' if geo is None else f'{geo:.2f}'}; "
                f"mean percentile {self.mean_percentile:.1f} (50 ± {28.9 / math.sqrt(n):.1f} "
                "if the twins were the recordings' distribution)"
            )
        if self.not_checked:
            lines.append(
                f"not checked (no truth, no footprints or no speed): {', '.join(self.not_checked)}"
            )
        return "\n".join(lines)


def twin_speed(speed_mps: float) -> tuple[float, float]:
    """The twins' stride speed range for a recording walked at ``speed_mps``."""
    lo = min(max(speed_mps * (1 - SPEED_SPREAD), SPEED_LIMITS_MPS[0]), SPEED_LIMITS_MPS[1])
    hi = min(max(speed_mps * (1 + SPEED_SPREAD), SPEED_LIMITS_MPS[0]), SPEED_LIMITS_MPS[1])
    return lo, hi


def twin_key(samples: WalkSamples) -> int:
    """A recording's identity for its twins' seeds (module docstring): the first 8 bytes
    (little-endian, an integer below 2⁶⁴) of the SHA-256 of its footfall points
    (:func:`pednav_env.calibration.path_turns.footfall_points`: its footprints, or the
    mean truth position of each stance) in units of :data:`TWIN_KEY_RESOLUTION_M`,
    rounded, as little-endian 64-bit integers x₁ y₁ x₂ y₂ …. The key depends on the walk,
    not on its file: a hallway walk's ``.mat`` and its SensorConnect CSV carry the same
    footprints and get the same key. A walk with no footfall points (no footprints, and
    truth stances from the detector only) is known by its name instead: the SHA-256 of
    ``"name:"`` and the name in UTF-8, so that a copy under another name draws other
    twins."""
    points = footfall_points(samples)
    if points.size:
        units = np.rint(points / TWIN_KEY_RESOLUTION_M).astype("<i8")
        payload = units.tobytes()
    else:
        payload = b"name:" + samples.name.encode("utf-8")
    return int.from_bytes(hashlib.sha256(payload).digest()[:8], "little")


def twin_seed(seed: int, samples: WalkSamples) -> tuple[int, int]:
    """The seed of a recording's twins: ``(seed, twin_key(samples))``; twin i draws
    from ``numpy.random.default_rng([seed, key, i])``. ``seed`` ≥ 0 (the user's
    ``--seed``)."""
    if seed < 0:
        raise ValueError(f"seed must be ≥ 0, got {seed}")
    return (int(seed), twin_key(samples))


def twin_recordings(
    model: SimModel,
    walks: int,
    seed: int | Sequence[int],
    speed_mps: tuple[float, float],
    duration_s: float,
    footprints: bool,
    turn_per_stride_rad: tuple[float, float] | None = None,
) -> list[Recording]:
    """``walks`` simulated twins (walk i from ``default_rng([seed, i])``, or
    ``[*seed, i]`` for a sequence such as :func:`twin_seed`'s) as recordings:
    with their truth track, or with ``footprints`` footprints only (module docstring);
    with ``turn_per_stride_rad`` every leg on a circle."""
    truth, imu = model.batch(speed_mps, walks, seed, (duration_s, duration_s), turn_per_stride_rad)
    return _as_recordings(model, truth, imu, walks, seed, footprints)


def footfall_twin_recordings(
    model: SimModel,
    walks: int,
    seed: int | Sequence[int],
    strides: StrideSequence,
    footprints: bool,
) -> list[Recording]:
    """``walks`` simulated twins that walk the recording's own strides
    (:meth:`SimModel.footfall_batch`, walk i from ``default_rng([seed, i])``, or
    ``[*seed, i]`` for a sequence such as :func:`twin_seed`'s), as
    :func:`twin_recordings` returns them."""
    truth, imu = model.footfall_batch(*strides, walks, seed)
    return _as_recordings(model, truth, imu, walks, seed, footprints)


def _as_recordings(
    model: SimModel,
    truth: FootTrajectory,
    imu: ImuMeasurements,
    walks: int,
    seed: int | Sequence[int],
    footprints: bool,
) -> list[Recording]:
    out = []
    for i in range(walks):
        entropy = "-".join(str(e) for e in walk_entropy(seed, i))
        rec = recording_from_simulation(truth, imu, i, f"{model.name}-{entropy}")
        if footprints:
            stance = truth.stance[i, : rec.num_samples]
            last = np.flatnonzero(stance[:-1] & ~stance[1:])  # the last sample of a stance
            marks = Footprints(last.astype(np.int64), rec.truth_pos[last, :2], rec.name)
            rec = replace(rec, truth_pos=None, footprints=marks)
        out.append(rec)
    return out


def error_level(
    recordings: Sequence[Recording],
    model: SimModel,
    walks: int = DEFAULT_WALKS,
    seed: int = 0,
    setup: RealFilterSetup | None = None,
    setup_name: str = "real-fixed",
    twins: str = "footfalls",
) -> ErrorLevelReport:
    """The report of the module docstring for ``recordings`` and ``model``; ``setup``
    (named ``setup_name``) instead of ``real-fixed``'s if given; ``twins`` one of
    :data:`TWIN_FORMS` (module docstring). A recording's twins depend on ``seed``, the
    recording (:func:`twin_seed`) and the other arguments, not on the other recordings
    or their order."""
    if seed < 0:
        raise ValueError(f"seed must be ≥ 0, got {seed}")
    if walks < 2:
        raise ValueError(f"walks must be ≥ 2 (a spread of twins), got {walks}")
    if twins not in TWIN_FORMS:
        raise ValueError(f"twins must be one of {', '.join(TWIN_FORMS)}, got {twins!r}")
    setup = setup or real_fixed_setup()
    rows, not_checked = [], []
    for rec in recordings:
        dense = rec.has_truth
        if not dense and rec.footprints is None:
            not_checked.append(rec.name)
            continue
        samples = samples_from_recording(rec)
        speed = walk_stats(samples, per_stride=False).speed_mps
        if not math.isfinite(speed):
            not_checked.append(rec.name)
            continue
        duration = max(rec.duration_s, MIN_DURATION_S)
        strides = stride_sequence(samples) if twins == "footfalls" else None
        turn = route_turn_range(samples) if twins != "straight" else None
        entropy = twin_seed(seed, samples)
        if strides is not None and strides.speed_mps.size >= MIN_TWIN_STRIDES:
            form = "footfalls"
            made = footfall_twin_recordings(model, walks, entropy, strides, footprints=not dense)
        else:
            form = "straight" if turn is None else "circles"
            made = twin_recordings(
                model,
                walks,
                entropy,
                twin_speed(speed),
                duration,
                footprints=not dense,
                turn_per_stride_rad=turn,
            )
        errors = np.array([lane_errors(t, setup, {})[0] for t in made])
        own = float(lane_errors(rec, setup, {})[0])
        measure = "PyShoe ARMSE" if dense else "footprint error"
        rows.append(
            RecordingLevel(
                rec.name, speed, rec.duration_s, own, errors, measure, turn, form, entropy[1]
            )
        )
    return ErrorLevelReport(model.name, walks, seed, rows, not_checked, setup_name)


def write_figure(report: ErrorLevelReport, directory: str | Path) -> Path | None:
    """``error_level_<model>.png`` in ``directory``: per recording (sorted by speed, one
    panel per measure), its twins' errors as dots, their 5–95 % range as a bar and the
    recording's own error as a red diamond (hollow when outside the range), on a log
    axis; diverged twins at the right edge. None when no recording was checked."""
    if not report.rows:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    measures = sorted({r.measure for r in report.rows})
    heights = [sum(r.measure == m for r in report.rows) for m in measures]
    fig, axes = plt.subplots(
        len(measures),
        1,
        figsize=(8.0, 1.2 + 0.28 * sum(heights)),
        gridspec_kw={"height_ratios": heights},
        squeeze=False,
    )
    finite = np.concatenate(
        [r.twins_m[np.isfinite(r.twins_m)] for r in report.rows]
        + [np.array([r.error_m]) for r in report.rows if math.isfinite(r.error_m)]
    )
    lo_x, hi_x = float(finite.min()) / 2, float(finite.max()) * 4
    for ax, measure in zip(axes[:, 0], measures, strict=True):
        rows = sorted((r for r in report.rows if r.measure == measure), key=lambda r: r.speed_mps)
        for y, r in enumerate(rows):
            twins = np.where(np.isfinite(r.twins_m), r.twins_m, hi_x / 1.5)
            ax.scatter(twins, np.full(twins.size, y), s=8, color="0.55", zorder=2)
            lo, hi = (min(v, hi_x / 1.5) for v in r.envelope_m)
            ax.plot([lo, hi], [y, y], color="0.3", linewidth=2.5, alpha=0.5, zorder=1)
            own = min(r.error_m, hi_x / 1.5)
            face = "C3" if r.covered else "none"
            ax.scatter([own], [y], s=60, marker="D", facecolor=face, edgecolor="C3", zorder=3)
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels([f"{r.name[:28]} ({r.speed_mps:.2f} m/s)" for r in rows], fontsize=7)
        ax.set_xscale("log")
        ax.set_xlim(lo_x, hi_x)
        ax.set_xlabel(f"{measure} (m); right edge: diverged")
        ax.grid(axis="x", alpha=0.3)
    k, n = report.coverage
    axes[0, 0].set_title(
        f"{report.setup} on each recording (red) and {report.walks} twins ({report.model}): "
        f"{k}/{n} inside their 5–95 %",
        fontsize=9,
    )
    fig.tight_layout()
    path = Path(directory) / f"error_level_{report.model}.png"
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path
