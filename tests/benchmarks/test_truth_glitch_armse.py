"""benchmarks/truth_glitch_armse.py: the glitch mask and the three ways of averaging."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from pednav_env.replay.metrics import track_errors

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # the script imports benchmarks.transfer_by_regime
    sys.path.insert(0, str(ROOT))
SCRIPT = ROOT / "benchmarks" / "truth_glitch_armse.py"
_spec = importlib.util.spec_from_file_location("truth_glitch_armse", SCRIPT)
assert _spec is not None and _spec.loader is not None
tga = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tga)

RATE = 100.0


def _walk(n: int = 600) -> tuple[np.ndarray, np.ndarray]:
    """A truth walking 1 m/s along x with a 0.3 s dropout (frozen, then a 0.3 m
    jump) at samples 300-330, and an estimate turned by 0.1 rad with a small wobble."""
    t = np.arange(n) / RATE
    truth = np.stack((t, 0.2 * np.sin(t), np.zeros(n)), axis=1)
    truth[300:330] = truth[300]
    c, s = np.cos(0.1), np.sin(0.1)
    xy = np.stack((t, 0.2 * np.sin(t)), axis=1) + 0.01 * np.cos(3 * t)[:, None]
    est = np.column_stack((c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1], np.zeros(n)))
    return est, truth


def test_glitch_mask_marks_inclusive_spans():
    mask = tga.glitch_mask(10, np.array([[1, 2], [5, 5]]))
    assert mask.tolist() == [False, True, True, False, False, True] + [False] * 4
    assert not tga.glitch_mask(4, np.zeros((0, 2), dtype=np.int64)).any()


def test_kept_rotation_with_nothing_left_out_is_the_shipped_metric():
    est, truth = _walk()
    want = track_errors(est, truth, 50)
    got = tga.armse_kept_rotation(est, truth, 50, np.zeros(len(truth), dtype=bool))
    for key in tga.FORMS:
        assert got[key] == pytest.approx(want[key], rel=1e-12)


def test_trial_figures_find_the_dropout_and_leave_it_out():
    est, truth = _walk()
    f = tga.trial_figures(est, truth, 50, RATE)
    assert f["glitch_spans"] == [[300, 330]]  # frozen 300-329, the jump 329 -> 330
    assert f["glitch_samples"] == 31
    assert f["share_all"] == pytest.approx(31 / 600)
    assert f["share_navigation"] == pytest.approx(31 / 550)
    assert not f["origin_in_glitch"]
    masked = truth.copy()
    masked[300:331] = np.nan
    for key in tga.FORMS:
        assert f["all"][key] == track_errors(est, truth, 50)[key]
        assert f["refit"][key] == track_errors(est, masked, 50)[key]
        # the frozen truth lags the walker: leaving it out lowers the error both ways
        assert f["refit"][key] < f["all"][key]
        assert f["kept"][key] < f["all"][key]
