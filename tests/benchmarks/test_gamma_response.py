"""benchmarks/gamma_response.py and shoe_divergence_floor.py: the threshold grid, its
actions, and the constant-action files they play."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import gymnasium as gym
import pytest

import pednav_env  # noqa: F401  (registers the environments)
from agents.policies import load_policy

ROOT = Path(__file__).resolve().parents[2]


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gr = _script("gamma_response")
sdf = _script("shoe_divergence_floor")


def test_the_grid_stays_inside_the_threshold_knob():
    # γ = 2.25e7 · 100^a0 (docs/ENV_FOOT.md), a0 in [-1, 1]
    assert gr.action_of(2.25e7) == pytest.approx(0.0)
    assert gr.action_of(2.25e9) == pytest.approx(1.0)
    assert gr.action_of(2.25e5) == pytest.approx(-1.0)
    assert all(-1.0 <= gr.action_of(g) <= 1.0 for g in gr.THRESHOLDS)
    assert gr.THRESHOLDS[0] == pytest.approx(1.3335e7, rel=1e-4)
    assert gr.THRESHOLDS[-1] == pytest.approx(1.3335e9, rel=1e-4)


def test_best_gamma_skips_diverged_means():
    errors = [None, 3.0, 1.0, None, 2.0, 5.0, 6.0, 7.0, 8.0]
    assert gr.best_gamma(errors) == gr.THRESHOLDS[2]
    assert gr.best_gamma([None] + [1.0] * 8) == gr.THRESHOLDS[1]


def test_the_sweep_files_play_the_stated_constants(tmp_path):
    space = gym.make("pednav/FootZupt-v0").action_space
    files = sdf.sweep_files(tmp_path)
    assert len(files) == len(sdf.GAMMA_KNOB) * len(sdf.OTHER_KNOBS)
    path = files["a0=+0.50, others real-fixed"]
    assert json.loads(Path(path).read_text()) == {
        "pednav/FootZupt-v0:shoe": {"action": [0.5, 0.0, 0.0, 0.0]}
    }
    policy = load_policy(path, space, "pednav/FootZupt-v0")
    assert policy.filter_family == "shoe"
    assert policy.action.tolist() == [0.5, 0.0, 0.0, 0.0]


def test_replayed_walks_are_scored_like_the_recordings(monkeypatch):
    # the replayed curve is PyShoe's ARMSE of pednav run's runner, the measure
    # threshold_sweep gives the recordings, on the same simulated walks
    import numpy as np

    from agents.choose_shoe import simulated_recordings, threshold_sweep
    from pednav_env.calibration.compare import MODELS
    from pednav_env.replay.setup import real_fixed_setup

    monkeypatch.setattr(gr, "REPLAYED_REGIMES", {"sim short": (0.8, 1.2)})
    monkeypatch.setattr(gr, "REPLAYED_DURATION_S", (12.0, 14.0))
    out = gr.replayed(walks=2, seed=5)["replayed short"]
    recs = simulated_recordings(MODELS["calibrated"], 2, 5, (0.8, 1.2), (12.0, 14.0))
    expected = threshold_sweep(real_fixed_setup(), recs, gr.THRESHOLDS)
    kept = np.isfinite(expected).all(axis=1)
    assert out["walks"] == 2 and out["walks_kept"] == int(kept.sum()) > 0
    assert out["diverged_walks"] == np.sum(~np.isfinite(expected), axis=0).tolist()
    assert out["mean_error_m"] == pytest.approx(expected[kept].mean(axis=0).tolist(), rel=1e-12)
    assert len(out["mean_error_start_rotation_m"]) == len(gr.THRESHOLDS)
