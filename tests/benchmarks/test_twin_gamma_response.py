"""benchmarks/twin_gamma_response.py: its grid, and the curve summaries on hand values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import gamma_response, twin_gamma_response
from benchmarks.twin_gamma_response import (
    THRESHOLDS,
    curve_summary,
    finite_or_none,
    geometric_mean,
)


def test_the_grid_is_gamma_responses():
    assert THRESHOLDS == gamma_response.THRESHOLDS


def test_geometric_mean_and_diverged_values():
    assert geometric_mean(np.array([1.0, 4.0])) == pytest.approx(2.0)
    assert geometric_mean(np.array([1.0, math.inf])) == math.inf
    assert finite_or_none(np.array([[1.0, math.inf]])) == [[1.0, None]]


def test_curve_summary_skips_diverged_points():
    curve = [None, None, 2.0, 1.0, 4.0, 4.0, 4.0, 4.0, 5.0]
    best, top = curve_summary(curve)
    assert best == THRESHOLDS[3] and top == pytest.approx(5.0)


def test_the_plot_draws_diverged_points_as_gaps(tmp_path):
    s = {"own_geomean_m": [1.0] * 9, "twin_geomean_m": [None] * 2 + [1.0] * 7}
    result = {"PyShoe trials": s, "hallway walks": s}
    twin_gamma_response.plot(result, tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 0
