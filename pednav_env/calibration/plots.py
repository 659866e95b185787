"""Figures of a :class:`pednav_env.calibration.compare.Sim2RealReport`.

One PNG per speed band with recordings, ``sim2real_<band>.png``: histograms
of log10 SHOE over the walking part, recordings pooled against simulated
walks pooled, with each recording's p10 and p50 as ticks and the simulator's
5–95 % envelopes of p10 and p50 as shaded spans; and
``sim2real_<model>_strides.png``: per stride-speed bin, the strides'
quietness (5th percentile of log10 SHOE over the stride), recordings beside
the simulator (box plots: quartiles, 5–95 % whiskers).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.calibration.compare import (
    SPEED_BANDS,
    Sim2RealReport,
    band_label,
    stride_quietness_by_bin,
)
from pednav_env.files import save_figure


def write_figures(report: Sim2RealReport, directory: str | Path) -> list[Path]:
    """Write the figures into ``directory`` (created); return their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(directory)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"--plot {directory}: cannot create the directory ({exc})") from None
    paths = []
    bins = np.linspace(2.0, 11.0, 91)
    for band in report.bands:
        if not band.real:
            continue
        fig, ax = plt.subplots(figsize=(7, 3.6))
        real = np.concatenate([s.log_shoe for s in band.real])
        sim = np.concatenate([s.log_shoe for s in band.sim])
        ax.hist(real, bins=bins, density=True, alpha=0.55, label=f"recorded ({len(band.real)})")
        ax.hist(sim, bins=bins, density=True, alpha=0.55, label=f"simulated ({len(band.sim)})")
        for (lo, hi), color in ((band.p10_envelope, "tab:green"), (band.p50_envelope, "tab:red")):
            ax.axvspan(lo, hi, color=color, alpha=0.12)
        for s in band.real:
            ax.axvline(s.log_shoe_p10, ymax=0.08, color="tab:green")
            ax.axvline(s.log_shoe_p50, ymax=0.08, color="tab:red")
        w = band.distance()
        ax.set_title(
            f"{report.model}: {band_label(band.band)} m/s, W1 = {w:.2f} decades "
            "(shaded: sim 5-95 % of p10 green, p50 red; ticks: recordings)",
            fontsize=8,
        )
        ax.set_xlabel("log10 SHOE statistic (PyShoe σ's, 5 samples at 200 Hz)")
        ax.set_ylabel("density")
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = out_dir / f"sim2real_{report.model}_{band_label(band.band).replace('>', 'over')}.png"
        save_figure(fig, path, dpi=110)
        plt.close(fig)
        paths.append(path)
    stride_path = _stride_figure(report, out_dir, plt)
    if stride_path is not None:
        paths.append(stride_path)
    return paths


def _stride_figure(report: Sim2RealReport, out_dir: Path, plt: Any) -> Path | None:
    """The per-stride quietness by stride speed (module docstring)."""
    real = stride_quietness_by_bin([s for b in report.bands for s in b.real])
    sim = stride_quietness_by_bin([s for b in report.bands for s in b.sim])
    keys = [k for k in real if k in sim]
    if not keys:
        return None
    fig, ax = plt.subplots(figsize=(7, 3.6))
    pos = np.arange(len(keys), dtype=float)
    style = {"whis": (5, 95), "showfliers": False, "widths": 0.32, "patch_artist": True}
    for offset, data, color, label in (
        (-0.18, real, "tab:blue", "recorded"),
        (0.18, sim, "tab:orange", "simulated"),
    ):
        box = ax.boxplot([data[k] for k in keys], positions=pos + offset, **style)
        for patch in box["boxes"]:
            patch.set_facecolor(color)
            patch.set_alpha(0.55)
        ax.plot([], [], color=color, lw=6, alpha=0.55, label=label)
    ax.set_xticks(pos)
    ax.set_xticklabels(
        [f"{band_label(SPEED_BANDS[k])}\n{real[k].size} / {sim[k].size}" for k in keys], fontsize=8
    )
    ax.set_xlabel("stride speed (m/s); strides recorded / simulated")
    ax.set_ylabel("stride quietness: p5 of log10 SHOE")
    ax.set_title(
        f"{report.model}: the SHOE threshold log10 γ a stride needs (box: quartiles, "
        "whiskers 5-95 %)",
        fontsize=8,
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out_dir / f"sim2real_{report.model}_strides.png"
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path
