"""The text table and the figures of ``pednav evaluate``.

- :func:`format_table`: mean error with its 95 % CI, final error as % of the
  distance walked (not for MarkerTrack, whose error is a marker-tracking error
  that does not grow with distance), the share of diverged episodes in %, and
  the paired difference against the paper policy and, when it was played, the
  tuned constant. Long policy paths are shortened (the JSON keeps them whole);
  the privileged oracle is labelled ``oracle (privileged)``.
- :func:`write_plots`: ``error_over_time.png`` (median and quartiles over the
  episodes still running, against time in seconds, with the number of running
  episodes below) and ``per_episode.png`` (each episode's error against the
  paper policy's on the same seed). Axes are fitted to the data, on a log
  scale only where the data span a decade or more.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from agents.episode_result import EpisodeResult
from agents.policies import ZERO_ACTION
from baselines.oracle import LABEL as ORACLE_LABEL
from pednav_env.files import save_figure

#: Envs whose error does not accumulate with the distance walked: no "% of distance".
NO_DISTANCE_PERCENT = frozenset({"pednav/MarkerTrack-v0"})
#: Name of the scored error per env (default: horizontal position error).
ERROR_NAMES = {"pednav/MarkerTrack-v0": "RMS marker error"}
#: Width of the policy column of the table (and of legend entries).
NAME_WIDTH = 28
#: The median over time is drawn only where at least this many episodes still run.
MIN_RUNNING = 3


def error_name(env_id: str) -> str:
    return ERROR_NAMES.get(env_id, "horizontal error")


def short_name(name: str, width: int = NAME_WIDTH) -> str:
    """``name`` if it fits in ``width`` characters, else its last path parts after "…";
    the oracle as ``oracle (privileged)``."""
    if name == "oracle":
        return ORACLE_LABEL
    if len(name) <= width:
        return name
    parts = Path(name).parts
    tail = ""
    for part in reversed(parts):
        candidate = part if not tail else f"{part}/{tail}"
        if len(candidate) + 2 > width:
            break
        tail = candidate
    return f"…/{tail}" if tail else "…" + name[-(width - 1) :]


#: Between the table's columns: two spaces, so that multi-word headers ("95 % CI",
#: "not diverged (m)") read as separate columns.
COLUMN_GAP = "  "


def format_table(result: dict[str, Any]) -> str:
    """Plain-text table of an evaluation result (the JSON object of ``evaluate``)."""
    env_id = result["env"]
    show_pct = env_id not in NO_DISTANCE_PERCENT
    cols = [
        (f"{'policy':<{NAME_WIDTH}}", None),
        (f"{'mean error (m)':>14}", None),
        (f"{'95 % CI':>18}", None),
        (f"{'not diverged (m)':>16}", None),
        (f"{'final % dist':>12}", "pct"),
        (f"{'diverged':>8}", None),
        (f"{'Δ vs paper':>10}", None),
        (f"{'p paired':>8}", None),
    ]
    with_tuned = any(p.get("vs_tuned") for p in result["policies"])
    if with_tuned:
        cols += [(f"{'Δ vs tuned':>10}", None), (f"{'p paired':>8}", None)]
    head = COLUMN_GAP.join(c for c, kind in cols if show_pct or kind != "pct")
    families = list(dict.fromkeys(p["filter"] for p in result["policies"] if "filter" in p))
    pairing = "each filter family's action 0" if families else "paper"
    lines = [
        f"{env_id}: {result['episodes']} episodes, seeds {result['seed']}…"
        f"{result['seed'] + result['episodes'] - 1}; error (m) = time-averaged "
        f"{error_name(env_id)}; Δ and p: paired with {pairing}"
        f"{' (and tuned)' if with_tuned else ''} by seed (t-test)",
        head,
        "-" * len(head),
    ]
    blocks = (
        [(None, result["policies"])]
        if not families
        else [(f, [p for p in result["policies"] if p.get("filter") == f]) for f in families]
    )
    for family, entries in blocks:
        if family is not None:
            zero = ZERO_ACTION[family]
            lines.append(f"filter family {family} (action 0 = {zero}; Δ and p: paired with {zero})")
        lines.extend(_rows(entries, show_pct, with_tuned))
    if result.get("episode_recordings"):
        lines += ["", *recording_rows(result)]
    return "\n".join(lines)


def recording_rows(result: dict[str, Any]) -> list[str]:
    """Per recording (replay env): each policy's error on it, by seed, one column
    per policy of the table above."""
    names = result["episode_recordings"]
    heads = [short_name(p["name"], 16) for p in result["policies"]]
    widths = [max(len(h), 8) for h in heads]
    first = max(len("recording"), *(len(n) for n in names))
    head = f"{'seed':>6} {'recording':<{first}} " + " ".join(
        f"{h:>{w}}" for h, w in zip(heads, widths, strict=True)
    )
    lines = ["error (m) per recording, by seed:", head, "-" * len(head)]
    for k, name in enumerate(names):
        cells = [
            f"{p['episode_errors'][k]:>{w}.3f}"
            for p, w in zip(result["policies"], widths, strict=True)
        ]
        lines.append(f"{result['seed'] + k:>6} {name:<{first}} " + " ".join(cells))
    return lines


def _rows(entries: list[dict[str, Any]], show_pct: bool, with_tuned: bool) -> list[str]:
    lines = []
    for p in entries:
        lo, hi = p["ci95"]
        pv = p["vs_paper"]["p_value"]
        nd = p.get("mean_error_non_diverged")
        diff = (
            "—"
            if pv is None and p["vs_paper"]["mean_diff"] == 0.0
            else f"{p['vs_paper']['mean_diff']:+.3f}"
        )
        row = [
            f"{short_name(p['name']):<{NAME_WIDTH}}",
            f"{p['mean_error']:>14.3f}",
            f"{f'[{lo:.3f}, {hi:.3f}]':>18}",
            f"{'—' if nd is None else f'{nd:.3f}':>16}",
        ]
        if show_pct:
            row.append(f"{p['final_error_pct']:>12.1f}")
        diverged = f"{100 * p['divergence_rate']:.0f} %"
        row += [
            f"{diverged:>8}",
            f"{diff:>10}",
            f"{'—' if pv is None else f'{pv:.2g}':>8}",
        ]
        if with_tuned:
            vt = p.get("vs_tuned") or {}
            tdiff = "—" if p["name"] == "tuned" or not vt else f"{vt['mean_diff']:+.3f}"
            tp = vt.get("p_value")
            row += [f"{tdiff:>10}", f"{'—' if tp is None else f'{tp:.2g}':>8}"]
        lines.append(COLUMN_GAP.join(row))
    return lines


def _trace_grid(res: list[EpisodeResult]) -> np.ndarray:
    """Episodes × steps, NaN after an episode's end."""
    longest = max(len(r.error_trace) for r in res)
    grid = np.full((len(res), longest), np.nan)
    for j, r in enumerate(res):
        grid[j, : len(r.error_trace)] = r.error_trace
    return grid


