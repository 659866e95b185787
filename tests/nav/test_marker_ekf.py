"""Marker EKF of paper 001 (pednav_env.nav.marker_ekf, marker_model, marker_run)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter
from scipy.stats import chi2
from simulated import marker_walks

from pednav_env.gait.heel_knee import HeelKneeConfig
from pednav_env.gait.heel_knee_model import HeelKneeNominal
from pednav_env.nav.marker_model import MarkerEkfConfig, marker_jacobian, marker_measurement
from pednav_env.nav.marker_run import MarkerEKF, run_marker_ekf
from pednav_env.sensors.uwb import UwbSpec

# --------------------------------------------------------------------------- model functions


def test_jacobian_matches_central_differences() -> None:
    rng = np.random.default_rng(0)
    M = 0.5
    p0 = HeelKneeNominal().vector
    for _ in range(20):
        p = p0 + 0.1 * np.abs(p0) * rng.standard_normal(6)
        t = rng.uniform(0.0, 15.0)
        H = marker_jacobian(p, t, M)
        step = 1e-6 * np.maximum(np.abs(p), 1e-3)
        num = np.empty((4, 6))
        for j in range(6):
            dp = np.zeros(6)
            dp[j] = step[j]
            num[:, j] = (marker_measurement(p + dp, t, M) - marker_measurement(p - dp, t, M)) / (
                2 * step[j]
            )
        np.testing.assert_allclose(H, num, rtol=1e-6, atol=1e-7 * max(1.0, t))


def test_jacobian_structure_of_eq_5_3() -> None:
    # Thesis (5.3): x₁ does not depend on ΔA_z, Δc_z, ΔA; z₁ not on ΔA_x, Δc_x, ΔA;
    # ∂x₁/∂Δc_x = kT, ∂z₁/∂Δc_z = 1.
    H = marker_jacobian(HeelKneeNominal().vector + 0.01, 2.3, 0.5)
    assert np.all(H[0, [1, 3, 4]] == 0) and np.all(H[1, [0, 2, 4]] == 0)
    assert H[0, 2] == 2.3 and H[2, 2] == 2.3 and H[1, 3] == 1.0 and H[3, 3] == 1.0
    assert np.all(H[2:, 1:4:2] == H[:2, 1:4:2])


# --------------------------------------------------------------------------- filterpy oracle


def filterpy_run(cfg: MarkerEkfConfig, z, valid, q_scale, r_scale):
    """Reference: filterpy's ExtendedKalmanFilter with the same h and H functions."""
    proc = cfg.process
    p0 = cfg.nominal.vector
    M = cfg.nominal.shank_length
    f = ExtendedKalmanFilter(dim_x=6, dim_z=4)
    f.x = np.zeros((6, 1))
    f.P = np.diag(proc.P0)
    f.F = np.diag(proc.F)
    f.Q = np.diag(proc.Gamma**2 * proc.Q * q_scale)
    R = cfg.R * r_scale
    xs, Ps = [], []
    for k in range(z.shape[0]):
        t = k * cfg.sample_period
        if k:
            f.predict()
        rows = np.repeat(valid[k], 2)
        if rows.any():
            f.update(
                z[k].reshape(4)[rows][:, None],
                lambda x, t, rows=rows: marker_jacobian(p0 + x.ravel(), t, M)[rows],
                lambda x, t, rows=rows: marker_measurement(p0 + x.ravel(), t, M)[rows][:, None],
                R=R[np.ix_(rows, rows)],
                args=(t,),
                hx_args=(t,),
            )
        xs.append(f.x.ravel().copy())
        Ps.append(f.P.copy())
    return np.array(xs), np.array(Ps)


