"""benchmarks/sim_error_budget.py: the simulator arms switch off what they name, and the
summary's means, medians and diverged counts on a hand-built error table."""

from __future__ import annotations

import importlib.util
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("seb", ROOT / "benchmarks" / "sim_error_budget.py")
assert spec is not None and spec.loader is not None
seb = importlib.util.module_from_spec(spec)
spec.loader.exec_module(seb)


def test_the_arms_change_only_what_they_name():
    arms = seb.arms()
    cal = arms["calibrated"]
    assert (cal.imu_grade, arms["ideal IMU"].imu_grade) == ("microstrain_gx5", "ideal")
    assert arms["ideal IMU"].stance == cal.stance
    still = arms["no stance micro-motion"]
    assert still.imu_grade == cal.imu_grade
    a = cal.stance.draw(np.random.default_rng(3))
    b = still.stance.draw(np.random.default_rng(3))
    assert b.quiet_rad == pytest.approx(1e-7) and b.edge_rad == pytest.approx(1e-7)
    assert b.roll_rad == 0.0 and a.roll_rad > 0.0
    # the walker's gait timing and swing are the same draw
    assert (b.flat_fraction, b.heel_fraction) == (a.flat_fraction, a.heel_fraction)
    rocker = arms["heel rocker"]
    assert rocker.stance.heel_rocker and not cal.stance.heel_rocker
    assert rocker.imu_grade == cal.imu_grade
    assert replace(rocker.stance, heel_rocker=False) == cal.stance
    assert arms["ideal IMU, no micro-motion"] == type(still)(
        arms["ideal IMU, no micro-motion"].name, "ideal", still.stance
    )


def test_without_micro_motion_the_standing_foot_is_still():
    # ideal IMU: the angular rate in the middle of each stance is the micro-motion's only
    arms = seb.arms()
    rates = {}
    for name in ("ideal IMU", "ideal IMU, no micro-motion"):
        truth, imu = arms[name].batch((1.0, 1.0), 1, 7, (12.0, 12.0))
        step = np.diff(np.concatenate(([0], truth.stance[0].astype(int), [0])))
        starts, ends = np.flatnonzero(step == 1), np.flatnonzero(step == -1)
        runs = zip(starts, ends, strict=True)
        mid = [np.linalg.norm(imu.omega_b[0, (s + e) // 2]) for s, e in runs if e - s > 20]
        rates[name] = float(np.median(mid))
    assert rates["ideal IMU"] > 1e-3
    assert rates["ideal IMU, no micro-motion"] < 1e-4 * rates["ideal IMU"]


def test_summary_by_hand():
    errors = np.array([[1.0, 2.0], [3.0, math.inf], [5.0, 6.0], [math.inf, math.inf]])
    s = seb.summary(errors)
    assert (s["walks"], s["walks_kept"]) == (4, 2)
    assert s["diverged_walks"] == [1, 2]
    assert s["mean_armse_m"] == [3.0, 4.0]
    assert s["median_armse_m"] == [3.0, 4.0]
    assert s["mean_ci_low_m"][0] >= 1.0 and s["mean_ci_high_m"][0] <= 5.0
