"""UWB marker sensor of paper 001 (pednav_env.sensors.uwb)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pednav_env.sensors.uwb import UwbMeasurements, UwbSpec, hold_last_valid, measure_uwb


def rngs(seed: int, n: int) -> list[np.random.Generator]:
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


def truth(n: int, k: int) -> np.ndarray:
    t = np.arange(k) * 0.1
    heel = np.stack((3.0 * t + 0.4 * np.sin(9.0 * t), 0.1 + 0.1 * np.sin(9.0 * t)), axis=-1)
    knee = heel + [0.0, 0.5]
    return np.broadcast_to(np.stack((heel, knee), axis=-2), (n, k, 2, 2)).copy()


def test_paper_noise_is_gaussian_with_sigma_0_1() -> None:
    spec = UwbSpec.paper()
    assert spec.noise_std == 0.1 and spec.rate_hz == 10.0 and spec.is_ideal
    x = truth(50, 400)
    m = measure_uwb(spec, x, rngs(0, 50))
    err = (m.z - x).reshape(-1, 4)
    # 20000 samples per axis: s.e. of the std ≈ 0.1/sqrt(40000) = 0.0005 and of
    # the mean ≈ 0.0007; tolerances are 4–6 s.e.
    np.testing.assert_allclose(err.std(axis=0), 0.1, atol=0.003)
    np.testing.assert_allclose(err.mean(axis=0), 0.0, atol=0.004)
    # independent axes and markers: |correlation| ≲ 4/sqrt(20000) ≈ 0.03
    corr = np.corrcoef(err.T)
    assert np.max(np.abs(corr - np.eye(4))) < 0.03
    assert m.valid.all() and not m.nlos.any() and not m.outlier.any()


def test_realistic_errors_match_their_specification() -> None:
    spec = UwbSpec.realistic()
    n, k = 40, 3000
    x = truth(n, k)
    m = measure_uwb(spec, x, rngs(1, n))
    assert np.all(np.isfinite(m.z))
    # Stationary NLOS fraction of the two-state chain: p_in / (p_in + p_out),
    # p_in = 1 − exp(−0.2 · 0.1) ≈ 0.0198, p_out = T / mean duration = 0.1,
    # i.e. ≈ 0.165. The 240000
    # samples hold ≈ 4000 bursts of ≈ 10 samples; s.e. of the fraction ≈ 0.004.
    p_in, p_out = 1 - math.exp(-0.2 * 0.1), 0.1
    assert m.nlos.mean() == pytest.approx(p_in / (p_in + p_out), abs=0.02)
    # mean burst length ≈ 1 / p_out samples (geometric)
    starts = np.sum(m.nlos[:, 1:] & ~m.nlos[:, :-1])
    assert m.nlos.sum() / starts == pytest.approx(1.0 / p_out, rel=0.1)
    # drop rates inside and outside bursts (binomial s.e. ≤ 0.003)
    assert (~m.valid[m.nlos]).mean() == pytest.approx(spec.nlos_drop_prob, abs=0.015)
    assert (~m.valid[~m.nlos]).mean() == pytest.approx(spec.drop_prob, abs=0.005)
    assert m.outlier.mean() == pytest.approx(spec.outlier_prob, abs=0.003)
    # clean samples (valid, LOS, no outlier) keep σ = 0.1 m per axis
    clean = m.valid & ~m.nlos & ~m.outlier
    err = (m.z - x)[clean]
    np.testing.assert_allclose(err.std(axis=0), 0.1, rtol=0.03)
    # inside a burst the error has the bias (σ_b = 0.3) and 2× noise: per-axis
    # variance 0.3² + 0.2² = 0.13 (bias constant per burst, still ≈ 0.13 over
    # thousands of bursts)
    nl = m.valid & m.nlos & ~m.outlier
    assert np.var((m.z - x)[nl]) == pytest.approx(0.13, rel=0.15)


def test_dropped_samples_hold_the_last_valid_value() -> None:
    spec = UwbSpec(drop_prob=0.3)
    x = truth(6, 200)
    m = measure_uwb(spec, x, rngs(2, 6))
    assert not m.valid.all()
    for i in range(6):
        for j in range(2):
            last = None
            for kk in range(200):
                if m.valid[i, kk, j]:
                    last = m.z[i, kk, j]
                elif last is not None:
                    assert np.array_equal(m.z[i, kk, j], last)


def test_hold_last_valid_by_hand() -> None:
    z = np.arange(5 * 2 * 2, dtype=float).reshape(1, 5, 2, 2)
    valid = np.array(
        [[[False, False], [True, False], [False, False], [True, False], [False, False]]]
    )
    out = hold_last_valid(z, valid)
    heel = out[0, :, 0, 0]
    np.testing.assert_array_equal(heel, [4.0, 4.0, 4.0, 12.0, 12.0])  # first valid back-fills
    np.testing.assert_array_equal(out[0, :, 1], 0.0)  # knee never valid: zeros, not NaN


def test_determinism_and_walker_independence() -> None:
    spec = UwbSpec.realistic()
    x = truth(4, 300)
    a = measure_uwb(spec, x, rngs(3, 4))
    b = measure_uwb(spec, x, rngs(3, 4))
    assert np.array_equal(a.z, b.z) and np.array_equal(a.valid, b.valid)
    for i, g in enumerate(rngs(3, 4)):
        one = measure_uwb(spec, x[i : i + 1], [g])
        assert np.array_equal(one.z[0], a.z[i])
        assert np.array_equal(one.valid[0], a.valid[i])
        assert np.array_equal(one.nlos[0], a.nlos[i])


def reference_measure_uwb(spec: UwbSpec, truth: np.ndarray, gens: list) -> UwbMeasurements:
    """Straightforward per-walker, per-sample version of measure_uwb (same draws,
    same arithmetic): the NLOS chain and the burst bias stepped sample by sample."""
    n, k = truth.shape[:2]
    noise = np.empty_like(truth)
    nlos = np.zeros((n, k, 2), dtype=bool)
    outlier = np.zeros((n, k, 2), dtype=bool)
    dropped = np.zeros((n, k, 2), dtype=bool)
    bias = np.zeros_like(truth)
    extra = np.zeros_like(truth)
    for i, rng in enumerate(gens):
        noise[i] = spec.noise_std * rng.standard_normal((k, 2, 2))
        if spec.is_ideal:
            continue
        u_state = rng.random((k, 2))
        burst_bias = spec.nlos_bias_std * rng.standard_normal((k, 2, 2))
        out_flag = rng.random((k, 2)) < spec.outlier_prob
        out_err = spec.outlier_std * rng.standard_normal((k, 2, 2))
        u_drop = rng.random((k, 2))
        state = np.zeros(2, dtype=bool)
        current_bias = np.zeros((2, 2))
        for j in range(k):
            enter = ~state & (u_state[j] < spec.nlos_enter_prob)
            leave = state & (u_state[j] < spec.nlos_exit_prob)
            current_bias = np.where(enter[:, None], burst_bias[j], current_bias)
            state = (state | enter) & ~leave
            nlos[i, j] = state
            bias[i, j] = np.where(state[:, None], current_bias, 0.0)
        outlier[i] = out_flag
        extra[i] = np.where(out_flag[..., None], out_err, 0.0)
        dropped[i] = u_drop < np.where(nlos[i], spec.nlos_drop_prob, spec.drop_prob)
    scale = np.where(nlos, spec.nlos_noise_scale, 1.0)[..., None]
    z = truth + scale * noise + bias + extra
    valid = ~dropped
    for i in range(n):  # hold the last valid report, else the first, else 0
        for m in range(2):
            ok = np.flatnonzero(valid[i, :, m])
            for j in range(k):
                if valid[i, j, m]:
                    continue
                before = ok[ok < j]
                z[i, j, m] = z[i, before[-1] if before.size else ok[0], m] if ok.size else 0.0
    return UwbMeasurements(z=z, valid=valid, nlos=nlos, outlier=outlier)


@pytest.mark.parametrize(
    "spec",
    [
        UwbSpec.paper(),
        UwbSpec(drop_prob=0.25),
        UwbSpec(outlier_prob=0.05),
        UwbSpec(nlos_start_rate_hz=0.3, nlos_mean_duration=1.5, nlos_drop_prob=0.3),
        UwbSpec.realistic(),
        # frequent short bursts (many entries and exits), walks starting with drops
        UwbSpec(
            nlos_start_rate_hz=3.0,
            nlos_mean_duration=0.1,
            nlos_drop_prob=1.0,
            drop_prob=0.9,
            outlier_prob=0.5,
        ),
    ],
    ids=["paper", "dropouts", "outliers", "nlos", "realistic", "harsh"],
)
def test_measure_uwb_equals_a_per_sample_reference_bit_for_bit(spec: UwbSpec) -> None:
    x = truth(5, 300)
    got = measure_uwb(spec, x, rngs(4, 5))
    want = reference_measure_uwb(spec, x, rngs(4, 5))
    for name in ("z", "valid", "nlos", "outlier"):
        a, b = getattr(got, name), getattr(want, name)
        assert a.shape == b.shape and a.dtype == b.dtype, name
        assert a.tobytes() == b.tobytes(), name


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"rate_hz": 0.0}, "rate_hz"),
        ({"rate_hz": -10.0}, "rate_hz"),
        ({"rate_hz": math.inf}, "rate_hz"),
        ({"noise_std": -0.1}, "noise_std"),
        ({"noise_std": math.nan}, "noise_std"),
        ({"nlos_bias_std": -1.0}, "nlos_bias_std"),
        ({"outlier_std": math.inf}, "outlier_std"),
        ({"nlos_start_rate_hz": -0.5}, "nlos_start_rate_hz"),
        ({"drop_prob": -0.1}, "drop_prob"),
        ({"outlier_prob": math.nan}, "outlier_prob"),
        ({"nlos_drop_prob": 2.0}, "nlos_drop_prob"),
        ({"nlos_mean_duration": 0.01}, "nlos_mean_duration"),
        ({"nlos_noise_scale": 0.5}, "nlos_noise_scale"),
    ],
)
def test_spec_rejects_impossible_values(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        UwbSpec(**kwargs)


def test_measure_rejects_bad_inputs() -> None:
    spec = UwbSpec()
    x = truth(2, 10)
    with pytest.raises(ValueError, match="markers"):
        measure_uwb(spec, x[..., 0], rngs(0, 2))
    bad = x.copy()
    bad[1, 3, 0, 1] = np.nan
    with pytest.raises(ValueError, match="markers"):
        measure_uwb(spec, bad, rngs(0, 2))
    with pytest.raises(ValueError, match="rngs"):
        measure_uwb(spec, x, rngs(0, 3))
    with pytest.raises(ValueError, match=r"rngs\[0\]"):
        measure_uwb(spec, x, [1, np.random.default_rng(0)])  # type: ignore[list-item]
