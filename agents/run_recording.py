"""``pednav run``: the ZUPT-UKF on one recording, with a named policy.

Policies:

- ``paper`` and ``real-fixed``: fixed setups (:mod:`pednav_env.replay.setup`)
  run directly by the filter;
- any other name that ``pednav evaluate`` understands (``tuned``,
  ``adaptive``, ``pretrained``, a run directory or a saved SB3 model): the
  policy drives the knobs online through the replay environment's core
  (``pednav/FootZuptReplay-v0``'s observation and action, so a tuner trained
  in simulation runs unchanged) with the policy's own filter family (shoe
  for ``tuned``, ``adaptive`` and ``pretrained`` unless named ``NAME:paper``;
  a training run's from its meta.json); the knob values it chose in each
  decision interval are then replayed through the same filter to record the
  track sample by sample.

JSON keys (docs/REAL_DATA.md): ``duration_s``, ``rate_hz``,
``navigation_start_s``, ``distance_m``, ``final_position_m``, ``stances``;
with truth ``armse_m``, ``armse_pyshoe_m``, ``final_error_m``,
``truth_glitches`` and ``truth_glitch_samples`` (tracking glitches of the
reference, :func:`pednav_env.calibration.strides.truth_glitches`: reported, and
left in the metrics); with
footprints ``footprints``, ``footprint_mean_error_m``,
``footprint_final_error_m``, ``footprint_final_error_pct``; with neither
``loop_closure_m``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.calibration.strides import truth_glitches
from pednav_env.io import CsvLayout, LoadOptions, Recording, find_recordings, load_recording
from pednav_env.io.hallway import AUTO, FootprintChoice
from pednav_env.replay.metrics import footprint_errors, loop_closure, track_errors
from pednav_env.replay.runner import PreparedRecording, RecordingRun, prepare, run_prepared
from pednav_env.replay.setup import (
    SETUP_NAMES,
    RealFilterSetup,
    load_setup,
    named_setup,
    real_fixed_setup,
)
from pednav_env.replay.simulate import check_output_path as output_file
from pednav_env.replay.track import run_states, write_track_csv

#: Footprint keys of the JSON summary (:func:`pednav_env.replay.metrics.footprint_errors`).
FOOTPRINT_KEYS = (
    "footprints",
    "footprint_mean_error_m",
    "footprint_final_error_m",
    "footprint_final_error_pct",
)
#: The default policy of ``pednav run``: the configuration chosen on real walks.
DEFAULT_POLICY = "real-fixed"
#: ``--policy twins``: ``real-fixed`` with its SHOE threshold chosen for each recording on
#: simulated twins of the recording's own strides as its IMU shows them
#: (:func:`agents.twin_choice.choose_threshold_on_twins`; no truth used).
TWIN_POLICY = "twins"
#: Seed of ``--policy twins``: twin i draws from ``numpy.random.default_rng([TWIN_SEED, i])``.
TWIN_SEED = 0

#: The simulated env whose policies (tuned, adaptive, pretrained) are used.
SIM_ENV_ID = "pednav/FootZupt-v0"
#: Why the privileged oracle does not run on a recording.
ORACLE_ON_RECORDINGS = (
    "oracle: not applicable on recordings: it plays the constant of the simulator's true "
    "context (speed band, IMU grade), which a recording does not give it"
)


def _load_policy(name: str, action_space: Any) -> Any:
    from agents.policies import load_policy

    return load_policy(name, action_space, SIM_ENV_ID, other_names=SETUP_NAMES)


def run_with_policy(
    rec: Recording, policy_name: str, interval_s: float = 0.5, track: bool = False
) -> tuple[RecordingRun, dict[str, np.ndarray]]:
    """Drive the replay core with a policy; return the replayed run (``track``:
    :func:`pednav_env.replay.runner.run_prepared`'s) and the knob schedule."""
    from gymnasium import spaces

    from agents.policies import split_name

    if split_name(policy_name)[0] == "oracle":
        raise ValueError(ORACLE_ON_RECORDINGS)
    # the action space is the same for both filter families (four knobs)
    policy = _load_policy(policy_name, spaces.Box(-1.0, 1.0, (4,), np.float32))
    if getattr(policy, "needs_context", False):
        raise ValueError(ORACLE_ON_RECORDINGS)
    family = getattr(policy, "filter_family", None) or "paper"
    state, start = None, np.array([True])

    def act(obs: np.ndarray) -> np.ndarray:
        nonlocal state, start
        action, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        start = np.array([False])
        return np.asarray(action, dtype=np.float64).reshape(1, -1)

    prep, schedule = knob_schedule(rec, family, 1, act, interval_s, "pednav run")
    return run_prepared(prep, schedule=schedule, interval_s=interval_s, track=track), schedule


def knob_schedule(
    rec: Recording,
    family: str,
    lanes: int,
    act: Callable[[np.ndarray], np.ndarray],
    interval_s: float = 0.5,
    env_name: str = "pednav run",
) -> tuple[PreparedRecording, dict[str, np.ndarray]]:
    """Play ``act(obs (lanes, d)) -> (lanes, 4)`` on ``lanes`` lanes of the replay
    core over ``rec`` (filter family ``family``); return the prepared recording and
    each knob's values per decision interval and lane, ``(K, lanes)``, for
    :func:`pednav_env.replay.runner.run_prepared`. A lane whose filter diverged
    keeps the knobs of that interval (``run_prepared`` holds the last row); the
    play stops at the end of the recording or when every lane has diverged."""
    from pednav_env.envs.foot_replay_core import FootReplayConfig, FootReplayCore

    config = FootReplayConfig(decision_interval_s=interval_s, filter_family=family)
    core = FootReplayCore(config, lanes, env_name, recordings=[rec])
    core.reset_lanes(np.arange(lanes), [np.random.default_rng(0) for _ in range(lanes)])
    rows: dict[str, list[np.ndarray]] = {}
    dead = np.zeros(lanes, dtype=bool)
    obs = core.obs.copy()
    while core.cursor[0] < core.length[0] and not dead.all():
        obs, _, terminated, _, _ = core.step(act(obs))
        for k, v in core.knob_values().items():
            row = v.copy()
            if rows.get(k):
                row[dead] = rows[k][-1][dead]
            rows.setdefault(k, []).append(row)
        dead |= terminated & core.engine.diverged
    return core.trials[0].prepared, {k: np.array(v) for k, v in rows.items()}


def run_named(rec: Recording, policy_name: str, track: bool = False) -> RecordingRun:
    """``rec`` filtered under a policy name of ``pednav run --policy`` (a fixed
    setup, ``twins``, or a policy driving the replay core; :func:`resolve_policy`)."""
    if policy_name == TWIN_POLICY:
        return run_twin_choice(rec, real_fixed_setup(), track)[0]
    policy = resolve_policy(policy_name)
    if isinstance(policy, RealFilterSetup):
        return run_prepared(prepare(rec, policy), track=track)
    return run_with_policy(rec, policy, track=track)[0]


def run_twin_choice(
    rec: Recording, base: RealFilterSetup, track: bool = False
) -> tuple[RecordingRun, dict[str, Any]]:
    """``rec`` filtered with ``base`` and the SHOE threshold chosen for it on simulated
    twins of its own IMU-estimated strides (:data:`TWIN_POLICY`), and the choice as
    ``pednav run --json`` reports it under ``twin_choice``. The twins are scored by
    their footprint error when the recording has footprints and no truth track
    (as the recording is), else by their ARMSE."""
    from agents.twin_choice import TWIN_WALKS, choose_threshold_on_twins

    metric = "footprints" if rec.footprints is not None and not rec.has_truth else "armse"
    choice = choose_threshold_on_twins(rec, TWIN_SEED, setup=base, twin_metric=metric)
    info = {
        "shoe_threshold": choice.threshold,
        "route_strides": int(choice.strides.speed_mps.size),
        "route_median_speed_mps": float(np.median(choice.strides.speed_mps)),
        "twins": TWIN_WALKS,
        "seed": TWIN_SEED,
        "twin_metric": metric,
        "twin_median_m": {
            f"{g:.4g}": float(m) if np.isfinite(m) else None
            for g, m in zip(choice.thresholds, choice.twin_median_m, strict=True)
        },
    }
    return run_prepared(prepare(rec, choice.setup), track=track), info


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
        spans = truth_glitches(prep.truth_pos, prep.rate_hz)
        out["truth_glitches"] = int(spans.shape[0])
        out["truth_glitch_samples"] = int(np.sum(spans[:, 1] - spans[:, 0] + 1))
    if prep.footprints is not None:
        m = footprint_errors(pos[prep.footprints.sample], prep.footprints.pos)
        out.update({k: v for k, v in m.items() if k in FOOTPRINT_KEYS})
    if not rec.has_truth and prep.footprints is None:
        out["loop_closure_m"] = loop_closure(pos, prep.n_align)
    return out


def resolve_policy(name: str) -> RealFilterSetup | str:
    """A fixed setup (``real-fixed``, ``paper``, or a setup JSON file), or the name
    of a simulated-env policy (``tuned``, ``adaptive``, ``pretrained``, ``gait-rule``,
    a gait-rule parameter file, a run directory, an SB3 ``.zip``); ``ValueError``
    listing the choices otherwise."""
    from agents.evaluate import BUILTIN_POLICIES
    from agents.policies import split_name

    if name == TWIN_POLICY:
        return name
    if name in SETUP_NAMES:
        return named_setup(name)
    if split_name(name)[0] == "oracle":
        raise ValueError(ORACLE_ON_RECORDINGS)
    path = Path(name)
    if path.suffix.lower() == ".json":
        from agents.gait_rule import is_params_file

        return name if is_params_file(path) else load_setup(path)
    if split_name(name)[0] in BUILTIN_POLICIES or path.suffix == ".zip" or path.is_dir():
        return name
    others = [n for n in dict.fromkeys(SETUP_NAMES + BUILTIN_POLICIES) if n != DEFAULT_POLICY]
    raise ValueError(
        f"unknown policy {name!r}: use {DEFAULT_POLICY} (the default), {TWIN_POLICY}, "
        f"{', '.join(n for n in others if n != 'oracle')}, "
        "a setup JSON file, or a path to a run directory or saved SB3 model (.zip)"
    )


def check_policy(name: str) -> None:
    """``ValueError`` when ``name`` cannot run on a recording — unknown, the
    privileged oracle, a tuner that is not shipped — so that a long run can
    refuse it before it starts."""
    from gymnasium import spaces

    if name != TWIN_POLICY and isinstance(resolve_policy(name), str):
        _load_policy(name, spaces.Box(-1.0, 1.0, (4,), np.float32))


def check_policies(names: list[str], option: str = "--policies") -> None:
    """:func:`check_policy` for every name; a one-line ``SystemExit`` naming ``option``
    and the first name that cannot run (for scripts that refuse before a long run)."""
    for name in names:
        try:
            check_policy(name)
        except ValueError as exc:
            raise SystemExit(f"{option} {name}: {exc}") from None


def check_output_path(path: str | Path, option: str) -> Path:
    """An output file whose directory exists and is writable (checked before the run,
    not after): :func:`pednav_env.replay.simulate.check_output_path`, the message
    naming ``option``."""
    try:
        return output_file(path)
    except ValueError as exc:
        raise ValueError(f"{option} {exc}") from None


@dataclass(frozen=True)
class RunOptions:
    """How ``pednav run`` loads and filters: the loader's arguments
    (:func:`pednav_env.io.load_recording`), the policy, a mounting override."""

    fmt: str = "auto"
    policy: str = DEFAULT_POLICY
    mounting: str | None = None
    load: LoadOptions | None = None
    layout: CsvLayout | None = None
    footprints: FootprintChoice = AUTO


def run(
    path: str | Path,
    options: RunOptions | None = None,
    plot: str | Path | None = None,
    out: str | Path | None = None,
) -> tuple[dict[str, Any], Recording]:
    """Load, filter and summarise one recording (the ``pednav run`` command);
    returns the JSON object and the recording (for its issues). ``plot`` writes
    the top view, ``out`` the track with its covariance (:mod:`pednav_env.replay.track`)."""
    o = options or RunOptions()
    policy = resolve_policy(o.policy)
    plot = None if plot is None else check_output_path(plot, "--plot")
    out = None if out is None else check_output_path(out, "--out")
    rec = load_recording(path, o.fmt, o.load, o.layout, o.footprints)
    track = out is not None
    twin_choice = None
    if policy == TWIN_POLICY:
        base = real_fixed_setup()
        base = base if o.mounting is None else replace(base, mounting=o.mounting)
        result, twin_choice = run_twin_choice(rec, base, track)
    elif isinstance(policy, RealFilterSetup):
        setup = policy if o.mounting is None else replace(policy, mounting=o.mounting)
        result = run_prepared(prepare(rec, setup), track=track)
    else:
        if o.mounting is not None:
            raise ValueError(
                "--mounting applies to the fixed setups (paper, real-fixed, JSON) and twins"
            )
        result, _ = run_with_policy(rec, policy, track=track)
    summary = summarize(rec, result)
    if twin_choice is not None:
        summary["twin_choice"] = twin_choice
    if plot is not None:
        from agents.run_plot import write_plot

        write_plot(
            rec, result, plot, Path(o.policy).stem if o.policy.endswith(".json") else o.policy
        )
    if out is not None:
        write_track_csv(run_states(result, float(rec.time[0])), out)
    return summary, rec


def run_folder(
    directory: str | Path,
    options: RunOptions | None = None,
    plot_dir: str | Path | None = None,
    out_dir: str | Path | None = None,
) -> dict[str, Any]:
    """:func:`run` on every recording of ``directory`` (:func:`pednav_env.io.find_recordings`).

    Returns ``{"policy", "recordings": [...]}``: per recording its ``recording``
    (file name) and either the JSON object of :func:`run` plus ``issues`` (their
    count) or ``error`` (the message). Plots and tracks go to ``plot_dir`` /
    ``out_dir`` (created) as ``<stem>.png`` and ``<stem>_track.csv``.
    """
    o = options or RunOptions()
    resolve_policy(o.policy)
    paths = find_recordings(directory)
    if not paths:
        raise ValueError(f"{directory}: no recordings (.csv, .mat) found")
    for d in (plot_dir, out_dir):
        if d is not None:
            Path(d).mkdir(parents=True, exist_ok=True)
    rows = []
    for path in paths:
        row: dict[str, Any] = {"recording": path.name}
        plot = None if plot_dir is None else Path(plot_dir) / f"{path.stem}.png"
        out = None if out_dir is None else Path(out_dir) / f"{path.stem}_track.csv"
        try:
            summary, rec = run(path, o, plot, out)
        except ValueError as exc:
            row["error"] = str(exc)
        else:
            row.update(summary)
            row["issues"] = len(rec.issues)
        rows.append(row)
    return {"policy": o.policy, "recordings": rows}


#: Columns of the folder table: (JSON key, header, format).
FOLDER_COLUMNS = (
    ("duration_s", "s", "{:.1f}"),
    ("distance_m", "dist. m", "{:.1f}"),
    ("stances", "stances", "{}"),
    ("armse_m", "ARMSE m", "{:.3f}"),
    ("final_error_m", "final m", "{:.3f}"),
    ("footprint_mean_error_m", "fp. mean m", "{:.3f}"),
    ("footprint_final_error_pct", "fp. final %", "{:.2f}"),
    ("loop_closure_m", "loop m", "{:.3f}"),
)


def format_folder(result: dict[str, Any]) -> str:
    """The summary table of :func:`run_folder` (— where a measure does not apply)."""
    rows = result["recordings"]
    used = [c for c in FOLDER_COLUMNS if any(c[0] in r for r in rows)]
    head = ["recording"] + [h for _, h, _ in used]
    table = []
    for r in rows:
        if "error" in r:
            table.append([r["recording"], "error: " + r["error"]])
            continue
        cells = [fmt.format(r[k]) if k in r else "—" for k, _, fmt in used]
        table.append([r["recording"]] + cells)
    ok = [t for t in table if not (len(t) == 2 and t[1].startswith("error: "))]
    widths = [max(len(t[i]) for t in ok + [head]) for i in range(len(head))]
    widths[0] = max(len(t[0]) for t in table + [head])
    lines = [f"policy {result['policy']}"]
    lines.append(
        "  ".join(
            [head[0].ljust(widths[0])]
            + [h.rjust(w) for h, w in zip(head[1:], widths[1:], strict=True)]
        )
    )
    for t in table:
        if t not in ok:
            lines.append(f"{t[0].ljust(widths[0])}  {t[1]}")
            continue
        cells = [c.rjust(w) for c, w in zip(t[1:], widths[1:], strict=True)]
        lines.append("  ".join([t[0].ljust(widths[0])] + cells))
    failed = sum("error" in r for r in rows)
    lines.append(
        f"{len(rows) - failed} of {len(rows)} recordings run"
        + (f", {failed} failed" if failed else "")
    )
    return "\n".join(lines)


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
        if summary.get("truth_glitches"):
            lines.append(
                f"truth glitches   {summary['truth_glitches']} ({summary['truth_glitch_samples']} "
                "samples where the reference froze or jumped faster than 20 m/s; in the ARMSE)"
            )
    if "footprints" in summary:
        lines += [
            f"footprints       {summary['footprints']}",
            f"footprint error  {summary['footprint_mean_error_m']:.3f} m mean, final "
            f"{summary['footprint_final_error_m']:.3f} m "
            f"({summary['footprint_final_error_pct']:.2f} % of the footprint path)",
        ]
    if "loop_closure_m" in summary:
        lines.append(f"loop closure     {summary['loop_closure_m']:.3f} m (end − start)")
    if "twin_choice" in summary:
        c = summary["twin_choice"]
        lines.append(
            f"SHOE threshold   {c['shoe_threshold']:.3g}, chosen on {c['twins']} simulated twins "
            f"of {c['route_strides']} strides at a median {c['route_median_speed_mps']:.2f} m/s"
        )
    if issues:
        lines.append(issues)
    return "\n".join(lines)
