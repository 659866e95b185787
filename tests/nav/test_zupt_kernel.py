"""The compiled ZUPT kernel (nav.zupt_kernel, nav.detector_kernel): a block advance with
preintegrated sigma-point moves is sample-by-sample filtering, and the compiled stance
logic flags what the offline numpy detectors flag."""

import numpy as np
from simulated import FOOT_RATE_HZ, foot_imu

from pednav_env.nav.detectors import ShoeDetectorConfig
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.sensors.imu import ImuSpec

RATE = FOOT_RATE_HZ


def test_block_advance_equals_sample_by_sample(paper_walk):
    """A block of 50 samples (ZUPTs of all walkers in rounds, sigma points moved by
    preintegrals) is the same filter as 50 one-sample calls: identical stance
    flags and ZUPT counts, positions equal to rounding. Loose thresholds on a
    noisy consumer-grade record make stances flicker, so blocks hold several
    ZUPTs per walker."""
    imu = foot_imu(paper_walk, 4, seed=11, spec=ImuSpec.consumer())
    omega, f = imu.omega_b, imu.f_b
    runs = {}
    for block in (1, 50):
        eng = ZuptUkf(ZuptUkfConfig(calibrate_gyro_bias=True), RATE, 4)
        eng.omega_max[:] = [0.22, 0.5, 1.0, 2.0]
        runs[block] = (eng.run(omega, f, block_samples=block), eng.updates.copy())
    (one, upd_one), (blk, upd_blk) = runs[1], runs[50]
    flicker = np.diff(blk.stance.astype(int), axis=1) != 0
    # several stance changes within some 0.5 s block: the rounds are exercised
    blocks = (flicker.shape[1] - 100) // 50
    per_block = flicker[:, 100 : 100 + 50 * blocks].reshape(4, blocks, 50).sum(axis=2)
    assert per_block.max() >= 4
    np.testing.assert_array_equal(blk.stance, one.stance)
    np.testing.assert_array_equal(upd_blk, upd_one)
    assert np.abs(blk.x[..., :3] - one.x[..., :3]).max() < 1e-6  # m; rounding, amplified


def test_engine_stance_logic_equals_the_offline_detectors(paper_walk):
    """The kernel's detector (causal window, minimum stance duration, SHOE
    condition) flags the same samples as the offline numpy detectors of
    :mod:`pednav_env.testing.detectors` on the same inputs."""
    from pednav_env.nav.detectors import (
        ThresholdDetectorConfig,
        causal_moving_mean,
        shoe_statistic,
    )
    from pednav_env.testing.detectors import apply_min_duration

    imu = foot_imu(paper_walk, 3, seed=11)
    omega, f = imu.omega_b, imu.f_b
    # SHOE with a 5-sample window and a 0.06 s minimum stance
    shoe_cfg = ShoeDetectorConfig(window_s=0.05, min_stance_s=0.06)
    run = ZuptUkf(ZuptUkfConfig(detector=shoe_cfg), RATE, 3).run(omega, f)
    k0 = run.start_sample
    cond = shoe_statistic(omega, f, shoe_cfg, RATE)[:, k0:] <= shoe_cfg.threshold
    expected = apply_min_duration(cond, 6)
    np.testing.assert_array_equal(run.stance[:, k0:], expected)
    assert 0.2 < expected.mean() < 0.8  # both phases present
    # eq (5) with only the rate condition active (Δf_max out of reach): 0.07 s causal
    # mean of |ω'| against ω_max, 0.04 s minimum; the window restarts after alignment
    thr_cfg = ThresholdDetectorConfig(window_s=0.07, min_stance_s=0.04, delta_f_max=1e9)
    run = ZuptUkf(ZuptUkfConfig(detector=thr_cfg), RATE, 3).run(omega, f)
    mean_rate = causal_moving_mean(np.linalg.norm(omega[:, k0:], axis=-1), 7)
    expected = apply_min_duration(mean_rate <= thr_cfg.omega_max, 4)
    np.testing.assert_array_equal(run.stance[:, k0:], expected)
    assert 0.2 < expected.mean() < 0.8