def test_batched_ekf_equals_filterpy_step_by_step() -> None:
    gait = HeelKneeConfig(param_corr_time=300.0)
    uwb = UwbSpec.realistic()
    n, k = 3, 120
    _, meas = marker_walks(21, n, k, gait, uwb)
    assert not meas.valid.all() and meas.outlier.any()  # skipped rows and outliers occur
    cfg = MarkerEkfConfig.matched(gait, uwb)
    q_scale = np.array([[1.0] * 6, [0.5, 2.0, 1.0, 3.0, 0.7, 1.5], [2.0] * 6])
    r_scale = np.array([[1.0] * 4, [2.0, 0.5, 1.0, 3.0], [0.7] * 4])
    # Moderate scales: a lane whose ω̂ runs away to ≈ 0 (seen with a walker
    # drawn 2σ off nominal, Q × 4, R × 0.3) is a chaotic map in which rounding
    # differences between any two correct implementations (inv vs solve,
    # symmetrised or not) grow to ~1e-6 over 120 steps.
    ekf = MarkerEKF(cfg, n)
    for i in range(n):
        xs, Ps = filterpy_run(cfg, meas.z[i], meas.valid[i], q_scale[i], r_scale[i])
        ekf = MarkerEKF(cfg, n)
        for j in range(k):
            if j:
                ekf.predict(q_scale)
            ekf.update(meas.z[:, j], j * cfg.sample_period, meas.valid[:, j], r_scale)
            # ≤ 1e-8 relative (to the norm of filterpy's value) at every step
            assert np.max(np.abs(ekf.x[i] - xs[j])) <= 1e-8 * np.max(np.abs(xs[j])) + 1e-300
            assert np.max(np.abs(ekf.P[i] - Ps[j])) <= 1e-8 * np.max(np.abs(Ps[j]))
    assert ekf.repairs.sum() == 0


def test_walker_of_a_batch_equals_a_batch_of_one_bit_for_bit() -> None:
    gait = HeelKneeConfig(param_corr_time=100.0, initial_deviation="stationary")
    uwb = UwbSpec.realistic()
    _, meas = marker_walks(22, 5, 60, gait, uwb)
    cfg = MarkerEkfConfig.matched(gait, uwb)
    q = np.array([1.0, 2.0, 0.5, 1.0, 3.0])
    r = np.array([1.0, 0.5, 2.0, 1.0, 1.5])
    full = run_marker_ekf(cfg, meas.z, meas.valid, q_scale=q, r_scale=r)
    again = run_marker_ekf(cfg, meas.z, meas.valid, q_scale=q, r_scale=r)
    assert np.array_equal(full.x, again.x) and np.array_equal(full.markers, again.markers)
    for i in range(5):
        one = run_marker_ekf(
            cfg,
            meas.z[i : i + 1],
            meas.valid[i : i + 1],
            q_scale=q[i : i + 1],
            r_scale=r[i : i + 1],
        )
        assert np.array_equal(one.x[0], full.x[i])
        assert np.array_equal(one.P_diag[0], full.P_diag[i])
        assert np.array_equal(one.markers[0], full.markers[i])


# --------------------------------------------------------------------------- filter behaviour


def test_predict_adds_scaled_process_noise_of_eq_5_4() -> None:
    cfg = MarkerEkfConfig(param_corr_time=2.0)
    ekf = MarkerEKF(cfg, 2)
    before = ekf.P.copy()
    ekf.predict(q_scale=np.array([1.0, 2.0]))
    d = math.exp(-0.1 / 2.0)
    # Γ Q Γᵀ = (1 − d)² (1 + d)/(1 − d) 0.03 p⁰² = (1 − d²) 0.03 p⁰², written out
    q = (1 - d**2) * 0.03 * HeelKneeNominal().vector ** 2
    np.testing.assert_allclose(ekf.P[0], d * d * before[0] + np.diag(q), rtol=1e-12)
    np.testing.assert_allclose(ekf.P[1], d * d * before[1] + np.diag(2 * q), rtol=1e-12)


def test_initialisation_of_eqs_5_7_and_5_8() -> None:
    ekf = MarkerEKF(MarkerEkfConfig(), 3)
    assert np.all(ekf.x == 0)
    want = np.diag(
        0.03
        * np.array(
            [0.4, 0.1, 3.0, 0.1, ekf.config.nominal.shank_angle_amplitude, 2 * math.pi / 0.7]
        )
        ** 2
    )
    np.testing.assert_allclose(ekf.P, np.broadcast_to(want, (3, 6, 6)), rtol=1e-12)


