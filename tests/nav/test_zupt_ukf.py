"""ZUPT-UKF engine behaviour: batching, determinism, repairs, gating, bad input."""

import math
import warnings

import numpy as np
import pytest
from simulated import FOOT_RATE_HZ, foot_imu

from pednav_env.nav.detectors import ShoeDetectorConfig
from pednav_env.nav.ukf import MerweWeights, repair_covariance
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.nav.zupt_ukf import ZuptUkf

RATE = FOOT_RATE_HZ


def test_walker_result_does_not_depend_on_batch(paper_walk):
    imu = foot_imu(paper_walk, 3, seed=5)
    batch = ZuptUkf(ZuptUkfConfig(), RATE, 3).run(imu.omega_b, imu.f_b)
    single = ZuptUkf(ZuptUkfConfig(), RATE, 1).run(imu.omega_b[2:], imu.f_b[2:])
    np.testing.assert_array_equal(batch.x[2], single.x[0])
    np.testing.assert_array_equal(batch.stance[2], single.stance[0])
    again = ZuptUkf(ZuptUkfConfig(), RATE, 3).run(imu.omega_b, imu.f_b)
    np.testing.assert_array_equal(batch.x, again.x)


def test_noiseless_walk_is_tracked_to_centimetres(paper_walk):
    run = ZuptUkf(ZuptUkfConfig(), RATE, 1).run(paper_walk.omega_b, paper_walk.f_b)
    err = np.linalg.norm(run.x[0, :, :3] - paper_walk.pos_n[0], axis=-1)
    assert err.max() < 0.02
    assert run.updates[0] == 2 * 12 + 1  # start and end of every stance, start of the last
    assert run.repairs[0] == 0 and not run.diverged[0]


def test_shoe_detector_variant_tracks_too(paper_walk):
    imu = foot_imu(paper_walk, 4, seed=1)
    eq5 = ZuptUkf(ZuptUkfConfig(), RATE, 4).run(imu.omega_b, imu.f_b)
    shoe = ZuptUkf(ZuptUkfConfig(detector=ShoeDetectorConfig()), RATE, 4).run(imu.omega_b, imu.f_b)
    k = eq5.start_sample  # detection starts after the alignment window
    true = paper_walk.stance[0, k:]
    for run in (eq5, shoe):
        assert np.mean(run.stance[:, k:][:, true]) > 0.9
        assert np.mean(run.stance[:, k:][:, ~true]) < 0.02
    e5 = np.sqrt(np.mean(np.sum((eq5.x[..., :3] - paper_walk.pos_n) ** 2, -1)))
    es = np.sqrt(np.mean(np.sum((shoe.x[..., :3] - paper_walk.pos_n) ** 2, -1)))
    assert es < 3 * e5 and e5 < 3 * es


def test_false_zupt_in_mid_swing_is_gated(paper_walk):
    """Thresholds opened for one mid-swing sample make a false stance; the χ²
    gate rejects its ZUPTs, the ungated filter swallows them."""
    tr = paper_walk
    swing = np.flatnonzero(~tr.stance[0] & (tr.t[:-1] > 3.0))
    speed = np.linalg.norm(tr.vel_n[0, swing], axis=-1)
    m_false = int(swing[np.argmax(speed)])  # fastest instant of a swing
    results = {}
    for gate in (None, 0.999):
        eng = ZuptUkf(ZuptUkfConfig(gate_probability=gate), RATE, 1)
        eng.initialize(tr.f_b[:, :100])
        for m in range(100, m_false + 20):
            if m == m_false:
                eng.omega_max[:] = 1e3
                eng.delta_f_max[:] = 1e3
            elif m == m_false + 1:
                eng.omega_max[:] = 0.22
                eng.delta_f_max[:] = 0.33
            eng.step(tr.omega_b[:, m], tr.f_b[:, m])
        err = np.linalg.norm(eng.mean_state()[0, 3:6] - tr.vel_n[0, m_false + 20])
        results[gate] = (err, int(eng.rejected[0]))
    assert results[None][1] == 0 and results[None][0] > 0.5  # velocity pulled to zero
    assert results[0.999][1] == 2 and results[0.999][0] < 0.05  # start and end rejected


def test_covariance_repair_is_counted_and_never_nan():
    P = np.diag([1.0, 2.0, -1e-3, 1.0, 1.0, 1.0, 1e-4, 1e-4, 1e-4])[None]
    fixed, bad = repair_covariance(P)
    assert bad[0] and np.all(np.linalg.eigvalsh(fixed) > 0)
    eng = ZuptUkf(ZuptUkfConfig(), RATE, 2)
    x = np.zeros((2, 9))
    eng.set_state(np.arange(2), x, np.concatenate((P, np.eye(9)[None] * 1e-4)))
    assert eng.repairs.tolist() == [1, 0]
    assert np.all(np.isfinite(eng.sig_p)) and np.all(np.isfinite(eng.sig_C))


