"""Paper 000's inverted-pendulum model: closed form, chaining, batching, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pednav_env.gait.pendulum import (
    PendulumSteps,
    hip_rise,
    simulate_walk,
    step_kinematics,
    step_length_from_rise,
)
from pednav_env.rotations import body_rates_from_euler
from pednav_env.sensors.imu import ImuSpec, ideal_specific_force, simulate_imu

L_PAPER, PHI_PAPER, T_PAPER = 0.7, math.pi / 3, 0.5


def _random_steps(rng: np.random.Generator, n: int, k: int, slope: bool = True) -> PendulumSteps:
    return PendulumSteps(
        leg_length=rng.uniform(0.8, 1.0, (n, k)),
        phi_min=np.radians(rng.uniform(55.0, 70.0, (n, k))),
        step_period=rng.uniform(0.45, 0.65, (n, k)),
        slope=np.radians(rng.uniform(-10.0, 10.0, (n, k))) if slope else 0.0,
        heading=rng.uniform(-math.pi, math.pi, (n, k)),
    )


def test_derivatives_match_central_differences() -> None:
    # Central differences with h = 1e-5 s: truncation h²/6·|x'''| ≤ 1e-10·ω³l ≈ 1e-9,
    # round-off eps·|x|/h ≈ 1e-11, so 1e-7 absolute is a safe bound that a wrong
    # derivative (errors of order ω l ≈ 1) cannot meet.
    t = np.linspace(0.0, T_PAPER, 41)
    h = 1e-5
    for slope in (0.0, math.radians(8.0), math.radians(-12.0)):
        args = (L_PAPER, PHI_PAPER, T_PAPER, slope)
        _, _, vx, vy, ax, ay = step_kinematics(t, *args)
        xp, yp, vxp, vyp, *_ = step_kinematics(t + h, *args)
        xm, ym, vxm, vym, *_ = step_kinematics(t - h, *args)
        np.testing.assert_allclose((xp - xm) / (2 * h), vx, atol=1e-7)
        np.testing.assert_allclose((yp - ym) / (2 * h), vy, atol=1e-7)
        np.testing.assert_allclose((vxp - vxm) / (2 * h), ax, atol=1e-7)
        np.testing.assert_allclose((vyp - vym) / (2 * h), ay, atol=1e-7)


def test_slope_is_rotation_of_level_model() -> None:
    # Eqs (18)–(19): the sloped path is the level path (12)–(13) rotated by α.
    t = np.linspace(0.0, T_PAPER, 11)
    a = math.radians(7.0)
    x0, y0, *_ = step_kinematics(t, L_PAPER, PHI_PAPER, T_PAPER, 0.0)
    x, y, *_ = step_kinematics(t, L_PAPER, PHI_PAPER, T_PAPER, a)
    np.testing.assert_allclose(x, x0 * math.cos(a) - y0 * math.sin(a), atol=1e-15)
    np.testing.assert_allclose(y, x0 * math.sin(a) + y0 * math.cos(a), atol=1e-15)


def test_double_support_values_printed_in_paper() -> None:
    # Paper 000's list of x', x'', y', y'' at t = 0 and t = T on a slope α.
    a = math.radians(5.0)
    w = (math.pi - 2 * PHI_PAPER) / T_PAPER
    _, _, vx0, vy0, ax0, ay0 = step_kinematics(0.0, L_PAPER, PHI_PAPER, T_PAPER, a)
    _, _, vx1, vy1, ax1, ay1 = step_kinematics(T_PAPER, L_PAPER, PHI_PAPER, T_PAPER, a)
    lw, lw2 = L_PAPER * w, L_PAPER * w * w
    assert vx0 == pytest.approx(lw * math.sin(PHI_PAPER - a), abs=1e-14)
    assert vx1 == pytest.approx(lw * math.sin(PHI_PAPER + a), abs=1e-14)
    assert ax0 == pytest.approx(lw2 * math.cos(PHI_PAPER - a), abs=1e-14)
    assert ax1 == pytest.approx(-lw2 * math.cos(PHI_PAPER + a), abs=1e-14)
    assert vy0 == pytest.approx(lw * math.cos(PHI_PAPER - a), abs=1e-14)
    assert vy1 == pytest.approx(-lw * math.cos(PHI_PAPER + a), abs=1e-14)
    assert ay0 == pytest.approx(-lw2 * math.sin(PHI_PAPER - a), abs=1e-14)
    assert ay1 == pytest.approx(-lw2 * math.sin(PHI_PAPER + a), abs=1e-14)


def test_step_length_and_mean_velocity() -> None:
    # Eq (1) with h = l(1 − sin φ_min) gives L = 2 l cos φ_min; paper: V̄ = 1.4 m/s.
    h = hip_rise(L_PAPER, PHI_PAPER)
    assert step_length_from_rise(h, L_PAPER) == pytest.approx(2 * L_PAPER * math.cos(PHI_PAPER))
    steps = PendulumSteps(np.full((1, 1), L_PAPER), PHI_PAPER, T_PAPER)
    assert steps.mean_velocity[0, 0] == pytest.approx(1.4, abs=1e-14)


def test_chained_walk_is_continuous_and_reverses_vertical_velocity() -> None:
    rng = np.random.default_rng(3)
    n, k, rate = 3, 8, 200.0
    base = _random_steps(rng, n, k)
    # Step periods on the sample grid, so every boundary is a sample instant.
    steps = PendulumSteps(
        base.leg_length,
        base.phi_min,
        np.round(base.step_period * rate) / rate,
        base.slope,
        base.heading,
    )
    walk = simulate_walk(steps, rate)
    dt = 1.0 / rate
    # Position continuity: no sample-to-sample jump beyond max speed · dt.
    vmax = np.max(np.linalg.norm(walk.vel_n, axis=-1))
    assert np.max(np.linalg.norm(np.diff(walk.pos_n, axis=1), axis=-1)) <= vmax * dt * (1 + 1e-9)
    first = np.rint(steps.step_start[:, 1:-1] * rate).astype(int)  # boundaries k = 1 … K−1
    for i in range(n):
        for j, s in enumerate(first[i]):
            kk = j + 1
            w = (math.pi - 2 * steps.phi_min[i, kk]) / steps.step_period[i, kk]
            w_prev = (math.pi - 2 * steps.phi_min[i, j]) / steps.step_period[i, j]
            # Up velocity right after the boundary is step kk's start value, the
            # extrapolation of step j to its end is −ω l cos(φ_min + α).
            up_after = walk.vel_n[i, s, 2]
            want_after = (
                w * steps.leg_length[i, kk] * math.cos(steps.phi_min[i, kk] - steps.slope[i, kk])
            )
            assert up_after == pytest.approx(want_after, abs=1e-12)
            end_prev = (
                -w_prev * steps.leg_length[i, j] * math.cos(steps.phi_min[i, j] + steps.slope[i, j])
            )
            assert up_after - end_prev > 0.5  # the double-support reversal
    # Mean horizontal speed per step = 2 l cos φ_min cos α / T (eq 1, slope projection).
    edges = np.rint(steps.step_start * rate).astype(int)
    for i in range(n):
        for j in range(k - 1):
            d = walk.pos_n[i, edges[i, j + 1], :2] - walk.pos_n[i, edges[i, j], :2]
            speed = np.linalg.norm(d) / steps.step_period[i, j]
            assert speed == pytest.approx(steps.mean_velocity[i, j], rel=1e-12)


def test_mean_acceleration_integrates_to_velocity_across_steps() -> None:
    rng = np.random.default_rng(4)
    walk = simulate_walk(_random_steps(rng, 2, 6), 100.0)
    v = walk.vel_n[:, :1] + np.cumsum(walk.acc_n_mean[:, 1:], axis=1) / walk.rate_hz
    np.testing.assert_allclose(v, walk.vel_n[:, 1:], atol=1e-12)
    # Point samples miss the reversal impulses: the vertical velocity drifts.
    v_pt = walk.vel_n[:, :1] + np.cumsum(walk.acc_n[:, 1:], axis=1) / walk.rate_hz
    assert np.max(np.abs(v_pt - walk.vel_n[:, 1:])) > 1.0


def test_level_feet_stay_on_slope_line() -> None:
    # Constant parameters: all stance feet lie on the line of slope α (eqs 18–19).
    a = math.radians(6.0)
    steps = PendulumSteps(np.full((1, 5), 0.9), math.radians(62.0), 0.55, slope=a, heading=0.3)
    walk = simulate_walk(steps, 100.0)
    feet = walk.foot_pos_n[0]
    horiz = np.linalg.norm(feet[:, :2], axis=-1)
    np.testing.assert_allclose(feet[:, 2], horiz * math.tan(a), atol=1e-12)


def test_batch_lane_equals_single_walker() -> None:
    rng = np.random.default_rng(5)
    steps = _random_steps(rng, 4, 7)
    walk = simulate_walk(steps, 100.0)
    for i in range(4):
        one = PendulumSteps(
            steps.leg_length[i : i + 1],
            steps.phi_min[i : i + 1],
            steps.step_period[i : i + 1],
            steps.slope[i : i + 1],
            steps.heading[i : i + 1],
        )
        w1 = simulate_walk(one, 100.0, n_samples=walk.t.size)
        for name in ("pos_n", "vel_n", "acc_n", "acc_n_mean", "euler", "euler_rate", "step_index"):
            np.testing.assert_array_equal(getattr(walk, name)[i], getattr(w1, name)[0])


def test_usable_by_imu_model() -> None:
    # Level walk at 100 Hz with aligned boundaries: f from the mean acceleration has
    # |f| < g during single support (hip on its arc, eq 17) and |f| > g at the
    # double-support sample; body rates match the finite difference of yaw.
    steps = PendulumSteps(np.full((1, 6), L_PAPER), PHI_PAPER, T_PAPER, heading=[[0, 0, 0.3] * 2])
    walk = simulate_walk(steps, 100.0)
    f = ideal_specific_force(walk.acc_n_mean, walk.euler)
    omega = body_rates_from_euler(walk.euler, walk.euler_rate)
    meas = simulate_imu(omega, f, 100.0, ImuSpec.ideal(), [np.random.default_rng(0)])
    np.testing.assert_allclose(meas.f_b, f)
    g = 9.80665
    norm = np.linalg.norm(f[0], axis=-1)
    boundary = np.arange(1, 6) * 50
    assert np.all(norm[boundary] > g + 50.0)
    inner = np.setdiff1d(np.arange(1, 300), boundary)
    assert np.all(norm[inner] < g)
    yaw = walk.euler[0, :, 0]
    np.testing.assert_allclose(
        np.diff(yaw) * 100.0, 0.5 * (omega[0, 1:, 2] + omega[0, :-1, 2]), atol=2e-3
    )


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(leg_length=-0.7), "leg_length"),
        (dict(phi_min=math.pi / 2), "phi_min"),
        (dict(step_period=0.0), "step_period"),
        (dict(slope=math.radians(70.0)), "slope"),
        (dict(leg_length=np.nan), "leg_length"),
    ],
)
def test_invalid_steps_raise(kwargs: dict, name: str) -> None:
    args = dict(leg_length=np.full((1, 2), 0.7), phi_min=PHI_PAPER, step_period=0.5)
    if "leg_length" in kwargs:
        args["leg_length"] = np.full((1, 2), kwargs.pop("leg_length"))
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        PendulumSteps(**args)


def test_invalid_inputs_raise() -> None:
    with pytest.raises(ValueError, match="leg_length"):
        PendulumSteps.from_step_length(np.full((1, 2), 1.5), 0.7, 0.5)  # L ≥ 2 l
    with pytest.raises(ValueError, match="hip_rise"):
        step_length_from_rise(0.8, 0.7)
    steps = PendulumSteps(np.full((1, 2), 0.7), PHI_PAPER, 0.5)
    with pytest.raises(ValueError, match="rate_hz"):
        simulate_walk(steps, 0.0)
    with pytest.raises(ValueError, match="PendulumSteps"):
        PendulumSteps(0.7, PHI_PAPER, 0.5)  # no (N, K) array: shape unknown
    with pytest.raises(ValueError, match="step_period"):
        PendulumSteps(np.full((2, 3), 0.7), PHI_PAPER, np.ones((3, 2)))
    walk = simulate_walk(PendulumSteps.from_step_length(np.full((1, 2), 0.7), 0.7, 0.5), 100.0)
    assert walk.pos_n.shape == (1, 101, 3)
