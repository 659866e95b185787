"""``pednav/FootZupt-v0``: retune a foot-mounted ZUPT-UKF online (paper 003)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from pednav_env.envs.foot_core import (
    ACTION_KNOBS,
    MIN_STANCE_MAX_S,
    OBS_FEATURES,
    FootZuptConfig,
    FootZuptCore,
)
from pednav_env.envs.foot_filters import FILTER_FAMILIES
from pednav_env.envs.native import NativeScalarEnv, NativeVectorEnv, make_config

ENV_ID = "pednav/FootZupt-v0"


class FamilyFront:
    """The ``filter`` constructor argument of the foot envs, scalar and vector."""

    @classmethod
    def build_config(cls, config: Any, arguments: dict[str, Any]) -> Any:
        """The config, with the ``filter`` argument (a family name) as its
        ``filter_family`` field and that family's filter at action 0 when it
        differs from ``config``'s (``config.filter`` is the filter itself)."""
        family = arguments.get("filter")
        if family is not None and not isinstance(family, str):
            raise ValueError(f"filter: a family name {FILTER_FAMILIES}, got {family!r}")
        rest = {k: v for k, v in arguments.items() if k != "filter"}
        built = super().build_config(config, rest)  # type: ignore[misc]
        if family is None or family == built.filter_family:
            return built
        if config is None:  # the family's own defaults (scenario, rate, filter)
            return make_config(cls.config_cls, None, **rest, filter_family=family)  # type: ignore[attr-defined]
        return cls.with_family(built, family)

    @staticmethod
    def with_family(config: FootZuptConfig, family: str) -> FootZuptConfig:
        """``config`` with filter family ``family`` and that family's filter."""
        return replace(config, filter_family=family, filter=None)


