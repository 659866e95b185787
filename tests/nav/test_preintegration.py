"""Preintegrals of the ZUPT kernel (nav.preintegration): moving sigma points by the
accumulated increments is the strapdown of eq 3."""

import numpy as np

from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import paper_stride_shape, square_route
from pednav_env.nav.strapdown import integrate
from pednav_env.rotations import euler_to_quat


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
