"""Throughput benchmark of ``pednav/MarkerTrack-v0`` against a filterpy reference.

``pednav bench marker [--json]`` measures, for N = 1, 16, 64, 256, the env
steps per second of the native vector env (all N walks in one batched
filter, paper policy, autoresets included) and, in the same process, of a
reference that steps N scalar environments one after another, each with its
own ``filterpy.kalman.ExtendedKalmanFilter`` doing the same work: the scalar
environment's own episode core (:class:`MarkerTrackCore` with N = 1: the same
episodes, features, rewards, re-anchoring and divergence checks) whose
filter is a plain filterpy EKF used the ordinary way — ``predict()`` with
F = d I and Q = Γ Q Γᵀ, ``update(z, HJacobian, Hx, R)`` with the model
functions of :mod:`pednav_env.nav.marker_ekf` (eq 4.10 / 5.3) on the valid
coordinates of each sample.

The two loops are timed in alternating chunks of 0.25 s until each has run
``min_seconds`` / ``reference_seconds`` (3 s), so that both see the same load
on a shared machine.

JSON: ``{"bench": "marker", "rows": [{"num_envs": 256, "steps_per_s": ..,
"reference_steps_per_s": .., "ratio": ..}, ...]}`` (plus ``peak_rss_mb``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from gymnasium.utils import seeding
from numpy.typing import NDArray
from scipy.linalg import solve_triangular

from agents.bench_common import DEFAULT_SIZES, bench_result, bench_row
from pednav_env.envs.marker_core import MarkerTrackConfig, MarkerTrackCore
from pednav_env.envs.marker_track import ENV_ID, MarkerTrackVectorEnv
from pednav_env.nav.marker_ekf import (
    DIM_X,
    DIM_Z,
    MarkerEkfConfig,
    marker_jacobian,
    marker_measurement,
)


class FilterpyMarkerEngine:
    """The engine interface of :class:`MarkerTrackCore` over one
    ``filterpy.kalman.ExtendedKalmanFilter`` per lane (a Python loop over lanes).

    The model is eq 4.10 about the lane's time origin (t_a, X_a), as in
    :class:`pednav_env.nav.marker_ekf.MarkerEkfEngine`: h(x, τ) =
    ``marker_measurement(p⁰ + x, τ, M)`` + [X_a, 0, X_a, 0] with τ = t − t_a,
    H = ``marker_jacobian(p⁰ + x, τ, M)``; skipped coordinates are left out
    of z, H and R. The normalised innovations returned by :meth:`update` are
    L⁻¹ y with S = L Lᵀ (filterpy keeps y and S), which equal the engine's
    sequential ones.
    """

    def __init__(self, config: MarkerEkfConfig, num_lanes: int) -> None:
        n = int(num_lanes)
        self.config = config
        self.n = n
        proc = config.process
        self.q0 = proc.process_noise.copy()
        self.r0 = config.meas_std**2
        self.p0 = config.nominal.vector[:, None].copy()
        self.M = config.nominal.shank_length
        self.P0 = np.diag(proc.P0)
        self.q = np.repeat(self.q0[:, None], n, axis=1)
        self.r = np.full((DIM_Z, n), self.r0)
        self.t_anchor = np.zeros(n)
        self.x_anchor = np.zeros(n)
        self.repairs = np.zeros(n, dtype=np.int64)
        self.filters = []
        for _ in range(n):
            f = ExtendedKalmanFilter(dim_x=DIM_X, dim_z=DIM_Z)
            f.F = np.diag(proc.F)
            self.filters.append(f)
        self.reset(np.arange(n))

    @property
    def x(self) -> NDArray[np.float64]:
        return np.stack([f.x[:, 0] for f in self.filters], axis=1)

    @property
    def P(self) -> NDArray[np.float64]:
        return np.ascontiguousarray(np.stack([f.P for f in self.filters], axis=2))

    def reset(self, lanes: NDArray[np.integer]) -> None:
        for i in lanes:
            self.filters[i].x = np.zeros((DIM_X, 1))
            self.filters[i].P = self.P0.copy()
        self.t_anchor[lanes] = 0.0
        self.x_anchor[lanes] = 0.0

    def predict(self) -> None:
        for i, f in enumerate(self.filters):
            f.Q = np.diag(self.q[:, i])
            f.predict()

    def _hx(self, x, tau, offset, rows):
        return (marker_measurement(self.p0[:, 0] + x[:, 0], tau, self.M) + offset)[rows][:, None]

    def _H(self, x, tau, rows):
        return marker_jacobian(self.p0[:, 0] + x[:, 0], tau, self.M)[rows]

    def update(self, z, valid, t) -> NDArray[np.float64]:
        nu = np.zeros((DIM_Z, self.n))
        for i, f in enumerate(self.filters):
            rows = valid[:, i]
            if not rows.any():
                continue
            tau = t[i] - self.t_anchor[i]
            offset = np.array([self.x_anchor[i], 0.0, self.x_anchor[i], 0.0])
            f.update(
                z[rows, i][:, None],
                self._H,
                self._hx,
                R=np.diag(self.r[rows, i]),
                args=(tau, rows),
                hx_args=(tau, offset, rows),
            )
            L = np.linalg.cholesky(f.S)
            nu[rows, i] = solve_triangular(L, f.y[:, 0], lower=True)
        return nu

    def markers(self, t, x=None) -> NDArray[np.float64]:
        x = self.x if x is None else x
        params = self.p0[:, 0] + np.moveaxis(x, 0, -1)  # (..., N, 6)
        out = marker_measurement(params, t - self.t_anchor, self.M)  # (..., N, 4)
        out[..., (0, 2)] += self.x_anchor[..., None]
        return np.moveaxis(out, -1, 0)

    def repair(self) -> NDArray[np.bool_]:
        return ~np.array([np.isfinite(f.P).all() for f in self.filters])


class ReferenceMarkerEnv:
    """One scalar marker environment whose filter is filterpy's EKF (paper policy)."""

    def __init__(self, config: MarkerTrackConfig, seed: int) -> None:
        self.core = MarkerTrackCore(config, 1, ENV_ID, engine_factory=FilterpyMarkerEngine)
        self.rng = seeding.np_random(seed)[0]
        self.core.reset_lanes(np.array([0]), [self.rng])
        self.zeros = np.zeros((1, config.action_dim))

    def step(self) -> None:
        """One decision interval; a new episode (autoreset) when the walk ends."""
        _, _, terminated, truncated, _ = self.core.step(self.zeros)
        if terminated[0] or truncated[0]:
            self.core.reset_lanes(np.array([0]), [self.rng])


