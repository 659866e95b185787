"""The Schuler INS error model of papers 000/004 (sensors.ins_error): the transition
matrix, the simulated error recursion and its validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from pednav_env.constants import EARTH_RADIUS, STANDARD_GRAVITY
from pednav_env.sensors.ins_error import (
    SchulerErrorConfig,
    per_sample_velocity_error,
    schuler_transition,
    simulate_schuler_errors,
)

G, RE = STANDARD_GRAVITY, EARTH_RADIUS


def test_transition_matches_printed_matrices() -> None:
    T = 0.5
    phi = schuler_transition(np.array([[T, T]]), G, RE)
    np.testing.assert_array_equal(phi[0, 0], [[1, -G * T, 0], [T / RE, 1, T], [0, 0, 1]])
    np.testing.assert_array_equal(phi[0, 1], [[1, G * T, 0], [-T / RE, 1, T], [0, 0, 1]])


def test_transition_is_euler_step_of_schuler_loop() -> None:
    # Φ_E = I + A T, the first-order step of δV̇ = −gβ, β̇ = δV/R + ε, ε̇ = 0 (paper
    # 000's continuous model); expm(A T) adds the second-order terms (−gT²/2 from ε to
    # δV being the largest); the discrete loop's rotation per step is ω_s T, giving
    # the 84.4-min Schuler period (paper 004).
    T = 0.5
    A = np.array([[0, -G, 0], [1 / RE, 0, 1], [0, 0, 0]])
    phi = schuler_transition(T, G, RE, 1.0)
    np.testing.assert_allclose(phi, np.eye(3) + A * T, rtol=0, atol=1e-15)
    # Third-order terms are (A T)³/6 ≈ g T ω_s² T² / 6 ≈ 3e-7: bound 1e-6.
    np.testing.assert_allclose(expm(A * T) - phi, (A * T) @ (A * T) / 2, rtol=0, atol=1e-6)
    lam = np.linalg.eigvals(phi[:2, :2])
    period = 2 * math.pi / np.abs(np.angle(lam[0])) * T
    assert period / 60 == pytest.approx(84.4, abs=0.05)
    assert SchulerErrorConfig().schuler_period / 60 == pytest.approx(84.4, abs=0.05)


def test_schuler_errors_deterministic_and_batch_independent() -> None:
    T = np.full((3, 40), 0.5)
    cfg = SchulerErrorConfig(accel_bias=1e-3)
    seeds = np.random.SeedSequence(7).spawn(3)
    x = simulate_schuler_errors(T, cfg, [np.random.default_rng(s) for s in seeds])
    x2 = simulate_schuler_errors(T, cfg, [np.random.default_rng(s) for s in seeds])
    np.testing.assert_array_equal(x, x2)
    for i in range(3):
        one = simulate_schuler_errors(T[i : i + 1], cfg, [np.random.default_rng(seeds[i])])
        np.testing.assert_array_equal(one[0], x[i])
    # Noise-free check of the recursion, including the bias term B·T.
    quiet = SchulerErrorConfig(
        accel_noise_std=0,
        drift_noise_std=0,
        initial_velocity_std=0,
        initial_tilt_std=0,
        initial_drift_std=0,
        accel_bias=0.01,
    )
    xq = simulate_schuler_errors(np.full((1, 3), 0.5), quiet, [np.random.default_rng(0)])
    np.testing.assert_allclose(xq[0, 1, :, 0], 0.005)
    np.testing.assert_allclose(xq[0, 2, 0, 1], 0.5 / RE * 0.005)
    dv = per_sample_velocity_error(xq, np.array([[0, 0, 1, 2, 3]]))
    np.testing.assert_allclose(
        dv[0, :, 0], [0.005, 0.005, xq[0, 2, 0, 0], xq[0, 3, 0, 0], xq[0, 3, 0, 0]]
    )


def test_schuler_errors_follow_transition_matrix() -> None:
    # Noise-free, random initial state, variable T_k: x(k) = Φ(T_k) x(k−1) + [B T_k, 0, 0].
    T = np.random.default_rng(1).uniform(0.3, 0.9, (2, 25))
    cfg = SchulerErrorConfig(
        accel_noise_std=0,
        drift_noise_std=0,
        initial_velocity_std=0.5,
        initial_tilt_std=1e-3,
        initial_drift_std=1e-4,
        accel_bias=0.02,
    )
    x = simulate_schuler_errors(T, cfg, [np.random.default_rng(s) for s in (3, 4)])
    phi = schuler_transition(T[..., None], cfg.g, cfg.earth_radius)  # (2, 25, 2, 3, 3)
    want = np.einsum("nkcij,nkcj->nkci", phi, x[:, :-1])
    want[..., 0] += cfg.accel_bias * T[..., None]
    np.testing.assert_allclose(x[:, 1:], want, rtol=1e-13, atol=1e-16)


def test_schuler_error_config_validation() -> None:
    with pytest.raises(ValueError, match="accel_noise_std"):
        SchulerErrorConfig(accel_noise_std=-0.1)
    with pytest.raises(ValueError, match="drift_noise_std"):
        SchulerErrorConfig(drift_noise_std=math.nan)
    with pytest.raises(ValueError, match="step_periods"):
        simulate_schuler_errors(np.zeros((1, 3)), SchulerErrorConfig(), [np.random.default_rng(0)])
    with pytest.raises(ValueError, match="rngs"):
        simulate_schuler_errors(np.ones((2, 3)), SchulerErrorConfig(), np.random.default_rng(0))