class FootZuptEnv(FamilyFront, NativeScalarEnv):
    """
    ## Description
    A walker with an IMU on the foot walks a route; a zero-velocity-update
    unscented Kalman filter (paper 003, Bolotin & Fatehrad 2015) tracks the
    foot. Every ``decision_interval_s`` (0.5 s) of IMU data the agent retunes
    the filter: the stance-detection thresholds of the paper's eq (5), the
    process-noise and ZUPT-noise scales, and optionally a minimum stance
    duration. It is scored on horizontal position error. Action 0 is exactly
    the paper's fixed filter, so the zero policy is the paper baseline.

    Filter families (``filter=``, :mod:`pednav_env.envs.foot_filters`):
    ``"paper"`` (the default) is the filter above, eq (5) with ZUPTs at stance
    start and end; ``"shoe"`` is the filter foot-mounted systems run: the SHOE
    detector (Skog et al. 2010) with a ZUPT at every stance sample, action 0 =
    ``real-fixed`` (``pednav_env/replay/real_fixed.json``), knobs log γ, the
    statistic's window and the Q and R scales. Both run through the same
    compiled filter; the observation is the same.

    Episodes are drawn from the reset seed (domain randomisation): a route of
    60–180 s with turns, stops (standing for 1–8 s) and gait changes between
    slow walking, walking, fast walking and running; stance is not perfectly
    still at speed (roll-over and micro-motion) and heel strikes shake the
    IMU; the IMU grade is paper 003's, ADIS16470-like or consumer-grade with
    random biases, scale factors and misalignments. ``scenario="paper"`` gives
    paper 003's 5 m square with 1 m strides and its IMU. ``scenario="calibrated"``
    (the shoe family's default) is the simulator calibrated on recordings: 60–120 s
    walks at 200 Hz, every stride's speed in 0.3–3 m/s (a new speed per leg),
    turns, stops of 1–8 s, walker stance dynamics drawn from the calibrated
    population, the MicroStrain 3DM-GX5-25 grade with random errors.

    ## Action Space
    ``Box(-1, 1, (4,), float32)`` (``(5,)`` with ``tune_min_stance=True``).
    Component i sets knob i to ``base_i · span_i ** a_i``; ``filter="paper"``:

    | Num | Knob | Base (paper) | Span | Range | Unit |
    |-----|------|--------------|------|-------|------|
    | 0 | ω_max, eq (5) gyro threshold | 0.22 | 10 | 0.022–2.2 | rad/s |
    | 1 | Δf_max, eq (5) vertical specific-force threshold | 0.33 | 10 | 0.033–3.3 | m/s² |
    | 2 | process-noise scale (× paper Q) | 1 | 100 | 0.01–100 | 1 |
    | 3 | ZUPT measurement-noise scale (× paper R) | 1 | 100 | 0.01–100 | 1 |
    | 4 | minimum stance duration ``0.15 · max(a, 0)``, linear (a ≤ 0: none) | 0 | — | 0–0.15 | s |

    ``filter="shoe"`` (bases: ``real-fixed``'s values):

    | Num | Knob | Base (real-fixed) | Span | Range | Unit |
    |-----|------|-------------------|------|-------|------|
    | 0 | γ, SHOE threshold (T_k < γ) | 2.25e7 | 100 | 2.25e5–2.25e9 | 1 |
    | 1 | SHOE window | 0.025 | 4 | 0.00625–0.1 | s |
    | 2 | process-noise scale | 0.03 | 100 | 3e-4–3 | 1 |
    | 3 | ZUPT measurement-noise scale | 3 | 100 | 0.03–300 | 1 |
    | 4 | minimum stance duration, as above | 0 | — | 0–0.15 | s |

    Actions outside [-1, 1] are clipped and counted (``info["clipped_actions"]``);
    wrong shapes, NaN or inf raise ``ValueError``.

    ## Observation Space
    ``Box(low, high, (16 + k,), float32)``, from the IMU and the filter only
    (never the truth); values are clipped to the bounds below.

    | Num | Observation | Min | Max | Unit |
    |-----|-------------|-----|-----|------|
    | 0 | mean \\|ω'\\| over the last interval | 0 | 50 | rad/s |
    | 1 | std of \\|ω'\\| | 0 | 50 | rad/s |
    | 2 | max \\|ω'\\| | 0 | 50 | rad/s |
    | 3 | mean \\|f'\\| − g | −20 | 200 | m/s² |
    | 4 | std of \\|f'\\| − g | 0 | 200 | m/s² |
    | 5 | max \\|\\|f'\\| − g\\| | 0 | 200 | m/s² |
    | 6 | fraction of the interval detected as stance | 0 | 1 | 1 |
    | 7 | stance starts detected in the interval | 0 | 50 | 1 |
    | 8 | moving average of detected stance durations | 0 | 20 | s |
    | 9 | time since the last accepted ZUPT | 0 | 200 | s |
    | 10 | log(1 + NIS) of the last ZUPT | 0 | 30 | 1 |
    | 11 | mean log(1 + NIS) of the interval's ZUPTs (0 if none) | 0 | 30 | 1 |
    | 12 | log₁₀ trace of the position covariance | −12 | 8 | log m² |
    | 13 | log₁₀ trace of the velocity covariance | −12 | 8 | log (m/s)² |
    | 14 | log₁₀ trace of the attitude covariance | −12 | 8 | log rad² |
    | 15 | fraction of ZUPTs rejected by the χ² gate | 0 | 1 | 1 |
    | 16… | the action in force (one entry per knob) | −1 | 1 | 1 |

    Right after reset, entries 0–5 describe the 1 s alignment window.

    ## Rewards
    ``−e · Δ / D`` per step: e is the horizontal position error (m) at the end
    of the interval, Δ the interval length and D the navigation duration of
    the walk; the return is minus the time-averaged horizontal error (m).
    ``info["reward_error"]`` carries that term.

    ## Starting State
    The walker stands for 1 s; the filter aligns on it (paper 003 eq 4:
    position 0, velocity 0, heading 0, pitch and roll from the accelerometers)
    and navigation starts at its end.

    ## Episode End
    - Truncation: the end of the walk.
    - Termination (divergence): a non-finite or runaway filter state (speed
      above 50 m/s), or horizontal error above 25 m + 25 % of the distance
      walked. The final error is then held for the rest of the walk in the
      last reward, so the return is still minus the time-averaged error and
      diverging never pays.

    ## Arguments
    ``gymnasium.make("pednav/FootZupt-v0", scenario=None, filter="paper",
    decision_interval_s=0.5, rate_hz=None, tune_min_stance=False, config=None,
    render_mode=None)``; ``scenario`` None is ``"random"`` for the paper family
    and ``"calibrated"`` for the shoe family, ``rate_hz`` None is 200 Hz in the
    calibrated scenario and 100 Hz otherwise; ``config`` is a full
    :class:`pednav_env.envs.foot_core.FootZuptConfig` (``filter`` then sets its
    ``filter_family`` and that family's filter at action 0).

    ## Vectorized environment
    ``gymnasium.make_vec("pednav/FootZupt-v0", num_envs=N,
    vectorization_mode="vector_entry_point")`` gives :class:`FootZuptVectorEnv`:
    all N walks step through one batched filter. Autoreset mode: SAME_STEP
    (the reset observation is returned at once; the last one is in
    ``info["final_obs"]``, its info in ``info["final_info"]``). Lane i of a
    vector env reset with seed s plays the same episodes, bit for bit, as
    this env reset with seed s + i.

    ## Info
    ``pos_true``, ``pos_est`` (m), ``error`` (m), ``distance`` walked (m),
    ``stance_detections`` and their split into ``true_stance_detections`` /
    ``false_stance_detections`` (against the simulated stances), ``zupts``,
    ``zupts_rejected``, ``clipped_actions``, ``covariance_repairs``,
    ``diverged``, ``reward_error``, ``imu_grade``, ``knobs`` (physical values),
    and ``context``: PRIVILEGED truth about the interval the next action
    governs, never in the observation — a float64 row ``(speed_band,
    imu_grade, speed_mps)`` (:data:`pednav_env.envs.foot_context.CONTEXT_FIELDS`;
    codes into ``SPEED_BANDS`` and ``CONTEXT_GRADES``), in every reset and step
    info (after an autoreset the new episode's).

    ## Example
    >>> import gymnasium as gym, numpy as np, pednav_env
    >>> env = gym.make("pednav/FootZupt-v0", scenario="paper")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape
    (20,)
    >>> obs, reward, terminated, truncated, info = env.step(np.zeros(4, np.float32))
    >>> bool(reward <= 0)
    True

    ## Version History
    - v0: initial version; filter families, the calibrated scenario and
      ``info["context"]`` added without changing the paper family's episodes.
    """

    env_id = ENV_ID
    core_cls = FootZuptCore
    config_cls = FootZuptConfig
    arguments = ("scenario", "filter", "decision_interval_s", "rate_hz", "tune_min_stance")
    track_dim = 3
    estimate_label = "ZUPT-UKF"

    def lane_info(self) -> dict[str, Any]:
        return {"imu_grade": self.core.grade[0], "context": self.core.context[0].copy()}


class FootZuptVectorEnv(FamilyFront, NativeVectorEnv):
    """Native vector version of :class:`FootZuptEnv` (see its docstring):
    one batched filter for all ``num_envs`` walks, SAME_STEP autoreset."""

    scalar_env = FootZuptEnv

    def lane_info(self) -> dict[str, np.ndarray]:
        return {
            "imu_grade": np.array(self.core.grade, dtype=object),
            "context": self.core.context.copy(),
        }


# ACTION_KNOBS / MIN_STANCE_MAX_S / OBS_FEATURES are re-exported for documentation tools.
__all__ = [
    "ACTION_KNOBS",
    "ENV_ID",
    "MIN_STANCE_MAX_S",
    "OBS_FEATURES",
    "FootZuptEnv",
    "FootZuptVectorEnv",
]
