"""``pednav/WaistStep-v0``: retune paper 004's step-fusion Kalman filter online."""

from __future__ import annotations

from typing import Any

import numpy as np

from pednav_env.envs.native import NativeScalarEnv, NativeVectorEnv
from pednav_env.envs.waist_config import ACTION_DIM, ACTION_KNOBS, OBS_FEATURES, WaistStepConfig
from pednav_env.envs.waist_core import WaistStepCore
from pednav_env.sensors.waist_grades import WAIST_GRADES

ENV_ID = "pednav/WaistStep-v0"


class WaistStepEnv(NativeScalarEnv):
    """
    ## Description
    A walker with an IMU on the belt walks a route of inverted-pendulum steps
    (paper 000). Paper 004's filter (Kaplin, Stepanov & Yarmolich) detects
    steps at the zero crossings of |a| − g and, once per detected step, fuses
    the INS step-mean velocity with the pendulum step velocity
    2 sqrt(2lh − h²)/T in a Kalman filter on the Schuler error model
    (per channel [δV, β, ε], eqs 1–6). Every ``decision_interval_s`` (0.5 s) of
    sensor data the agent retunes the step detector (threshold, hysteresis,
    minimum step duration) and the filter's noise (σ_n and Q scales). It is
    scored on horizontal position error. Action 0 is exactly paper 004's
    configuration, so the zero policy is the paper baseline.

    Episodes are drawn from the reset seed (domain randomisation,
    :class:`pednav_env.envs.waist_config.WaistRandomization`): a walk of 60–180 s
    after a 0.5–2 s stand; leg length 0.75–1 m (the filter's assumed leg
    length off by ~2 %); bouts of 8–50 steps in slow / normal / fast gait
    (step period 0.42–0.8 s, step length 0.55–1.05 leg lengths, 3 % jitter
    per step); slopes of 2–8° on 30 % of the bouts; turns of 30–120° on 6 % of
    the steps; stops of 1–8 s after 35 % of the bouts; heel-strike ringing of
    the belt (0.3–4 m/s², 12–25 Hz). Sensor grade ``paper004`` (ideal
    accelerometer), ``tactical``, ``industrial`` or ``consumer``: accelerometer
    noise and bias, the INS Schuler error model (σ_a, σ_ε, initial δV, β, ε,
    bias B) and the step-velocity irregularity σ_n, with σ_a and σ_n scaled
    by a factor of 0.5–2 per episode. ``scenario="paper"`` gives paper 004's
    walk: l = 0.7 m, φ_min = 60°, T = 0.5 s, six legs at azimuths 30°, 90°, …,
    ``paper_steps`` = 10 128 steps (84.4 min, 10 128 env steps), its INS errors
    (σ_a = 0.5 m/s, σ_ε = 1e-6 1/s, σ_n = 0.5 m/s) and an ideal accelerometer.

    ## Action Space
    ``Box(-1, 1, (5,), float32)``; a = 0 is paper 004's configuration:

    | Num | Knob | Mapping | Paper (a = 0) | Range | Unit |
    |-----|------|---------|---------------|-------|------|
    | 0 | step-detection threshold on \\|a\\| − g | ``3 a`` (linear) | 0 | −3 … 3 | m/s² |
    | 1 | detector hysteresis (re-arm below threshold − H) | ``2 max(a, 0)`` | 0 | 0 … 2 | m/s² |
    | 2 | minimum step duration | ``0.5 max(a, 0)`` | 0 | 0 … 0.5 | s |
    | 3 | σ_n scale (× 0.5 m/s; R × its square) | ``10 ** a`` | 1 | 0.1 … 10 | 1 |
    | 4 | process-noise scale (× paper Q) | ``100 ** a`` | 1 | 0.01 … 100 | 1 |

    Knobs 0–2 are linear because paper 004's detector is the pure zero
    crossing (0 cannot be reached on a log scale). Actions outside [-1, 1] are
    clipped and counted (``info["clipped_actions"]``); wrong shapes, NaN or
    inf raise ``ValueError``.

    ## Observation Space
    ``Box(low, high, (25,), float32)``, from the sensors and the filter only
    (never the truth); values are clipped to the bounds below.

    | Num | Observation | Min | Max | Unit |
    |-----|-------------|-----|-----|------|
    | 0 | mean of \\|a\\| − g over the last interval | −20 | 20 | m/s² |
    | 1 | std of \\|a\\| − g | 0 | 100 | m/s² |
    | 2 | max of \\|a\\| − g | −20 | 500 | m/s² |
    | 3 | min of \\|a\\| − g | −20 | 20 | m/s² |
    | 4 | fraction of the interval with \\|a\\| − g ≥ threshold | 0 | 1 | 1 |
    | 5 | step boundaries detected in the interval | 0 | 50 | 1 |
    | 6 | duration of the last detected step | 0 | 60 | s |
    | 7 | moving average of detected step durations | 0 | 60 | s |
    | 8 | time since the last detected boundary (= filter update) | 0 | 600 | s |
    | 9 | log(1 + NIS) of the last update (both channels) | 0 | 30 | 1 |
    | 10 | mean log(1 + NIS) of the interval's updates (0 if none) | 0 | 30 | 1 |
    | 11 | last innovation S − Hx̂⁻, east | −20 | 20 | m/s |
    | 12 | last innovation, north | −20 | 20 | m/s |
    | 13 | sqrt P[δV_E] | 0 | 50 | m/s |
    | 14 | sqrt P[δV_N] | 0 | 50 | m/s |
    | 15 | log₁₀ sqrt P[β] (larger channel) | −12 | 2 | log rad |
    | 16 | log₁₀ sqrt P[ε] (larger channel) | −14 | 0 | log rad/s |
    | 17 | pendulum step velocity V̄^BM of the last step | −20 | 50 | m/s |
    | 18 | INS step speed \\|V̄^INS\\| of the last step | 0 | 100 | m/s |
    | 19 | hip rise h of the last step | 0 | 2 | m |
    | 20… | the action in force (one entry per knob) | −1 | 1 | 1 |

    Right after reset only the covariance entries 13–16 are non-zero (and the action, 0).

    ## Rewards
    ``−e · Δ / D`` per step: e is the horizontal position error (m) at the end
    of the interval, Δ the interval length and D the duration of the walk; the
    return is minus the time-averaged horizontal error (m).
    ``info["reward_error"]`` carries that term. Between step updates the
    estimate runs on the INS velocity corrected by the filter's extrapolated
    error (eq 5 over the open step), so it equals eq (6) at each boundary.

    ## Starting State
    Position estimate at the true start, the filter at paper 004's
    x̂(0) = (0.3 m/s, 0, 0.1 °/h) and P(0) in both channels; the start of the
    episode counts as a step boundary.

    ## Episode End
    - Truncation: the end of the walk.
    - Termination (divergence): a non-finite filter state, or horizontal error
      above 25 m + 25 % of the distance walked. The final error is then held
      for the rest of the walk in the last reward, so the return is still
      minus the time-averaged error and diverging never pays.

    ## Arguments
    ``gymnasium.make("pednav/WaistStep-v0", scenario="random", decision_interval_s=0.5,
    rate_hz=100.0, paper_steps=10128, config=None, render_mode=None)``;
    ``config`` is a full :class:`pednav_env.envs.waist_config.WaistStepConfig`
    (walk duration range, randomisation, grades, filter, divergence bound).

    ## Vectorized environment
    ``gymnasium.make_vec("pednav/WaistStep-v0", num_envs=N,
    vectorization_mode="vector_entry_point")`` gives :class:`WaistStepVectorEnv`:
    all N walks step through one batched detector and filter. Autoreset mode:
    SAME_STEP (the reset observation is returned at once; the last one is in
    ``info["final_obs"]``, its info in ``info["final_info"]``). Lane i of a
    vector env reset with seed s plays the same episodes, bit for bit, as
    this env reset with seed s + i.

    ## Info
    ``pos_true``, ``pos_est`` (horizontal, m), ``error`` (m), ``distance``
    walked (m), ``step_detections`` and their split into
    ``true_step_detections`` / ``false_step_detections`` (within ±0.03 s of a
    simulated footfall, start or stop), ``filter_updates``,
    ``clipped_actions``, ``covariance_repairs``, ``diverged``,
    ``reward_error``, ``sensor_grade``, ``knobs`` (physical values).
    ``context`` is privileged truth for oracle policies only (never part of
    the observation): the episode's sensor-grade index in
    ``config.sensor_grades`` (−1 for the paper scenario's ``paper004`` when it
    is not listed), the factors on σ_a and σ_n, and the belt-ringing amplitude
    (m/s²), in the order of
    :data:`pednav_env.envs.waist_config.CONTEXT_FIELDS`.

    ## Example
    >>> import gymnasium as gym, numpy as np, pednav_env
    >>> env = gym.make("pednav/WaistStep-v0", scenario="paper", paper_steps=40)
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape
    (25,)
    >>> obs, reward, terminated, truncated, info = env.step(np.zeros(5, np.float32))
    >>> bool(reward <= 0), int(info["step_detections"])
    (True, 1)

    ## Version History
    - v0: initial version.
    """

    env_id = ENV_ID
    core_cls = WaistStepCore
    config_cls = WaistStepConfig
    arguments = ("scenario", "decision_interval_s", "rate_hz", "paper_steps")
    estimate_label = "step-fusion KF"

    def action_dim(self) -> int:
        return ACTION_DIM

    def lane_info(self) -> dict[str, Any]:
        return {"sensor_grade": self.core.grade[0], "context": self.core.context[0].copy()}


class WaistStepVectorEnv(NativeVectorEnv):
    """Native vector version of :class:`WaistStepEnv` (see its docstring):
    one batched detector and filter for all ``num_envs`` walks, SAME_STEP autoreset."""

    scalar_env = WaistStepEnv

    def lane_info(self) -> dict[str, np.ndarray]:
        return {
            "sensor_grade": np.array(self.core.grade, dtype=object),
            "context": self.core.context.copy(),
        }


# Re-exported for documentation tools.
__all__ = [
    "ACTION_KNOBS",
    "ENV_ID",
    "OBS_FEATURES",
    "WAIST_GRADES",
    "WaistStepEnv",
    "WaistStepVectorEnv",
]
