"""IMU error model (paper 003 eq 2 and the extensions)."""

import math

import numpy as np
import pytest

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.sensors.imu import DriftModel, ImuSpec, simulate_imu

G = STANDARD_GRAVITY


def static_truth(n=4, t=20000):
    omega = np.zeros((n, t, 3))
    f = np.zeros((n, t, 3))
    f[..., 2] = G
    return omega, f


def gens(n, seed=0):
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


def test_static_imu_reads_gravity_up_to_its_noise():
    omega, f = static_truth()
    spec = ImuSpec.paper003(drift_model=DriftModel.PER_SAMPLE)
    m = simulate_imu(omega, f, 100.0, spec, gens(4))
    n = omega.shape[0] * omega.shape[1]
    # mean: (0, 0, g) within 5 standard errors
    for axis, truth, std in ((0, 0.0, 0.1), (1, 0.0, 0.1), (2, G, 0.1)):
        assert abs(m.f_b[..., axis].mean() - truth) < 5 * std / math.sqrt(n)
    # per-sample std: accel 0.1; gyro white 0.05 plus per-sample drift 0.02
    np.testing.assert_allclose(m.f_b.std(axis=(0, 1)), 0.1, rtol=0.02)
    np.testing.assert_allclose(m.omega_b.std(axis=(0, 1)), math.hypot(0.05, 0.02), rtol=0.02)


def test_drift_is_constant_within_a_gait_step():
    omega, f = static_truth(n=1, t=1000)
    steps = np.repeat(np.arange(10), 100)[None]
    spec = ImuSpec(gyro_noise_density=0.0, accel_noise_density=0.0, gyro_step_drift_std=0.02)
    m = simulate_imu(omega, f, 100.0, spec, gens(1), gait_step_index=steps)
    w = m.omega_b[0].reshape(10, 100, 3)
    np.testing.assert_array_equal(w, np.broadcast_to(w[:, :1], w.shape))
    assert np.unique(w[:, 0, 0]).size == 10
    per_sample = simulate_imu(
        omega,
        f,
        100.0,
        ImuSpec(0.0, 0.0, 0.02, DriftModel.PER_SAMPLE),
        gens(1),
        gait_step_index=steps,
    )
    assert np.unique(per_sample.omega_b[0, :, 0]).size == 1000


def test_saturation_is_clipped_and_flagged_and_quantisation_applies():
    t = np.linspace(0, 1, 101)
    omega = np.zeros((1, 101, 3))
    omega[0, :, 1] = 10 * np.sin(2 * np.pi * t)  # paper 003: pitch rate up to 10 rad/s
    f = np.zeros_like(omega)
    f[..., 2] = G
    spec = ImuSpec(0.0, 0.0, 0.0, gyro_range=6.0, gyro_lsb=0.01)
    m = simulate_imu(omega, f, 100.0, spec, gens(1))
    assert np.abs(m.omega_b).max() == pytest.approx(6.0)
    np.testing.assert_array_equal(m.gyro_saturated[0], np.abs(omega[0, :, 1]) > 6.0)
    q = m.omega_b[0, ~m.gyro_saturated[0], 1] / 0.01
    np.testing.assert_allclose(q, np.round(q), atol=1e-9)


def test_walker_errors_do_not_depend_on_the_batch():
    omega, f = static_truth(n=3, t=500)
    g3 = gens(3, seed=11)
    batch = simulate_imu(omega, f, 100.0, ImuSpec.adis16405(), g3)
    single = simulate_imu(omega[2:], f[2:], 100.0, ImuSpec.adis16405(), gens(3, seed=11)[2:])
    np.testing.assert_array_equal(batch.omega_b[2], single.omega_b[0])
    np.testing.assert_array_equal(batch.f_b[2], single.f_b[0])
    again = simulate_imu(omega, f, 100.0, ImuSpec.adis16405(), gens(3, seed=11))
    np.testing.assert_array_equal(batch.f_b, again.f_b)


def test_grades_differ_in_the_expected_direction():
    omega, f = static_truth(n=8, t=2000)
    adis = simulate_imu(omega, f, 100.0, ImuSpec.adis16405(), gens(8))
    consumer = simulate_imu(omega, f, 100.0, ImuSpec.consumer(), gens(8))
    # consumer turn-on biases are larger: spread of per-walker mean gyro readings
    assert consumer.omega_b.mean(axis=1).std() > adis.omega_b.mean(axis=1).std()


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"gyro_noise_density": -1.0}, "gyro_noise_density"),
        ({"accel_noise_density": math.nan}, "accel_noise_density"),
        ({"gyro_range": 0.0}, "gyro_range"),
        ({"accel_bias_std": math.inf}, "accel_bias_std"),
        ({"drift_model": "per_week"}, "per_week"),
    ],
)
def test_bad_spec_raises(kwargs, name):
    with pytest.raises(ValueError, match=name):
        ImuSpec(**kwargs)


def test_bad_inputs_raise():
    omega, f = static_truth(n=1, t=10)
    with pytest.raises(ValueError, match="rate_hz"):
        simulate_imu(omega, f, 0.0, ImuSpec(), gens(1))
    bad = omega.copy()
    bad[0, 3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        simulate_imu(bad, f, 100.0, ImuSpec(), gens(1))
    with pytest.raises(ValueError, match=r"\(N, T, 3\)"):
        simulate_imu(omega[0], f[0], 100.0, ImuSpec(), gens(1))
    with pytest.raises(ValueError, match="rngs"):
        simulate_imu(np.zeros((2, 10, 3)), np.zeros((2, 10, 3)), 100.0, ImuSpec(), gens(3))
    with pytest.raises(ValueError, match="rate_hz"):
        ImuSpec.paper003(rate_hz=-1.0)
