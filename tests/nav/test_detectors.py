"""Stance detectors: paper 003 eq 5 and SHOE (Skog et al. 2010)."""

import numpy as np
import pytest

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.detectors import (
    ShoeDetectorConfig,
    ThresholdDetectorConfig,
    causal_moving_mean,
    shoe_statistic,
)
from pednav_env.rotations import euler_to_dcm
from pednav_env.testing.detectors import (
    OnlineStanceDetector,
    apply_min_duration,
    threshold_condition,
)


def true_f_n3(tr):
    e_mid = 0.5 * (tr.euler[:, :-1] + tr.euler[:, 1:])
    return np.einsum("ntij,ntj->nti", euler_to_dcm(e_mid), tr.f_b)[..., 2]


def near_boundary(mask, samples):
    """Samples within ``samples`` of a stance start or end."""
    edges = np.flatnonzero(np.diff(mask.astype(int)) != 0)
    out = np.zeros_like(mask)
    for e in edges:
        out[max(0, e - samples) : e + samples + 2] = True
    return out


@pytest.mark.parametrize("walk", ["paper_walk", "realistic_walk"])
def test_threshold_detector_finds_simulated_stances(walk, request):
    tr = request.getfixturevalue(walk)
    det = threshold_condition(tr.omega_b, true_f_n3(tr), ThresholdDetectorConfig(), tr.rate_hz)[0]
    truth = tr.stance[0]
    f_dev = np.abs(true_f_n3(tr)[0] - STANDARD_GRAVITY)
    still = truth & (np.linalg.norm(tr.omega_b[0], axis=-1) < 1e-9) & (f_dev < 1e-9)
    assert np.all(det[still])  # a still foot is always detected
    if walk == "paper_walk":
        assert np.all(still[truth])  # the paper's stances are perfectly still
    else:
        # Stands and stops are still; the stance phases move. Heel micro-motion (foot.py:
        # 0.2 v² mm at 13 Hz vertically, ≈ 1.1 m/s² peak at this walk's 0.9 m/s, under a
        # sin² envelope) stays within Δf_max = 0.33 m/s² on ≈ 60 % of those samples, and
        # the heel-strike transient (10 v² m/s², ~0.1 s) takes the first quarter of each
        # ≈ 0.36 s stance: ≈ 45 % of the moving stance samples are expected to pass.
        moving = truth & ~still
        assert still.sum() > 0.5 * truth.sum() and moving.sum() > 100
        assert np.mean(det[moving]) > 0.4
    false = det & ~truth
    # false detections only next to true stances (foot almost still at heel-off/strike)
    assert not np.any(false & ~near_boundary(truth, 8))


def test_shoe_detector_finds_simulated_stances(paper_walk):
    cfg = ShoeDetectorConfig()
    stat = shoe_statistic(paper_walk.omega_b, paper_walk.f_b, cfg, paper_walk.rate_hz)[0]
    truth = paper_walk.stance[0]
    window = 3
    inner = truth & ~near_boundary(truth, window)
    assert np.all(stat[inner] < 1e-9)  # noiseless: statistic exactly zero in stance
    det = stat < cfg.threshold
    assert not np.any(det & ~truth & ~near_boundary(truth, 8))


def test_shoe_threshold_scales_with_inverse_noise_variance(paper_walk):
    a = shoe_statistic(paper_walk.omega_b, paper_walk.f_b, ShoeDetectorConfig(), 100.0)
    b = shoe_statistic(
        paper_walk.omega_b,
        paper_walk.f_b,
        ShoeDetectorConfig(accel_noise_std=0.2, gyro_noise_std=0.108),
        100.0,
    )
    np.testing.assert_allclose(b, a / 4, rtol=1e-10, atol=1e-12)


def test_causal_mean_and_min_duration():
    x = np.arange(10.0)[None]
    np.testing.assert_allclose(causal_moving_mean(x, 3)[0], [0, 0.5, 1, 2, 3, 4, 5, 6, 7, 8])
    cond = np.array([[1, 1, 0, 1, 1, 1, 1, 0, 1, 1]], dtype=bool)
    np.testing.assert_array_equal(apply_min_duration(cond, 3)[0], [0, 0, 0, 0, 0, 1, 1, 0, 0, 0])


def test_online_detector_matches_offline_and_emits_events():
    rng = np.random.default_rng(1)
    w = np.abs(rng.normal(scale=0.2, size=(2, 300)))
    f3 = STANDARD_GRAVITY + rng.normal(scale=0.3, size=(2, 300))
    cfg = ThresholdDetectorConfig(window_s=0.05, min_stance_s=0.03)
    offline = apply_min_duration(
        (causal_moving_mean(w, 5) <= cfg.omega_max)
        & (np.abs(causal_moving_mean(f3, 5) - cfg.g) <= cfg.delta_f_max),
        3,
    )
    det = OnlineStanceDetector(cfg, 100.0, 2)
    online = np.zeros_like(offline)
    starts = ends = 0
    for m in range(300):
        c = det.condition_threshold(
            w[:, m], f3[:, m], np.full(2, cfg.omega_max), np.full(2, cfg.delta_f_max)
        )
        s, e = det.advance(c, cfg.min_stance_s)
        online[:, m] = det.in_stance
        starts += s.sum()
        ends += e.sum()
    np.testing.assert_array_equal(online, offline)
    assert starts == np.sum(np.diff(offline.astype(int), axis=1) == 1) + offline[:, 0].sum()
    assert ends == np.sum(np.diff(offline.astype(int), axis=1) == -1)


@pytest.mark.parametrize(
    ("factory", "name"),
    [
        (lambda: ThresholdDetectorConfig(omega_max=-0.1), "omega_max"),
        (lambda: ThresholdDetectorConfig(delta_f_max=float("nan")), "delta_f_max"),
        (lambda: ThresholdDetectorConfig(window_s=-1), "window_s"),
        (lambda: ShoeDetectorConfig(accel_noise_std=0.0), "accel_noise_std"),
        (lambda: ShoeDetectorConfig(threshold=-3), "threshold"),
        (lambda: OnlineStanceDetector(ThresholdDetectorConfig(), 0.0, 1), "rate_hz"),
    ],
)
def test_bad_detector_configs_raise(factory, name):
    with pytest.raises(ValueError, match=name):
        factory()


def test_compiled_lane_shoe_statistic_equals_the_numpy_one_bit_for_bit():
    """The compiled SHOE statistic of lanes with their own windows and interval starts
    (windows reaching before the record included; a still lane, whose mean specific
    force is zero, and a lane with large values) repeats the batched numpy version's
    arithmetic exactly."""
    from pednav_env.nav.detectors import shoe_statistic_at
    from pednav_env.testing.detectors import shoe_statistic_at_numpy

    rng = np.random.default_rng(7)
    omega = rng.normal(0.0, 0.4, (5, 300, 3))
    f = rng.normal(0.0, 2.0, (5, 300, 3)) + [0.3, -0.2, 9.81]
    f[2] = 0.0  # |f̄| = 0: the 1e-12 floor of the direction
    f[3] *= 1e3
    windows = np.array([1, 3, 17, 40, 8])
    cfg = ShoeDetectorConfig(accel_noise_std=0.03, gyro_noise_std=0.004, g=9.8)
    for first, k in (([0, 5, 2, 260, 30], 40), ([100, 0, 39, 12, 1], 25)):
        first = np.array(first)
        fast = shoe_statistic_at(omega, f, first, k, windows, cfg)
        slow = shoe_statistic_at_numpy(omega, f, first, k, windows, cfg)
        assert fast.shape == (5, k)
        np.testing.assert_array_equal(fast, slow)
