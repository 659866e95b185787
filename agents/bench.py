"""Throughput benchmarks: the native vector env against a filterpy reference.

``pednav bench foot [--json]`` measures, for N = 1, 16, 64, 256, the env
steps per second of the native vector env (all N walks in one batched
filter, paper policy, autoresets included) and, in the same process, of a
reference that steps N scalar environments one after another, each with its
own ``filterpy.kalman.UnscentedKalmanFilter`` doing the same work: the same
episodes, the same detector on the same samples, the same strapdown process
function (filterpy loops over the sigma points), the same Q, R and updates.

JSON: ``{"bench": "foot", "rows": [{"num_envs": 256, "steps_per_s": ..,
"reference_steps_per_s": .., "ratio": ..}, ...]}`` (plus ``peak_rss_mb``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter
from gymnasium.utils import seeding

from agents.bench_common import DEFAULT_SIZES, bench_result, bench_row, timed_calls
from agents.bench_marker import bench_marker
from agents.bench_waist import bench_waist
from pednav_env.envs.foot_core import FootZuptConfig, generate_episode
from pednav_env.envs.foot_zupt import FootZuptVectorEnv
from pednav_env.nav.alignment import align_static
from pednav_env.nav.detectors import OnlineStanceDetector
from pednav_env.nav.zupt_ukf import (
    STATE_DIM,
    ZuptUkf,
    measure,
    process_noise,
    propagate_state,
    state_add,
    state_mean,
    state_residual,
    state_to_nav,
)
from pednav_env.rotations import quat_rotate


class FilterpyFootReference:
    """One scalar foot environment whose filter is a plain filterpy UKF.

    Same episode as lane ``seed`` of the native env; paper policy. Between
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
        points = MerweScaledSigmaPoints(STATE_DIM, alpha=fc.alpha, beta=fc.beta, kappa=fc.kappa)
        self.ukf = UnscentedKalmanFilter(
            dim_x=STATE_DIM,
            dim_z=4,
            dt=1 / self.rate,
            hx=measure,
            fx=self._fx,
            points=points,
            x_mean_fn=state_mean,
            residual_x=state_residual,
            state_add=state_add,
        )
        engine = ZuptUkf(fc, self.rate, 1)  # only for its initial-state helper
        x0, P0 = engine.initial_state(align_static(self.f[None, : self.n_align], fc.g))
        self.ukf.x, self.ukf.P = x0[0].copy(), P0[0].copy()
        self.R = np.diag([fc.zupt_height_std**2] + [fc.zupt_velocity_std**2] * 3)
        self.detector = OnlineStanceDetector(fc.detector, self.rate, 1)
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
            q, _, _ = state_to_nav(self.mean)
            f_n3 = quat_rotate(q, self.f[m])[2]
            cond = self.detector.condition_threshold(
                np.array([np.linalg.norm(w)]),
                np.array([f_n3]),
                np.array([fc.detector.omega_max]),
                np.array([fc.detector.delta_f_max]),
            )
            start, end = self.detector.advance(cond, fc.detector.min_stance_s)
            if start[0] or end[0]:
                tau = np.array([(m - self.last) / self.rate])
                self.ukf.Q = process_noise(fc.assumed_imu, self.rate, tau, np.ones(1))[0]
                self.ukf.predict(dt=tau[0], a=self.last, b=m)
                self.ukf.update(np.zeros(4), R=self.R)
                self.mean = self.ukf.x.copy()
                self.last = m
            self.mean = propagate_state(
                self.mean[None, None], w[None, None], self.f[m][None, None], self.rate
            )[0, 0]
            self.cursor += 1


def bench_foot(
    sizes: tuple[int, ...] = DEFAULT_SIZES,
    min_seconds: float = 3.0,
    reference_seconds: float = 3.0,
    config: FootZuptConfig | None = None,
) -> dict[str, Any]:
    """Steps per second of the native vector env and of the filterpy reference."""
    config = config or FootZuptConfig()
    rows = []
    for n in sizes:
        env = FootZuptVectorEnv(num_envs=n, config=config)
        env.reset(seed=0)
        zeros = np.zeros((n, config.action_dim), np.float32)
        env.step(zeros)  # warm-up
        calls, elapsed = timed_calls(lambda env=env, z=zeros: env.step(z), min_seconds, 3)
        refs = [FilterpyFootReference(config, seed=i) for i in range(n)]
        # ≥ 3 rounds: the first interval after alignment is mostly standing (few
        # corrections), so one round alone would flatter the reference.
        ref_calls, ref_elapsed = timed_calls(
            lambda refs=refs: [r.step() for r in refs], reference_seconds, 3
        )
        rows.append(bench_row(n, calls, elapsed, ref_calls, ref_elapsed))
    return bench_result("foot", rows)


BENCHES: dict[str, Callable[..., dict[str, Any]]] = {
    "foot": bench_foot,
    "marker": bench_marker,
    "waist": bench_waist,
}


def run(name: str, **kwargs: Any) -> dict[str, Any]:
    """Run the benchmark ``name`` (foot, waist, marker)."""
    if name not in BENCHES:
        raise ValueError(f"bench {name!r} does not exist; known: {', '.join(sorted(BENCHES))}")
    return BENCHES[name](**kwargs)


def format_table(result: dict[str, Any]) -> str:
    lines = [
        f"bench {result['bench']} (peak RSS {result.get('peak_rss_mb', float('nan')):.0f} MB)",
        f"{'num_envs':>8} {'steps/s':>12} {'filterpy steps/s':>17} {'ratio':>8}",
    ]
    for r in result["rows"]:
        lines.append(
            f"{r['num_envs']:>8} {r['steps_per_s']:>12.0f} "
            f"{r['reference_steps_per_s']:>17.1f} {r['ratio']:>8.1f}"
        )
    return "\n".join(lines)
