"""Paper 004's step-fusion KF (nav.step_fusion_kf); its truth is the Schuler INS error
model of papers 000/004 (tested in tests/sensors/test_ins_error.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from pednav_env.constants import EARTH_RADIUS, STANDARD_GRAVITY
from pednav_env.nav.step_fusion_kf import (
    H_DV,
    StepFusionConfig,
    StepFusionKF,
    joseph_update,
    kf_predict,
    kf_update,
    repair_covariance,
)
from pednav_env.sensors.ins_error import (
    SchulerErrorConfig,
    schuler_transition,
    simulate_schuler_errors,
)

G, RE = STANDARD_GRAVITY, EARTH_RADIUS


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# ----------------------------------------------------------------------------- filterpy oracle
@pytest.mark.parametrize("channel", [0, 1])
def test_matches_filterpy_step_by_step(channel: int) -> None:
    cfg = StepFusionConfig(accel_noise_std=0.3, initial_std=(0.4, 2e-3, 1e-5))
    q_scale, r_scale = 1.7, 0.6
    kf = StepFusionKF(cfg, 1, q_scale=q_scale, r_scale=r_scale)
    ref = KalmanFilter(dim_x=3, dim_z=1)
    ref.x = np.array(cfg.initial_estimate)[:, None]
    ref.P = cfg.P0.copy()
    ref.Q = cfg.Q * q_scale
    ref.R = cfg.R * r_scale
    ref.H = H_DV.copy()
    rng = np.random.default_rng(11)
    sign = 1.0 if channel == 0 else -1.0
    worst = 0.0
    for _ in range(300):
        T = rng.uniform(0.35, 0.8)
        vi, vb = rng.normal(1.0, 0.5, (1, 2)), rng.normal(1.0, 0.5, (1, 2))
        kf.step(vi, vb, np.array([T]))
        ref.F = schuler_transition(T, cfg.g, cfg.earth_radius, sign)
        ref.predict()
        worst = max(worst, _rel(kf.x_prior[0, channel], ref.x[:, 0]))
        worst = max(worst, _rel(kf.P_prior[0, channel], ref.P))
        ref.update(np.array([[vi[0, channel] - vb[0, channel]]]))
        worst = max(worst, _rel(kf.x[0, channel], ref.x[:, 0]))
        worst = max(worst, _rel(kf.P[0, channel], ref.P))
        worst = max(worst, _rel(kf.K[0, channel], ref.K[:, 0]))
        assert kf.y[0, channel] == pytest.approx(ref.y[0, 0], rel=1e-8, abs=1e-12)
        assert kf.S[0, channel] == pytest.approx(ref.S[0, 0], rel=1e-8)
    assert worst <= 1e-8
    assert kf.repairs[0] == 0 and not kf.diverged[0]


def test_joseph_form_holds_for_any_gain() -> None:
    # The Joseph form (I − KH)P(I − KH)ᵀ + KRKᵀ is the covariance for any gain, not
    # only the optimal one (where it equals (I − KH)P).
    rng = np.random.default_rng(14)
    A = rng.normal(size=(3, 3))
    P, K = A @ A.T, rng.normal(size=(3, 1))
    R = np.array([[0.3]])
    I_KH = np.eye(3) - K @ H_DV
    np.testing.assert_allclose(joseph_update(P, K, H_DV, R), I_KH @ P @ I_KH.T + K @ R @ K.T)


def test_stateless_functions_match_filterpy_for_general_sizes() -> None:
    rng = np.random.default_rng(12)
    n, m = 4, 2
    A = rng.normal(size=(n, n))
    P = A @ A.T + np.eye(n)
    F, H = np.eye(n) + 0.1 * rng.normal(size=(n, n)), rng.normal(size=(m, n))
    Q, R = np.diag(rng.uniform(0.1, 1, n)), np.diag(rng.uniform(0.1, 1, m))
    x, z = rng.normal(size=n), rng.normal(size=m)
    ref = KalmanFilter(dim_x=n, dim_z=m)
    ref.x, ref.P, ref.F, ref.Q, ref.H, ref.R = x[:, None], P.copy(), F, Q, H, R
    ref.predict()
    ref.update(z[:, None])
    xp, Pp = kf_predict(x, P, F, Q)
    xu, Pu, y, S, K = kf_update(xp, Pp, z, H, R)
    assert _rel(xu, ref.x[:, 0]) <= 1e-12 and _rel(Pu, ref.P) <= 1e-12
    assert _rel(y, ref.y[:, 0]) <= 1e-12
    assert _rel(K, ref.K) <= 1e-12 and _rel(S, ref.S) <= 1e-12


# ----------------------------------------------------------------------------- engine behaviour
def test_corrected_velocity_and_position_eqs_5_6() -> None:
    cfg = StepFusionConfig()
    kf = StepFusionKF(cfg, 2, pos0=[[10.0, -5.0], [0.0, 0.0]])
    x_prev = kf.x.copy()
    vi = np.array([[1.2, 0.7], [-0.3, 1.1]])
    vb = np.array([[1.0, 0.8], [-0.2, 0.9]])
    T = np.array([0.5, 0.6])
    vc = kf.step(vi, vb, T)
    F = schuler_transition(T[:, None], cfg.g, cfg.earth_radius)
    pred = np.einsum("ncij,ncj->nci", F, x_prev)[..., 0]
    np.testing.assert_allclose(vc, vi - pred, atol=1e-15)
    np.testing.assert_allclose(kf.pos, [[10.0, -5.0], [0.0, 0.0]] + T[:, None] * vc, atol=1e-14)
    np.testing.assert_allclose(kf.y, (vi - vb) - pred, atol=1e-15)


def test_batch_lanes_and_masking() -> None:
    rng = np.random.default_rng(13)
    cfg = StepFusionConfig(accel_noise_std=0.2)
    n = 5
    q = rng.uniform(0.5, 2.0, n)
    r = rng.uniform(0.5, 2.0, n)
    kf = StepFusionKF(cfg, n, q_scale=q, r_scale=r)
    singles = [StepFusionKF(cfg, 1, q_scale=q[i], r_scale=r[i]) for i in range(n)]
    for _ in range(40):
        vi, vb = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
        T = rng.uniform(0.4, 0.7, n)
        mask = rng.random(n) < 0.7
        before = kf.x.copy(), kf.P.copy(), kf.pos.copy()
        kf.step(vi, vb, T, mask)
        for i in range(n):
            if mask[i]:
                singles[i].step(vi[i : i + 1], vb[i : i + 1], T[i : i + 1])
            else:
                np.testing.assert_array_equal(kf.x[i], before[0][i])
                np.testing.assert_array_equal(kf.P[i], before[1][i])
                np.testing.assert_array_equal(kf.pos[i], before[2][i])
    for i in range(n):
        # Same arithmetic per lane: bit-identical to a batch of one.
        np.testing.assert_array_equal(kf.x[i], singles[i].x[0])
        np.testing.assert_array_equal(kf.P[i], singles[i].P[0])
        assert kf.steps[i] == singles[i].steps[0]


def test_consistency_with_true_error_model() -> None:
    # Truth from the Schuler error model with the filter's own statistics: after a
    # few steps the sample std of e = δV − δV̂ over N walkers must match sqrt(P00).
    # Relative std of a sample std is 1/sqrt(2N) = 0.025 for N = 800; the bound
    # 0.12 is ≈ 5 of those over the 20 steps checked.
    n, k = 800, 60
    filt = StepFusionConfig(accel_noise_std=0.5, initial_estimate=(0.0, 0.0, 0.0))
    truth = SchulerErrorConfig(
        accel_noise_std=0.5,
        initial_velocity_std=filt.initial_std[0],
        initial_tilt_std=filt.initial_std[1],
        initial_drift_std=filt.initial_std[2],
    )
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(3).spawn(n)]
    x = simulate_schuler_errors(np.full((n, k), 0.5), truth, rngs)
    noise = np.random.default_rng(99).normal(0, filt.bm_noise_std, (k, n, 2))
    kf = StepFusionKF(filt, n)
    rel = []
    for j in range(k):
        vbar = np.array([1.4, 0.0])
        kf.step(vbar + x[:, j + 1, :, 0], vbar + noise[j], np.full(n, 0.5))
        if j >= k - 20:
            e = x[:, j + 1, :, 0] - kf.x[..., 0]
            rel.append(np.abs(e.std(axis=0, ddof=1) / np.sqrt(kf.P[0, :, 0, 0]) - 1))
    assert np.max(rel) < 0.12


def test_covariance_repair_is_counted_not_fatal() -> None:
    P = np.array(
        [[[1.0, 2.0, 0], [2.0, 1.0, 0], [0, 0, 1.0]], [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]]
    )
    fixed, bad = repair_covariance(P)
    np.testing.assert_array_equal(bad, [True, False])
    assert np.linalg.eigvalsh(fixed[0]).min() >= -1e-15
    np.testing.assert_array_equal(fixed[1], P[1])
    kf = StepFusionKF(StepFusionConfig(), 2)
    kf.P[0, 0] = P[0]
    kf.step(np.zeros((2, 2)), np.zeros((2, 2)), np.full(2, 0.5))
    assert kf.repairs.tolist() == [1, 0]
    assert np.all(np.isfinite(kf.x)) and np.all(np.isfinite(kf.P))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(accel_noise_std=-0.1), "accel_noise_std"),
        (dict(bm_noise_std=0.0), "bm_noise_std"),
        (dict(drift_noise_std=math.inf), "drift_noise_std"),
        (dict(initial_std=(0.3, 0.0)), "initial_std"),
        (dict(initial_std=(0.3, -1.0, 0.0)), "initial_std"),
    ],
)
def test_invalid_config_raises(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        StepFusionConfig(**kwargs)


def test_invalid_step_inputs_raise() -> None:
    kf = StepFusionKF(StepFusionConfig(), 2)
    ok = np.zeros((2, 2))
    with pytest.raises(ValueError, match="vbar_ins"):
        kf.step(np.zeros((2, 3)), ok, np.full(2, 0.5))
    with pytest.raises(ValueError, match="NaN"):
        kf.step(np.array([[np.nan, 0], [0, 0]]), ok, np.full(2, 0.5))
    with pytest.raises(ValueError, match="step_period"):
        kf.step(ok, ok, np.array([0.5, 0.0]))
    kf.q_scale = np.array([1.0, -1.0])
    with pytest.raises(ValueError, match="q_scale"):
        kf.step(ok, ok, np.full(2, 0.5))
    with pytest.raises(ValueError, match="n_walkers"):
        StepFusionKF(StepFusionConfig(), 0)
    # NaN input of a masked-out walker is ignored.
    kf.q_scale = 1.0
    kf.step(np.array([[np.nan, 0], [0, 0]]), ok, np.array([-1.0, 0.5]), np.array([False, True]))
    assert kf.steps.tolist() == [0, 1]


def test_step_sequence_equals_masked_steps_bit_for_bit() -> None:
    # A sequence of steps (several per walker, some walkers none) must give exactly
    # the numbers of one masked step per round, and leave step-less walkers untouched.
    rng = np.random.default_rng(17)
    cfg = StepFusionConfig(accel_noise_std=0.3)
    n = 5
    q, r = rng.uniform(0.5, 2.0, n), rng.uniform(0.5, 2.0, n)
    masked = StepFusionKF(cfg, n, q_scale=q, r_scale=r)
    seq = StepFusionKF(cfg, n, q_scale=q, r_scale=r)
    for _ in range(10):
        counts = rng.integers(0, 4, n)  # steps per walker in this call
        walker = np.repeat(np.arange(n), counts)
        vi, vb = rng.normal(size=(walker.size, 2)), rng.normal(size=(walker.size, 2))
        T = rng.uniform(0.3, 0.8, walker.size)
        first = np.cumsum(counts) - counts
        y_want, S_want = np.full((walker.size, 2), np.nan), np.full((walker.size, 2), np.nan)
        for j in range(counts.max()):
            m = counts > j
            e = first[m] + j
            vi_j, vb_j, T_j = np.zeros((n, 2)), np.zeros((n, 2)), np.ones(n)
            vi_j[m], vb_j[m], T_j[m] = vi[e], vb[e], T[e]
            masked.step(vi_j, vb_j, T_j, m)
            y_want[e], S_want[e] = masked.y[m], masked.S[m]
        y, S = seq.step_sequence(walker, vi, vb, T)
        np.testing.assert_array_equal(y, y_want)
        np.testing.assert_array_equal(S, S_want)
    for name in ("x", "P", "pos", "x_prior", "P_prior", "y", "S", "K", "repairs", "steps"):
        np.testing.assert_array_equal(getattr(seq, name), getattr(masked, name))
    ok = np.zeros((2, 2))
    bad = (([1, 0], "non-decreasing"), ([0, 5], r"\[0, 5\)"), ([0.0, 1.0], "integer"))
    for walker, match in bad:
        with pytest.raises(ValueError, match=match):
            seq.step_sequence(np.array(walker), ok, ok, np.full(2, 0.5))
    with pytest.raises(ValueError, match=r"\(2, 2\)"):
        seq.step_sequence(np.array([0, 1]), np.zeros((n, 2)), np.zeros((n, 2)), np.full(n, 0.5))
    with pytest.raises(ValueError, match="step_period"):
        seq.step_sequence(np.array([0, 1]), ok, ok, np.array([0.5, 0.0]))
