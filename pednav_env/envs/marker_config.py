"""Settings of ``pednav/MarkerTrack-v0`` (paper 001): knobs, scenarios, UWB conditions.

:data:`ACTION_KNOBS` are the filter settings the action sets.
:class:`MarkerTrackConfig` holds what every lane of the marker environment
shares: the scenario (``"random"`` domain randomisation or ``"paper"``), the
decision interval, the walk and sensor ranges drawn per episode, the filter at
action 0, the re-anchoring and the divergence bounds (the last two explained
in :mod:`pednav_env.envs.marker_core`). :func:`uwb_spec` gives the UWB model of
each episode condition of the random scenario.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

from pednav_env.envs.spec import (
    EnvConfig,
    Knob,
    require_nonnegative,
    require_positive,
    require_range,
    require_weights,
)
from pednav_env.gait.heel_knee import HeelKneeConfig
from pednav_env.gait.heel_knee_model import HeelKneeNominal
from pednav_env.nav.marker_model import MarkerEkfConfig
from pednav_env.sensors.uwb import UwbSpec

#: Knobs set by the action (log mapping, base · span ** a). The Q scales
#: multiply the diagonal of Γ Q Γᵀ (eqs 5.2, 5.4) of their parameter group, the
#: R scale the diagonal of R = σ² I (eq 5.5); base 1 is the thesis's filter.
ACTION_KNOBS: tuple[Knob, ...] = (
    Knob("q_amplitude_scale", "log", 1.0, 1000.0, "1"),
    Knob("q_trend_scale", "log", 1.0, 1000.0, "1"),
    Knob("q_cadence_scale", "log", 1.0, 1000.0, "1"),
    Knob("r_scale", "log", 1.0, 100.0, "1"),
)


def uwb_spec(condition: str, rate_hz: float, noise_factor: float = 1.0) -> UwbSpec:
    """The UWB model of one episode condition (random scenario).

    ``clean`` is the thesis's sensor (σ = 0.1 m, eq 5.5); ``noisy`` σ = 0.25 m;
    ``nlos`` frequent, long non-line-of-sight bursts (0.3 /s, 1.5 s, 30 % drops
    inside); ``outliers`` 5 % outliers of 1 m; ``dropouts`` 25 % dropped samples;
    ``realistic`` :meth:`UwbSpec.realistic`. ``noise_factor`` multiplies σ.
    These magnitudes are illustrative (ours), not fitted to a data set.
    """
    sigma = 0.1 * noise_factor
    return _condition_spec(condition, rate_hz).with_noise_std(
        2.5 * sigma if condition == "noisy" else sigma
    )


@functools.lru_cache(maxsize=64)
def _condition_spec(condition: str, rate_hz: float) -> UwbSpec:
    """The spec of a condition but its σ, built and checked once (per episode
    :func:`uwb_spec` only sets σ)."""
    if condition in ("clean", "noisy"):
        return UwbSpec(rate_hz=rate_hz)
    if condition == "nlos":
        return UwbSpec(
            rate_hz=rate_hz,
            nlos_start_rate_hz=0.3,
            nlos_mean_duration=1.5,
            nlos_drop_prob=0.3,
        )
    if condition == "outliers":
        return UwbSpec(rate_hz=rate_hz, outlier_prob=0.05)
    if condition == "dropouts":
        return UwbSpec(rate_hz=rate_hz, drop_prob=0.25)
    if condition == "realistic":
        return UwbSpec.realistic(rate_hz)
    raise ValueError(f"uwb_conditions: unknown condition {condition!r}; known: {UWB_CONDITIONS}")


#: Episode UWB conditions of the random scenario (see :func:`uwb_spec`).
UWB_CONDITIONS: tuple[str, ...] = ("clean", "noisy", "nlos", "outliers", "dropouts", "realistic")

#: Entries of the privileged ``info["context"]`` (the episode's truth, never observed):
#: the UWB condition as its index in ``MarkerTrackConfig.uwb_conditions`` (−1 in the
#: paper scenario) and the factor on its σ.
CONTEXT_FIELDS: tuple[str, ...] = ("uwb_condition_index", "uwb_noise_factor")


@dataclass(frozen=True)
class MarkerTrackConfig(EnvConfig):
    """Settings of the marker environment (all lanes share them).

    ``scenario``: ``"random"`` (domain randomisation) or ``"paper"`` (paper
    001's setup: eq 4.10 taken literally, 10 s walks, σ = 0.1 m, 10 Hz; the
    reproduction's headline scenario, docs/REPRODUCTION.md, paper 001).
    """

    scenario: str = "random"
    decision_interval_s: float = 0.5  # ours, as every env's (docs/CONTRACTS.md)
    rate_hz: float = 10.0  # ours: DecaWave TWR RTLS rate, as paper001
    #: Random scenario: walk duration range (s); ours, as the foot env's walks.
    duration_s: tuple[float, float] = (60.0, 180.0)
    #: Paper scenario: walk duration (s); the reproduction's 10 s.
    paper_duration_s: float = 10.0
    #: Random scenario truth: correlation time (s) of the parameter deviations
    #: (eq 4.11; the walker's own p = p⁰ + L(0) is drawn from the stationary law,
    #: 17 % std per parameter, thesis eq 5.4/5.8).
    truth_corr_time_s: float = 100.0
    #: Gait changes within a walk (Poisson rate, factor ranges; ours).
    gait_change_rate_hz: float = 1.0 / 20.0
    cadence_factor_range: tuple[float, float] = (0.85, 1.15)
    stride_factor_range: tuple[float, float] = (0.85, 1.15)
    #: UWB conditions drawn per episode and their weights (random scenario).
    uwb_conditions: tuple[str, ...] = UWB_CONDITIONS
    uwb_condition_weights: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0)
    #: Per-episode factor on the UWB σ, uniform in this range (random scenario).
    noise_factor_range: tuple[float, float] = (0.7, 1.5)
    #: The paper filter (the policy at action 0). None = MarkerEkfConfig with the
    #: sample period 1/rate_hz (thesis p⁰, 0.03, σ = 0.1 m; τ = 10⁴ s).
    filter: MarkerEkfConfig | None = None
    #: Time-origin re-anchoring (module docstring). None: 8 s in the random
    #: scenario, never (inf) in the paper scenario.
    reanchor_after_s: float | None = None
    reanchor_keep_s: float = 3.0
    #: Divergence / lock loss (module docstring).
    divergence_error_m: float = 1.0
    cadence_bounds: tuple[float, float] = (0.25, 4.0)

    def __post_init__(self) -> None:
        self.check_env_settings(sample="UWB sample")
        require_range("duration_s", self.duration_s, positive=True)
        if round(self.duration_s[0] * self.rate_hz) < 2:
            raise ValueError(
                f"duration_s must be (lo, hi) covering ≥ 2 samples, got {self.duration_s!r}"
            )
        p = self.paper_duration_s
        if not (isinstance(p, int | float) and math.isfinite(p) and round(p * self.rate_hz) >= 2):
            raise ValueError(f"paper_duration_s must cover ≥ 2 samples, got {p!r}")
        require_positive("truth_corr_time_s", self.truth_corr_time_s)
        require_nonnegative("gait_change_rate_hz", self.gait_change_rate_hz)
        for name in ("cadence_factor_range", "stride_factor_range", "noise_factor_range"):
            require_range(name, getattr(self, name), positive=True)
        if not self.uwb_conditions:
            raise ValueError("uwb_conditions must name at least one condition")
        for c in self.uwb_conditions:
            if c not in UWB_CONDITIONS:
                raise ValueError(
                    f"uwb_conditions: unknown condition {c!r}; known: {UWB_CONDITIONS}"
                )
        require_weights(
            "uwb_condition_weights", self.uwb_condition_weights, len(self.uwb_conditions)
        )
        if self.filter is None:
            object.__setattr__(self, "filter", MarkerEkfConfig(sample_period=1.0 / self.rate_hz))
        elif not isinstance(self.filter, MarkerEkfConfig):
            raise ValueError(f"filter must be a MarkerEkfConfig, got {self.filter!r}")
        if not math.isclose(self.filter.sample_period, 1.0 / self.rate_hz, rel_tol=1e-12):
            raise ValueError(
                f"filter.sample_period={self.filter.sample_period!r} must equal 1/rate_hz="
                f"{1.0 / self.rate_hz!r}"
            )
        if self.reanchor_after_s is None:
            after = 8.0 if self.scenario == "random" else math.inf
            object.__setattr__(self, "reanchor_after_s", after)
        a = self.reanchor_after_s
        k = self.reanchor_keep_s
        require_nonnegative("reanchor_keep_s", k)
        if not (isinstance(a, int | float) and not math.isnan(a) and a > k):
            raise ValueError(f"reanchor_after_s must be > reanchor_keep_s={k!r}, got {a!r}")
        require_range("cadence_bounds", self.cadence_bounds, positive=True)
        if not self.cadence_bounds[0] < 1.0 < self.cadence_bounds[1]:
            raise ValueError(
                f"cadence_bounds must be (lo, hi) with 0 < lo < 1 < hi, got {self.cadence_bounds!r}"
            )
        # build the models once so that their own checks name bad values now
        for c in self.uwb_conditions:
            uwb_spec(c, self.rate_hz, self.noise_factor_range[0])
            uwb_spec(c, self.rate_hz, self.noise_factor_range[1])
        self.truth_gait  # noqa: B018  (validates the truth model)

    @property
    def sample_period(self) -> float:
        """T = 1/rate (s)."""
        return 1.0 / self.rate_hz

    @property
    def action_dim(self) -> int:
        return len(ACTION_KNOBS)

    @property
    def max_samples(self) -> int:
        """Capacity of the per-lane buffers (longest possible walk)."""
        if self.scenario == "paper":
            return round(self.paper_duration_s * self.rate_hz)
        return round(self.duration_s[1] * self.rate_hz)

    @property
    def truth_gait(self) -> HeelKneeConfig:
        """Truth simulator of the scenario."""
        if self.scenario == "paper":
            return replace(HeelKneeConfig.paper(), sample_period=self.sample_period)
        return HeelKneeConfig(
            nominal=HeelKneeNominal(),
            sample_period=self.sample_period,
            param_corr_time=self.truth_corr_time_s,
            kinematics="integrated",
            initial_deviation="stationary",
            gait_change_rate_hz=self.gait_change_rate_hz,
            cadence_factor_range=tuple(self.cadence_factor_range),
            stride_factor_range=tuple(self.stride_factor_range),
        )
