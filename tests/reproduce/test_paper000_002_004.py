"""Small reproductions of papers 000, 002 and 004 (full sizes: docs/REPRODUCTION.md)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from pednav_env import reproduce
from pednav_env.gait.waist_walk import route_azimuths
from pednav_env.nav.step_fusion_kf import StepFusionConfig, StepFusionKF
from pednav_env.reproduce import paper002, paper004
from pednav_env.sensors.ins_error import schuler_transition


def _rows(result: reproduce.ReproductionResult) -> dict[tuple[str, str], reproduce.ReproductionRow]:
    return {(r.config, r.metric): r for r in result.rows}


# ----------------------------------------------------------------------------- 000
def test_paper000_digits_and_contract() -> None:
    res = reproduce.run("000")
    rows = _rows(res)
    contract = (
        "vbar_true",
        "vbar_from_ax",
        "vbar_from_h",
        "max_velocity_error",
        "max_position_error",
    )
    assert all(("paper", m) in rows for m in contract)
    # Printed to 8 decimals: agreement to rounding (5e-9) singles out the rule.
    assert abs(rows["paper", "vbar_from_ax"].ours - 1.39994406) < 5e-9
    assert abs(rows["paper", "vbar_from_h"].ours - 1.39999891) < 5e-9
    assert rows["paper", "vbar_true"].ours == pytest.approx(1.4, abs=1e-12)
    # "Of the order of 1e-5": within one decade either side.
    for m in ("max_velocity_error", "max_position_error"):
        assert 1e-6 <= rows["paper", m].ours <= 1e-4
    # The rectangle rule misses the printed digits by far more than rounding.
    assert abs(rows["paper:rectangle_rule", "vbar_from_ax"].ours - 1.39994406) > 1e-3
    json.loads(res.to_json())


# ----------------------------------------------------------------------------- 002
def test_paper002_contract_rows_and_hypotheses() -> None:
    res = paper002.run(runs=3)
    rows = _rows(res)
    assert ("no_oscillation", "end_miss") in rows and ("no_oscillation", "end_miss_pct") in rows
    for cfg in ("roll_only", "pitch_only", "yaw_only"):
        assert (cfg, "slope") in rows and (cfg, "intercept") in rows
    assert rows["pitch_only", "slope"].paper == 45.85
    assert rows["yaw_only", "slope"].paper is None
    r0 = rows["no_oscillation", "end_miss"].ours
    assert rows["no_oscillation", "end_miss_pct"].ours == pytest.approx(100 * r0 / 16.0)
    # Grid-aligned corners: the one-sample yaw-offset mechanism (see
    # test_waist_dr.py) gives ≈ 0.53 m; the paper's 0.57 m is read off its Fig. 6
    # and rounded — accept ±15 %.
    assert rows["no_oscillation:grid_aligned", "end_miss"].ours == pytest.approx(0.57, rel=0.15)
    # Mᵀ-for-M⁻¹ hypothesis: pitch errors of the paper's order of magnitude (its
    # sweep range, g and corner timing are unknown — accept a factor of 2), while
    # the printed scheme stays two orders below.
    assert 0.5 < rows["pitch_only:kinematic_transpose", "slope"].ours / 45.85 < 2.0
    assert rows["pitch_only", "slope"].ours < 0.1 * 45.85


# ----------------------------------------------------------------------------- 004
def _exact_moments(
    cfg: StepFusionConfig, steps: int, T: float = 0.5
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact mean/std of e = δV − δV̂, RMS of E − Ê and sqrt(P00), east channel.

    Independent of the Monte Carlo code: the augmented linear system
    z = [x (3), x̂ (3), E − Ê] driven by [w_a, w_ε, n] propagated in mean and
    covariance, with the gains of a plain (textbook) covariance recursion.
    """
    Phi = schuler_transition(T, cfg.g, cfg.earth_radius, 1.0)
    Q, R, P = cfg.Q, cfg.R[0, 0], cfg.P0.copy()
    mean = np.zeros(7)
    mean[3:6] = cfg.initial_estimate
    cov = np.zeros((7, 7))
    cov[:3, :3] = cfg.P0
    W = np.diag([cfg.accel_noise_std**2, cfg.drift_noise_std**2, R])
    out = np.zeros((steps + 1, 4))
    e = np.array([1, 0, 0, -1, 0, 0, 0.0])
    out[0] = [e @ mean, math.sqrt(e @ cov @ e), 0.0, math.sqrt(P[0, 0])]
    for k in range(steps):
        Pp = Phi @ P @ Phi.T + Q
        K = Pp[:, 0] / (Pp[0, 0] + R)
        P = (np.eye(3) - np.outer(K, [1, 0, 0])) @ Pp
        A = np.zeros((7, 7))
        B = np.zeros((7, 3))
        A[:3, :3] = Phi
        B[0, 0], B[2, 1] = 1.0, 1.0  # w_a → δV, w_ε → ε
        # x̂ = Φx̂ + K(δV_k − n − (Φx̂)[0]), δV_k = (Φx)[0] + w_a
        A[3:6, 3:6] = Phi - np.outer(K, Phi[0])
        A[3:6, :3] = np.outer(K, Phi[0])
        B[3:6, 0] = K
        B[3:6, 2] = -K
        # E − Ê += −T (δV_k − (Φx̂)[0])
        A[6, 6] = 1.0
        A[6, :3] = -T * Phi[0]
        A[6, 3:6] = T * Phi[0]
        B[6, 0] = -T
        mean = A @ mean
        cov = A @ cov @ A.T + B @ W @ B.T
        rms = math.sqrt(cov[6, 6] + mean[6] ** 2)
        out[k + 1] = [e @ mean, math.sqrt(e @ cov @ e), rms, math.sqrt(P[0, 0])]
    return out[:, 0], out[:, 1], out[:, 2], out[:, 3]


