"""benchmarks/oracle_gap.py: the "gap closed" column is a share of a real gap or n/a."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "oracle_gap.py"
BASE = np.linspace(1.0, 2.0, 20)
#: ±0.01 around zero: paired differences that are not all equal (a t-test is defined)
WIGGLE = 0.01 * np.where(np.arange(20) % 2 == 0, 1.0, -1.0)


def run_script(tmp_path: Path, errors: dict[str, np.ndarray]) -> list[str]:
    """The script's Markdown rows (policy name → its cells) on a result of ``errors``."""
    result = {
        "env": "pednav/MarkerTrack-v0",
        "episodes": len(BASE),
        "seed": 5000,
        "policies": [
            {"name": name, "episode_errors": e.tolist(), "divergence_rate": 0.0}
            for name, e in errors.items()
        ],
    }
    path = tmp_path / "result.json"
    path.write_text(json.dumps(result))
    out = subprocess.run(
        [sys.executable, str(SCRIPT), str(path), "--markdown"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "nan" not in out
    return out.splitlines()


def gap_cells(lines: list[str]) -> dict[str, str]:
    rows = [line.strip("| ").split(" | ") for line in lines if line.startswith("| ")]
    return {row[0]: row[-1] for row in rows[1:] if not row[0].startswith("---")}


def test_share_of_the_gap_and_n_a_for_a_policy_worse_than_tuned(tmp_path):
    """tuned 1 m above the oracle: a policy 0.5 m below tuned closes 50 %, one 2 m
    above tuned is "n/a (worse than tuned)", not −200 %."""
    cells = gap_cells(
        run_script(
            tmp_path,
            {
                "tuned": BASE + 1.0,
                "oracle": BASE + WIGGLE,
                "half": BASE + 0.5 - WIGGLE,
                "worse": BASE + 3.0 + WIGGLE,
                "runs/seed0": BASE + 0.25 + WIGGLE,
                "runs/seed1": BASE + 0.75 - WIGGLE,
            },
        )
    )
    assert cells["half"] == "50 %"
    assert cells["oracle (privileged)"] == "100 %" and cells["tuned"] == "0 %"
    assert cells["worse"] == "n/a (worse than tuned)"
    assert cells["runs/seed0"] == "75 %" and cells["runs/seed1"] == "25 %"


def test_no_gap_to_close_when_the_oracle_is_not_better(tmp_path):
    """An oracle 0.1 m worse than tuned: every row says n/a with the ceiling (−x %)."""
    lines = run_script(
        tmp_path,
        {"tuned": BASE, "oracle": BASE + 0.1 + WIGGLE, "policy": BASE - 0.5 + WIGGLE},
    )
    assert "no gap to close" in lines[0]
    cells = gap_cells(lines)
    ceiling = f"{100 * -0.1 / BASE.mean():.1f} %"
    assert len(cells) == 3
    assert all(v.startswith(f"n/a (ceiling {ceiling}, p = ") for v in cells.values())


def test_no_oracle_in_the_result(tmp_path):
    lines = run_script(tmp_path, {"tuned": BASE, "policy": BASE + 1.0 + WIGGLE})
    assert "no oracle in this result" in lines[0]
    assert set(gap_cells(lines).values()) == {"n/a (no oracle)"}
