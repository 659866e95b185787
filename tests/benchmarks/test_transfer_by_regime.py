"""benchmarks/transfer_by_regime.py: the paired ratio-of-means interval and the verdict."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "transfer_by_regime.py"
_spec = importlib.util.spec_from_file_location("transfer_by_regime", SCRIPT)
assert _spec is not None and _spec.loader is not None
tbr = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tbr)


def test_ratio_interval_is_paired_over_recordings():
    """Errors that scatter 40-fold between recordings but are 1.5x their reference on
    each (±1 %): the paired interval stays within 1.48-1.52; the same numbers with
    the pairing broken (reference reversed) give a much wider one."""
    ref = np.geomspace(0.05, 2.0, 12)
    wiggle = 1.0 + 0.01 * np.where(np.arange(12) % 2 == 0, 1.0, -1.0)
    err = 1.5 * ref * wiggle
    paired = tbr.paired_ratio_ci(err.tolist(), ref.tolist())
    assert paired["ratio"] == pytest.approx(sum(err) / sum(ref))
    assert paired["method"] == "BCa"
    lo, hi = paired["ci95"]
    assert 1.48 < lo <= paired["ratio"] <= hi < 1.52
    broken = tbr.paired_ratio_ci(err.tolist(), ref[::-1].tolist())
    assert broken["ci95"][1] - broken["ci95"][0] > 10 * (hi - lo)


def test_degenerate_ratio_falls_back_to_the_percentile_interval():
    """Every recording exactly twice its reference: every resample's ratio is 2, BCa
    has no interval, the percentile one is [2, 2] and the output says so."""
    ref = [0.1, 0.3, 0.2, 0.5, 0.4]
    out = tbr.paired_ratio_ci([2 * r for r in ref], ref)
    assert out["method"] == "percentile"
    assert out["ci95"] == pytest.approx([2.0, 2.0])


@pytest.mark.parametrize(
    ("ratio", "ci", "expected"),
    [
        (1.36, [1.1, 1.49], "met"),
        (1.36, [1.1, 1.5], "point estimate inside, CI not"),
        (1.36, [1.1, 2.9], "point estimate inside, CI not"),
        (1.5, [1.2, 1.9], "not met"),
        (1.7, [1.6, 1.8], "not met"),
    ],
)
def test_a_target_is_met_only_when_the_whole_interval_is_below_it(ratio, ci, expected):
    assert tbr.verdict({"ratio": ratio, "ci95": ci}, 1.5) == expected
