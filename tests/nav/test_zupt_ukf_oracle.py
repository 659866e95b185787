"""The batched ZUPT-UKF equals filterpy's UnscentedKalmanFilter step for step.

filterpy (2.0) is driven by the engine's own model functions (process =
strapdown over the interval, h = [x₃, v₁, v₂, v₃], wrapped angle mean and
residual), the engine's Q for each interval and the same R, at the update
instants the engine detected. Every prior and posterior must agree to 1e-8
relative over a whole simulated walk, for both filter families: paper 003's
(eq 5, ZUPTs at stance start and end) and the shoe family's action 0
(``real-fixed``: SHOE detector, a ZUPT at every stance sample, its Q and R scales;
the sigma points' angles by the angle-sum forms of nav.sigma_angles).
"""

import numpy as np
import pytest

from pednav_env.envs.foot_filters import family_filter
from pednav_env.nav.alignment import align_static
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.nav.zupt_model import process_noise, propagate_state
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.sensors.imu import ImuSpec, simulate_imu
from pednav_env.testing.reference_foot import filterpy_zupt_ukf, zupt_noise

RATE = 100.0


#: Relative tolerance per family. The engine moves the sigma points by
#: preintegrated increments and filterpy integrates each one sample by sample,
#: so the two differ by rounding that grows with the number of updates: at
#: worst 5e-9 of the largest entry over the paper filter's boundary ZUPTs,
#: 1e-8 over the shoe family's (a ZUPT at every stance sample, many times as
#: many); a wrong Q, R, update instant or weight moves them by far more.
RTOL = {"paper": 1e-8, "shoe": 1e-7}


def assert_close(actual, desired, what, rtol=1e-8):
    scale = max(np.abs(desired).max(), 1e-300)
    np.testing.assert_allclose(actual, desired, rtol=rtol, atol=rtol * scale, err_msg=what)


#: The shoe family's filter is real-fixed's with the angle-sum forms (nav.sigma_angles).
FILTERS = {"paper": ZuptUkfConfig(), "shoe": family_filter("shoe", "calibrated")}


@pytest.mark.parametrize("family", FILTERS)
def test_engine_equals_filterpy_over_a_whole_walk(paper_walk, family):
    imu = simulate_imu(
        paper_walk.omega_b,
        paper_walk.f_b,
        RATE,
        ImuSpec.paper003(),
        [np.random.default_rng(2024)],
        gait_step_index=paper_walk.gait_step,
    )
    omega, f = imu.omega_b, imu.f_b
    cfg = FILTERS[family]
    engine = ZuptUkf(cfg, RATE, 1, record_updates=True)
    engine.run(omega, f, record=False)
    history = engine.history
    assert len(history) >= 2 * 12  # at least two ZUPTs per stance of the 12-stride walk
    kinds = {rec.kind for rec in history}
    assert kinds == ({"start", "end"} if family == "paper" else {"start", "end", "stance"})
    bias = engine.gyro_bias[0]  # zero unless the filter calibrates it at rest

    def fx(x, dt, omega_seg, f_seg):
        w = omega_seg - bias
        return propagate_state(x[None, None], w[None], f_seg[None], RATE)[0, 0]

    ukf = filterpy_zupt_ukf(cfg, RATE, fx)
    n_align = int(round(cfg.alignment_s * RATE))
    x0, P0 = engine.initial_state(align_static(f[:, :n_align]))
    ukf.x, ukf.P = x0[0].copy(), P0[0].copy()
    R = zupt_noise(cfg) * cfg.zupt_noise_scale
    last = n_align
    for k, rec in enumerate(history):
        m = rec.sample
        tau = np.array([(m - last) / RATE])
        scale = np.full(1, cfg.process_noise_scale)
        ukf.Q = process_noise(cfg.assumed_imu, RATE, tau, scale)[0]
        ukf.predict(dt=tau[0], omega_seg=omega[0, last:m], f_seg=f[0, last:m])
        assert_close(rec.x_prior, ukf.x_prior, f"prior mean at update {k}", RTOL[family])
        assert_close(rec.P_prior, ukf.P_prior, f"prior covariance at update {k}", RTOL[family])
        ukf.update(np.zeros(4), R=R)
        assert_close(rec.x, ukf.x, f"posterior mean at update {k}", RTOL[family])
        assert_close(rec.P, ukf.P, f"posterior covariance at update {k}", RTOL[family])
        last = m
