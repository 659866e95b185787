"""Paper 003 (Bolotin & Fatehrad 2015): foot-mounted ZUPT-UKF, Tables 1 and 2.

Scenario (choices the paper leaves open are listed in docs/REPRODUCTION.md):
a 5 m square walked once, turning left at the corners, 1 s gait cycles
(T₀ = T₂ = 0.35 s, T₁ = T₃ = 0.15 s), 1 s of standing for the alignment
(eq 4; navigation starts at its end, t₀) and 1 s at the end; the paper's
knots only (stance, mid-swing); 100 Hz; the paper's
IMU (σ[δω] = 0.05 rad/s, σ[ν] = 0.02 rad/s, σ[δf] = 0.1 m/s²); the eq-5
detector with thresholds sized for that IMU (0.22 rad/s, 0.33 m/s²); ZUPTs
at stance start and end. Each configuration runs M Monte-Carlo walks as one
batch; all configurations share the seeds (common random numbers).

Metrics (RMS over runs and over every sample from t₀ to the end): ``sigma_x`` of
the 3-D position error norm (m), ``sigma_theta`` / ``sigma_gamma`` /
``sigma_psi`` of the pitch / roll / yaw errors (rad).

Rows with the contract's config names use the primary readings: gyro drift
ν redrawn per gait cycle, thresholds fixed across Table 2. Variant rows carry
a suffix: ``:drift_per_sample`` (ν redrawn every Δt) and
``:resized_thresholds`` (Table 2 thresholds resized for σ_f).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pednav_env.files import save_figure
from pednav_env.gait.foot import FootTrajectory, simulate_foot
from pednav_env.gait.foot_route import paper_stride_shape, square_route
from pednav_env.nav.detectors import ThresholdDetectorConfig
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.nav.zupt_results import ZuptRun
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.reproduce import ReproductionResult, ReproductionRow
from pednav_env.rotations import wrap_angle
from pednav_env.sensors.imu import DriftModel, ImuSpec, simulate_imu

#: Published values: Table 1 (σ_f = 0.1) and Table 2 (1 m steps).
PAPER_TABLES: dict[str, dict[str, float]] = {
    "table1_step_0.5m": {
        "sigma_x": 0.064,
        "sigma_theta": 0.047,
        "sigma_gamma": 0.048,
        "sigma_psi": 0.011,
    },
    "table1_step_1.0m": {
        "sigma_x": 0.071,
        "sigma_theta": 0.051,
        "sigma_gamma": 0.052,
        "sigma_psi": 0.012,
    },
    "table2_sigma_f_0.1": {
        "sigma_x": 0.071,
        "sigma_theta": 0.051,
        "sigma_gamma": 0.052,
        "sigma_psi": 0.012,
    },
    "table2_sigma_f_0.2": {
        "sigma_x": 0.075,
        "sigma_theta": 0.053,
        "sigma_gamma": 0.054,
        "sigma_psi": 0.013,
    },
    "table2_sigma_f_1.0": {
        "sigma_x": 0.240,
        "sigma_theta": 0.056,
        "sigma_gamma": 0.061,
        "sigma_psi": 0.031,
    },
}

#: (stride length m, accelerometer noise m/s²) of each configuration.
SETTINGS: dict[str, tuple[float, float]] = {
    "table1_step_0.5m": (0.5, 0.1),
    "table1_step_1.0m": (1.0, 0.1),
    "table2_sigma_f_0.1": (1.0, 0.1),
    "table2_sigma_f_0.2": (1.0, 0.2),
    "table2_sigma_f_1.0": (1.0, 1.0),
}

SQUARE_SIDE_M = 5.0
RATE_HZ = 100.0  # paper 003: Δt = 0.01 s
GYRO_STD = 0.05  # rad/s
DRIFT_STD = 0.02  # rad/s
#: Per-axis std of gyro noise plus drift, for threshold sizing.
GYRO_TOTAL_STD = float(np.hypot(GYRO_STD, DRIFT_STD))


@dataclass
class PaperRun:
    """Truth, filter output and metrics of one configuration."""

    truth: FootTrajectory
    run: ZuptRun
    metrics: dict[str, float]


def scenario(stride_length_m: float, square_side_m: float = SQUARE_SIDE_M) -> FootTrajectory:
    """The paper's square walk for one stride length (identical for every run)."""
    return simulate_foot(square_route(square_side_m, paper_stride_shape(stride_length_m)))


def run_config(
    stride_length_m: float,
    accel_noise_std: float,
    runs: int,
    seed: int = 0,
    drift_model: DriftModel = DriftModel.PER_GAIT_STEP,
    resized_thresholds: bool = False,
    square_side_m: float = SQUARE_SIDE_M,
) -> PaperRun:
    """Monte-Carlo runs of one configuration, batched over runs."""
    if runs < 1:
        raise ValueError(f"runs must be ≥ 1, got {runs!r}")
    truth = scenario(stride_length_m, square_side_m)
    spec = ImuSpec.paper003(GYRO_STD, accel_noise_std, DRIFT_STD, RATE_HZ, drift_model)
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(runs)]
    imu = simulate_imu(
        np.repeat(truth.omega_b, runs, axis=0),
        np.repeat(truth.f_b, runs, axis=0),
        RATE_HZ,
        spec,
        rngs,
        gait_step_index=np.repeat(truth.gait_step, runs, axis=0),
    )
    detector = (
        ThresholdDetectorConfig.sized_for_noise(GYRO_TOTAL_STD, accel_noise_std)
        if resized_thresholds
        else ThresholdDetectorConfig()
    )
    ukf = ZuptUkf(ZuptUkfConfig(detector=detector, assumed_imu=spec), RATE_HZ, runs)
    run = ukf.run(imu.omega_b, imu.f_b)
    return PaperRun(truth, run, error_metrics(truth, run))


