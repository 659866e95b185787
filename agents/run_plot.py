"""The top view of ``pednav run --plot``: the estimated track with its truth."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pednav_env.files import save_figure
from pednav_env.io import Recording
from pednav_env.replay.metrics import aligned_reference, footprint_errors, rotate_h
from pednav_env.replay.runner import RecordingRun


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
    save_figure(fig, path)
    plt.close(fig)