def test_paper004_monte_carlo_matches_exact_moments() -> None:
    # M = 400 runs: the std of a sample mean is σ/20, of a sample std σ/28, of a
    # sample mean square 7 %; bounds of 5 such standard errors at each step
    # (about 1e-6 false-alarm per step, 1e-4 over the 120 steps).
    M, K = 400, 120
    cfgs = [StepFusionConfig(accel_noise_std=s) for s in (0.1, 1.0)]
    stats = paper004.monte_carlo(cfgs, M, K, seed=5)
    for c, cfg in enumerate(cfgs):
        mean, std, rms, sqrt_p = _exact_moments(cfg, K)
        np.testing.assert_allclose(stats.sqrt_P[:, c, 0], sqrt_p, rtol=1e-10)
        # With x(0) ~ N(0, P0) the error covariance is P(k) exactly (the claim the
        # paper's Figs. 4–5 check): exact std equals sqrt(P00).
        np.testing.assert_allclose(std, sqrt_p, rtol=1e-9)
        assert np.all(np.abs(stats.mean_error[:, c, 0] - mean) <= 5 * std / math.sqrt(M))
        assert np.all(np.abs(stats.std_error[:, c, 0] / std - 1) <= 5 / math.sqrt(2 * M))
        ms = stats.position_rmse[1:, c, 0] ** 2 / rms[1:] ** 2
        assert np.all(np.abs(ms - 1) <= 5 * math.sqrt(2 / M))
        # The initial transient: mean error starts at −δV̂(0) = −0.3 m/s.
        assert mean[0] == pytest.approx(-0.3)


def test_paper004_shortcut_equals_engine() -> None:
    # The Monte Carlo's shared-gain state recursion must equal the batched engine
    # (StepFusionKF, one walker per run) fed with the same draws (block = 1).
    M, K, seed = 50, 40, 9
    cfg = StepFusionConfig(accel_noise_std=0.5)
    stats = paper004.monte_carlo([cfg], M, K, seed=seed, block=1)
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    x0 = rng.standard_normal((2, 3, M)) * np.asarray(cfg.initial_std)[None, :, None]
    x = np.moveaxis(x0, 2, 0).copy()  # (M, 2, 3)
    Phi = schuler_transition(np.full((1, 2), 0.5), cfg.g, cfg.earth_radius)
    kf = StepFusionKF(cfg, M)
    az = route_azimuths(K)
    E = np.zeros((M, 2))
    for k in range(K):
        wa, we, n = rng.standard_normal((1, 3, 2, M))[0]
        x = np.einsum("ncij,mcj->mci", Phi, x)
        x[..., 0] += cfg.accel_noise_std * wa.T
        x[..., 2] += cfg.drift_noise_std * we.T
        vbar = 1.4 * np.array([math.sin(az[k]), math.cos(az[k])])
        kf.step(vbar + x[..., 0], vbar + cfg.bm_noise_std * n.T, np.full(M, 0.5))
        E += 0.5 * vbar
        e = x[..., 0] - kf.x[..., 0]
        np.testing.assert_allclose(stats.mean_error[k + 1, 0], e.mean(0), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(stats.std_error[k + 1, 0], e.std(0, ddof=1), rtol=1e-9)
        rms = np.sqrt(np.mean((E - kf.pos) ** 2, axis=0))
        np.testing.assert_allclose(stats.position_rmse[k + 1, 0], rms, rtol=1e-8)


def test_paper004_deterministic_and_block_independent() -> None:
    cfgs = [StepFusionConfig(accel_noise_std=0.5)]
    a = paper004.monte_carlo(cfgs, 30, 50, seed=1, block=16)
    b = paper004.monte_carlo(cfgs, 30, 50, seed=1, block=7)
    c = paper004.monte_carlo(cfgs, 30, 50, seed=2, block=16)
    for name in ("mean_error", "std_error", "position_rmse"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert not np.array_equal(getattr(a, name), getattr(c, name))


def test_paper004_contract_rows() -> None:
    res = reproduce.run("004", runs=200, steps=100)
    rows = _rows(res)
    for cfg in ("sigma_a_0.1", "sigma_a_0.5", "sigma_a_1.0"):
        for m in ("max_abs_mean_error", "max_rel_diff_sigma_vs_sqrtP", "final_position_rmse_pct"):
            assert (cfg, m) in rows and math.isfinite(rows[cfg, m].ours)
        assert rows[cfg, "runs"].ours == 200 and rows[cfg, "runs"].paper == 10_000
        assert rows[cfg, "steps"].ours == 100 and rows[cfg, "steps"].paper == 10_128
    # The literal ε̂(0) = 0.1 rad/s with a narrow P(0) wrecks the filter (metres per
    # second of mean error); with a wide P(0) it is learned within the transient and
    # the mean error is Monte Carlo noise: ≤ 5σ/√M = 5·0.4/√20 ≈ 0.45 m/s for the
    # M/10 = 20 variant runs.
    assert rows["sigma_a_0.5:eps0_literal_narrow_P0", "max_abs_mean_error"].ours > 2.0
    assert rows["sigma_a_0.5:eps0_literal_wide_P0", "max_abs_mean_error"].ours < 0.45


def test_paper004_rejects_bad_sizes() -> None:
    with pytest.raises(ValueError, match="runs"):
        paper004.monte_carlo([StepFusionConfig()], 1, 10)
    with pytest.raises(ValueError, match="filters"):
        paper004.monte_carlo([StepFusionConfig(), StepFusionConfig(bm_noise_std=0.2)], 10, 10)
