"""What the angle-sum forms change numerically: the shoe family over a long episode.

Two scalar FootZupt envs of the shoe family play the same 84.4-minute walk (walking
gaits, ADIS16470-like grade, no error bound, the setup of
``long_episode_memory.py shoe``) with action 0: one with the family's filter (the
sigma points' angles by the angle-sum forms of :mod:`pednav_env.nav.sigma_angles`),
one with the same filter on the direct formulas (``angle_sums=False``, every
inverse-trigonometric and sincos call). After every decision step it compares the
posterior mean state of the last ZUPT, the per-walker counters and the
position error, and prints the largest differences over the episode.

    .venv/bin/python benchmarks/angle_sums_difference.py [MINUTES] [SEED]

MINUTES (default 84.4) shortens the walk; SEED (default 0) is the episode seed.
"""

import sys
from dataclasses import replace

import numpy as np

from pednav_env.envs.foot_core import FootZuptConfig
from pednav_env.envs.foot_filters import family_filter
from pednav_env.envs.foot_zupt import FootZuptEnv
from pednav_env.gait.foot_route import RouteRandomization


def config(minutes: float, angle_sums: bool) -> FootZuptConfig:
    filt = replace(family_filter("shoe", "random"), angle_sums=angle_sums)
    return FootZuptConfig(
        route=RouteRandomization(
            duration_s=(minutes * 60, minutes * 60), gait_weights=(0.3, 0.7, 0.0, 0.0)
        ),
        imu_grades=("adis16470",),
        imu_grade_weights=(1.0,),
        divergence_error_m=1e9,
        filter_family="shoe",
        filter=filt,
        scenario="random",
    )


if __name__ == "__main__":
    minutes = float(sys.argv[1]) if len(sys.argv) > 1 else 84.4
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    envs = [FootZuptEnv(config=config(minutes, a)) for a in (True, False)]
    for env in envs:
        env.reset(seed=seed)
    zero = np.zeros(4, np.float32)
    dx = np.zeros(9)
    d_err, steps, ended = 0.0, 0, False
    while not ended:
        out = [env.step(zero) for env in envs]
        steps += 1
        engines = [env.core.engine for env in envs]
        dx = np.maximum(dx, np.abs(engines[0].x[0] - engines[1].x[0]))
        d_err = max(d_err, abs(out[0][4]["error"] - out[1][4]["error"]))
        same = [
            np.array_equal(getattr(engines[0], a), getattr(engines[1], a))
            for a in ("updates", "stance_starts", "diverged")
        ]
        if not all(same):
            print(f"step {steps}: counters differ ({same})")
        ended = any(o[2] or o[3] for o in out)
        if (out[0][2] or out[0][3]) != (out[1][2] or out[1][3]):
            print(f"step {steps}: one episode ended, the other did not")
    e = envs[0]
    print(
        f"{steps} steps ({steps * e.config.decision_interval_s / 60:.1f} min), "
        f"{int(e.core.engine.updates[0])} ZUPTs; final error {out[0][4]['error']:.3f} m "
        f"(direct formulas: {out[1][4]['error']:.3f} m)"
    )
    print("largest |difference| of the posterior mean over the episode:")
    print("  position (m)      " + " ".join(f"{v:.2e}" for v in dx[:3]))
    print("  velocity (m/s)    " + " ".join(f"{v:.2e}" for v in dx[3:6]))
    print("  θ, γ, ψ (rad)     " + " ".join(f"{v:.2e}" for v in dx[6:]))
    print(f"  position error (m) {d_err:.2e}")
