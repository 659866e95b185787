"""The outcome of one evaluation episode of ``pednav evaluate`` (:mod:`agents.evaluate`),
shared by the evaluation and its report (:mod:`agents.evaluate_report`)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of one evaluation episode."""

    seed: int
    mean_error: float  # time-averaged horizontal error (m) = −return
    final_error: float  # m
    distance: float  # m walked
    diverged: bool
    #: horizontal error (m) at the end of each decision interval
    error_trace: tuple[float, ...] = ()
    #: the recording the episode played (replay env), else None
    trial: str | None = None

    @property
    def final_error_pct(self) -> float:
        return 100.0 * self.final_error / self.distance if self.distance > 0 else math.nan
