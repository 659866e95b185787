"""Put a recording on a uniform sample grid (the filter assumes one rate).

Real timestamps wobble: PyShoe's 200 Hz logs jitter by ±3 ms around 5 ms
(arrival times), x-io's 400 Hz logs lose packets (gaps of 2–6 samples). The
rule, documented in docs/REAL_DATA.md:

- the nominal interval is the median time step; the rate is its inverse;
- a step longer than 1.5 nominal intervals is a gap of ``round(dt/dt₀) − 1``
  missing samples only if neither neighbouring step compensates it (the sum
  with the step before and with the step after both exceed 2.5 dt₀);
  otherwise it is jitter;
- every recorded sample is kept, at its grid position; missing samples are
  linearly interpolated (angular rate, specific force and truth);
- jitter is ignored: sample k sits at t₀ + k·dt₀.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.io.recording import Recording

Array = NDArray[np.float64]


def grid_steps(time: Array) -> tuple[float, NDArray[np.int64]]:
    """(nominal interval s, grid steps between consecutive samples, ≥ 1 each)."""
    dt = np.diff(np.asarray(time, dtype=float))
    nominal = float(np.median(dt))
    steps = np.ones(dt.size, dtype=np.int64)
    long = np.flatnonzero(dt > 1.5 * nominal)
    for k in long:
        before = dt[k - 1] if k > 0 else np.inf
        after = dt[k + 1] if k + 1 < dt.size else np.inf
        if min(before, after) + dt[k] > 2.5 * nominal:
            steps[k] = max(1, int(round(dt[k] / nominal)))
    return nominal, steps


@dataclass(frozen=True)
class UniformSamples:
    """A recording on a uniform grid.

    ``omega_b``/``f_b``/``truth_pos`` are ``(M, 3)``; ``filled`` marks
    interpolated samples; ``source_index[k]`` is the recording sample at grid
    position k (−1 where filled).
    """

    rate_hz: float
    omega_b: Array
    f_b: Array
    truth_pos: Array | None
    filled: NDArray[np.bool_]
    source_index: NDArray[np.int64]

    @property
    def num_samples(self) -> int:
        return int(self.omega_b.shape[0])

    def grid_index(self, sample: NDArray[np.integer]) -> NDArray[np.int64]:
        """Grid positions of recording samples ``sample``."""
        return np.flatnonzero(self.source_index >= 0)[np.asarray(sample, dtype=np.int64)]

    def cropped(self, start: int) -> UniformSamples:
        """The grid from position ``start`` on."""
        truth = None if self.truth_pos is None else self.truth_pos[start:]
        return UniformSamples(
            self.rate_hz,
            self.omega_b[start:],
            self.f_b[start:],
            truth,
            self.filled[start:],
            self.source_index[start:],
        )


def to_uniform(rec: Recording) -> UniformSamples:
    """The recording on its nominal grid, gaps filled by linear interpolation."""
    nominal, steps = grid_steps(rec.time)
    pos = np.concatenate(([0], np.cumsum(steps)))
    m = int(pos[-1]) + 1
    grid = np.arange(m, dtype=float)

    def fill(a: Array) -> Array:
        out = np.empty((m, a.shape[1]))
        for c in range(a.shape[1]):
            out[:, c] = np.interp(grid, pos, a[:, c])
        return out

    truth = None
    if rec.truth_pos is not None:
        truth = fill(rec.truth_pos)  # NaN rows stay NaN next to them
    filled = np.ones(m, dtype=bool)
    filled[pos] = False
    src = np.full(m, -1, dtype=np.int64)
    src[pos] = np.arange(rec.num_samples)
    return UniformSamples(1.0 / nominal, fill(rec.omega_b), fill(rec.f_b), truth, filled, src)