def test_all_invalid_update_changes_nothing_partial_update_uses_valid_rows() -> None:
    cfg = MarkerEkfConfig()
    ekf = MarkerEKF(cfg, 2)
    ekf.predict()
    x, P = ekf.x.copy(), ekf.P.copy()
    z = np.full((2, 4), 1e3)  # absurd values in skipped rows must not matter
    ekf.update(z, 1.0, np.zeros((2, 2), dtype=bool))
    assert np.array_equal(ekf.x, x) and np.array_equal(ekf.P, P)
    assert np.all(ekf.num_valid == 0) and np.all(ekf.nis == 0)
    # heel only: the knee's (absurd) values are ignored, the heel's are used
    z_true = marker_measurement(cfg.nominal.vector, 1.0, cfg.nominal.shank_length)
    z = np.tile(np.r_[z_true[:2] + 0.05, 1e3, -1e3], (2, 1))
    ekf.update(z, 1.0, np.array([[True, False], [True, False]]))
    assert np.all(ekf.num_valid == 2)
    assert np.all(np.abs(ekf.x) < 1.0) and not np.array_equal(ekf.x, x)


def test_covariance_repair_is_counted_and_restores_positive_definiteness() -> None:
    cfg = MarkerEkfConfig()
    ekf = MarkerEKF(cfg, 3)
    ekf.predict()
    bad = ekf.P[1].copy()
    bad[0, 1] = bad[1, 0] = 2.0 * math.sqrt(bad[0, 0] * bad[1, 1])  # |ρ| = 2: indefinite
    ekf.P[1] = bad
    ekf.update(np.zeros((3, 4)), 0.5)
    assert list(ekf.repairs) == [0, 1, 0]
    assert np.min(np.linalg.eigvalsh(ekf.P[1])) > 0
    np.testing.assert_array_equal(ekf.P, ekf.P.transpose(0, 2, 1))


def test_walker_interface_is_a_view_of_the_engine_and_nonfinite_lanes_are_not_repaired() -> None:
    ekf = MarkerEKF(MarkerEkfConfig(), 3)
    assert np.shares_memory(ekf.x, ekf.engine.x) and np.shares_memory(ekf.P, ekf.engine.P)
    ekf.predict()
    ekf.P[2, 0, 0] = np.nan  # a diverged lane: reported by repair(), left alone, not counted
    diverged = ekf.engine.repair()
    assert list(diverged) == [False, False, True] and list(ekf.repairs) == [0, 0, 0]
    assert np.isnan(ekf.engine.P[2, 0, 0])


def test_filter_is_statistically_consistent_in_a_mildly_nonlinear_regime() -> None:
    # Truth drawn from the filter's own prior (stationary start), 5.5 % parameter
    # spread (var ratio 0.003), τ = 1000 s: the EKF should be consistent. With
    # N = 300 walkers the mean NEES at the last step is χ²(6N)/N and the mean
    # NIS over all N·(K−1) updates χ²(4N(K−1))/(N(K−1)); the bands are their
    # two-sided 99.9 % quantiles. (At the thesis's 17 % spread the EKF's phase
    # linearisation breaks and NEES inflates: docs/REPRODUCTION.md (paper 001).)
    gait = HeelKneeConfig(
        param_corr_time=1000.0, param_var_ratio=0.003, initial_deviation="stationary"
    )
    uwb = UwbSpec()
    n, k = 300, 100
    walk, meas = marker_walks(23, n, k, gait, uwb)
    res = run_marker_ekf(MarkerEkfConfig.matched(gait, uwb), meas.z)
    # NEES from the posterior covariance: only the diagonal is stored per step,
    # so rerun the last step's full P with a filter object.
    ekf = MarkerEKF(MarkerEkfConfig.matched(gait, uwb), n)
    for j in range(k):
        if j:
            ekf.predict()
        ekf.update(meas.z[:, j], j * gait.sample_period)
    assert np.array_equal(ekf.x, res.x[:, -1])
    err = walk.deviation[:, -1] - ekf.x
    nees = np.einsum("ni,ni->n", err, np.linalg.solve(ekf.P, err[..., None])[..., 0])
    lo, hi = chi2.ppf([0.0005, 0.9995], 6 * n) / n
    assert lo < nees.mean() < hi
    m = n * (k - 1)
    lo, hi = chi2.ppf([0.0005, 0.9995], 4 * m) / m
    assert lo < res.nis[:, 1:].mean() < hi


