"""``pednav run``: the ZUPT-UKF on one recording, with a named policy.

Policies:

- ``paper`` and ``real-fixed``: fixed setups (:mod:`pednav_env.replay.setup`)
  run directly by the filter;
- any other name that ``pednav evaluate`` understands (``tuned``,
  ``adaptive``, ``pretrained``, a run directory or a saved SB3 model): the
  policy drives the knobs online through the replay environment's core
  (``pednav/FootZuptReplay-v0``'s observation and action, so a tuner trained
  in simulation runs unchanged); the knob values it chose in each decision
  interval are then replayed through the same filter to record the track
  sample by sample.

JSON keys (docs/REAL_DATA.md): ``duration_s``, ``rate_hz``,
``navigation_start_s``, ``distance_m``, ``final_position_m``, ``stances``;
with truth ``armse_m``, ``armse_pyshoe_m``, ``final_error_m``; with
footprints ``footprints``, ``footprint_mean_error_m``,
``footprint_final_error_m``, ``footprint_final_error_pct``; with neither
``loop_closure_m``.
"""

from __future__ import annotations

import inspect
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.io import CsvLayout, LoadOptions, Recording, load_recording
from pednav_env.io.hallway import AUTO, FootprintChoice
from pednav_env.replay.metrics import (
    aligned_reference,
    footprint_errors,
    loop_closure,
    rotate_h,
    track_errors,
)
from pednav_env.replay.runner import RecordingRun, prepare, run_prepared
from pednav_env.replay.setup import SETUP_NAMES, RealFilterSetup, named_setup

#: Footprint keys of the JSON summary (:func:`pednav_env.replay.metrics.footprint_errors`).
FOOTPRINT_KEYS = (
    "footprints",
    "footprint_mean_error_m",
    "footprint_final_error_m",
    "footprint_final_error_pct",
)
#: The default policy of ``pednav run``: the configuration chosen on real walks.
DEFAULT_POLICY = "real-fixed"

#: The simulated env whose policies (tuned, adaptive, pretrained) are used.
SIM_ENV_ID = "pednav/FootZupt-v0"


def _load_policy(name: str, action_space: Any) -> Any:
    from agents.evaluate import load_policy

    if len(inspect.signature(load_policy).parameters) >= 3:
        return load_policy(name, action_space, SIM_ENV_ID)
    return load_policy(name, action_space)


def run_with_policy(
    rec: Recording, policy_name: str, interval_s: float = 0.5
) -> tuple[RecordingRun, dict[str, np.ndarray]]:
    """Drive the replay core with a policy; return the replayed run and the knob schedule."""
    from pednav_env.envs.foot_replay_core import FootReplayConfig, FootReplayCore
    from pednav_env.envs.native import lane_spaces

    config = FootReplayConfig(decision_interval_s=interval_s)
    core = FootReplayCore(config, 1, "pednav run", recordings=[rec])
    action_space, _ = lane_spaces(core, core.config.action_dim)
    policy = _load_policy(policy_name, action_space)
    core.reset_lanes(np.array([0]), [np.random.default_rng(0)])
    obs = core.obs.copy()
    rows: dict[str, list[np.ndarray]] = {}
    state, start = None, np.array([True])
    while core.cursor[0] < core.length[0]:
        action, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        start = np.array([False])
        obs, _, terminated, _, _ = core.step(np.asarray(action, dtype=np.float64).reshape(1, -1))
        for k, v in core.knob_values().items():
            rows.setdefault(k, []).append(v.copy())
        if terminated[0] and core.engine.diverged[0]:
            break
    schedule = {k: np.array(v) for k, v in rows.items()}
    prep = core._trial(0).prepared
    return run_prepared(prep, schedule=schedule, interval_s=interval_s), schedule


def summarize(rec: Recording, run: RecordingRun) -> dict[str, Any]:
    """The JSON object of ``pednav run`` for lane 0 of ``run``."""
    prep = run.prepared
    pos = run.pos[0]
    d = np.diff(pos[prep.n_align :, :2], axis=0)
    out: dict[str, Any] = {
        "duration_s": round(rec.duration_s, 3),
        "rate_hz": round(prep.rate_hz, 3),
        "navigation_start_s": round(prep.navigation_start_s, 3),
        "distance_m": float(np.sum(np.linalg.norm(d, axis=1))),
        "final_position_m": [float(x) for x in pos[-1]],
        "stances": int(run.stances[0]),
    }
    if rec.has_truth:
        m = track_errors(pos, prep.truth_pos, prep.n_align)
        out.update({k: m[k] for k in ("armse_m", "armse_pyshoe_m", "final_error_m")})
    if prep.footprints is not None:
        m = footprint_errors(pos[prep.footprints.sample], prep.footprints.pos)
        out.update({k: v for k, v in m.items() if k in FOOTPRINT_KEYS})
    if not rec.has_truth and prep.footprints is None:
        out["loop_closure_m"] = loop_closure(pos, prep.n_align)
    return out


