"""The swing in three axes (calibration.swing_attitude) on walks whose rotation is known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pednav_env.calibration.stats import WalkSamples
from pednav_env.calibration.swing_attitude import attitude_profile, swing_attitudes
from pednav_env.constants import STANDARD_GRAVITY

RATE_HZ = 200.0
G = STANDARD_GRAVITY


def rz(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def turning_walk(
    turn_rad: float, strides: int = 6, mount: np.ndarray | None = None, heading0: float = 0.7
) -> WalkSamples:
    """Stances of 0.6 s at rest; swings of 0.5 s that turn the foot by ``turn_rad``
    about the vertical at a constant rate while it moves forward along its start
    heading (nav acceleration A sin(2πt/T): velocity zero at both ends). Stance
    labels; ``mount`` rotates the sensor in the shoe (body = foot · mount)."""
    stance_n, swing_n = int(0.6 * RATE_HZ), int(0.5 * RATE_HZ)
    dt = 1.0 / RATE_HZ
    mount = np.eye(3) if mount is None else mount
    omegas, forces, labels = [], [], []
    psi = heading0
    wz = turn_rad / (swing_n * dt)
    for _ in range(strides):
        for _ in range(stance_n):
            c = rz(psi) @ mount
            omegas.append(np.zeros(3))
            forces.append(c.T @ np.array([0.0, 0.0, G]))
            labels.append(True)
        start = psi
        for k in range(swing_n):
            t = (k + 0.5) * dt
            psi = start + wz * t
            c = rz(psi) @ mount
            accel = 8.0 * math.sin(2 * math.pi * t / (swing_n * dt))
            a_nav = np.array([accel * math.cos(start), accel * math.sin(start), 0.0])
            omegas.append(mount.T @ np.array([0.0, 0.0, wz]))
            forces.append(c.T @ (a_nav + np.array([0.0, 0.0, G])))
            labels.append(False)
        psi = start + turn_rad
    for _ in range(stance_n):
        c = rz(psi) @ mount
        omegas.append(np.zeros(3))
        forces.append(c.T @ np.array([0.0, 0.0, G]))
        labels.append(True)
    return WalkSamples(
        omega_b=np.array(omegas),
        f_b=np.array(forces),
        rate_hz=RATE_HZ,
        name="turning",
        stance=np.array(labels),
    )


def test_a_turning_swing_yaws_by_its_turn_and_nothing_else():
    att = swing_attitudes(turning_walk(0.6))
    ends = np.r_[np.flatnonzero(np.diff(att.phase) < 0), att.phase.size - 1]
    assert ends.size == 6
    np.testing.assert_allclose(np.abs(att.yaw_rad[ends]), 0.6, atol=0.01)
    assert np.max(np.abs(att.pitch_rad)) < 1e-6
    assert np.max(np.abs(att.roll_rad)) < 1e-6
    # yaw grows in proportion to the phase
    np.testing.assert_allclose(np.abs(att.yaw_rad), 0.6 * att.phase, atol=0.01)
    assert np.all(att.end_tilt_rad < 1e-6)


def test_the_sensor_mounting_cancels():
    tilt = np.array(
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    ) @ np.array(  # 90° about z then 20° about x
        [
            [1.0, 0.0, 0.0],
            [0.0, math.cos(0.35), -math.sin(0.35)],
            [0.0, math.sin(0.35), math.cos(0.35)],
        ]
    )
    plain = swing_attitudes(turning_walk(0.4))
    mounted = swing_attitudes(turning_walk(0.4, mount=tilt))
    np.testing.assert_allclose(np.abs(mounted.yaw_rad), np.abs(plain.yaw_rad), atol=1e-6)
    np.testing.assert_allclose(mounted.pitch_rad, 0.0, atol=1e-6)


def test_profile_bins_and_refusals():
    profile = attitude_profile([turning_walk(0.5)], bins=5)
    assert profile["swings"] == 6
    # median |yaw| in bin k is the turn at the bin's middle phase
    np.testing.assert_allclose(
        np.abs(profile["yaw_median_rad"]), 0.5 * (np.arange(5) + 0.5) / 5, atol=0.01
    )
    with pytest.raises(ValueError, match="bins"):
        attitude_profile([turning_walk(0.5)], bins=0)
    walk = turning_walk(0.5)
    unlabelled = WalkSamples(walk.omega_b, walk.f_b, RATE_HZ, name="nolabels")
    with pytest.raises(ValueError, match="nolabels"):
        swing_attitudes(unlabelled)
