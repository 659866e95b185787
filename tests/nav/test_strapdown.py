"""Strapdown mechanisation (paper 003 eq 3) and static alignment (eq 4)."""

import numpy as np
import pytest

from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import paper_stride_shape, square_route
from pednav_env.nav.alignment import align_static
from pednav_env.nav.strapdown import integrate, strapdown_step
from pednav_env.rotations import euler_to_dcm, euler_to_quat, quat_to_euler, wrap_angle


def free_inertial_error(rate_hz):
    tr = simulate_foot(square_route(3.0, paper_stride_shape(1.0)), FootSimConfig(rate_hz=rate_hz))
    q, _v, p = integrate(
        euler_to_quat(tr.euler[:, 0]),
        tr.vel_n[:, 0],
        tr.pos_n[:, 0],
        tr.omega_b,
        tr.f_b,
        1.0 / rate_hz,
    )
    att = np.abs(wrap_angle(quat_to_euler(q) - tr.euler)).max()
    return np.abs(p - tr.pos_n).max(), att


def test_noiseless_walk_integrates_back_to_the_truth():
    """Free-inertial (no ZUPT) over a 14 s walk: second-order convergence in Δt,
    and at 400 Hz the position stays within a centimetre of the truth."""
    e100, a100 = free_inertial_error(100.0)
    e200, _ = free_inertial_error(200.0)
    e400, a400 = free_inertial_error(400.0)
    assert 3.5 < e100 / e200 < 4.5 and 3.5 < e200 / e400 < 4.5
    assert e400 < 0.01
    assert a100 < 1e-3 and a400 < 1e-4


def test_step_and_batched_integrate_agree():
    rng = np.random.default_rng(2)
    omega = rng.normal(scale=2.0, size=(3, 50, 3))
    f = rng.normal(scale=5.0, size=(3, 50, 3)) + [0, 0, 9.8]
    q0 = euler_to_quat(rng.uniform(-0.5, 0.5, (3, 3)))
    v0 = rng.normal(size=(3, 3))
    p0 = rng.normal(size=(3, 3))
    q, _v, p = integrate(q0, v0, p0, omega, f, 0.01)
    qs, vs, ps = q0, v0, p0
    for m in range(50):
        qs, vs, ps = strapdown_step(qs, vs, ps, omega[:, m], f[:, m], 0.01)
    np.testing.assert_allclose(q[:, -1], qs, atol=1e-12)
    np.testing.assert_allclose(p[:, -1], ps, atol=1e-10)


def test_standing_still_stays_put():
    f = np.zeros((1, 1000, 3))
    f[..., 2] = 9.80665
    _q, v, p = integrate(
        np.array([[1.0, 0, 0, 0]]), np.zeros((1, 3)), np.zeros((1, 3)), np.zeros_like(f), f, 0.01
    )
    assert np.abs(p).max() < 1e-10 and np.abs(v).max() < 1e-12


def test_alignment_recovers_tilt():
    euler = np.array([[0.0, 0.10, 0.13], [0.0, -0.4, 0.2]])  # paper 003's real-data 0.10, 0.13
    f = np.einsum("nji,j->ni", euler_to_dcm(euler), [0, 0, 9.80665])
    np.testing.assert_allclose(align_static(f), euler, atol=1e-12)
    rng = np.random.default_rng(0)
    noisy = f[:, None, :] + rng.normal(scale=0.1, size=(2, 100, 3))
    # averaging 100 samples of σ = 0.1 m/s²: tilt error ≈ 0.01/g rad per axis
    np.testing.assert_allclose(align_static(noisy), euler, atol=5 * 0.01 / 9.8)


def test_alignment_rejects_bad_input():
    with pytest.raises(ValueError, match="NaN"):
        align_static(np.array([[np.nan, 0, 9.8]]))
    with pytest.raises(ValueError, match="f_b"):
        align_static(np.zeros((2, 2, 2, 3)))
    with pytest.raises(ValueError, match="g"):
        align_static(np.array([[0, 0, 9.8]]), g=0.0)
    with pytest.raises(ValueError, match="dt"):
        integrate(
            np.array([[1.0, 0, 0, 0]]),
            np.zeros((1, 3)),
            np.zeros((1, 3)),
            np.zeros((1, 5, 3)),
            np.zeros((1, 5, 3)),
            0.0,
        )


def test_preintegrated_increments_equal_sample_by_sample_strapdown():
    """Moving states from sample a to t by the ZUPT kernel's preintegrals (C₀D,
    v₀ + C₀A − gτe₃, x₀ + v₀τ + C₀B − ½gτ²e₃, accumulated sample by sample) is
    the strapdown of eq (3) run over samples a … t−1, to rounding."""
    from pednav_env.nav.preintegration import (
        Preintegral,
        SigmaPoints,
        accumulate,
        anchor_force,
        move_sigmas,
        strapdown_increment,
    )
    from pednav_env.rotations import quat_to_dcm

    rate = 100.0
    dt = 1.0 / rate
    tr = simulate_foot(square_route(3.0, paper_stride_shape(1.0)), FootSimConfig(rate_hz=rate))
    s0, k = 250, 60  # a block inside the walk: swing and stance
    omega, f = tr.omega_b[:, s0 : s0 + k], tr.f_b[:, s0 : s0 + k]
    g = 9.80665
    dC, f_mid, F = np.empty((3, 3)), np.empty(3), np.empty(3)
    for a, t in ((0, k), (7, 41), (33, 34)):
        q0 = euler_to_quat(tr.euler[:, s0 + a])
        v0, p0 = tr.vel_n[:, s0 + a], tr.pos_n[:, s0 + a]
        q, v, p = integrate(q0, v0, p0, omega[:, a:t], f[:, a:t], dt, g)
        pre = Preintegral(np.eye(3), np.zeros(3), np.zeros(3))
        for j in range(a, t):
            strapdown_increment(omega[0, j].copy(), f[0, j].copy(), dt, dC, f_mid)
            anchor_force(pre.D, f_mid, F)
            accumulate(pre, F, dC, dt)
        C_t, v_t, p_t = quat_to_dcm(q0), v0.copy(), p0.copy()  # (1, 3, 3), (1, 3), (1, 3)
        move_sigmas(SigmaPoints(C_t, v_t, p_t), pre, (t - a) * dt, g)
        np.testing.assert_allclose(C_t, quat_to_dcm(q[:, -1]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(v_t, v[:, -1], rtol=0, atol=1e-12)
        np.testing.assert_allclose(p_t, p[:, -1], rtol=0, atol=1e-12)
