"""IMU error model (paper 003 eq 2 and the extensions)."""

import math

import numpy as np
import pytest

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.sensors.imu import IMU_GRADES, DriftModel, ImuSpec, grade_spec, simulate_imu

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


@pytest.mark.parametrize("walk_density", [0.0, 0.03])
def test_errors_are_the_generators_normal_draws_in_order(walk_density):
    """K, b, ν, then the (T, 3) records b_rw,ω, b_rw,f, δω, δf, each row by row, all
    from the walker's Generator as its own ``standard_normal`` draws them; the
    random-walk draws are made even when their density is zero."""
    t, rate = 300, 100.0
    omega, f = np.zeros((1, t, 3)), np.zeros((1, t, 3))
    spec = ImuSpec(
        gyro_noise_density=0.01,
        accel_noise_density=0.02,
        gyro_step_drift_std=0.0,
        gyro_bias_rw_density=walk_density,
        accel_bias_rw_density=2 * walk_density,
    )
    m = simulate_imu(omega, f, rate, spec, [np.random.default_rng(7)])
    ref = np.random.default_rng(7)
    ref.standard_normal(9 + 9 + 3 + 3 + 3)  # K_ω, K_f, b_ω, b_f, ν (one gait step)
    walk_w, walk_f, noise_w, noise_f = (ref.standard_normal((t, 3)) for _ in range(4))
    root_dt = math.sqrt(1.0 / rate)
    expect_w = np.cumsum(walk_w, axis=0) * walk_density * root_dt + noise_w * 0.01 * 10.0
    expect_f = np.cumsum(walk_f, axis=0) * 2 * walk_density * root_dt + noise_f * 0.02 * 10.0
    np.testing.assert_allclose(m.omega_b[0], expect_w, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(m.f_b[0], expect_f, rtol=1e-12, atol=1e-15)


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


def test_grade_spec_is_the_named_grade_built_once():
    for name, make in IMU_GRADES.items():
        assert grade_spec(name) == make()
        assert grade_spec(name) is grade_spec(name)
    with pytest.raises(ValueError, match="grade"):
        grade_spec("no_such_grade")
