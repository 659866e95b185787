"""Paper reproductions: one module per paper, one shared result format.

Each module ``paperNNN`` exposes ``run(runs: int | None = None, seed: int = 0,
**kw) -> ReproductionResult``. ``pednav reproduce ID`` prints the table and,
with ``--json``, the object described in docs/CONTRACTS.md ("pednav reproduce")::

    {"paper": "003", "seconds": 12.3,
     "rows": [{"config": "table1_step_0.5m", "metric": "sigma_x", "unit": "m",
               "paper": 0.064, "ours": 0.071}, ...]}
"""

from __future__ import annotations

import importlib
import json
from dataclasses import asdict, dataclass, field
from typing import Any

#: Paper ids with a reproduction module, mapped to the module name.
PAPERS: dict[str, str] = {
    "000": "paper000",
    "001": "paper001",
    "002": "paper002",
    "003": "paper003",
    "004": "paper004",
}


@dataclass(frozen=True)
class ReproductionRow:
    """One figure: our value beside the paper's (``paper`` is None where the
    paper prints no number)."""

    config: str
    metric: str
    unit: str
    paper: float | None
    ours: float


@dataclass
class ReproductionResult:
    """All rows of one paper's reproduction, plus the wall time it took."""

    paper: str
    seconds: float
    rows: list[ReproductionRow]
    notes: list[str] = field(default_factory=list)

    def to_json_dict(self) -> dict[str, Any]:
        """The JSON object of docs/CONTRACTS.md (notes are not part of it)."""
        return {
            "paper": self.paper,
            "seconds": round(self.seconds, 3),
            "rows": [asdict(r) for r in self.rows],
        }

    def to_json(self) -> str:
        return json.dumps(self.to_json_dict())

    def format_table(self) -> str:
        """Plain-text table: config, metric, unit, paper, ours, ours/paper."""
        head = f"{'config':<38} {'metric':<28} {'unit':<5} {'paper':>10} {'ours':>12} {'ratio':>7}"
        lines = [f"paper {self.paper} reproduction ({self.seconds:.1f} s)", head, "-" * len(head)]
        for r in self.rows:
            paper = "—" if r.paper is None else f"{r.paper:.4g}"
            ratio = "" if not r.paper else f"{r.ours / r.paper:.2f}"
            lines.append(
                f"{r.config:<38} {r.metric:<28} {r.unit:<5} {paper:>10} {r.ours:>12.4g} {ratio:>7}"
            )
        lines.extend(f"note: {n}" for n in self.notes)
        return "\n".join(lines)


def run(paper_id: str, **kwargs: Any) -> ReproductionResult:
    """Run the reproduction of ``paper_id`` ("000" … "004")."""
    if paper_id not in PAPERS:
        known = ", ".join(sorted(PAPERS))
        raise ValueError(f"paper_id={paper_id!r} has no reproduction; known: {known}")
    module = importlib.import_module(f"pednav_env.reproduce.{PAPERS[paper_id]}")
    return module.run(**kwargs)
