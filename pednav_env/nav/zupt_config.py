"""Configuration of paper 003's ZUPT-UKF (:class:`pednav_env.nav.zupt_ukf.ZuptUkf`).

Defaults are paper 003's simulation. Choices the paper leaves open
(docs/REPRODUCTION.md):

- ZUPT noise R = diag(σ_h², σ_v², σ_v², σ_v²) · ``zupt_noise_scale`` with
  σ_h = σ_v = 0.01 (m, m/s), not printed;
- process noise Q from the filter's assumed IMU model ``assumed_imu``
  (:mod:`pednav_env.nav.zupt_model`), times ``process_noise_scale``;
- optional χ² gating of a ZUPT on its NIS (off in the paper scenario);
- ZUPTs at stance boundaries (the paper) or at every stance sample;
- the sigma points' angles by the direct formulas (every inverse-trigonometric
  and sincos call; paper 003's path) or, with ``angle_sums``, by the angle-sum
  and difference forms of :mod:`pednav_env.nav.sigma_angles` (the same filter,
  other rounding; the foot envs' shoe family, whose ZUPT at every stance sample
  makes these calls most of its cost).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.nav.detectors import DetectorConfig, ThresholdDetectorConfig
from pednav_env.nav.ukf import MerweWeights
from pednav_env.nav.zupt_model import STATE_DIM
from pednav_env.sensors.imu import ImuSpec


class UpdateMode(StrEnum):
    """When ZUPTs are applied."""

    #: At each detected stance start and stance end (paper 003).
    STANCE_BOUNDARIES = "stance_boundaries"
    #: At every sample of a detected stance (common practice, e.g. OpenShoe).
    EVERY_STANCE_SAMPLE = "every_stance_sample"


@dataclass(frozen=True)
class ZuptUkfConfig:
    """Configuration of the ZUPT-UKF; defaults = paper 003's simulation."""

    detector: DetectorConfig = field(default_factory=ThresholdDetectorConfig)
    #: The filter's assumed IMU model, source of Q (paper 003's sensor).
    assumed_imu: ImuSpec = field(default_factory=ImuSpec.paper003)
    alpha: float = 1e-3  # paper 003: a ~ 1e-3
    beta: float = 0.0  # paper 003 prints W0c = λ/(λ+L) + (1 − a²), i.e. β = 0
    kappa: float = 0.0  # paper 003: λ = a²L − L
    zupt_height_std: float = 0.01  # m, not printed
    zupt_velocity_std: float = 0.01  # m/s, not printed
    process_noise_scale: float = 1.0
    zupt_noise_scale: float = 1.0
    update_mode: UpdateMode = UpdateMode.STANCE_BOUNDARIES
    #: χ² gate probability for ZUPTs (None = no gate, paper 003).
    gate_probability: float | None = None
    initial_position_std: float = 1e-3  # m: the start position is known
    initial_velocity_std: float = 1e-2  # m/s: standing still
    initial_tilt_std: float = 1e-2  # rad: eq (4) from noisy data
    initial_yaw_std: float = 1e-3  # rad: ψ = 0 defines the frame
    #: Static alignment window at the start (s); paper 003 eq (4).
    alignment_s: float = 1.0
    #: Subtract the mean gyro reading of the alignment window from every later
    #: sample (paper 003's real-data calibration, "b_ω = ⟨ω''⟩ before walking").
    #: Off for the paper's simulation, whose drift changes every step.
    calibrate_gyro_bias: bool = False
    g: float = STANDARD_GRAVITY
    #: Sigma-point angles by angle-sum forms (:mod:`pednav_env.nav.sigma_angles`).
    angle_sums: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "update_mode", UpdateMode(self.update_mode))
        for name in (
            "alpha",
            "zupt_height_std",
            "zupt_velocity_std",
            "process_noise_scale",
            "zupt_noise_scale",
            "initial_position_std",
            "initial_velocity_std",
            "initial_tilt_std",
            "initial_yaw_std",
            "alignment_s",
            "g",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"ZuptUkfConfig.{name} must be a finite number > 0, got {v!r}")
        if not isinstance(self.angle_sums, bool):
            raise ValueError(
                f"ZuptUkfConfig.angle_sums must be True or False, got {self.angle_sums!r}"
            )
        if not math.isfinite(self.beta):
            raise ValueError(f"ZuptUkfConfig.beta must be finite, got {self.beta!r}")
        if self.gate_probability is not None and not (0 < self.gate_probability < 1):
            raise ValueError(
                f"ZuptUkfConfig.gate_probability must be in (0, 1), got {self.gate_probability!r}"
            )
        MerweWeights(STATE_DIM, self.alpha, self.beta, self.kappa)  # validates α, κ

    @property
    def weights(self) -> MerweWeights:
        return MerweWeights(STATE_DIM, self.alpha, self.beta, self.kappa)
