"""Paper 004 reproduction: Monte Carlo of the step-velocity fusion filter.

Setup (paper 004, "Sequence and results of simulation"): test motion model
l = 0.7 m, φ_min = 60°, T = 0.5 s → V = 1.4 m/s, ΔL = 0.7 m; K = 10 128 steps
(7 089.6 m, 84.4 min = one Schuler period); M = 10 000 runs; σ_a ∈ {0.1,
0.5, 1} m/s, σ_ε = 1e-6 1/s, σ_n = 0.5 m/s; both channels. Per run: the
true errors follow x(k) = Φ x(k−1) + w(k−1) from x(0); V̄^INS = V̄ + δV,
V̄^BM = V̄ + n (eqs 1–2); the filter of :mod:`pednav_env.nav.step_fusion_kf`
runs eqs (3)–(6).

Efficiency: P(k) and K(k) do not depend on the data, so one covariance
recursion (the engine's :func:`kf_predict` / :func:`kf_gain` /
:func:`joseph_update` on ``(C, 2, 3, 3)``) serves all runs, whose states are
then advanced by the same gain, x̂ = x̂⁻ + K (S − x̂⁻[0]), componentwise on
``(C, 2, M)`` arrays. All σ_a configurations run in one pass on common random
numbers (the same standard-normal draws scaled by each σ_a); per step only
the statistics over runs are kept (mean and std of e = δV − δV̂, the RMS of
the position error E − Ê), so memory stays flat.

Readings (docs/REPRODUCTION.md (papers 000/002/004)): filter x̂(0) = (0.3 m/s, 0,
0.1 °/h) — the printed ε̂(0) = 0.1 "1/s" read as 0.1 °/h — and P(0) =
diag(0.3², (1 mrad)², (0.1 °/h)²) (not printed); the true x(0) is drawn from
N(0, P(0)), so e(0) has covariance P(0) and mean −x̂(0): the mean error
shows the initial transient, then decays. Route: six equal legs (10 128 =
6 × 1 688 steps), azimuths 30°, 90°, …, 330° (the first is the printed 30°;
Fig. 2 is not in the text) — the metrics do not depend on it, because V̄
cancels in S and in E − Ê.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from pednav_env.constants import EARTH_RADIUS, STANDARD_GRAVITY
from pednav_env.files import save_figure
from pednav_env.gait.waist_walk import PAPER_STEPS, route_azimuths
from pednav_env.nav.step_fusion_kf import (
    H_DV,
    StepFusionConfig,
    joseph_update,
    kf_gain,
    kf_predict,
    repair_covariance,
)
from pednav_env.reproduce import ReproductionResult, ReproductionRow
from pednav_env.sensors.ins_error import CHANNEL_SIGN, schuler_transition

PAPER_RUNS = 10_000
SIGMA_A = (0.1, 0.5, 1.0)
#: Steps k ≥ TRANSIENT enter the agreement metrics (after the initial transient).
TRANSIENT = 30


@dataclass(frozen=True)
class MonteCarloStats:
    """Per-step statistics over runs, arrays (K+1, C, 2) (k = 0 … K), channel 0 east."""

    mean_error: np.ndarray  #: ē(k), m/s
    std_error: np.ndarray  #: σ̄(k) (unbiased), m/s
    sqrt_P: np.ndarray  #: sqrt(P(k)[0, 0]), m/s
    position_rmse: np.ndarray  #: Δ(k) = RMS over runs of E − Ê, m
    distance: np.ndarray  #: (K+1,) distance walked, m
    runs: int
    repairs: int


def monte_carlo(
    filters: list[StepFusionConfig],
    runs: int,
    steps: int,
    seed: int = 0,
    truth_init_std: tuple[float, float, float] | None = None,
    truth_init_zero: bool | list[bool] = False,
    step_period: float = 0.5,
    velocity: float = 1.4,
    block: int = 16,
) -> MonteCarloStats:
    """Run paper 004's Monte Carlo for several filter configurations at once.

    Parameters
    ----------
    filters : list of C StepFusionConfig
        The filter's model; the truth uses the same σ_a, σ_ε, σ_n (paper 004:
        "the accepted model of the errors"). All must share g, R_E, σ_ε, σ_n.
    runs, steps : int
        M and K.
    seed : int
        One ``SeedSequence(seed)`` generator drives the whole Monte Carlo: per
        step it draws a (3, 2, M) block [w_a, w_ε, n] of standard normals
        shared by all C configurations (common random numbers).
    truth_init_std : 3 floats, optional
        Std of the zero-mean true x(0); default the first filter's ``initial_std``.
    truth_init_zero : bool or list of C bools
        x(0) = 0 instead (another reading of the paper), for all or per configuration.
    step_period, velocity : float
        T (s) and V̄ (m/s) of the test motion model.
    block : int
        Steps per random-number block (speed only; results do not depend on it).
    """
    if runs < 2 or steps < 1:
        raise ValueError(f"runs must be ≥ 2 and steps ≥ 1, got runs={runs!r}, steps={steps!r}")
    if not filters:
        raise ValueError("filters: need at least one StepFusionConfig")
    f0 = filters[0]
    for f in filters:
        if (f.g, f.earth_radius, f.drift_noise_std, f.bm_noise_std) != (
            f0.g,
            f0.earth_radius,
            f0.drift_noise_std,
            f0.bm_noise_std,
        ):
            raise ValueError("filters must share g, earth_radius, drift_noise_std, bm_noise_std")
    C, M, K, T = len(filters), int(runs), int(steps), float(step_period)
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    std0 = np.asarray(f0.initial_std if truth_init_std is None else truth_init_std, dtype=float)

    # Shared covariance, one per configuration and channel: (C, 2, 3, 3).
    F = schuler_transition(np.full((1, 2), T), f0.g, f0.earth_radius, CHANNEL_SIGN[None, :])
    Q = np.stack([f.Q for f in filters])[:, None]
    R = f0.R
    P = np.broadcast_to(np.stack([f.P0 for f in filters])[:, None], (C, 2, 3, 3)).copy()
    x_dummy = np.zeros((C, 2, 3))

    # States (C, 2, M): truth, estimate, position error.
    x0 = rng.standard_normal((2, 3, M)) * std0[None, :, None]
    zero = np.broadcast_to(np.asarray(truth_init_zero, dtype=bool), (C,))
    x0 = np.where(zero[:, None, None, None], 0.0, x0[None])  # (C, 2, 3, M)
    dv = x0[:, :, 0].copy()
    beta = x0[:, :, 1].copy()
    eps = x0[:, :, 2].copy()
    est0 = np.stack([np.asarray(f.initial_estimate) for f in filters])  # (C, 3)
    dv_h = np.broadcast_to(est0[:, None, None, 0], (C, 2, M)).copy()
    beta_h = np.broadcast_to(est0[:, None, None, 1], (C, 2, M)).copy()
    eps_h = np.broadcast_to(est0[:, None, None, 2], (C, 2, M)).copy()
    dpos = np.zeros((C, 2, M))

    sig_a = np.array([f.accel_noise_std for f in filters])[:, None, None]
    sig_e, sig_n = f0.drift_noise_std, f0.bm_noise_std
    a_gT = (CHANNEL_SIGN * f0.g * T)[None, :, None]  # Φ[0,1] = −a_gT
    b_TR = (CHANNEL_SIGN * T / f0.earth_radius)[None, :, None]
    az = route_azimuths(K)
    vbar = velocity * np.stack((np.sin(az), np.cos(az)), axis=1)  # (K, 2) east, north

    mean_e = np.empty((K + 1, C, 2))
    std_e = np.empty((K + 1, C, 2))
    sqrt_P = np.empty((K + 1, C, 2))
    rmse = np.empty((K + 1, C, 2))
    e = dv - dv_h
    mean_e[0], std_e[0] = e.mean(-1), e.std(-1, ddof=1)
    sqrt_P[0] = np.sqrt(P[..., 0, 0])
    rmse[0] = 0.0
    repairs = 0
    tmp = np.empty((C, 2, M))
    noise = np.empty((block, 3, 2, M))
    for k in range(K):
        j = k % block
        if j == 0:
            rng.standard_normal(out=noise[: min(block, K - k)])
        w_a = noise[j, 0] * sig_a  # (C, 2, M), common numbers scaled per config
        w_e = noise[j, 1] * sig_e
        n_bm = noise[j, 2] * sig_n
        # Covariance (shared by all runs): predict, gain, Joseph update, repair.
        _, P_prior = kf_predict(x_dummy, P, F, Q)
        Kg, _ = kf_gain(P_prior, H_DV, R)
        P, bad = repair_covariance(joseph_update(P_prior, Kg, H_DV, R))
        repairs += int(bad.sum())
        Kg = Kg[..., 0][..., None]  # (C, 2, 3, 1) → gains per state
        # Truth: x(k) = Φ x(k−1) + w(k−1).
        np.multiply(beta, a_gT, out=tmp)
        beta += b_TR * dv + T * eps
        dv -= tmp
        dv += w_a
        eps += w_e
        # Filter prior x̂⁻ = Φ x̂(k−1).
        np.multiply(beta_h, a_gT, out=tmp)
        beta_h += b_TR * dv_h + T * eps_h
        dv_h -= tmp
        # Measurements: V̄^INS = V̄ + δV, V̄^BM = V̄ + n, S = V̄^INS − V̄^BM (eqs 1–3).
        v_ins = vbar[k][None, :, None] + dv
        v_bm = vbar[k][None, :, None] + n_bm
        # Position: Ê += T (V̄^INS − δV̂⁻), E += T V̄ (eqs 5–6) → E − Ê.
        dpos += T * (vbar[k][None, :, None] - (v_ins - dv_h))
        # Update x̂ = x̂⁻ + K (S − x̂⁻[0]).
        np.subtract(v_ins - v_bm, dv_h, out=tmp)
        beta_h += Kg[..., 1, :] * tmp
        eps_h += Kg[..., 2, :] * tmp
        dv_h += Kg[..., 0, :] * tmp
        np.subtract(dv, dv_h, out=tmp)
        mean_e[k + 1] = tmp.mean(-1)
        std_e[k + 1] = tmp.std(-1, ddof=1)
        sqrt_P[k + 1] = np.sqrt(P[..., 0, 0])
        rmse[k + 1] = np.sqrt(np.mean(dpos * dpos, axis=-1))
    distance = np.arange(K + 1) * velocity * T
    return MonteCarloStats(mean_e, std_e, sqrt_P, rmse, distance, M, repairs)


def summarise(stats: MonteCarloStats, transient: int = TRANSIENT) -> dict[str, np.ndarray]:
    """Contract metrics per configuration (C,), worst of the two channels."""
    sl = slice(transient, None)
    rel = np.abs(stats.std_error[sl] - stats.sqrt_P[sl]) / stats.sqrt_P[sl]
    return {
        "max_abs_mean_error": np.abs(stats.mean_error[sl]).max(axis=(0, 2)),
        "max_rel_diff_sigma_vs_sqrtP": rel.max(axis=(0, 2)),
        "final_position_rmse_pct": (100.0 * stats.position_rmse[-1] / stats.distance[-1]).max(-1),
    }


def run(
    runs: int | None = None,
    seed: int = 0,
    *,
    steps: int | None = None,
    sigma_a: tuple[float, ...] = SIGMA_A,
    base: StepFusionConfig | None = None,
    variants: bool = True,
    plot_dir: str | Path | None = None,
) -> ReproductionResult:
    """Reproduce paper 004's Monte Carlo (default full size: M = 10 000, K = 10 128).

    Parameters
    ----------
    runs, steps : int, optional
        M and K (tests use small values).
    seed : int
    sigma_a : tuple
        σ_a values (m/s per step), one config each (``sigma_a_<value>``).
    base : StepFusionConfig, optional
        Everything but σ_a; default paper 004 with our reading of x̂(0), P(0).
    variants : bool
        Also run, at σ_a = 0.5 and M/10 runs, the other readings of the initial
        conditions: ``:truth_zero_init`` (x(0) = 0), ``:eps0_literal_narrow_P0``
        (ε̂(0) = 0.1 rad/s, P(0) as the default) and ``:eps0_literal_wide_P0``
        (ε̂(0) = 0.1 rad/s with σ_ε0 = 0.1 rad/s in P(0)).
    plot_dir : path, optional
        Write ``paper004_mean.png``, ``paper004_sigma.png`` (Figs. 3–5) and
        ``paper004_position.png`` (Fig. 6, with the 3 % line) there.
    """
    start = time.perf_counter()
    M = PAPER_RUNS if runs is None else int(runs)
    K = PAPER_STEPS if steps is None else int(steps)
    base = (
        base
        if base is not None
        else StepFusionConfig(g=STANDARD_GRAVITY, earth_radius=EARTH_RADIUS)
    )
    filters = [replace(base, accel_noise_std=s) for s in sigma_a]
    stats = monte_carlo(filters, M, K, seed)
    summary = summarise(stats, min(TRANSIENT, K))
    seconds = time.perf_counter() - start
    names = [f"sigma_a_{float(s)!r}" for s in sigma_a]
    M_var = 0
    if variants:
        # Other readings of the printed initial conditions, at σ_a = 0.5, reduced M.
        M_var = max(2, M // 10)
        mid = replace(base, accel_noise_std=0.5)
        literal = (base.initial_estimate[0], base.initial_estimate[1], 0.1)
        var_filters = [
            mid,
            replace(mid, initial_estimate=literal),
            replace(mid, initial_estimate=literal, initial_std=(*base.initial_std[:2], 0.1)),
        ]
        var_stats = monte_carlo(
            var_filters,
            M_var,
            K,
            seed + 1,
            truth_init_std=base.initial_std,
            truth_init_zero=[True, False, False],
        )
        var_summary = summarise(var_stats, min(TRANSIENT, K))
        names += [
            "sigma_a_0.5:truth_zero_init",
            "sigma_a_0.5:eps0_literal_narrow_P0",
            "sigma_a_0.5:eps0_literal_wide_P0",
        ]
        summary = {k: np.concatenate((summary[k], var_summary[k])) for k in summary}
    rows: list[ReproductionRow] = []
    for c, cfg in enumerate(names):
        M_row = M if c < len(sigma_a) else M_var
        rows += [
            ReproductionRow(
                cfg, "max_abs_mean_error", "m/s", None, float(summary["max_abs_mean_error"][c])
            ),
            ReproductionRow(
                cfg,
                "max_rel_diff_sigma_vs_sqrtP",
                "",
                None,
                float(summary["max_rel_diff_sigma_vs_sqrtP"][c]),
            ),
            ReproductionRow(
                cfg,
                "final_position_rmse_pct",
                "%",
                None,
                float(summary["final_position_rmse_pct"][c]),
            ),
            ReproductionRow(cfg, "runs", "", float(PAPER_RUNS), float(M_row)),
            ReproductionRow(cfg, "steps", "", float(PAPER_STEPS), float(K)),
        ]
    east_final = 100.0 * stats.position_rmse[-1, :, 0] / stats.distance[-1]
    notes = [
        "paper prints no numbers for these metrics: ē ≈ 0 ('almost unbiased'), σ̄ 'in good "
        "agreement' with sqrt(P[0,0]), position RMSE far below the 3 % line (its Figs. 3–6)",
        f"metrics over steps k ≥ {TRANSIENT}, worst of east/north; east-channel final RMSE "
        + ", ".join(f"{p:.3f} %" for p in east_final),
        f"Monte Carlo sampling: std of a sample mean ≈ σ/√M, of σ̄/σ ≈ 1/√(2M) = "
        f"{1 / math.sqrt(2 * M):.4f}; covariance repairs: {stats.repairs}",
        f"main Monte Carlo {seconds:.1f} s for M = {M}, K = {K}, {len(sigma_a)} configs × 2 "
        f"channels; variant rows use M = {M_var}",
    ]
    if plot_dir is not None:
        _plots(Path(plot_dir), stats, sigma_a)
    return ReproductionResult("004", time.perf_counter() - start, rows, notes)


def _plots(out: Path, stats: MonteCarloStats, sigma_a: tuple[float, ...]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    k = np.arange(stats.mean_error.shape[0])
    fig, ax = plt.subplots(figsize=(6, 4))
    for c, s in enumerate(sigma_a):
        ax.plot(k[:31], stats.mean_error[:31, c, 0], "o-", ms=3, label=f"σ_a = {s:g}")
    ax.set_xlabel("step k")
    ax.set_ylabel("ē_E (m/s)")
    ax.legend()
    save_figure(fig, out / "paper004_mean.png", dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4))
    for c, s in enumerate(sigma_a):
        ax.plot(k, stats.std_error[:, c, 0], "-", label=f"σ̄_E, σ_a = {s:g}")
        ax.plot(k, stats.sqrt_P[:, c, 0], "k--", lw=0.8)
    ax.set_xscale("symlog", linthresh=30)
    ax.set_xlabel("step k")
    ax.set_ylabel("m/s (dashed: sqrt P[0,0])")
    ax.legend()
    save_figure(fig, out / "paper004_sigma.png", dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4))
    for c, s in enumerate(sigma_a):
        ax.plot(stats.distance, stats.position_rmse[:, c, 0], label=f"σ_a = {s:g}")
    ax.plot(stats.distance, 0.03 * stats.distance, "k--", label="3 %")
    ax.set_xlabel("distance R (m)")
    ax.set_ylabel("Δ_E (m)")
    ax.legend()
    save_figure(fig, out / "paper004_position.png", dpi=100)
    plt.close(fig)