def log_limits(values: np.ndarray, margin: float = 1.25) -> tuple[float, float]:
    """Log-axis limits around the positive finite ``values`` (a factor ``margin`` out)."""
    v = values[np.isfinite(values) & (values > 0)]
    if v.size == 0:
        return 1e-3, 1.0
    lo, hi = float(v.min()), float(v.max())
    if hi <= lo * margin:
        lo, hi = lo / 2.0, hi * 2.0
    return lo / margin, hi * margin


def spans_a_decade(lo: float, hi: float) -> bool:
    """Whether a log axis suits the range [lo, hi] (a factor of 10 or more)."""
    return hi >= 10.0 * lo


def write_plots(
    env_id: str,
    outcomes: dict[str, list[EpisodeResult]],
    out: Path,
    interval_s: float | None = None,
) -> list[Path]:
    """Write ``error_over_time.png`` and ``per_episode.png`` to ``out``; returns the
    paths. ``interval_s``: seconds per env step (the x axis is in steps without it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    what = error_name(env_id)
    episodes = len(next(iter(outcomes.values())))

    fig, (ax, ax_n) = plt.subplots(
        2,
        1,
        figsize=(8.5, 6.0),
        sharex=True,
        height_ratios=(3, 1),
        layout="constrained",
    )
    medians = []
    for name, res in outcomes.items():
        grid = _trace_grid(res)
        running = np.sum(np.isfinite(grid), axis=0)
        step = np.arange(1, grid.shape[1] + 1)
        t = step * interval_s if interval_s else step
        enough = running >= min(MIN_RUNNING, episodes)
        with np.errstate(all="ignore"):
            median = np.where(enough, np.nanmedian(np.where(enough, grid, 0.0), axis=0), np.nan)
            q1, q3 = np.nanpercentile(np.where(enough, grid, 0.0), [25, 75], axis=0)
        q1, q3 = np.where(enough, q1, np.nan), np.where(enough, q3, np.nan)
        line = ax.plot(t, median, label=short_name(name), lw=1.3)[0]
        ax.fill_between(t, q1, q3, color=line.get_color(), alpha=0.15, lw=0)
        ax_n.step(t, running, where="post", color=line.get_color(), lw=1.1)
        medians.append(median[len(median) // 20 :])  # past the first 5 %: errors start at 0
    lo, hi = log_limits(np.concatenate(medians))
    if spans_a_decade(lo, hi):
        ax.set_yscale("log")
        ax.set_ylim(lo, hi)
    else:
        ax.set_ylim(0.0, hi)
    ax.set_ylabel(f"{what} (m)\nmedian, 25–75 % band")
    ax.set_title(
        f"{env_id}: {what} over time, {episodes} episodes per policy\n"
        f"(statistics over the episodes still running; drawn while ≥ {MIN_RUNNING} run)",
        fontsize="medium",
    )
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize="small", loc="lower right")
    ax_n.set_ylabel("episodes\nrunning")
    ax_n.set_ylim(0, episodes * 1.08)
    ax_n.grid(True, alpha=0.3)
    ax_n.set_xlabel("time since navigation start (s)" if interval_s else "decision step")
    files = [out / "error_over_time.png"]
    save_figure(fig, files[0], dpi=110)
    plt.close(fig)

    paper = np.array([r.mean_error for r in outcomes["paper"]])
    others = {
        n: np.array([r.mean_error for r in res]) for n, res in outcomes.items() if n != "paper"
    }
    fig, ax = plt.subplots(figsize=(6.0, 6.2), layout="constrained")
    markers = "osD^v<>"
    for k, (name, err) in enumerate(others.items()):
        ax.scatter(paper, err, s=16, label=short_name(name), alpha=0.7, marker=markers[k % 7])
    lim = log_limits(np.concatenate([paper, *others.values()]), margin=1.15)
    ax.plot(lim, lim, "k:", lw=1, label="equal to paper")
    if spans_a_decade(*lim):
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlim(*lim)
    ax.set_ylim(*lim)
    ax.set_aspect("equal")
    ax.grid(True, which="major", alpha=0.3)
    ax.set_xlabel(f"paper policy: time-averaged {what} (m)")
    ax.set_ylabel(f"policy: time-averaged {what} (m)")
    ax.set_title(
        f"{env_id}, {episodes} episodes\neach point: one seed (below the line = better than paper)",
        fontsize="medium",
    )
    ax.legend(fontsize="small", loc="upper left")
    files.append(out / "per_episode.png")
    save_figure(fig, files[1], dpi=110)
    plt.close(fig)
    return files
