"""Heel–knee gait model of paper 001 (pednav_env.gait.heel_knee)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from pednav_env.gait.heel_knee import HeelKneeConfig, simulate_heel_knee
from pednav_env.gait.heel_knee_model import I_AX, I_CX, I_OMEGA, HeelKneeNominal, process_model
from pednav_env.nav.marker_model import heel_knee_positions


def rngs(seed: int, n: int) -> list[np.random.Generator]:
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


def test_paper_nominal_values() -> None:
    nom = HeelKneeNominal()
    # Thesis §4.2 prints ω₀ = 8.976 rad/s for τ₀ = 0.7 s (eq 4.8).
    assert nom.omega == pytest.approx(8.976, abs=5e-4)
    assert (nom.heel_x_amplitude, nom.heel_z_amplitude) == (0.4, 0.1)
    assert (nom.heel_x_speed, nom.heel_z_offset, nom.shank_length) == (3.0, 0.1, 0.5)
    # Our A⁰: straight leg of length 2M, heel excursion A_x⁰ → sin|A⁰| = 0.4 / 1.0.
    assert math.sin(-nom.shank_angle_amplitude) == pytest.approx(0.4, rel=1e-12)


def test_positions_follow_eq_4_10_written_out() -> None:
    # p = [A_x, A_z, c_x, c_z, A, ω]; scalar formulas of eq 4.10 typed out by hand.
    p = [0.37, 0.12, 2.6, 0.09, -0.3, 7.9]
    M = 0.48
    for t in (0.0, 0.3, 1.7, 12.05):
        phi = p[5] * t
        x1 = p[2] * t + p[0] * math.sin(phi)
        z1 = p[3] + p[1] * math.sin(phi)
        beta = p[4] * math.sin(phi)
        want = [[x1, z1], [x1 + M * math.sin(beta), z1 + M * math.cos(beta)]]
        np.testing.assert_allclose(heel_knee_positions(p, t, M), want, rtol=0, atol=1e-13)


@pytest.mark.parametrize("kinematics", ["paper", "integrated"])
def test_shank_length_is_preserved(kinematics: str) -> None:
    cfg = HeelKneeConfig(param_corr_time=5.0, kinematics=kinematics, initial_deviation="stationary")
    walk = simulate_heel_knee(cfg, 300, rngs(1, 4))
    dist = np.linalg.norm(walk.knee - walk.heel, axis=-1)
    np.testing.assert_allclose(dist, cfg.nominal.shank_length, rtol=1e-12)


def test_process_model_stationary_variance_by_iteration() -> None:
    # Iterate the variance recursion v ← F v F + Γ Q Γ (eq 4.11) to its fixed
    # point and compare with 0.03 · p⁰² (our reading of eqs 5.4, 5.8).
    nom = HeelKneeNominal().vector
    proc = process_model(0.9, 0.03, nom)
    v = np.zeros(6)
    for _ in range(2000):
        v = proc.F**2 * v + proc.Gamma**2 * proc.Q
    np.testing.assert_allclose(v, 0.03 * nom**2, rtol=1e-10)
    np.testing.assert_allclose(proc.P0, 0.03 * nom**2, rtol=1e-12)
    assert np.all(proc.F == 0.9) and np.allclose(proc.Gamma, 0.1)


def test_simulated_deviations_have_the_stated_statistics() -> None:
    # τ = 1 s at T = 0.1 s: d = e^{-0.1}. 20 walkers × 2000 samples of an AR(1)
    # with ρ = d give ≈ 40000 (1 − ρ)/(1 + ρ) ≈ 2000 effective samples, so the
    # variance estimate has a relative s.e. ≈ sqrt(2/2000) ≈ 3.2 %; the lag-1
    # correlation an s.e. ≈ sqrt((1 − ρ²)/40000) ≈ 0.002. Tolerances ≈ 4–5 s.e.
    cfg = HeelKneeConfig(param_corr_time=1.0, initial_deviation="stationary")
    walk = simulate_heel_knee(cfg, 2000, rngs(2, 20))
    dev = walk.deviation
    var = np.mean(dev**2, axis=(0, 1))
    want = 0.03 * cfg.nominal.vector**2
    np.testing.assert_allclose(var, want, rtol=0.15)
    rho = np.sum(dev[:, 1:] * dev[:, :-1], axis=(0, 1)) / np.sum(dev[:, :-1] ** 2, axis=(0, 1))
    np.testing.assert_allclose(rho, math.exp(-0.1), atol=0.01)


def test_zero_initial_deviation_starts_at_nominal() -> None:
    cfg = HeelKneeConfig()
    walk = simulate_heel_knee(cfg, 50, rngs(3, 3))
    assert np.all(walk.deviation[:, 0] == 0.0)
    nom = cfg.nominal
    # t = 0: heel at (0, c_z⁰), knee straight above it (sin 0 = 0 ⇒ β = 0).
    np.testing.assert_allclose(walk.markers[:, 0, 0], [[0.0, 0.1]] * 3, atol=1e-15)
    np.testing.assert_allclose(walk.markers[:, 0, 1], [[0.0, 0.1 + nom.shank_length]] * 3)


def test_constant_parameters_make_both_kinematics_agree() -> None:
    base = HeelKneeConfig(param_var_ratio=0.0)
    a = simulate_heel_knee(base, 200, rngs(4, 2))
    b = simulate_heel_knee(replace(base, kinematics="integrated"), 200, rngs(4, 2))
    np.testing.assert_allclose(a.markers, b.markers, rtol=0, atol=1e-9)
    # and the heel advances at c_x⁰ on average over whole cycles
    t = a.t
    assert a.heel[0, -1, 0] == pytest.approx(
        3.0 * t[-1] + 0.4 * math.sin(base.nominal.omega * t[-1])
    )


def test_paper_kinematics_are_rough_late_in_a_walk_integrated_are_not() -> None:
    # Mechanism documented in docs/REPRODUCTION.md (paper 001): eq 4.10 multiplies the
    # parameters' sample-to-sample jitter by kT. With τ = 10 s, T = 0.1 s a
    # deviation jumps per sample by sqrt(1 − d²) ≈ 0.141 of its stationary std
    # (σ_c = 0.520 m/s, σ_ω = 1.555 rad/s), so for t in [15, 20] s (rms 17.5 s)
    # the literal heel x jumps by ≈ 17.5 · 0.141 · sqrt(σ_c² + A_x² σ_ω² / 2)
    # ≈ 1.68 m rms, ≈ 1.72 m with the nominal travel (≈ 0.39 m rms) added in
    # quadrature. 8 walkers × 49 steps give the rms to ≈ 4 %; the 25 %
    # tolerance also covers the cos² ≈ 1/2 approximation.
    cfg = HeelKneeConfig(param_corr_time=10.0, initial_deviation="stationary")
    lit = simulate_heel_knee(cfg, 200, rngs(5, 8))
    smooth = simulate_heel_knee(replace(cfg, kinematics="integrated"), 200, rngs(5, 8))
    late = slice(150, None)
    step_lit = np.diff(lit.heel[:, late, 0], axis=1)
    step_int = np.diff(smooth.heel[:, late, 0], axis=1)
    assert np.sqrt(np.mean(step_lit**2)) == pytest.approx(1.72, rel=0.25)
    # integrated: never more than the fastest nominal heel travel (with the
    # deviations' ≈ 3σ excursions: speed ≤ c⁰ + 3σ_c + (A_x⁰ + 3σ_A)(ω₀ + 3σ_ω)) per sample.
    nom = cfg.nominal
    s = math.sqrt(0.03)
    vmax = nom.heel_x_speed * (1 + 3 * s) + nom.heel_x_amplitude * nom.omega * (1 + 3 * s) ** 2
    assert np.max(np.abs(step_int)) < vmax * cfg.sample_period


def test_gait_changes_stay_in_range_and_are_continuous() -> None:
    cfg = HeelKneeConfig(
        param_var_ratio=0.0,
        kinematics="integrated",
        gait_change_rate_hz=0.2,
        cadence_factor_range=(0.8, 1.1),
        stride_factor_range=(0.6, 1.0),
    )
    walk = simulate_heel_knee(cfg, 1200, rngs(6, 6))
    nom = cfg.nominal
    omega = walk.nominal[..., I_OMEGA] / nom.omega
    stride = walk.nominal[..., I_AX] / nom.heel_x_amplitude
    assert omega.min() >= 0.8 - 1e-12 and omega.max() <= 1.1 + 1e-12
    assert stride.min() >= 0.6 - 1e-12 and stride.max() <= 1.0 + 1e-12
    # speed = stride × cadence (the coupling stated in the module docstring)
    np.testing.assert_allclose(walk.nominal[..., I_CX], nom.heel_x_speed * omega * stride)
    # some walker actually changed gait within the 120 s walk
    assert np.ptp(omega, axis=1).max() > 0.05
    # the phase advances at the instantaneous frequency (trapezoid integral)
    dphi = np.diff(walk.phase, axis=1) / cfg.sample_period
    mid = 0.5 * (walk.params[:, 1:, I_OMEGA] + walk.params[:, :-1, I_OMEGA])
    np.testing.assert_allclose(dphi, mid, rtol=1e-9)
    # no jumps: per-sample heel motion bounded by the fastest gait's max speed
    vmax = nom.heel_x_speed * 1.1 + nom.heel_x_amplitude * nom.omega * 1.1
    assert np.max(np.abs(np.diff(walk.heel[..., 0], axis=1))) <= vmax * cfg.sample_period * 1.05


def test_determinism_and_walker_independence() -> None:
    cfg = HeelKneeConfig(
        param_corr_time=20.0,
        initial_deviation="stationary",
        kinematics="integrated",
        gait_change_rate_hz=0.1,
        cadence_factor_range=(0.8, 1.2),
    )
    a = simulate_heel_knee(cfg, 300, rngs(7, 5))
    b = simulate_heel_knee(cfg, 300, rngs(7, 5))
    assert np.array_equal(a.markers, b.markers) and np.array_equal(a.deviation, b.deviation)
    for i, g in enumerate(rngs(7, 5)):
        one = simulate_heel_knee(cfg, 300, [g])
        assert np.array_equal(one.markers[0], a.markers[i])
        assert np.array_equal(one.params[0], a.params[i])
    c = simulate_heel_knee(cfg, 300, rngs(8, 5))
    assert not np.array_equal(a.markers, c.markers)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"sample_period": 0.0}, "sample_period"),
        ({"sample_period": -0.1}, "sample_period"),
        ({"sample_period": math.nan}, "sample_period"),
        ({"param_var_ratio": -0.03}, "param_var_ratio"),
        ({"param_corr_time": 0.0}, "param_corr_time"),
        ({"param_corr_time": math.inf}, "param_corr_time"),
        ({"kinematics": "spline"}, "kinematics"),
        ({"initial_deviation": "random"}, "initial_deviation"),
        ({"gait_change_rate_hz": -1.0}, "gait_change_rate_hz"),
        ({"gait_change_rate_hz": 0.1}, "gait_change_rate_hz"),  # needs integrated
        ({"cadence_factor_range": (1.2, 0.8)}, "cadence_factor_range"),
        ({"stride_factor_range": (0.0, 1.0)}, "stride_factor_range"),
        ({"gait_transition_time": 0.0}, "gait_transition_time"),
    ],
)
def test_config_rejects_impossible_values(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        HeelKneeConfig(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"stride_period": 0.0}, "stride_period"),
        ({"shank_length": -0.5}, "shank_length"),
        ({"heel_x_speed": math.nan}, "heel_x_speed"),
        ({"heel_z_amplitude": math.inf}, "heel_z_amplitude"),
        ({"shank_angle_amplitude": 2.0}, "shank_angle_amplitude"),
    ],
)
def test_nominal_rejects_impossible_values(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        HeelKneeNominal(**kwargs)


def test_simulate_and_process_model_reject_bad_arguments() -> None:
    cfg = HeelKneeConfig()
    with pytest.raises(ValueError, match="num_samples"):
        simulate_heel_knee(cfg, 0, rngs(0, 1))
    with pytest.raises(ValueError, match="rngs"):
        simulate_heel_knee(cfg, 10, np.random.default_rng(0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rngs"):
        simulate_heel_knee(cfg, 10, [])
    with pytest.raises(ValueError, match=r"rngs\[1\]"):
        simulate_heel_knee(cfg, 10, [np.random.default_rng(0), 3])  # type: ignore[list-item]
    with pytest.raises(ValueError, match="inertia"):
        process_model(1.0, 0.03, np.ones(6))
    with pytest.raises(ValueError, match="var_ratio"):
        process_model(0.5, -1.0, np.ones(6))
    with pytest.raises(ValueError, match="nominal"):
        process_model(0.5, 0.03, [1.0, 2.0, math.nan, 0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="nominal"):
        process_model(0.5, 0.03, np.ones(5))
