"""The ZUPT-UKF of paper 003 as a plain ``filterpy.kalman.UnscentedKalmanFilter``.

:func:`filterpy_zupt_ukf` builds filterpy's UKF from the engine's model functions
(process = strapdown over the interval, h = [x₃, v₁, v₂, v₃], wrapped-angle mean
and residual); the oracle test drives it at the engine's update instants.
:class:`FilterpyFootReference` is one scalar foot environment around it, streaming
the samples through the eq (5) detector like the env (``pednav bench foot``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter
from gymnasium.utils import seeding
from numpy.typing import NDArray

from pednav_env.envs.foot_core import FootZuptConfig, generate_episode
from pednav_env.nav.alignment import align_static
from pednav_env.nav.detectors import ShoeDetectorConfig, shoe_statistic
from pednav_env.nav.zupt_config import UpdateMode, ZuptUkfConfig
from pednav_env.nav.zupt_model import (
    STATE_DIM,
    measure,
    process_noise,
    propagate_state,
    state_add,
    state_mean,
    state_residual,
    state_to_nav,
)
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.rotations import quat_rotate
from pednav_env.testing.detectors import OnlineStanceDetector


def filterpy_zupt_ukf(
    config: ZuptUkfConfig, rate_hz: float, fx: Callable[..., NDArray[np.float64]]
) -> UnscentedKalmanFilter:
    """filterpy's UKF with the engine's sigma points, h, state mean/residual/add.

    ``fx(x, dt, *args)`` is the process function (filterpy calls it per sigma point).
    """
    points = MerweScaledSigmaPoints(
        STATE_DIM, alpha=config.alpha, beta=config.beta, kappa=config.kappa
    )
    return UnscentedKalmanFilter(
        dim_x=STATE_DIM,
        dim_z=4,
        dt=1 / rate_hz,
        hx=measure,
        fx=fx,
        points=points,
        x_mean_fn=state_mean,
        residual_x=state_residual,
        state_add=state_add,
    )


def zupt_noise(config: ZuptUkfConfig) -> NDArray[np.float64]:
    """R = diag(σ_h², σ_v², σ_v², σ_v²) of a ZUPT (scale 1)."""
    return np.diag([config.zupt_height_std**2] + [config.zupt_velocity_std**2] * 3)


class FilterpyFootReference:
    """One scalar foot environment whose filter is a plain filterpy UKF.

    Same episode as lane ``seed`` of the native env; action 0 of its filter
    family (eq 5 at stance boundaries, or SHOE at every stance sample). Between
    corrections the mean state is integrated sample by sample for the
    detector (paper 003: the model solution gives f'_x3); at a stance
    boundary filterpy predicts (its sigma points through the strapdown over
    the interval) and updates.
    """

    def __init__(self, config: FootZuptConfig, seed: int) -> None:
        self.config = config
        fc = config.filter
        self.rate = config.rate_hz
        rng = seeding.np_random(seed)[0]
        ep = generate_episode(config, rng)
        self.omega, self.f = ep.omega_b, ep.f_b
        self.k = config.interval_samples
        self.n_align = int(round(fc.alignment_s * self.rate))
        self.bias = self.omega[: self.n_align].mean(0) if fc.calibrate_gyro_bias else np.zeros(3)
        self.ukf = filterpy_zupt_ukf(fc, self.rate, self._fx)
        engine = ZuptUkf(fc, self.rate, 1)  # only for its initial-state helper
        x0, P0 = engine.initial_state(align_static(self.f[None, : self.n_align], fc.g))
        self.ukf.x, self.ukf.P = x0[0].copy(), P0[0].copy()
        self.R = zupt_noise(fc) * fc.zupt_noise_scale
        self.q_scale = np.full(1, fc.process_noise_scale)
        self.detector = OnlineStanceDetector(fc.detector, self.rate, 1)
        #: SHOE detector: its statistic over the record (the env's per-interval one
        #: agrees to rounding), a ZUPT at every stance sample
        self.shoe = None
        if isinstance(fc.detector, ShoeDetectorConfig):
            self.shoe = shoe_statistic(self.omega[None], self.f[None], fc.detector, self.rate)[0]
        self.every_sample = fc.update_mode is UpdateMode.EVERY_STANCE_SAMPLE
        self.mean = self.ukf.x.copy()
        self.cursor = self.last = self.n_align

    def _fx(self, x, dt, a, b):
        w = self.omega[a:b] - self.bias
        return propagate_state(x[None, None], w[None], self.f[a:b][None], self.rate)[0, 0]

    def step(self) -> None:
        """One decision interval (wraps around at the end of the walk)."""
        fc = self.config.filter
        for _ in range(self.k):
            m = self.cursor
            if m >= len(self.omega):
                self.__init__(self.config, int(m))  # new episode, like an autoreset
                return
            w = self.omega[m] - self.bias
            if self.shoe is None:
                q, _, _ = state_to_nav(self.mean)
                f_n3 = quat_rotate(q, self.f[m])[2]
                cond = self.detector.condition_threshold(
                    np.array([np.linalg.norm(w)]),
                    np.array([f_n3]),
                    np.array([fc.detector.omega_max]),
                    np.array([fc.detector.delta_f_max]),
                )
            else:
                cond = np.array([self.shoe[m] <= fc.detector.threshold])
            start, end = self.detector.advance(cond, fc.detector.min_stance_s)
            stance_now = bool(self.detector.in_stance[0])
            if start[0] or end[0] or (self.every_sample and stance_now):
                tau = np.array([(m - self.last) / self.rate])
                self.ukf.Q = process_noise(fc.assumed_imu, self.rate, tau, self.q_scale)[0]
                self.ukf.predict(dt=tau[0], a=self.last, b=m)
                self.ukf.update(np.zeros(4), R=self.R)
                self.mean = self.ukf.x.copy()
                self.last = m
            self.mean = propagate_state(
                self.mean[None, None], w[None, None], self.f[m][None, None], self.rate
            )[0, 0]
            self.cursor += 1