def _interleaved(
    native: Callable[[], None],
    reference: Callable[[], None],
    min_seconds: float,
    reference_seconds: float,
    chunk_seconds: float = 0.25,
) -> tuple[int, float, int, float]:
    """Time both loops in alternating chunks until each has run its minimum time.

    On a shared machine the load drifts; alternating keeps the two measurements
    under the same conditions, so their ratio is stable. Returns (calls, seconds)
    of the native loop, then of the reference.
    """
    n_calls = r_calls = 0
    n_time = r_time = 0.0
    while n_time < min_seconds or r_time < reference_seconds or not (n_calls and r_calls):
        for fn, is_native in ((native, True), (reference, False)):
            start = time.perf_counter()
            calls = 0
            while calls == 0 or time.perf_counter() - start < chunk_seconds:
                fn()
                calls += 1
            elapsed = time.perf_counter() - start
            if is_native:
                n_calls, n_time = n_calls + calls, n_time + elapsed
            else:
                r_calls, r_time = r_calls + calls, r_time + elapsed
    return n_calls, n_time, r_calls, r_time


def bench_marker(
    sizes: tuple[int, ...] = DEFAULT_SIZES,
    min_seconds: float = 3.0,
    reference_seconds: float = 3.0,
    config: MarkerTrackConfig | None = None,
) -> dict[str, Any]:
    """Steps per second of the native vector env and of the filterpy reference."""
    config = config or MarkerTrackConfig()
    rows = []
    for n in sizes:
        env = MarkerTrackVectorEnv(num_envs=n, config=config)
        env.reset(seed=0)
        zeros = np.zeros((n, config.action_dim), np.float32)
        env.step(zeros)  # warm-up
        refs = [ReferenceMarkerEnv(config, seed=i) for i in range(n)]
        calls, elapsed, ref_calls, ref_elapsed = _interleaved(
            lambda env=env, z=zeros: env.step(z),
            lambda refs=refs: [r.step() for r in refs],
            min_seconds,
            reference_seconds,
        )
        rows.append(bench_row(n, calls, elapsed, ref_calls, ref_elapsed))
    return bench_result("marker", rows)
