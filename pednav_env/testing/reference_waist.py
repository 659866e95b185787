"""Paper 004's step-fusion filter as two plain ``filterpy.kalman.KalmanFilter`` objects.

:class:`FilterpyWaistReference` is one scalar ``pednav/WaistStep-v0`` environment
(paper policy by default) doing the env's work the ordinary way: it plays the
same episodes, streams its sensor samples one at a time through the engine's step
detector (:func:`pednav_env.nav.waist_dr.detect_steps` with N = 1 and its carried
state), and at each detected step computes V̄^INS, the pendulum step velocity with
the library's :func:`~pednav_env.nav.step_velocity.biomechanical_step_velocity` on the
step's samples, and runs two ``KalmanFilter`` objects (east and north channel of
paper 004) through ``predict(F=Φ(T), Q=Q)`` and ``update(S)``, with the position of
eqs (5)–(6); at the end of each interval it forms the position estimate and its
error, like the env. The env's oracle test and ``pednav bench waist`` use it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from filterpy.kalman import KalmanFilter
from gymnasium.utils import seeding

from pednav_env.envs.waist_config import WaistStepConfig
from pednav_env.envs.waist_episode import generate_episode
from pednav_env.nav.step_fusion_kf import H_DV
from pednav_env.nav.step_velocity import biomechanical_step_velocity
from pednav_env.nav.waist_dr import StepDetectorConfig, StepDetectorState, detect_steps
from pednav_env.sensors.ins_error import CHANNEL_SIGN, schuler_transition


class FilterpyWaistReference:
    """One scalar waist environment whose filter is plain filterpy (paper policy).

    Plays the same episodes as lane ``seed`` of the native env (a new episode
    from the same generator at the end of each walk, like an autoreset).
    ``knobs`` are the physical detector/filter values: threshold, hysteresis,
    minimum step duration, σ_n scale, Q scale (default: paper 004's).
    """

    def __init__(
        self,
        config: WaistStepConfig,
        seed: int,
        knobs: tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 1.0, 1.0),
    ) -> None:
        self.config = config
        self.rng = seeding.np_random(seed)[0]
        self.dt = 1.0 / config.rate_hz
        self.k = config.interval_samples
        self.knobs = knobs
        self.det_cfg = StepDetectorConfig(g=config.g)
        self.finished: dict[str, Any] | None = None
        self._new_episode()

    def _new_episode(self) -> None:
        fc = self.config.filter
        self.ep = generate_episode(self.config, self.rng)
        self.filters = []
        for _ in range(2):  # east, north
            kf = KalmanFilter(dim_x=3, dim_z=1)
            kf.x = np.array(fc.initial_estimate, dtype=float)[:, None]
            kf.P = fc.P0.copy()
            kf.H = H_DV.copy()
            kf.Q = fc.Q * self.knobs[4]
            kf.R = fc.R * self.knobs[3] ** 2
            self.filters.append(kf)
        self.state = StepDetectorState.initial(1)
        self.pos = np.zeros(2)  # Ê at the last boundary
        self.last_b = 0
        self.cursor = 0
        self.interval = 0
        self.estimates: list[np.ndarray] = []
        self.errors: list[float] = []
        self.weights: list[float] = []

    def _close_step(self, j1: int) -> None:
        ep, dt, fc = self.ep, self.dt, self.config.filter
        j0 = self.last_b
        T = (j1 - j0) * dt
        v_ins = (ep.ins_pos[j1] - ep.ins_pos[j0]) / T
        bm = biomechanical_step_velocity(
            ep.a_up[j0 : j1 + 1][None], dt, [[0, j1 - j0]], ep.leg_length_assumed, rule="delta_v"
        )
        v_bm = bm.velocity[0, 0] + ep.bm_noise[(j0 + j1) // 2]
        psi = ep.yaw[j1]
        vb = v_bm * np.array([np.cos(psi), np.sin(psi)])
        for c, kf in enumerate(self.filters):
            F = schuler_transition(T, fc.g, fc.earth_radius, CHANNEL_SIGN[c])
            kf.predict(F=F)
            v_corr = v_ins[c] - kf.x[0, 0]  # eq (5), extrapolated estimate
            kf.update(np.array([[v_ins[c] - vb[c]]]))  # eqs (3)-(4)
            self.pos[c] += T * v_corr  # eq (6)
        self.last_b = j1

    def estimate(self) -> np.ndarray:
        """Position estimate at the last processed sample (eqs 5–6 over the open step)."""
        fc = self.config.filter
        tau = (self.cursor - self.last_b) * self.dt
        disp = self.ep.ins_pos[self.cursor] - self.ep.ins_pos[self.last_b]
        corr = np.array(
            [
                kf.x[0, 0] - s * fc.g * tau * kf.x[1, 0]
                for kf, s in zip(self.filters, CHANNEL_SIGN, strict=True)
            ]
        )
        return self.pos + disp - tau * corr

    def step(self) -> bool:
        """One decision interval; True when the walk ended (a new one is started)."""
        ep = self.ep
        L = ep.f_norm.shape[0]
        thr, hys, min_d = self.knobs[:3]
        f = np.zeros((1, 1, 3))
        used = 0
        for _ in range(self.k):
            s = self.cursor + 1
            if s > L - 1:
                break
            f[0, 0, 0] = ep.f_norm[s]
            b, self.state = detect_steps(
                f, self.dt, self.det_cfg, self.state, [thr], [hys], [min_d]
            )
            if b[0, 0]:
                self._close_step(s)
            self.cursor = s
            used += 1
        self.interval += 1
        est = self.estimate()
        self.estimates.append(est)
        truth = ep.pos_n[self.cursor]
        self.errors.append(float(np.hypot(*(est - truth))))
        self.weights.append(used / (L - 1))
        if self.cursor >= L - 1:
            self.finished = {
                "estimates": np.array(self.estimates),
                "errors": np.array(self.errors),
                "weights": np.array(self.weights),
                "episode": ep,
            }
            self._new_episode()
            return True
        return False
