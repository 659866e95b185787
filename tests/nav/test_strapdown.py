"""Strapdown mechanisation (paper 003 eq 3)."""

import numpy as np

from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import paper_stride_shape, square_route
from pednav_env.nav.strapdown import integrate, strapdown_step
from pednav_env.rotations import euler_to_quat, quat_to_euler, wrap_angle


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
