"""benchmarks/false_stance.py: the per-band medians and percentiles over walks."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _script():
    spec = importlib.util.spec_from_file_location(
        "false_stance", ROOT / "benchmarks" / "false_stance.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _walk(source: str, band: str | None, value: float | None) -> dict:
    cells = [value] * 4
    return {
        "source": source,
        "band": band,
        "name": f"{source}{value}",
        "below": cells,
        "below_quiet_free": cells,
        "speed_weighted": cells,
        "swing_speed_mps": None if value is None else 1.0,
        "nonstance_share": 0.6,
    }


def test_band_medians_by_band_and_source() -> None:
    fs = _script()
    walks = [_walk("sim", "0.8-1.3", v) for v in (0.1, 0.2, 0.3)]
    walks += [_walk("hallway", "0.8-1.3", None), _walk("PyShoe", None, 0.9)]
    bands = fs.band_medians(walks)
    assert [(b["band"], b["source"], b["walks"]) for b in bands] == [
        ("0.8-1.3", "sim", 3),
        ("0.8-1.3", "hallway", 1),
    ]
    sim, hall = bands
    assert sim["below"] == pytest.approx([0.2] * 4)
    assert sim["speed_weighted_p5"] == pytest.approx([0.11] * 4)
    assert sim["below_p95"] == pytest.approx([0.29] * 4)
    # a measure no walk has is None; the unbanded walk is in no row
    assert hall["speed_weighted"] == [None] * 4 and hall["swing_speed_mps"] is None


def test_rounded_rounds_numbers_and_lists_only() -> None:
    row = {"name": "w", "below": [0.123456, None], "walking_s": 1.23456, "walks": 3}
    assert _script().rounded(row) == {
        "name": "w",
        "below": [0.1235, None],
        "walking_s": 1.2346,
        "walks": 3,
    }
