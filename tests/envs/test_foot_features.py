"""The foot env's interval statistics (:mod:`pednav_env.envs.foot_features`) equal,
bit for bit, the plain numpy forms they replace and a lane-by-lane loop."""

import numpy as np
import pytest

from pednav_env.envs.foot_features import (
    masked,
    masked_moments,
    update_stance_average,
    vector_norms,
)


@pytest.mark.parametrize("shape", [(1, 1, 3), (3, 50, 3), (256, 50, 3), (7, 100, 3), (5, 3)])
def test_vector_norms_are_numpys_norms_bit_for_bit(shape):
    rng = np.random.default_rng(sum(shape))
    x = rng.standard_normal(shape) * rng.uniform(1e-3, 1e3, shape)
    x.reshape(-1, 3)[::7] = 0.0  # exact zeros, as standing still gives
    assert np.array_equal(vector_norms(x), np.linalg.norm(x, axis=-1))


@pytest.mark.parametrize("used", [None, "partial"])
def test_masked_moments_are_the_where_forms_bit_for_bit(used):
    rng = np.random.default_rng(1)
    b, k = 64, 50
    x = rng.standard_normal((b, k)) * 3.0 + 9.0
    valid = np.full(b, k) if used is None else rng.integers(0, k + 1, b)
    mask = np.arange(k)[None, :] < np.maximum(valid, 1)[:, None]
    count = mask.sum(axis=1)
    mean, std = masked_moments(x, mask, count, bool(mask.all()))
    plain_mean = np.where(mask, x, 0).sum(1) / count
    plain_var = np.where(mask, (x - plain_mean[:, None]) ** 2, 0).sum(1) / count
    assert np.array_equal(mean, plain_mean)
    assert np.array_equal(std, np.sqrt(plain_var))
    assert np.array_equal(masked(x, mask, bool(mask.all())).max(1), np.where(mask, x, 0).max(1))
    assert (used is None) == bool(mask.all())


def _stance_average_loop(average, open_run, stance, end, dt):
    """Lane by lane, sample by sample: the run length of the detector's stance and,
    at each stance end, the moving average of the durations (weight 0.2)."""
    average = average.copy()
    run = open_run.copy()
    for i in range(stance.shape[0]):
        for j in range(stance.shape[1]):
            before = run[i]
            run[i] = run[i] + 1 if stance[i, j] else 0
            duration = before * dt[i]
            if end[i, j] and duration > 0:
                average[i] = 0.8 * average[i] + 0.2 * duration if average[i] > 0 else duration
    return average, run


def test_stance_average_equals_a_lane_by_lane_loop():
    rng = np.random.default_rng(2)
    b, k = 40, 50
    # flickering detectors (many short stances) and long ones, as the paper filter gives
    stance = rng.uniform(size=(b, k)) < np.linspace(0.2, 0.95, b)[:, None]
    end = np.zeros((b, k), dtype=bool)
    end[:, 1:] = stance[:, :-1] & ~stance[:, 1:]
    open_run = rng.integers(0, 30, b)
    end[:, 0] = (open_run > 0) & ~stance[:, 0]
    average = np.where(rng.uniform(size=b) < 0.3, 0.0, rng.uniform(0.1, 0.6, b))
    dt = np.where(np.arange(b) % 2 == 0, 0.01, 0.005)
    got_average, got_run = update_stance_average(average, open_run, stance, end, dt)
    want_average, want_run = _stance_average_loop(average, open_run, stance, end, dt)
    assert end.sum(axis=1).max() >= 5  # lanes with many ends in one interval
    assert np.array_equal(got_average, want_average)
    assert np.array_equal(got_run, want_run)
    # no stance end: nothing changes but the open runs
    none = np.zeros_like(end)
    same, _ = update_stance_average(average, open_run, stance, none, dt)
    assert np.array_equal(same, average)
