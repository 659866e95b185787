"""The marker EKF of paper 001 as plain ``filterpy.kalman.ExtendedKalmanFilter`` objects.

:class:`FilterpyMarkerEngine` has the engine interface of :class:`MarkerTrackCore`
over one filterpy EKF per lane, used the ordinary way — ``predict()`` with F = d I
and Q = Γ Q Γᵀ, ``update(z, HJacobian, Hx, R)`` with the model functions of
:mod:`pednav_env.nav.marker_model` (eq 4.10 / 5.3) on the valid coordinates of each
sample. :class:`ReferenceMarkerEnv` is one scalar environment around it: the env's
own episode core (:class:`MarkerTrackCore` with N = 1: the same episodes,
features, rewards, re-anchoring and divergence checks) with the filterpy engine.
The env's oracle test and ``pednav bench marker`` use them.
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from gymnasium.utils import seeding
from numpy.typing import NDArray
from scipy.linalg import solve_triangular

from pednav_env.envs.marker_config import MarkerTrackConfig
from pednav_env.envs.marker_core import MarkerTrackCore
from pednav_env.envs.marker_track import ENV_ID
from pednav_env.nav.marker_model import (
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
        self.p0 = config.nominal.vector
        self.M = config.nominal.shank_length
        self.P0 = np.diag(proc.P0)
        self.q = np.repeat(self.q0[None], n, axis=0)
        self.r = np.full((n, DIM_Z), self.r0)
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
        return np.stack([f.x[:, 0] for f in self.filters])

    @property
    def P(self) -> NDArray[np.float64]:
        return np.stack([f.P for f in self.filters])

    def reset(self, lanes: NDArray[np.integer]) -> None:
        for i in lanes:
            self.filters[i].x = np.zeros((DIM_X, 1))
            self.filters[i].P = self.P0.copy()
        self.t_anchor[lanes] = 0.0
        self.x_anchor[lanes] = 0.0

    def predict(self) -> None:
        for i, f in enumerate(self.filters):
            f.Q = np.diag(self.q[i])
            f.predict()

    def _hx(self, x, tau, offset, rows):
        return (marker_measurement(self.p0 + x[:, 0], tau, self.M) + offset)[rows][:, None]

    def _H(self, x, tau, rows):
        return marker_jacobian(self.p0 + x[:, 0], tau, self.M)[rows]

    def update(self, z, valid, t) -> NDArray[np.float64]:
        nu = np.zeros((self.n, DIM_Z))
        for i, f in enumerate(self.filters):
            rows = valid[i]
            if not rows.any():
                continue
            tau = t[i] - self.t_anchor[i]
            offset = np.array([self.x_anchor[i], 0.0, self.x_anchor[i], 0.0])
            f.update(
                z[i, rows][:, None],
                self._H,
                self._hx,
                R=np.diag(self.r[i, rows]),
                args=(tau, rows),
                hx_args=(tau, offset, rows),
            )
            L = np.linalg.cholesky(f.S)
            nu[i, rows] = solve_triangular(L, f.y[:, 0], lower=True)
        return nu

    def markers(self, t, x=None) -> NDArray[np.float64]:
        x = self.x if x is None else x
        lane = (self.n,) + (1,) * (t.ndim - 1)
        out = marker_measurement(self.p0 + x, t - self.t_anchor.reshape(lane), self.M)
        out[..., (0, 2)] += self.x_anchor.reshape(lane)[..., None]
        return out  # (N, ..., 4)

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
