"""Attitude algebra: Euler (paper 003, 3-2-1) ↔ DCM ↔ quaternion, body rates."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pednav_env.rotations import (
    body_angular_acceleration_from_euler,
    body_rates_from_euler,
    euler_to_dcm,
    euler_to_quat,
    quat_from_rotvec,
    quat_multiply,
    quat_rotate,
    quat_to_dcm,
    quat_to_euler,
    right_product_matrix,
    wrap_angle,
)

angles = st.tuples(st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1)).map(np.array)


def paper_B(euler):
    """Paper 003's B_zx = B(γ) B(θ) B(ψ), written out from its elementary matrices."""
    psi, th, ga = euler
    Bg = np.array([[1, 0, 0], [0, np.cos(ga), np.sin(ga)], [0, -np.sin(ga), np.cos(ga)]])
    Bt = np.array([[np.cos(th), 0, -np.sin(th)], [0, 1, 0], [np.sin(th), 0, np.cos(th)]])
    Bp = np.array([[np.cos(psi), np.sin(psi), 0], [-np.sin(psi), np.cos(psi), 0], [0, 0, 1]])
    return Bg @ Bt @ Bp


@given(angles)
@settings(max_examples=60, deadline=None)
def test_dcm_is_transpose_of_paper_B(euler):
    np.testing.assert_allclose(euler_to_dcm(euler), paper_B(euler).T, atol=1e-12)


@given(angles)
@settings(max_examples=60, deadline=None)
def test_quaternion_round_trips(euler):
    q = euler_to_quat(euler)
    assert abs(np.linalg.norm(q) - 1) < 1e-12
    np.testing.assert_allclose(quat_to_dcm(q), euler_to_dcm(euler), atol=1e-12)
    np.testing.assert_allclose(wrap_angle(quat_to_euler(q) - euler), 0, atol=1e-9)


def test_alignment_sign_convention():
    """Paper 003 eq 4 relies on f₁ = −g sin θ, f₂ = g cos θ sin γ at rest."""
    euler = np.array([0.3, 0.2, -0.1])
    f_b = euler_to_dcm(euler).T @ np.array([0, 0, 9.8])
    assert np.isclose(f_b[0], -9.8 * np.sin(0.2))
    assert np.isclose(f_b[1], 9.8 * np.cos(0.2) * np.sin(-0.1))


def test_rotate_and_product_agree_with_matrices():
    rng = np.random.default_rng(0)
    q = euler_to_quat(rng.uniform(-1, 1, (20, 3)))
    p = euler_to_quat(rng.uniform(-1, 1, (20, 3)))
    v = rng.normal(size=(20, 3))
    np.testing.assert_allclose(
        quat_rotate(q, v), np.einsum("nij,nj->ni", quat_to_dcm(q), v), atol=1e-12
    )
    np.testing.assert_allclose(
        quat_to_dcm(quat_multiply(q, p)), quat_to_dcm(q) @ quat_to_dcm(p), atol=1e-12
    )
    np.testing.assert_allclose(
        quat_multiply(q, p), np.einsum("nij,nj->ni", right_product_matrix(p), q), atol=1e-12
    )


def test_rotvec_small_angle_series_and_exact():
    k = np.array([[1e-9, -2e-9, 3e-9], [0.3, -0.2, 0.1]])
    q = quat_from_rotvec(k)
    angle = np.linalg.norm(k[1])
    np.testing.assert_allclose(q[1, 0], np.cos(angle / 2), rtol=1e-15)
    np.testing.assert_allclose(q[1, 1:], k[1] / angle * np.sin(angle / 2), rtol=1e-14)
    np.testing.assert_allclose(q[0, 1:], k[0] / 2, rtol=1e-12)


def test_body_rates_and_acceleration_match_finite_differences():
    t = np.linspace(0.0, 2.0, 40001)
    e = np.stack((np.sin(t), 0.5 * np.cos(2 * t), 0.3 * np.sin(3 * t)), -1)
    de = np.stack((np.cos(t), -np.sin(2 * t), 0.9 * np.cos(3 * t)), -1)
    dde = np.stack((-np.sin(t), -2 * np.cos(2 * t), -2.7 * np.sin(3 * t)), -1)
    C = euler_to_dcm(e)
    Omega = np.einsum("tji,tjk->tik", C, np.gradient(C, t, axis=0))  # C_nbᵀ Ċ_nb = [ω×]
    w_fd = np.stack((Omega[:, 2, 1], Omega[:, 0, 2], Omega[:, 1, 0]), -1)
    w = body_rates_from_euler(e, de)
    np.testing.assert_allclose(w[10:-10], w_fd[10:-10], atol=1e-7)
    dw_fd = np.gradient(w, t, axis=0)
    dw = body_angular_acceleration_from_euler(e, de, dde)
    np.testing.assert_allclose(dw[10:-10], dw_fd[10:-10], atol=1e-6)