def check_policy(name: str) -> None:
    """``ValueError`` listing what ``pednav run --policy`` accepts, for an unknown name."""
    from agents.evaluate import BUILTIN_POLICIES

    if name in SETUP_NAMES or name in BUILTIN_POLICIES:
        return
    path = Path(name)
    if path.suffix == ".zip" or path.exists():
        return
    raise ValueError(
        f"unknown policy {name!r}: use {DEFAULT_POLICY} (the default), "
        f"{', '.join(n for n in SETUP_NAMES + BUILTIN_POLICIES if n != DEFAULT_POLICY)}, "
        "or a path to a run directory or saved SB3 model (.zip)"
    )


def check_output_path(path: str | Path, option: str) -> Path:
    """An output file whose directory exists (checked before the run, not after)."""
    path = Path(path)
    if not path.parent.is_dir():
        raise ValueError(f"{option} {path}: directory {path.parent} does not exist")
    if path.is_dir():
        raise ValueError(f"{option} {path}: is a directory; give a file name")
    return path


def run(
    path: str | Path,
    fmt: str = "auto",
    policy: str = DEFAULT_POLICY,
    mounting: str | None = None,
    options: LoadOptions | None = None,
    plot: str | Path | None = None,
    footprints: FootprintChoice = AUTO,
    layout: CsvLayout | None = None,
) -> tuple[dict[str, Any], Recording]:
    """Load, filter and summarise one recording (the ``pednav run`` command);
    returns the JSON object and the recording (for its issues). ``options``,
    ``layout`` and ``footprints`` are :func:`pednav_env.io.load_recording`'s."""
    check_policy(policy)
    if plot is not None:
        plot = check_output_path(plot, "--plot")
    rec = load_recording(path, fmt, options, layout, footprints)
    if policy in SETUP_NAMES:
        setup: RealFilterSetup = named_setup(policy)
        if mounting is not None:
            setup = replace(setup, mounting=mounting)
        result = run_prepared(prepare(rec, setup))
    else:
        if mounting is not None:
            raise ValueError("--mounting applies to the fixed setups (paper, real-fixed) only")
        result, _ = run_with_policy(rec, policy)
    summary = summarize(rec, result)
    if plot is not None:
        write_plot(rec, result, plot, policy)
    return summary, rec


def write_plot(rec: Recording, run: RecordingRun, path: Path, label: str) -> None:
    """Top view of the estimated track with the truth, turned as in the metrics:
    a dense reference as a line, a sparse one (few samples) as points, and
    footprints as circles joined to the estimate at their footfalls."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prep = run.prepared
    na = prep.n_align
    pos = run.pos[0]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=100)
    if rec.has_truth:
        ref = aligned_reference(pos, prep.truth_pos, na)
        ok = np.isfinite(ref).all(axis=1)
        sparse = ok.mean() < 0.5
        ax.plot(
            ref[ok, 0],
            ref[ok, 1],
            "k.:" if sparse else "k-",
            lw=1,
            ms=4,
            label=f"reference ({int(ok.sum())} samples)" if sparse else "reference",
        )
    if prep.footprints is not None:
        fp = prep.footprints
        est = pos[fp.sample, :2]
        m = footprint_errors(est, fp.pos)
        ref = est[0] + rotate_h(fp.pos - fp.pos[0], m["footprint_heading_offset_rad"])
        ax.plot(ref[:, 0], ref[:, 1], "ko", mfc="none", ms=5, label=f"footprints ({fp.count})")
        ax.plot(est[:, 0], est[:, 1], "r.", ms=4, label="estimate at the footfalls")
        for a, b in zip(ref, est, strict=True):
            ax.plot([a[0], b[0]], [a[1], b[1]], "-", color="0.6", lw=0.7)
    ax.plot(pos[na:, 0], pos[na:, 1], "r-", lw=1, label=f"ZUPT-UKF ({label})")
    st = run.stance[0] & ~np.roll(run.stance[0], 1)
    ax.plot(pos[st, 0], pos[st, 1], "b.", ms=3, label="stance starts")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(rec.name, fontsize=10)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def format_text(name: str, summary: dict[str, Any], issues: str = "") -> str:
    """Plain-text report of :func:`run`."""
    p = summary["final_position_m"]
    lines = [
        f"{name}",
        f"duration         {summary['duration_s']:.2f} s at {summary['rate_hz']:.1f} Hz",
        f"navigation from  {summary['navigation_start_s']:.2f} s (after the still start)",
        f"distance walked  {summary['distance_m']:.2f} m (estimate, horizontal)",
        f"final position   ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m",
        f"stances          {summary['stances']}",
    ]
    if "armse_m" in summary:
        lines += [
            f"ARMSE            {summary['armse_m']:.3f} m (horizontal, best heading)",
            f"ARMSE (PyShoe)   {summary['armse_pyshoe_m']:.3f} m",
            f"final error      {summary['final_error_m']:.3f} m",
        ]
    if "footprints" in summary:
        lines += [
            f"footprints       {summary['footprints']}",
            f"footprint error  {summary['footprint_mean_error_m']:.3f} m mean, final "
            f"{summary['footprint_final_error_m']:.3f} m "
            f"({summary['footprint_final_error_pct']:.2f} % of the footprint path)",
        ]
    if "loop_closure_m" in summary:
        lines.append(f"loop closure     {summary['loop_closure_m']:.3f} m (end − start)")
    if issues:
        lines.append(issues)
    return "\n".join(lines)
