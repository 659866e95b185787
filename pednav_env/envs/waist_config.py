"""Settings and spaces of ``pednav/WaistStep-v0``: knobs, observation features, configs.

- :data:`ACTION_KNOBS`: the five action components and their mapping to
  physical values (a = 0 is paper 004's configuration);
- :data:`OBS_FEATURES`: name and bounds of each observation entry;
- :class:`WaistRandomization`: the ranges of the random scenario (walk,
  belt ringing, grade scaling, leg-length calibration);
- :class:`WaistStepConfig`: the environment's settings (scenario, decision
  interval, sample rate, sensor grades, the filter at action 0, divergence).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.envs.spec import (
    EnvConfig,
    Knob,
    ObsFeature,
    require_choice,
    require_nonnegative,
    require_positive,
    require_probability,
    require_range,
    require_weights,
)
from pednav_env.gait.waist_walk import PAPER_STEP_PERIOD, PAPER_STEPS
from pednav_env.nav.step_fusion_kf import StepFusionConfig
from pednav_env.sensors.waist_grades import WAIST_GRADES

#: The five knobs, in action order. Paper 004 detects steps at the pure zero
#: crossing of |a| − g (threshold 0, no hysteresis, no minimum duration) and
#: uses σ_n = 0.5 m/s and Q = diag(σ_a², 0, σ_ε²) of its filter (the
#: :class:`StepFusionConfig` defaults); the scales multiply σ_n (R by its
#: square) and Q.
ACTION_KNOBS: tuple[Knob, ...] = (
    Knob("step_threshold", "linear", 0.0, 3.0, "m/s²"),
    Knob("step_hysteresis", "linear_positive", 0.0, 2.0, "m/s²"),
    Knob("min_step_duration", "linear_positive", 0.0, 0.5, "s"),
    Knob("bm_noise_scale", "log", 1.0, 10.0, "1"),
    Knob("process_noise_scale", "log", 1.0, 100.0, "1"),
)
ACTION_DIM = len(ACTION_KNOBS)

#: Observation entries; documented in the env docstring.
OBS_FEATURES: tuple[ObsFeature, ...] = (
    ObsFeature("accel_excess_mean", -20.0, 20.0, "m/s²"),
    ObsFeature("accel_excess_std", 0.0, 100.0, "m/s²"),
    ObsFeature("accel_excess_max", -20.0, 500.0, "m/s²"),
    ObsFeature("accel_excess_min", -20.0, 20.0, "m/s²"),
    ObsFeature("above_threshold_fraction", 0.0, 1.0, "1"),
    ObsFeature("steps_detected", 0.0, 50.0, "1"),
    ObsFeature("step_duration_last", 0.0, 60.0, "s"),
    ObsFeature("step_duration_avg", 0.0, 60.0, "s"),
    ObsFeature("time_since_step", 0.0, 600.0, "s"),
    ObsFeature("log_nis_last", 0.0, 30.0, "1"),
    ObsFeature("log_nis_interval", 0.0, 30.0, "1"),
    ObsFeature("innovation_east", -20.0, 20.0, "m/s"),
    ObsFeature("innovation_north", -20.0, 20.0, "m/s"),
    ObsFeature("sqrt_p_dv_east", 0.0, 50.0, "m/s"),
    ObsFeature("sqrt_p_dv_north", 0.0, 50.0, "m/s"),
    ObsFeature("log10_sqrt_p_tilt", -12.0, 2.0, "log rad"),
    ObsFeature("log10_sqrt_p_drift", -14.0, 0.0, "log rad/s"),
    ObsFeature("bm_velocity_last", -20.0, 50.0, "m/s"),
    ObsFeature("ins_speed_last", 0.0, 100.0, "m/s"),
    ObsFeature("hip_rise_last", 0.0, 2.0, "m"),
)

#: Entries of the privileged ``info["context"]`` (the episode's truth, never observed):
#: the sensor grade as its index in ``WaistStepConfig.sensor_grades``, the factors
#: on the grade's σ_a and σ_n, and the belt-ringing amplitude (m/s²).
CONTEXT_FIELDS: tuple[str, ...] = (
    "sensor_grade_index",
    "accel_noise_scale",
    "bm_noise_scale",
    "vibration_amplitude_mps2",
)


# --------------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class WaistRandomization:
    """Ranges of the random scenario (uniform unless said; our choices, SI units).

    Gait styles slow / normal / fast set, per bout, the step period T and the
    step length as a fraction of the leg length (L = 2 l cos φ_min, paper 000);
    each step then jitters both by ``step_jitter`` (relative std). The walk's
    fields are the :class:`pednav_env.gait.waist_walk.WalkRanges` of
    :func:`pednav_env.gait.waist_walk.walk_plan`.
    """

    duration_s: tuple[float, float] = (60.0, 180.0)
    leg_length_m: tuple[float, float] = (0.75, 1.0)
    #: Relative std of the filter's assumed leg length around the truth (calibration).
    leg_length_error: float = 0.02
    gait_weights: tuple[float, float, float] = (0.25, 0.5, 0.25)
    gait_step_period_s: tuple[tuple[float, float], ...] = ((0.6, 0.8), (0.5, 0.6), (0.42, 0.5))
    gait_step_ratio: tuple[tuple[float, float], ...] = ((0.55, 0.75), (0.75, 0.9), (0.9, 1.05))
    step_jitter: float = 0.03
    bout_steps: tuple[int, int] = (8, 50)
    initial_stand_s: tuple[float, float] = (0.5, 2.0)
    stop_probability: float = 0.35
    stop_duration_s: tuple[float, float] = (1.0, 8.0)
    slope_probability: float = 0.3
    slope_deg: tuple[float, float] = (2.0, 8.0)
    turn_probability: float = 0.06
    turn_deg: tuple[float, float] = (30.0, 120.0)
    heading_wander_deg: float = 2.0
    #: Heel-strike ringing of the belt IMU on the vertical axis:
    #: A exp(−τ/τ_d) sin(2π f τ) after each footfall; A log-uniform per episode,
    #: ×U(0.7, 1.3) per step.
    vibration_amplitude: tuple[float, float] = (0.3, 4.0)
    vibration_frequency_hz: tuple[float, float] = (12.0, 25.0)
    vibration_decay_s: tuple[float, float] = (0.02, 0.05)
    #: σ_a and σ_n of the grade are multiplied by log-uniform factors from this range.
    grade_scale: tuple[float, float] = (0.5, 2.0)

    def __post_init__(self) -> None:
        inf = math.inf
        for name, within in (
            ("duration_s", (1.0, inf)),
            ("leg_length_m", (0.2, 2.0)),
            ("initial_stand_s", (0.0, inf)),
            ("stop_duration_s", (0.0, inf)),
            ("slope_deg", (0.0, 30.0)),
            ("turn_deg", (0.0, 180.0)),
            ("vibration_amplitude", (0.0, inf)),
            ("vibration_frequency_hz", (0.0, inf)),
            ("vibration_decay_s", (1e-4, inf)),
            ("grade_scale", (1e-3, inf)),
        ):
            require_range(name, getattr(self, name), within=within)
        if self.vibration_amplitude[0] <= 0 and self.vibration_amplitude[1] > 0:
            raise ValueError("vibration_amplitude: log-uniform needs low > 0 (or (0, 0))")
        if len(self.gait_step_period_s) != 3 or len(self.gait_step_ratio) != 3:
            raise ValueError("gait_step_period_s and gait_step_ratio need 3 ranges each")
        for r in self.gait_step_period_s:
            require_range("gait_step_period_s", r, within=(0.1, 3.0))
        for r in self.gait_step_ratio:
            # L = 2 l cos φ_min < 2 l; keep φ_min > slope (pendulum validity)
            require_range("gait_step_ratio", r, within=(0.05, 1.6))
        require_weights("gait_weights", self.gait_weights, 3)
        if not (1 <= self.bout_steps[0] <= self.bout_steps[1]):
            raise ValueError(f"bout_steps must satisfy 1 ≤ low ≤ high, got {self.bout_steps!r}")
        for name in ("stop_probability", "slope_probability", "turn_probability"):
            require_probability(name, getattr(self, name))
        for name, most in (
            ("leg_length_error", 0.2),
            ("step_jitter", 0.2),
            ("heading_wander_deg", 36.0),
        ):
            value = getattr(self, name)
            require_nonnegative(name, value)
            if value > most:
                raise ValueError(f"{name} must be a small number <= {most}, got {value!r}")


@dataclass(frozen=True)
class WaistStepConfig(EnvConfig):
    """Settings of the waist environment (all lanes share them).

    ``scenario``: ``"random"`` (domain randomisation, :class:`WaistRandomization`)
    or ``"paper"`` (paper 004: l = 0.7 m, φ_min = 60°, T = 0.5 s, six legs at
    azimuths 30°, 90°, … (:func:`pednav_env.gait.waist_walk.route_azimuths`),
    ``paper_steps`` steps — 10 128 = 84.4 min by default — its INS error model
    with σ_a = 0.5 m/s and σ_n = 0.5 m/s, ideal accelerometer, exact leg length).
    """

    scenario: str = "random"
    decision_interval_s: float = 0.5  # ours, as every env's (docs/CONTRACTS.md)
    rate_hz: float = 100.0  # paper 000
    randomization: WaistRandomization = field(default_factory=WaistRandomization)
    sensor_grades: tuple[str, ...] = ("paper004", "tactical", "industrial", "consumer")
    sensor_grade_weights: tuple[float, ...] = (0.25, 0.25, 0.25, 0.25)
    #: Paper scenario: number of steps (paper 004: K = 10 128).
    paper_steps: int = PAPER_STEPS
    #: The filter at action 0: paper 004's (σ_a = 0.5, σ_ε = 1e-6, σ_n = 0.5, x̂(0)).
    filter: StepFusionConfig = field(default_factory=StepFusionConfig)
    g: float = STANDARD_GRAVITY
    #: Divergence: horizontal error beyond this + fraction × distance walked.
    divergence_error_m: float = 25.0
    divergence_error_fraction: float = 0.25

    def __post_init__(self) -> None:
        self.check_env_settings()
        if not isinstance(self.randomization, WaistRandomization):
            raise ValueError("randomization must be a WaistRandomization")
        if not isinstance(self.filter, StepFusionConfig):
            raise ValueError("filter must be a StepFusionConfig")
        for grade in self.sensor_grades:
            require_choice("sensor_grades", grade, tuple(sorted(WAIST_GRADES)))
        require_weights("sensor_grade_weights", self.sensor_grade_weights, len(self.sensor_grades))
        if not (isinstance(self.paper_steps, int | np.integer) and self.paper_steps >= 1):
            raise ValueError(f"paper_steps must be an integer ≥ 1, got {self.paper_steps!r}")
        require_positive("g", self.g)

    @property
    def action_dim(self) -> int:
        return ACTION_DIM

    @property
    def max_samples(self) -> int:
        """Capacity of the per-lane buffers (longest possible walk, samples)."""
        if self.scenario == "paper":
            return int(round(self.paper_steps * PAPER_STEP_PERIOD * self.rate_hz)) + 1
        return int(math.ceil(self.randomization.duration_s[1] * self.rate_hz)) + 2
