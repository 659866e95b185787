"""What :class:`pednav_env.nav.zupt_ukf.ZuptUkf` returns: its records, block and run
results and tallies, and the constants they refer to (paper 003's ZUPT UKF; the filter
itself and its docs: :mod:`pednav_env.nav.zupt_ukf`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Velocity norm beyond which a walker is declared diverged (m/s).
DIVERGENCE_SPEED = 50.0
#: Samples per :meth:`ZuptUkf.advance` call in :meth:`ZuptUkf.run`.
RUN_BLOCK = 100
#: Kinds of ZUPT in :class:`UpdateRecord`, by the kernel's code.
UPDATE_KINDS = ("start", "end", "stance")


@dataclass
class UpdateRecord:
    """One ZUPT of one walker (kept when ``record_updates`` is on; within a block the
    records come walker by walker, each walker's in time order)."""

    walker: int
    sample: int
    kind: str  # "start", "end" or "stance"
    x_prior: Array
    P_prior: Array
    x: Array
    P: Array
    nis: float
    accepted: bool


@dataclass(frozen=True)
class BlockResult:
    """Output of :meth:`ZuptUkf.advance` over a block of K samples."""

    stance: NDArray[np.bool_]  # (N, K) detected stance after each sample
    start: NDArray[np.bool_]  # (N, K) stance declared at the sample
    end: NDArray[np.bool_]  # (N, K) stance ended at the sample
    accepted: NDArray[np.int64]  # (N,) ZUPTs applied in the block
    nis_log_sum: Array  # (N,) Σ log(1 + NIS) of those ZUPTs
    position: Array  # (N, 3) mean position (m) after each walker's valid samples
    positions: Array | None  # (N, K, 3) mean position after each sample (record)
    states: Array | None  # (N, K, 9) mean state after each sample (record="state")


@dataclass
class ZuptRun:
    """Output of :meth:`ZuptUkf.run` over whole records."""

    x: Array  # (N, T+1, 9) mean state on the sample grid (held at x₀ during alignment)
    start_sample: int  # first sample filtered (= alignment window length)
    stance: NDArray[np.bool_]  # (N, T) detected stance per sample
    updates: NDArray[np.int64]  # (N,) ZUPTs applied
    rejected: NDArray[np.int64]  # (N,) ZUPTs rejected by the gate
    repairs: NDArray[np.int64]  # (N,) covariance repairs
    diverged: NDArray[np.bool_]  # (N,)
    P_final: Array  # (N, 9, 9)


class ZuptTallies(NamedTuple):
    """Per-walker counts of :class:`ZuptUkf` (copies)."""

    updates: NDArray[np.int64]  # (N,) ZUPTs applied
    rejected: NDArray[np.int64]  # (N,) ZUPTs rejected by the gate
    repairs: NDArray[np.int64]  # (N,) covariance repairs
    diverged: NDArray[np.bool_]  # (N,)
