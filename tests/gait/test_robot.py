"""Paper 002's walking robot: frames, kinematics, route, batching, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pednav_env.gait.robot import (
    PAPER_BODY_FROM_OURS,
    PAPER_NAV_FROM_ENU,
    RobotConfig,
    paper_dcm,
    paper_kinematic_matrix,
    simulate_robot,
    vertical_amplitude_from_leg,
)
from pednav_env.rotations import body_rates_from_euler, euler_to_dcm
from pednav_env.sensors.imu import ImuSpec, ideal_imu, simulate_imu


def _skew(w: np.ndarray) -> np.ndarray:
    x, y, z = w
    return np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])


def test_paper_frames_map_to_ours() -> None:
    # B_paper = P_b C_nbᵀ P_nᵀ and eq (9) = body_rates_from_euler, under
    # ψ_ours = ψ_paper + π/2; both mappings proper rotations.
    rng = np.random.default_rng(0)
    e = rng.uniform(-0.6, 0.6, (20, 3))
    rates = rng.normal(size=(20, 3))
    B = paper_dcm(e[:, 0] - math.pi / 2, e[:, 1], e[:, 2])
    C = euler_to_dcm(e)
    np.testing.assert_allclose(
        B, PAPER_BODY_FROM_OURS @ np.swapaxes(C, -1, -2) @ PAPER_NAV_FROM_ENU.T, atol=1e-15
    )
    w_paper = np.einsum("nij,nj->ni", paper_kinematic_matrix(e[:, 1], e[:, 2]), rates)
    w_ours = body_rates_from_euler(e, rates)
    np.testing.assert_allclose(w_paper, w_ours @ PAPER_BODY_FROM_OURS.T, atol=1e-15)
    assert np.linalg.det(PAPER_NAV_FROM_ENU) == pytest.approx(1.0)
    assert np.linalg.det(PAPER_BODY_FROM_OURS) == pytest.approx(1.0)


def test_eq9_is_the_derivative_of_B() -> None:
    # Eq (9) must be the body rate of the rotation sequence of B: Ḃ = −[ω×] B.
    # Central difference h = 1e-6: error ~ h² ≈ 1e-12 ≪ 1e-8.
    rng = np.random.default_rng(1)
    for _ in range(5):
        e = rng.uniform(-0.7, 0.7, 3)
        d = rng.normal(size=3)
        h = 1e-6
        dB = (paper_dcm(*(e + h * d)) - paper_dcm(*(e - h * d))) / (2 * h)
        w = paper_kinematic_matrix(e[1], e[2]) @ d
        np.testing.assert_allclose(dB, -_skew(w) @ paper_dcm(*e), atol=1e-8)


def test_truth_derivatives_consistent() -> None:
    # At dt = 1 ms the trapezoid of the rates/velocities reproduces the angles and
    # positions between samples except across the printed velocity jumps
    # (stops, starts, the |cos| kink of eq 1); those samples are excluded.
    cfg = RobotConfig(yaw_amplitude=math.radians(2.0))
    dt = 1e-3
    walk = simulate_robot(cfg, dt)
    for x, v in ((walk.pos_n, walk.vel_n), (walk.euler, walk.euler_rate)):
        fd = np.diff(x[0], axis=0) / dt
        mid = 0.5 * (v[0, 1:] + v[0, :-1])
        jump = np.any(np.abs(np.diff(v[0], axis=0)) > 0.05, axis=1)
        # Trapezoid error ≤ dt²/12·max|v''| ≈ 1e-7·(ω² · 1) — bound 1e-4.
        assert np.max(np.abs(fd - mid)[~jump]) < 1e-4


def test_route_geometry_and_timing() -> None:
    cfg = RobotConfig.no_oscillation()
    assert cfg.route_length == 16.0
    assert cfg.route_duration == pytest.approx(2 * (5 + 3) / 0.93 + 3.0)
    walk = simulate_robot(cfg, 0.025)
    i = walk.end_index[0]
    np.testing.assert_allclose(walk.pos_n[0, i], 0.0, atol=1e-12)  # back at O₀
    corners = walk.pos_n[0, [int(np.floor(t / 0.025)) for t in np.cumsum([5 / 0.93, 1.0])]]
    np.testing.assert_allclose(corners[0, :2], [0.0, 5.0], atol=0.93 * 0.025)
    # Headings: north, then three left turns (west, south, east).
    psi = walk.euler[0, :, 0]
    assert psi[0] == pytest.approx(math.pi / 2)
    assert psi[i] == pytest.approx(2 * math.pi)
    # Turning rate π/2 per second, ψ̇* ≈ 1.57 s⁻¹ as printed.
    assert walk.euler_rate[0, :, 0].max() == pytest.approx(math.pi / 2)


def test_mean_acceleration_is_eq10() -> None:
    walk = simulate_robot(RobotConfig(), 0.025)
    np.testing.assert_allclose(
        walk.acc_n_mean[:, 1:], np.diff(walk.vel_n, axis=1) / 0.025, rtol=0, atol=1e-12
    )
    omega, f = ideal_imu(walk.euler, walk.euler_rate, walk.acc_n_mean)
    # Specific force magnitude is |a + g e_up| in any attitude (eq 12 is a rotation).
    acc = walk.acc_n_mean.copy()
    acc[..., 2] += 9.80665
    np.testing.assert_allclose(np.linalg.norm(f, axis=-1), np.linalg.norm(acc, axis=-1))
    assert omega.shape == f.shape == walk.vel_n.shape
    # Usable by the IMU model: ideal spec reproduces the ideal readings.
    meas = simulate_imu(omega, f, 40.0, ImuSpec.ideal(), [np.random.default_rng(0)])
    np.testing.assert_allclose(meas.omega_b, omega)
    np.testing.assert_allclose(meas.f_b, f)


def test_amplitudes_follow_eqs_3_4() -> None:
    th, ga = math.radians(0.69), math.radians(1.13)
    walk = simulate_robot(RobotConfig(pitch_amplitude=th, roll_amplitude=ga), 0.005)
    assert walk.euler[0, :, 1].min() >= -1e-15
    assert walk.euler[0, :, 1].max() == pytest.approx(2 * th, rel=1e-3)
    assert np.abs(walk.euler[0, :, 2]).max() == pytest.approx(ga, rel=1e-3)
    h = walk.pos_n[0, :, 2]
    assert h.min() >= 0 and h.max() == pytest.approx(0.06, rel=1e-3)
    # Pitch is 2ϑ_m where h = 0 (the footfall) and 0 where h = y_m.
    low = h < 1e-3
    assert np.all(walk.euler[0, low, 1] > 1.9 * th)


def test_oscillations_freeze_while_standing() -> None:
    cfg = RobotConfig(oscillate_when_stopped=False)
    walk = simulate_robot(cfg, 0.025)
    stand = ~walk.walking[0]
    np.testing.assert_array_equal(walk.euler_rate[0, stand, 1:], 0.0)
    np.testing.assert_array_equal(walk.vel_n[0, stand, 2], 0.0)
    moving = simulate_robot(RobotConfig(), 0.025)
    assert np.any(moving.euler_rate[0, ~moving.walking[0], 1] != 0.0)


def test_batch_lane_equals_single() -> None:
    cfgs = [
        RobotConfig(),
        RobotConfig(speed=0.8, pitch_amplitude=0.02),
        RobotConfig.no_oscillation(oscillate_when_stopped=False),
    ]
    walk = simulate_robot(cfgs, 0.025)
    for i, c in enumerate(cfgs):
        one = simulate_robot(c, 0.025, n_samples=walk.t.size)
        for name in ("pos_n", "vel_n", "acc_n_mean", "euler", "euler_rate", "walking"):
            np.testing.assert_array_equal(getattr(walk, name)[i], getattr(one, name)[0])


def test_grid_alignment_puts_events_on_samples() -> None:
    walk = simulate_robot(RobotConfig.no_oscillation(), 0.025, align_to_grid=True)
    speed = np.linalg.norm(walk.vel_n[0, :, :2], axis=-1)
    changes = np.nonzero(np.diff(speed > 0))[0] + 1
    np.testing.assert_array_equal(changes, [215, 255, 384, 424, 639, 679, 808])


def test_vertical_amplitude_formula() -> None:
    # Paper 002: y_m = l − sqrt(l² − 0.25 L₁²) with l = 1, L₁ = 0.6 (it prints ≈ 0.06).
    assert vertical_amplitude_from_leg(1.0, 0.6) == pytest.approx(1 - math.sqrt(0.91))
    with pytest.raises(ValueError, match="leg_length"):
        vertical_amplitude_from_leg(0.25, 0.6)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(speed=0.0), "speed"),
        (dict(pitch_amplitude=-0.01), "pitch_amplitude"),
        (dict(roll_amplitude=math.nan), "roll_amplitude"),
        (dict(speed_oscillation=1.0), "speed_oscillation"),
        (dict(side_lengths=(5.0, -3.0)), "side_lengths"),
        (dict(omega=-4.86), "omega"),
    ],
)
def test_invalid_config_raises(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        RobotConfig(**kwargs)


def test_invalid_simulation_inputs_raise() -> None:
    with pytest.raises(ValueError, match="dt"):
        simulate_robot(RobotConfig(), 0.0)
    with pytest.raises(ValueError, match="legs"):
        simulate_robot([RobotConfig(), RobotConfig(side_lengths=(5.0, 3.0))], 0.025)
