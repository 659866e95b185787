"""Angle-sum forms of the sigma points' angles (nav.sigma_angles): the same residuals
and attitudes as the direct formulas (moved_states + residuals, draw_sigmas), to
rounding; the series equal the library's functions; the filter that corrects at every
stance sample (the foot envs' shoe family) uses them and stays the same filter."""

import math
from dataclasses import replace

import numpy as np
import pytest

from pednav_env.nav.preintegration import Preintegral, SigmaPoints, moved_states
from pednav_env.nav.sigma_angles import (
    SMALL_ANGLE,
    atan_small,
    moved_residuals,
    sin_cos_small,
)
from pednav_env.nav.zupt_algebra import draw_sigmas, new_algebra_scratch, residuals
from pednav_env.nav.zupt_config import UpdateMode, ZuptUkfConfig
from pednav_env.rotations import euler_to_dcm

SPREAD = 9 * 1e-6  # L + λ at paper 003's α = 1e-3


def ulp_close(actual, desired, ulps=2.0):
    assert abs(actual - desired) <= ulps * math.ulp(max(abs(desired), 1e-300)), (actual, desired)


def test_series_equal_the_library_functions():
    rng = np.random.default_rng(3)
    angles = np.concatenate(
        [
            [0.0, -0.0, 1e-300, 1e-12, -1e-6, SMALL_ANGLE, -SMALL_ANGLE],
            rng.uniform(-SMALL_ANGLE, SMALL_ANGLE, 300),
            rng.uniform(-3.0, 3.0, 50),  # beyond the series: the library call
        ]
    )
    for a in angles:
        c, s = sin_cos_small(float(a))
        ulp_close(c, math.cos(a))
        ulp_close(s, math.sin(a))
        # atan2 of a vector at angle a with any positive or negative length
        for r in (1e-3, 0.7, 5.0):
            t = atan_small(r * math.sin(a), r * math.cos(a))
            ulp_close(t, math.atan2(r * math.sin(a), r * math.cos(a)))
    assert sin_cos_small(0.0) == (1.0, 0.0)
    # behind the origin: atan2's value, wrapped into [−π, π)
    assert atan_small(0.0, -1.0) == -math.pi
    assert math.isnan(atan_small(math.nan, 1.0))


def random_state(rng, yaw, pitch, roll, angle_std):
    x = np.concatenate([rng.normal(0, 2, 3), rng.normal(0, 1, 3), [pitch, roll, yaw]])
    G = rng.normal(size=(9, 9))
    P = G @ G.T / 9 + 0.1 * np.eye(9)
    sd = np.array([0.5] * 3 + [0.2] * 3 + [angle_std] * 3)
    return x, P * np.outer(sd, sd)


def random_preintegral(rng, tau):
    D = euler_to_dcm(rng.normal(0, 0.5, 3))
    return Preintegral(D, rng.normal(0, 2, 3) * tau, rng.normal(0, 1, 3) * tau * tau)


# (yaw, pitch, roll, angle std): ordinary, yaw at the ±π wrap, steep pitch, wide spread
CASES = [(0.3, 0.1, -0.2, 0.05), (3.14159, -0.4, 3.1, 0.2), (-1.0, 1.45, 0.5, 0.1), (1, 0, 0, 3.0)]


