"""benchmarks/gait_rule_seeds.py: the spread over searches and the selection rule
(a candidate replaces the shipped rule only if it beats it on the re-evaluation
episodes at paired p < 0.05), on hand-made search records (nothing is replayed)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "gait_rule_seeds.py"
N = 40
BASE = np.linspace(5.0, 25.0, N)
#: ±0.05 around zero, summing to zero: paired differences with a defined t-test
WIGGLE = 0.05 * np.where(np.arange(N) % 2 == 0, 1.0, -1.0)
TUNED = BASE + 2.0


def record(tmp_path: Path, name: str, errors: np.ndarray, tuned: np.ndarray = TUNED) -> str:
    data = {
        "env_id": "pednav/FootZupt-v0",
        "filter": "shoe",
        "feature": "accel_excess_absmax",
        "c": [0.5, 0.2, -0.6, -0.7, -0.5],
        "objective_m": 10.0,
        "episodes": 16,
        "reevaluation": {
            "episodes": N,
            "episode_seeds": [910_000_000, 910_000_000 + N - 1],
            "mean_m": float(errors.mean()),
            "tuned_mean_m": float(tuned.mean()),
            "episode_errors_m": errors.tolist(),
            "tuned_episode_errors_m": tuned.tolist(),
        },
    }
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(data))
    return str(path)


def run(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, str(SCRIPT), *args], capture_output=True, text=True, env=env
    )


def test_spread_and_a_candidate_clearly_better_than_the_shipped_rule(tmp_path):
    shipped = record(tmp_path, "shipped", BASE + 1.0 + WIGGLE)  # Δ vs tuned −1
    a = record(tmp_path, "a", BASE - WIGGLE)  # Δ vs tuned −2, vs shipped −1 (p ≪ 0.05)
    b = record(tmp_path, "b", BASE + 1.0 - WIGGLE)  # Δ vs tuned −1
    out = run("table", a, b, "--shipped", shipped)
    assert out.returncode == 0, out.stderr
    # Δ over the two searches: −2 and −1 → mean −1.5, sd √0.5 = 0.707
    assert "re-evaluated Δ vs tuned -1.500 ± 0.707 m" in out.stdout
    assert f"selection (re-evaluation only): replace the shipped rule by {a}" in out.stdout


def test_a_lower_mean_that_is_not_shown_better_keeps_the_shipped_rule(tmp_path):
    rng = np.random.default_rng(0)
    shipped = record(tmp_path, "shipped", BASE + 1.0)
    # 0.1 m lower on average, with per-episode differences of ±3 m: not significant
    noisy = BASE + 0.9 + 3.0 * rng.standard_normal(N)
    noisy += (BASE + 0.9).mean() - noisy.mean()
    out = run("table", record(tmp_path, "a", noisy), "--shipped", shipped)
    assert out.returncode == 0, out.stderr
    assert "selection (re-evaluation only): keep the shipped rule" in out.stdout


def test_dev_columns_count_searches_that_beat_tuned(tmp_path):
    shipped = record(tmp_path, "shipped", BASE + 1.0 + WIGGLE)
    a = record(tmp_path, "a", BASE - WIGGLE)
    b = record(tmp_path, "b", BASE + 1.0 - WIGGLE)
    dev = {
        "env": "pednav/FootZupt-v0",
        "episodes": N,
        "seed": 20200,
        "policies": [
            {"name": n, "episode_errors": e.tolist(), "divergence_rate": 0.1}
            for n, e in (
                ("tuned", TUNED),
                ("gait-rule", BASE + 1.0 + WIGGLE),
                (a, BASE + 1.0 + WIGGLE),  # −1 m, every episode: p ≪ 0.01
                (b, TUNED + 3.0 * np.where(np.arange(N) < N // 2, 1.0, -1.0)),  # Δ 0
            )
        ],
    }
    path = tmp_path / "dev.json"
    path.write_text(json.dumps(dev))
    out = run("table", a, b, "--shipped", shipped, "--dev", str(path))
    assert out.returncode == 0, out.stderr
    assert "dev Δ vs tuned -0.500 ± 0.707 m" in out.stdout
    assert "1 of 2 beat tuned at p < 0.01" in out.stdout
    # without the shipped rule in the evaluation its dev cells are empty; a search
    # missing from it is an error
    dev["policies"] = [p for p in dev["policies"] if p["name"] != "gait-rule"]
    path.write_text(json.dumps(dev))
    out = run("table", a, b, "--shipped", shipped, "--dev", str(path))
    assert out.returncode == 0, out.stderr
    assert "dev Δ vs tuned -0.500 ± 0.707 m" in out.stdout
    shipped_row = next(line for line in out.stdout.splitlines() if line.startswith("shipped"))
    assert shipped_row.endswith("  ".join(["—"] * 6))
    dev["policies"] = [p for p in dev["policies"] if p["name"] != b]
    path.write_text(json.dumps(dev))
    out = run("table", a, b, "--shipped", shipped, "--dev", str(path))
    assert out.returncode == 2 and f"no policy named {b}" in out.stderr


def test_records_on_other_episodes_are_refused_in_one_line(tmp_path):
    shipped = record(tmp_path, "shipped", BASE + 1.0)
    other = record(tmp_path, "other", BASE, tuned=TUNED + 0.5)
    out = run("table", other, "--shipped", shipped)
    assert out.returncode == 2
    assert out.stderr.startswith("error: ") and out.stderr.count("\n") == 1
    assert "other.json: its tuned errors differ" in out.stderr