def test_ekf_beats_raw_measurements_on_the_paper_model() -> None:
    # Not a paper number: a filter that knows the model must average the white
    # UWB noise (σ = 0.1 m) down. Its heel z error is bounded by the prior
    # spread of c_z and A_z (0.017 m each) plus phase error; 0.05 m is loose.
    gait = HeelKneeConfig(param_corr_time=1e4)
    uwb = UwbSpec()
    walk, meas = marker_walks(24, 50, 100, gait, uwb)
    res = run_marker_ekf(MarkerEkfConfig.matched(gait, uwb), meas.z)
    rms = np.sqrt(np.mean((res.markers - walk.markers) ** 2, axis=(0, 1))).ravel()
    assert np.all(rms < 0.08)
    assert rms[1] < 0.05 and rms[3] < 0.05


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"sample_period": 0.0}, "sample_period"),
        ({"sample_period": -1.0}, "sample_period"),
        ({"param_corr_time": math.nan}, "param_corr_time"),
        ({"meas_std": -0.1}, "meas_std"),
        ({"meas_std": 0.0}, "meas_std"),
        ({"param_var_ratio": -0.03}, "param_var_ratio"),
        ({"param_var_ratio": math.inf}, "param_var_ratio"),
        ({"eig_floor": 0.0}, "eig_floor"),
        ({"nominal": "paper"}, "nominal"),
    ],
)
def test_config_rejects_impossible_values(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        MarkerEkfConfig(**kwargs)


def test_filter_rejects_bad_inputs() -> None:
    ekf = MarkerEKF(MarkerEkfConfig(), 2)
    z = np.zeros((2, 4))
    with pytest.raises(ValueError, match="num_walkers"):
        MarkerEKF(MarkerEkfConfig(), 0)
    with pytest.raises(ValueError, match="z must"):
        ekf.update(np.zeros((3, 4)), 0.0)
    with pytest.raises(ValueError, match="z must be finite"):
        ekf.update(np.array([[0.0, np.nan, 0.0, 0.0], [0.0] * 4]), 0.0)
    # NaN in a skipped row is allowed (it is never read)
    ekf.update(np.array([[0.0, np.nan, 0.0, 0.0], [0.0] * 4]), 0.0, np.array([[False, True]] * 2))
    assert np.all(np.isfinite(ekf.x)) and np.all(np.isfinite(ekf.P))
    with pytest.raises(ValueError, match="t must"):
        ekf.update(z, np.inf)
    with pytest.raises(ValueError, match="t must"):
        ekf.update(z, np.zeros(3))
    with pytest.raises(ValueError, match="valid"):
        ekf.update(z, 0.0, np.ones((2, 3), dtype=bool))
    with pytest.raises(ValueError, match="valid"):
        ekf.update(z, 0.0, np.ones((2, 2)))
    with pytest.raises(ValueError, match="r_scale"):
        ekf.update(z, 0.0, r_scale=-1.0)
    with pytest.raises(ValueError, match="q_scale"):
        ekf.predict(q_scale=np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="q_scale"):
        ekf.predict(q_scale=np.ones((2, 5)))
    with pytest.raises(ValueError, match="z must"):
        run_marker_ekf(MarkerEkfConfig(), np.zeros((2, 5, 4)))
    with pytest.raises(ValueError, match="sample_period"):
        MarkerEkfConfig.matched(HeelKneeConfig(sample_period=0.01), UwbSpec(rate_hz=10.0))