def error_metrics(truth: FootTrajectory, run: ZuptRun) -> dict[str, float]:
    """σ[δx], σ[δθ], σ[δγ], σ[δψ] and detection statistics of a batch."""
    k = run.start_sample  # navigation starts after the alignment window
    x = run.x[:, k:]
    pos_err = np.linalg.norm(x[..., :3] - truth.pos_n[:, k:], axis=-1)
    e = truth.euler[:, k:]
    true_stance = np.broadcast_to(truth.stance, run.stance.shape)[:, k:]
    detected = run.stance[:, k:]
    strides = int(truth.gait_step.max())
    return {
        "sigma_x": float(np.sqrt(np.mean(pos_err**2))),
        "sigma_theta": float(np.sqrt(np.mean(wrap_angle(x[..., 6] - e[..., 1]) ** 2))),
        "sigma_gamma": float(np.sqrt(np.mean(wrap_angle(x[..., 7] - e[..., 2]) ** 2))),
        "sigma_psi": float(np.sqrt(np.mean(wrap_angle(x[..., 8] - e[..., 0]) ** 2))),
        "zupts_per_stride": float(run.updates.mean() / max(strides, 1)),
        "missed_stance_pct": float(100 * np.mean(true_stance & ~detected) / np.mean(true_stance)),
        "false_stance_pct": float(100 * np.mean(~true_stance & detected) / np.mean(~true_stance)),
    }


def _rows(
    config: str, metrics: dict[str, float], paper: dict[str, float] | None
) -> list[ReproductionRow]:
    units = {
        "sigma_x": "m",
        "sigma_theta": "rad",
        "sigma_gamma": "rad",
        "sigma_psi": "rad",
        "zupts_per_stride": "1",
        "missed_stance_pct": "%",
        "false_stance_pct": "%",
    }
    return [
        ReproductionRow(config, k, units[k], None if paper is None else paper.get(k), v)
        for k, v in metrics.items()
    ]


def run(
    runs: int | None = None,
    seed: int = 0,
    plot_dir: str | Path | None = None,
    variants: bool = True,
    square_side_m: float = SQUARE_SIDE_M,
) -> ReproductionResult:
    """Tables 1 and 2 of paper 003, our values beside the paper's.

    Parameters
    ----------
    runs : Monte-Carlo runs per configuration (default 100).
    seed : root seed; every configuration uses the same run seeds.
    plot_dir : where to write the figures (None: no figures).
    variants : also run the drift-per-sample and resized-threshold readings.
    """
    runs = 100 if runs is None else int(runs)
    start = time.perf_counter()
    rows: list[ReproductionRow] = []
    results: dict[str, PaperRun] = {}
    for config, (stride, sigma_f) in SETTINGS.items():
        res = run_config(stride, sigma_f, runs, seed, square_side_m=square_side_m)
        results[config] = res
        rows += _rows(config, res.metrics, PAPER_TABLES[config])
    if variants:
        for config, (stride, sigma_f) in SETTINGS.items():
            res = run_config(
                stride, sigma_f, runs, seed, DriftModel.PER_SAMPLE, square_side_m=square_side_m
            )
            rows += _rows(f"{config}:drift_per_sample", res.metrics, None)
        for config in ("table2_sigma_f_0.2", "table2_sigma_f_1.0"):
            stride, sigma_f = SETTINGS[config]
            res = run_config(
                stride, sigma_f, runs, seed, resized_thresholds=True, square_side_m=square_side_m
            )
            rows += _rows(f"{config}:resized_thresholds", res.metrics, None)
    notes = [
        f"{runs} Monte-Carlo runs per configuration, seed {seed}; {SQUARE_SIDE_M:g} m square, "
        "1 s gait cycle; RMS over runs and all samples.",
        "sigma_x and sigma_psi grow with walk duration (yaw is unobservable by ZUPT); the paper "
        "prints neither its square size nor its cadence — see docs/REPRODUCTION.md.",
    ]
    if plot_dir is not None:
        notes.append(f"figures written to {write_figures(results, Path(plot_dir))}")
    return ReproductionResult("003", time.perf_counter() - start, rows, notes)


def write_figures(results: dict[str, PaperRun], out: Path) -> Path:
    """Fig. 7 analogue (truth vs estimate, one run) and error-vs-time curves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, config in zip(axes, ("table1_step_0.5m", "table1_step_1.0m"), strict=True):
        r = results[config]
        ax.plot(r.truth.pos_n[0, :, 0], r.truth.pos_n[0, :, 1], "k-", label="truth")
        ax.plot(r.run.x[0, :, 0], r.run.x[0, :, 1], "r--", label="ZUPT-UKF (run 0)")
        ax.set_aspect("equal")
        ax.set_xlabel("x₁ east (m)")
        ax.set_ylabel("x₂ north (m)")
        ax.set_title(config)
        ax.legend()
    fig.tight_layout()
    save_figure(fig, out / "paper003_trajectory.png", dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    for config, r in results.items():
        t = r.truth.t
        pos = np.sqrt(np.mean(np.sum((r.run.x[..., :3] - r.truth.pos_n) ** 2, -1), axis=0))
        yaw = np.sqrt(np.mean(wrap_angle(r.run.x[..., 8] - r.truth.euler[..., 0]) ** 2, axis=0))
        axes[0].plot(t, pos, label=config)
        axes[1].plot(t, yaw, label=config)
    axes[0].set_ylabel("RMS |δx| (m)")
    axes[1].set_ylabel("RMS δψ (rad)")
    axes[1].set_xlabel("time (s)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out / "paper003_errors.png", dpi=110)
    plt.close(fig)
    return out
