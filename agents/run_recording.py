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

JSON keys (docs/REAL_DATA.md): ``duration_s``, ``rate_hz``, ``distance_m``,
``final_position_m``, ``stances``; with truth ``armse_m``,
``armse_pyshoe_m``, ``final_error_m``; without truth ``loop_closure_m``.
"""

from __future__ import annotations

import inspect
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.io import LoadOptions, Recording, load_recording
from pednav_env.replay.metrics import loop_closure, rotate_h, track_errors
from pednav_env.replay.runner import RecordingRun, prepare, run_prepared
from pednav_env.replay.setup import SETUP_NAMES, RealFilterSetup, named_setup

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
        "distance_m": float(np.sum(np.linalg.norm(d, axis=1))),
        "final_position_m": [float(x) for x in pos[-1]],
        "stances": int(run.stances[0]),
    }
    if rec.has_truth:
        m = track_errors(pos, prep.truth_pos, prep.n_align)
        out.update({k: m[k] for k in ("armse_m", "armse_pyshoe_m", "final_error_m")})
    else:
        out["loop_closure_m"] = loop_closure(pos, prep.n_align)
    return out


def run(
    path: str | Path,
    fmt: str = "auto",
    policy: str = "paper",
    mounting: str | None = None,
    options: LoadOptions | None = None,
    plot: str | Path | None = None,
) -> tuple[dict[str, Any], Recording]:
    """Load, filter and summarise one recording (the ``pednav run`` command);
    returns the JSON object and the recording (for its issues)."""
    rec = load_recording(path, format=fmt, options=options)
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
        write_plot(rec, result, Path(plot), policy)
    return summary, rec


def write_plot(rec: Recording, run: RecordingRun, path: Path, label: str) -> None:
    """Top view of the estimated track (and the reference, turned as in the metrics)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prep = run.prepared
    na = prep.n_align
    pos = run.pos[0]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=100)
    if rec.has_truth:
        m = track_errors(pos, prep.truth_pos, na)
        ref = prep.truth_pos[na:, :2] - prep.truth_pos[na, :2]
        ref = rotate_h(ref, m["heading_offset_rad"])
        ax.plot(ref[:, 0], ref[:, 1], "k-", lw=1, label="reference")
    ax.plot(pos[na:, 0], pos[na:, 1], "r-", lw=1, label=f"ZUPT-UKF ({label})")
    st = run.stance[0] & ~np.roll(run.stance[0], 1)
    ax.plot(pos[st, 0], pos[st, 1], "b.", ms=3, label="stance starts")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(rec.name)
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def format_text(name: str, summary: dict[str, Any], issues: str = "") -> str:
    """Plain-text report of :func:`run`."""
    p = summary["final_position_m"]
    lines = [
        f"{name}",
        f"duration         {summary['duration_s']:.2f} s at {summary['rate_hz']:.1f} Hz",
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
    else:
        lines.append(f"loop closure     {summary['loop_closure_m']:.3f} m (end − start)")
    if issues:
        lines.append(issues)
    return "\n".join(lines)