@pytest.mark.parametrize(("yaw", "pitch", "roll", "std"), CASES)
def test_moved_residuals_equal_the_direct_formulas(yaw, pitch, roll, std):
    rng = np.random.default_rng(11)
    x, P = random_state(rng, yaw, pitch, roll, std)
    sig = SigmaPoints(np.empty((19, 3, 3)), np.empty((19, 3)), np.empty((19, 3)))
    draw_sigmas(x, P, SPREAD, sig, new_algebra_scratch())
    for tau in (0.01, 0.37):
        pre = random_preintegral(rng, tau)
        chi_ref, C_ref, dev_ref = np.empty((19, 9)), np.empty((19, 3, 3)), np.empty((19, 9))
        moved_states(sig, pre, tau, 9.8, chi_ref, C_ref)
        residuals(chi_ref, dev_ref)
        chi, C_moved, dev = np.empty((19, 9)), np.empty((19, 3, 3)), np.empty((19, 9))
        moved_residuals(sig, pre, tau, 9.8, chi, C_moved, dev)
        # positions, velocities and the central point: the same arithmetic, the same bits
        np.testing.assert_array_equal(chi[:, :6], chi_ref[:, :6])
        np.testing.assert_array_equal(chi[0], chi_ref[0])
        np.testing.assert_array_equal(C_moved[0], C_ref[0])
        np.testing.assert_array_equal(dev[:, :6], dev_ref[:, :6])
        # angle residuals (rad, 1e-5 to 1e-2 here): equal to rounding of the angles themselves
        assert np.abs(dev_ref[:, 6:]).max() > 3e-5
        np.testing.assert_allclose(dev[:, 6:], dev_ref[:, 6:], rtol=0, atol=4e-15)


@pytest.mark.parametrize(("yaw", "pitch", "roll", "std"), CASES)
def test_draw_by_angle_sums_equals_the_direct_draw(yaw, pitch, roll, std):
    rng = np.random.default_rng(5)
    x, P = random_state(rng, yaw, pitch, roll, std)
    work = new_algebra_scratch()
    draws = []
    for angle_sums in (False, True):
        sig = SigmaPoints(np.empty((19, 3, 3)), np.empty((19, 3)), np.empty((19, 3)))
        repaired = draw_sigmas(x, P, SPREAD, sig, work, angle_sums)
        assert not repaired
        draws.append(sig)
    direct, sums = draws
    np.testing.assert_array_equal(sums.p, direct.p)
    np.testing.assert_array_equal(sums.v, direct.v)
    np.testing.assert_array_equal(sums.C[0], direct.C[0])
    assert np.abs(direct.C[1:] - direct.C[0]).max() > 1e-4  # the points do spread
    np.testing.assert_allclose(sums.C, direct.C, rtol=0, atol=2e-15)


def test_shoe_family_filter_uses_angle_sums_and_stays_the_same_filter(paper_walk):
    """The foot envs' shoe family runs the angle-sum path; paper 003's filter and
    ``real-fixed`` the direct one. Over a walk (over 500 ZUPTs per walker) the two
    paths differ by rounding only: at most 4.3e-9 (m, m/s, rad) when written,
    the size of the difference between blocks of 1 and 100 samples (6.4e-9)."""
    from simulated import FOOT_RATE_HZ, foot_imu

    from pednav_env.envs.foot_filters import family_filter
    from pednav_env.nav.zupt_ukf import ZuptUkf
    from pednav_env.replay.setup import real_fixed_setup

    assert not ZuptUkf(ZuptUkfConfig(), FOOT_RATE_HZ, 1).settings.angle_sums
    assert not ZuptUkf(real_fixed_setup().filter, FOOT_RATE_HZ, 1).settings.angle_sums
    cfg = family_filter("shoe", "calibrated")
    assert cfg.update_mode is UpdateMode.EVERY_STANCE_SAMPLE
    assert cfg == replace(real_fixed_setup().filter, angle_sums=True)
    imu = foot_imu(paper_walk, 2, seed=7)
    runs = {}
    for angle_sums in (True, False):
        eng = ZuptUkf(replace(cfg, angle_sums=angle_sums), FOOT_RATE_HZ, 2)
        assert eng.settings.angle_sums == angle_sums
        runs[angle_sums] = eng.run(imu.omega_b, imu.f_b, record=True)
        assert eng.updates.min() > 500
    fast, direct = runs[True], runs[False]
    np.testing.assert_array_equal(fast.stance, direct.stance)
    np.testing.assert_array_equal(fast.updates, direct.updates)
    diff = np.abs(fast.x - direct.x)
    assert 0 < diff.max() < 1e-7  # rounding (the paths do differ), nothing more
    with pytest.raises(ValueError, match="angle_sums"):
        ZuptUkfConfig(angle_sums=1)