def test_garbage_input_diverges_cleanly():
    eng = ZuptUkf(ZuptUkfConfig(), RATE, 2)
    f = np.zeros((2, 300, 3))
    f[..., 2] = 9.80665
    f[1, 100:, 0] = 1e5  # walker 1: absurd acceleration
    omega = np.zeros_like(f)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run = eng.run(omega, f)
    assert run.diverged.tolist() == [False, True]
    assert np.all(np.isfinite(run.x))
    # a diverged walker is frozen where it was declared diverged, not integrated further
    assert np.all(run.x[1, 110:] == run.x[1, -1])
    assert np.abs(run.x[1, :, :3]).max() < 1.0


def test_merwe_weights_follow_the_paper():
    w = ZuptUkfConfig().weights
    L, a = 9, 1e-3
    lam = a**2 * L - L
    assert w.lam == pytest.approx(lam)
    assert w.Wm[0] == pytest.approx(lam / (lam + L))
    assert w.Wc[0] == pytest.approx(lam / (lam + L) + 1 - a**2)  # paper's W0c, β = 0
    np.testing.assert_allclose(w.Wm[1:], 1 / (2 * (lam + L)))
    assert w.Wm.sum() == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("factory", "name"),
    [
        (lambda: ZuptUkfConfig(zupt_velocity_std=-0.01), "zupt_velocity_std"),
        (lambda: ZuptUkfConfig(process_noise_scale=0.0), "process_noise_scale"),
        (lambda: ZuptUkfConfig(alpha=math.nan), "alpha"),
        (lambda: ZuptUkfConfig(gate_probability=1.5), "gate_probability"),
        (lambda: ZuptUkfConfig(update_mode="sometimes"), "sometimes"),
        (lambda: MerweWeights(9, 1e-3, 0.0, -9.0), "kappa"),
        (lambda: ZuptUkf(ZuptUkfConfig(), 0.0, 1), "rate_hz"),
        (lambda: ZuptUkf(ZuptUkfConfig(), 100.0, 0), "num_walkers"),
    ],
)
def test_bad_configurations_raise(factory, name):
    with pytest.raises(ValueError, match=name):
        factory()


def test_bad_records_raise():
    eng = ZuptUkf(ZuptUkfConfig(), RATE, 1)
    f = np.zeros((1, 200, 3))
    f[..., 2] = 9.8
    bad = f.copy()
    bad[0, 50, 2] = np.inf
    with pytest.raises(ValueError, match="NaN or inf"):
        eng.run(np.zeros_like(f), bad)
    with pytest.raises(ValueError, match=r"\(1, T, 3\)"):
        eng.run(np.zeros((2, 200, 3)), np.zeros((2, 200, 3)))
    with pytest.raises(ValueError, match="alignment"):
        eng.run(np.zeros((1, 10, 3)), f[:, :10])
    shoe = ZuptUkf(ZuptUkfConfig(detector=ShoeDetectorConfig()), RATE, 1)
    shoe.initialize(f[:, :100])
    with pytest.raises(ValueError, match="shoe_statistic"):
        shoe.step(np.zeros((1, 3)), f[:, 0])


def test_advance_rejects_bad_blocks():
    eng = ZuptUkf(ZuptUkfConfig(), RATE, 2)
    ok = np.zeros((2, 5, 3))
    ok[..., 2] = 9.80665
    eng.initialize(np.repeat(ok, 20, axis=1))
    with pytest.raises(ValueError, match="omega_b"):
        eng.advance(np.zeros((3, 5, 3)), ok)
    with pytest.raises(ValueError, match="f_b"):
        eng.advance(np.zeros((2, 5, 3)), ok[:, :4])
    with pytest.raises(ValueError, match="record"):
        eng.advance(np.zeros((2, 5, 3)), ok, record="everything")
    with pytest.raises(ValueError, match="valid"):
        eng.advance(np.zeros((2, 5, 3)), ok, valid=np.array([5, 6]))
    with pytest.raises(ValueError, match="shoe_statistic"):
        ZuptUkf(ZuptUkfConfig(detector=ShoeDetectorConfig()), RATE, 2).advance(ok * 0, ok)
    rec = np.repeat(ok, 30, axis=1)
    with pytest.raises(ValueError, match="block_samples"):
        eng.run(np.zeros_like(rec), rec, block_samples=0)
