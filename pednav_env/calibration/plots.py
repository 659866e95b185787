"""Figures of a :class:`pednav_env.calibration.compare.Sim2RealReport`.

One PNG per speed band with recordings, ``sim2real_<band>.png``: histograms
of log10 SHOE over the walking part, recordings pooled against simulated
walks pooled, with each recording's p10 and p50 as ticks and the simulator's
5–95 % envelopes of p10 and p50 as shaded spans.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pednav_env.calibration.compare import Sim2RealReport, band_label


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
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths
