"""Batched episode engine behind ``pednav/WaistStep-v0`` (scalar and vector).

One implementation for any number of lanes: the scalar environment is this
core with N = 1, the native vector environment the same core with
N = ``num_envs``. Each lane owns its episode (walk, sensor record, seed); all
lanes step together through paper 004's step detector and step-fusion
Kalman filter (:func:`pednav_env.nav.waist_dr.detect_steps`,
:class:`pednav_env.nav.step_fusion_kf.StepFusionKF`) in one numpy call chain.

Episode (papers 000 and 004): a walker with a belt-level IMU walks a chain of
inverted-pendulum steps (:mod:`pednav_env.gait.pendulum`) with turns, stops,
slopes and gait changes. Sensors:

- the accelerometer, read as |f̃| (step detection on |f̃| − g, paper 004) and
  the vertical channel a_up = f̃_z − g (the level waist IMU of paper 000):
  the pendulum's interval-mean acceleration plus heel-strike ringing of the
  belt, white noise and a constant bias;
- the INS velocity V^INS = V + δV with δV from the Schuler error model of
  papers 000/004 (:mod:`pednav_env.sensors.ins_error`), held constant within a
  step (paper 004 eq 1);
- the INS yaw, taken error-free (paper 004 uses the known azimuth α(k)).

Navigation, per detected step k (boundaries j_{k−1} < j_k, T_k = (j_k − j_{k−1})Δt):
V̄^INS(k) from the INS displacement over the step; V̄^BM(k) = 2 sqrt(2 l h − h²)/T_k
from the doubly integrated a_up over the first half step (apex closure,
:func:`pednav_env.nav.waist_dr.biomechanical_step_velocity`) with the filter's
assumed leg length l, plus the walker's step-to-step irregularity n (paper
004: V̄^BM = V̄ + n); projected on the INS heading; then the filter's eqs (3)–(6).
Between boundaries the position estimate runs on the INS velocity corrected by
the extrapolated error, V^INS − HΦ(τ)x̂ (eq 5 over the open step), so that at
each boundary it equals eq (6).

A decision interval is ``decision_interval_s`` of sensor data (default 0.5 s,
50 samples at 100 Hz). The action sets the detector and filter knobs for the
next interval; a = 0 is paper 004's configuration (:data:`ACTION_KNOBS`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.gait.pendulum import PendulumSteps, simulate_walk
from pednav_env.nav.step_fusion_kf import (
    H_DV,
    StepFusionConfig,
    StepFusionKF,
    kf_predict,
    kf_update,
    repair_covariance,
)
from pednav_env.nav.waist_dr import (
    StepDetectorConfig,
    StepDetectorState,
    _prefix_integrals,
    detect_steps,
)
from pednav_env.reproduce.paper004 import PAPER_STEPS, route_azimuths
from pednav_env.sensors.ins_error import (
    CHANNEL_SIGN,
    SchulerErrorConfig,
    per_sample_velocity_error,
    schuler_transition,
    simulate_schuler_errors,
)

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Knob:
    """One action component: ``a`` ∈ [−1, 1] → physical value.

    ``mapping="log"``: ``base · span ** a`` (docs/CONTRACTS.md). ``"linear"``:
    ``span · a``; ``"linear_positive"``: ``span · max(a, 0)`` (a ≤ 0 keeps the
    paper's 0, as the foot env's minimum-stance knob). In every case a = 0 gives
    paper 004's value.
    """

    name: str
    mapping: str
    base: float
    span: float
    unit: str

    def value(self, a: Array) -> Array:
        if self.mapping == "log":
            return self.base * self.span**a
        if self.mapping == "linear":
            return self.base + self.span * a
        return self.base + self.span * np.maximum(a, 0.0)


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

#: Observation entries: (name, low, high); documented in the env docstring.
OBS_FEATURES: tuple[tuple[str, float, float], ...] = (
    ("accel_excess_mean", -20.0, 20.0),
    ("accel_excess_std", 0.0, 100.0),
    ("accel_excess_max", -20.0, 500.0),
    ("accel_excess_min", -20.0, 20.0),
    ("above_threshold_fraction", 0.0, 1.0),
    ("steps_detected", 0.0, 50.0),
    ("step_duration_last", 0.0, 60.0),
    ("step_duration_avg", 0.0, 60.0),
    ("time_since_step", 0.0, 600.0),
    ("log_nis_last", 0.0, 30.0),
    ("log_nis_interval", 0.0, 30.0),
    ("innovation_east", -20.0, 20.0),
    ("innovation_north", -20.0, 20.0),
    ("sqrt_p_dv_east", 0.0, 50.0),
    ("sqrt_p_dv_north", 0.0, 50.0),
    ("log10_sqrt_p_tilt", -12.0, 2.0),
    ("log10_sqrt_p_drift", -14.0, 0.0),
    ("bm_velocity_last", -20.0, 50.0),
    ("ins_speed_last", 0.0, 100.0),
    ("hip_rise_last", 0.0, 2.0),
)


# --------------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class WaistSensorGrade:
    """True sensor errors of one grade (the filter does not know them).

    Attributes
    ----------
    accel_noise_std : float
        White noise of each accelerometer axis per sample (m/s²).
    accel_bias_std : float
        Std of the constant accelerometer bias per axis, drawn per episode (m/s²).
    ins_accel_noise_std : float
        σ_a of the Schuler error model, std of the δV increment per step (m/s);
        paper 004: 0.1, 0.5, 1.
    ins_drift_noise_std : float
        σ_ε, std of the drift increment per step (rad/s); paper 004: 1e-6.
    ins_initial_std : tuple
        Std of the initial δV (m/s), β (rad), ε (rad/s); paper 004 prints none,
        our reading (0.3 m/s, 1 mrad, 0.1 °/h) as in :class:`SchulerErrorConfig`.
    ins_bias_std : float
        Std of paper 000's constant B (m/s²) in δV̇, drawn per episode.
    bm_noise_std : float
        Std of the step-to-step irregularity n of the pendulum step velocity
        (paper 004: V̄^BM = V̄ + n, σ_n = 0.5 m/s).
    """

    accel_noise_std: float
    accel_bias_std: float
    ins_accel_noise_std: float
    ins_drift_noise_std: float
    ins_initial_std: tuple[float, float, float]
    ins_bias_std: float
    bm_noise_std: float

    def __post_init__(self) -> None:
        for name in (
            "accel_noise_std",
            "accel_bias_std",
            "ins_accel_noise_std",
            "ins_drift_noise_std",
            "ins_bias_std",
            "bm_noise_std",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ValueError(f"WaistSensorGrade.{name} must be a finite number ≥ 0, got {v!r}")
        s = self.ins_initial_std
        if len(s) != 3 or not all(math.isfinite(x) and x >= 0 for x in s):
            raise ValueError(f"WaistSensorGrade.ins_initial_std needs 3 values ≥ 0, got {s!r}")


_DRIFT_DPH = math.radians(1.0) / 3600.0  # 1 °/h in rad/s

#: Named grades. ``paper004``: paper 004's simulation (ideal accelerometer, its
#: INS error model with σ_a = 0.5 m/s, σ_n = 0.5 m/s). The others are
#: illustrative belt-IMU/INS classes (our choice, not from a paper).
WAIST_GRADES: dict[str, WaistSensorGrade] = {
    "paper004": WaistSensorGrade(0.0, 0.0, 0.5, 1e-6, (0.3, 1e-3, 0.1 * _DRIFT_DPH), 0.0, 0.5),
    "tactical": WaistSensorGrade(
        0.005, 0.002, 0.05, 1e-7, (0.05, 2e-4, 0.01 * _DRIFT_DPH), 0.002, 0.08
    ),
    "industrial": WaistSensorGrade(
        0.02, 0.01, 0.2, 1e-6, (0.2, 1e-3, 0.1 * _DRIFT_DPH), 0.01, 0.15
    ),
    "consumer": WaistSensorGrade(0.08, 0.05, 0.8, 1e-5, (0.3, 3e-3, 1.0 * _DRIFT_DPH), 0.05, 0.3),
}


def _check_range(name: str, r: tuple[float, float], lo: float, hi: float = math.inf) -> None:
    if len(r) != 2 or not all(isinstance(x, int | float) and math.isfinite(x) for x in r):
        raise ValueError(f"{name} must be a (low, high) pair of finite numbers, got {r!r}")
    if not (lo <= r[0] <= r[1] <= hi):
        raise ValueError(f"{name} must satisfy {lo} ≤ low ≤ high ≤ {hi}, got {r!r}")


@dataclass(frozen=True)
class WaistRandomization:
    """Ranges of the random scenario (uniform unless said; our choices, SI units).

    Gait styles slow / normal / fast set, per bout, the step period T and the
    step length as a fraction of the leg length (L = 2 l cos φ_min, paper 000);
    each step then jitters both by ``step_jitter`` (relative std).
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
        _check_range("duration_s", self.duration_s, 1.0)
        _check_range("leg_length_m", self.leg_length_m, 0.2, 2.0)
        _check_range("initial_stand_s", self.initial_stand_s, 0.0)
        _check_range("stop_duration_s", self.stop_duration_s, 0.0)
        _check_range("slope_deg", self.slope_deg, 0.0, 30.0)
        _check_range("turn_deg", self.turn_deg, 0.0, 180.0)
        _check_range("vibration_amplitude", self.vibration_amplitude, 0.0)
        _check_range("vibration_frequency_hz", self.vibration_frequency_hz, 0.0)
        _check_range("vibration_decay_s", self.vibration_decay_s, 1e-4)
        _check_range("grade_scale", self.grade_scale, 1e-3)
        if self.vibration_amplitude[0] <= 0 and self.vibration_amplitude[1] > 0:
            raise ValueError("vibration_amplitude: log-uniform needs low > 0 (or (0, 0))")
        if len(self.gait_step_period_s) != 3 or len(self.gait_step_ratio) != 3:
            raise ValueError("gait_step_period_s and gait_step_ratio need 3 ranges each")
        for r in self.gait_step_period_s:
            _check_range("gait_step_period_s", r, 0.1, 3.0)
        for r in self.gait_step_ratio:
            # L = 2 l cos φ_min < 2 l; keep φ_min > slope (pendulum validity)
            _check_range("gait_step_ratio", r, 0.05, 1.6)
        w = np.asarray(self.gait_weights, dtype=float)
        if w.shape != (3,) or np.any(w < 0) or w.sum() <= 0:
            raise ValueError(f"gait_weights invalid: {self.gait_weights!r}")
        if not (1 <= self.bout_steps[0] <= self.bout_steps[1]):
            raise ValueError(f"bout_steps must satisfy 1 ≤ low ≤ high, got {self.bout_steps!r}")
        for name in ("stop_probability", "slope_probability", "turn_probability"):
            p = getattr(self, name)
            if not (0.0 <= p <= 1.0):
                raise ValueError(f"{name} must lie in [0, 1], got {p!r}")
        for name in ("leg_length_error", "step_jitter", "heading_wander_deg"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 <= v <= 0.2 * (180.0 if "deg" in name else 1.0)):
                raise ValueError(f"{name} must be a small number ≥ 0, got {v!r}")


@dataclass(frozen=True)
class WaistStepConfig:
    """Settings of the waist environment (all lanes share them).

    ``scenario``: ``"random"`` (domain randomisation, :class:`WaistRandomization`)
    or ``"paper"`` (paper 004: l = 0.7 m, φ_min = 60°, T = 0.5 s, six legs at
    azimuths 30°, 90°, … as in :mod:`pednav_env.reproduce.paper004`,
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
        if self.scenario not in ("random", "paper"):
            raise ValueError(f"scenario must be 'random' or 'paper', got {self.scenario!r}")
        if not (isinstance(self.rate_hz, int | float) and math.isfinite(self.rate_hz)):
            raise ValueError(f"rate_hz must be a finite number > 0, got {self.rate_hz!r}")
        if self.rate_hz <= 0:
            raise ValueError(f"rate_hz must be > 0, got {self.rate_hz!r}")
        dis = self.decision_interval_s
        if not (isinstance(dis, int | float) and math.isfinite(dis) and dis > 0):
            raise ValueError(f"decision_interval_s must be > 0, got {dis!r}")
        if round(dis * self.rate_hz) < 1:
            raise ValueError(f"decision_interval_s={dis!r} is shorter than one sample")
        if not isinstance(self.randomization, WaistRandomization):
            raise ValueError("randomization must be a WaistRandomization")
        if not isinstance(self.filter, StepFusionConfig):
            raise ValueError("filter must be a StepFusionConfig")
        for g in self.sensor_grades:
            if g not in WAIST_GRADES:
                raise ValueError(
                    f"sensor_grades: unknown grade {g!r}; known: {sorted(WAIST_GRADES)}"
                )
        w = np.asarray(self.sensor_grade_weights, dtype=float)
        if w.shape != (len(self.sensor_grades),) or np.any(w < 0) or w.sum() <= 0:
            raise ValueError(f"sensor_grade_weights invalid: {self.sensor_grade_weights!r}")
        if not (isinstance(self.paper_steps, int | np.integer) and self.paper_steps >= 1):
            raise ValueError(f"paper_steps must be an integer ≥ 1, got {self.paper_steps!r}")
        if not (math.isfinite(self.g) and self.g > 0):
            raise ValueError(f"g must be > 0, got {self.g!r}")
        if not (self.divergence_error_m > 0 and self.divergence_error_fraction >= 0):
            raise ValueError("divergence_error_m must be > 0 and divergence_error_fraction ≥ 0")

    @property
    def interval_samples(self) -> int:
        return int(round(self.decision_interval_s * self.rate_hz))

    @property
    def action_dim(self) -> int:
        return ACTION_DIM

    @property
    def max_samples(self) -> int:
        """Capacity of the per-lane buffers (longest possible walk, samples)."""
        if self.scenario == "paper":
            return int(round(self.paper_steps * PAPER_STEP_PERIOD * self.rate_hz)) + 1
        return int(math.ceil(self.randomization.duration_s[1] * self.rate_hz)) + 2


#: A detected boundary within this time of a simulated footfall, start or stop
#: counts as a true detection (info only).
TRUE_DETECTION_WINDOW_S = 0.03

#: Paper 004's test walker (paper 000's check): l, φ_min, T.
PAPER_LEG_LENGTH = 0.7
PAPER_PHI_MIN = math.pi / 3
PAPER_STEP_PERIOD = 0.5


# --------------------------------------------------------------------------- episodes
@dataclass
class Episode:
    """One lane's walk: sensor record (what the filter sees) and truth.

    Per-sample arrays have length L (sample 0 is the start, t = 0).
    """

    f_norm: Array  #: |f̃| (m/s²)
    a_up: Array  #: f̃_z − g, vertical acceleration of the level waist IMU (m/s²)
    ins_pos: Array  #: (L, 2) INS horizontal position relative to the start (m)
    yaw: Array  #: INS heading ψ (rad, counter-clockwise from east)
    bm_noise: Array  #: n of the error segment containing each sample (m/s)
    pos_n: Array  #: (L, 2) true horizontal hip position relative to the start (m)
    distance_m: Array  #: (L,) horizontal distance walked (m)
    true_boundary: NDArray[np.bool_]  #: (L,) footfall / start / stop samples
    leg_length: float  #: true l (m)
    leg_length_assumed: float  #: the filter's l (m)
    sensor_grade: str


def _walk_plan(
    rng: np.random.Generator, r: WaistRandomization, duration: float, leg: float
) -> tuple[Array, Array, Array, Array, float, list[tuple[int, float]]]:
    """Per-step T, L, slope and heading of the whole walk, the initial stand (s) and
    the stops as (index of the step after which the walker stops, duration s)."""
    T_parts, L_parts, a_parts, h_parts = [], [], [], []
    stops: list[tuple[int, float]] = []
    heading = rng.uniform(-math.pi, math.pi)
    initial_stand = rng.uniform(*r.initial_stand_s)
    t = initial_stand
    steps = 0
    w = np.asarray(r.gait_weights, dtype=float)
    w = w / w.sum()
    while t < duration:
        gait = int(rng.choice(3, p=w))
        n = int(rng.integers(r.bout_steps[0], r.bout_steps[1] + 1))
        T0 = rng.uniform(*r.gait_step_period_s[gait])
        ratio = rng.uniform(*r.gait_step_ratio[gait])
        slope = 0.0
        if rng.random() < r.slope_probability:
            slope = math.radians(rng.uniform(*r.slope_deg)) * (1.0 if rng.random() < 0.5 else -1.0)
        jit = np.minimum(np.maximum(1.0 + rng.standard_normal((2, n)) * r.step_jitter, 0.8), 1.2)
        turn = rng.random(n) < r.turn_probability
        turn_deg = rng.uniform(*r.turn_deg, n) * np.where(rng.random(n) < 0.5, 1.0, -1.0)
        wander = rng.standard_normal(n) * r.heading_wander_deg
        dpsi = np.radians(wander + np.where(turn, turn_deg, 0.0))
        T_parts.append(T0 * jit[0])
        L_parts.append(ratio * leg * jit[1])
        a_parts.append(np.full(n, slope))
        h_parts.append(heading + np.cumsum(dpsi))
        heading = float(h_parts[-1][-1])
        t += float(T_parts[-1].sum())
        steps += n
        if rng.random() < r.stop_probability:
            stop_s = rng.uniform(*r.stop_duration_s)
            stops.append((steps - 1, stop_s))
            t += stop_s
    return (
        np.concatenate(T_parts),
        np.concatenate(L_parts),
        np.concatenate(a_parts),
        np.concatenate(h_parts),
        initial_stand,
        stops,
    )


def _assemble_walk(
    leg: float,
    T: Array,
    L: Array,
    slope: Array,
    heading: Array,
    initial_stand_s: float,
    stops: list[tuple[int, float]],
    rate: float,
    n_total: int,
) -> dict[str, Array]:
    """One pendulum chain (paper 000) with stands spliced in, on one sample grid.

    The chain is simulated without stops; a stand of duration D after step k
    begins at the first sample after that footfall, holds that hip position
    (velocity 0) for round(D·rate) samples, and the chain then resumes (the
    velocity jump at resumption is the start footfall). Returns the per-sample
    hip position, velocity and yaw, the error-segment index (steps and stands,
    in time order) and each segment's duration (s).
    """
    steps = PendulumSteps.from_step_length(L[None], leg, T[None], slope[None], heading[None])
    bounds = steps.step_start[0]
    src_parts: list[NDArray[np.int64]] = []
    stand_parts: list[NDArray[np.bool_]] = []
    m0 = int(round(initial_stand_s * rate))
    src_parts.append(np.zeros(m0, dtype=np.int64))
    stand_parts.append(np.ones(m0, dtype=bool))
    have, orig = m0, 0
    for k, dur in stops:
        if have >= n_total:
            break
        j = int(math.ceil(bounds[k + 1] * rate - 1e-9))  # first sample after the footfall
        src_parts += [np.arange(orig, j), np.full(int(round(dur * rate)), j)]
        stand_parts += [np.zeros(j - orig, dtype=bool), np.ones(int(round(dur * rate)), dtype=bool)]
        have += j - orig + int(round(dur * rate))
        orig = j
    rest = max(n_total - have, 0)
    src_parts.append(np.arange(orig, orig + rest))
    stand_parts.append(np.zeros(rest, dtype=bool))
    src = np.concatenate(src_parts)[:n_total]
    stand = np.concatenate(stand_parts)[:n_total]
    walk = simulate_walk(steps, rate, n_samples=int(src.max()) + 1)
    pos = walk.pos_n[0, src]
    pos -= pos[0]
    vel = np.where(stand[:, None], 0.0, walk.vel_n[0, src])
    # Segments in time order: step k → 2k, a stand before step k → 2k − 1,
    # standing after the last step → 2K.
    step_idx = walk.step_index[0, src]
    key = 2 * step_idx - stand.astype(np.int64)
    key[stand & (step_idx == T.size)] = 2 * T.size
    change = np.flatnonzero(key[1:] != key[:-1]) + 1  # keys never decrease
    seg = np.zeros(key.size, dtype=np.int64)
    seg[change] = 1
    np.cumsum(seg, out=seg)
    keys = key[np.concatenate(([0], change))]
    counts = np.diff(np.concatenate(([0], change, [key.size])))
    is_step = (keys % 2 == 0) & (keys < 2 * T.size)
    periods = np.where(is_step, T[np.minimum(keys // 2, T.size - 1)], counts / rate)
    return {"pos": pos, "vel": vel, "yaw": walk.euler[0, src, 0], "seg": seg, "periods": periods}


def generate_episode(config: WaistStepConfig, rng: np.random.Generator) -> Episode:
    """Draw one episode from ``rng`` (fixed draw order: walk, grade, sensor errors)."""
    rate = float(config.rate_hz)
    dt = 1.0 / rate
    g = config.g
    if config.scenario == "paper":
        K = int(config.paper_steps)
        leg = leg_assumed = PAPER_LEG_LENGTH
        az = route_azimuths(K)  # from north, clockwise → yaw from east, counter-clockwise
        heading = 0.5 * math.pi - az
        T = np.full(K, PAPER_STEP_PERIOD)
        L = np.full(K, 2.0 * leg * math.cos(PAPER_PHI_MIN))
        n_total = config.max_samples
        walk = _assemble_walk(leg, T, L, np.zeros(K), heading, 0.0, [], rate, n_total)
        grade_name = "paper004"
        grade = WAIST_GRADES[grade_name]
        sigma_a, sigma_n = grade.ins_accel_noise_std, grade.bm_noise_std
        vib_amp = 0.0
        vib_f = vib_tau = 1.0
        ins_bias = 0.0
    else:
        r = config.randomization
        duration = rng.uniform(*r.duration_s)
        n_total = int(round(duration * rate)) + 1
        leg = rng.uniform(*r.leg_length_m)
        T, L, slope, heading, initial, stops = _walk_plan(rng, r, duration, leg)
        walk = _assemble_walk(leg, T, L, slope, heading, initial, stops, rate, n_total)
        w = np.asarray(config.sensor_grade_weights, dtype=float)
        grade_name = config.sensor_grades[int(rng.choice(len(w), p=w / w.sum()))]
        grade = WAIST_GRADES[grade_name]
        lo, hi = np.log(r.grade_scale)
        sigma_a = grade.ins_accel_noise_std * math.exp(rng.uniform(lo, hi))
        sigma_n = grade.bm_noise_std * math.exp(rng.uniform(lo, hi))
        err = float(np.clip(rng.standard_normal() * r.leg_length_error, -0.06, 0.06))
        leg_assumed = leg * (1.0 + err)
        a_lo, a_hi = r.vibration_amplitude
        vib_amp = math.exp(rng.uniform(math.log(a_lo), math.log(a_hi))) if a_hi > 0 else 0.0
        vib_f = rng.uniform(*r.vibration_frequency_hz)
        vib_tau = rng.uniform(*r.vibration_decay_s)
        ins_bias = rng.standard_normal() * grade.ins_bias_std
    pos, vel, psi, seg = walk["pos"], walk["vel"], walk["yaw"], walk["seg"]
    n = pos.shape[0]
    # Footfalls (step starts), walk starts and stops: where the error segment changes.
    boundary = np.zeros(n, dtype=bool)
    boundary[1:] = seg[1:] != seg[:-1]
    # IMU: interval-mean acceleration (delta-velocity), level body axes rotated by yaw.
    acc = np.zeros((n, 3))
    acc[1:] = np.diff(vel, axis=0) * rate
    c, s = np.cos(psi), np.sin(psi)
    f_b = np.empty((n, 3))
    f_b[:, 0] = c * acc[:, 0] + s * acc[:, 1]
    f_b[:, 1] = -s * acc[:, 0] + c * acc[:, 1]
    f_b[:, 2] = acc[:, 2] + g
    n_seg = int(walk["periods"].size)
    if vib_amp > 0:
        amp = vib_amp * rng.uniform(0.7, 1.3, n_seg)
        idx = np.arange(n)
        last = np.maximum.accumulate(np.where(boundary, idx, 0))
        tau = (idx - last) * dt
        ring = amp[seg] * np.exp(-tau / vib_tau) * np.sin(2.0 * math.pi * vib_f * tau)
        f_b[:, 2] += np.where(last > 0, ring, 0.0)
    if grade.accel_bias_std > 0:
        f_b += rng.standard_normal(3) * grade.accel_bias_std
    if grade.accel_noise_std > 0:
        f_b += rng.standard_normal((n, 3)) * grade.accel_noise_std
    # INS velocity error per error segment (paper 004), constant within a segment.
    i0 = grade.ins_initial_std
    schuler = SchulerErrorConfig(
        accel_noise_std=sigma_a,
        drift_noise_std=grade.ins_drift_noise_std,
        initial_velocity_std=i0[0],
        initial_tilt_std=i0[1],
        initial_drift_std=i0[2],
        accel_bias=ins_bias,
        g=g,
        earth_radius=config.filter.earth_radius,
    )
    x = simulate_schuler_errors(walk["periods"][None], schuler, [rng])
    dv = per_sample_velocity_error(x, seg[None])[0]  # (n, 2)
    bm_noise = rng.standard_normal(n_seg) * sigma_n
    ins = np.zeros((n, 2))
    ins[1:] = np.cumsum(np.diff(pos[:, :2], axis=0) + dv[1:] * dt, axis=0)
    step_len = np.hypot(*np.diff(pos[:, :2], axis=0).T)
    return Episode(
        f_norm=np.sqrt(np.sum(f_b * f_b, axis=-1)),
        a_up=f_b[:, 2] - g,
        ins_pos=ins,
        yaw=psi,
        bm_noise=bm_noise[seg],
        pos_n=pos[:, :2] - pos[0, :2],
        distance_m=np.concatenate(([0.0], np.cumsum(step_len))),
        true_boundary=boundary,
        leg_length=float(leg),
        leg_length_assumed=float(leg_assumed),
        sensor_grade=grade_name,
    )


def prefix_integrals(a_up: Array, dt: float) -> tuple[Array, Array]:
    """Running integrals C1, C2 of a_up (rule ``delta_v``: IMU interval means).

    The same prefix sums :func:`pednav_env.nav.waist_dr.biomechanical_step_velocity`
    builds; computed once per episode here so that each detected step costs O(1).
    """
    return _prefix_integrals(a_up, dt, "delta_v")


def pendulum_step_velocity(
    c1: Array,
    c2: Array,
    lane: NDArray[np.integer],
    j0: NDArray[np.integer],
    n: NDArray[np.integer],
    leg: Array,
    dt: float,
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """V̄^BM = 2 sqrt(2 l h − h²)/T for steps starting at samples ``j0`` (papers 000/004).

    Evaluates :func:`pednav_env.nav.waist_dr.biomechanical_step_velocity`
    (apex closure V_up(T/2) = 0, rule ``delta_v``, level ground) from prefix
    integrals: h = V_up(0)·T/2 + ∫₀^{T/2}∫₀^t a_up over the first n/2 sample
    intervals (odd n: the last half interval interpolated within the sample).

    Parameters
    ----------
    c1, c2 : (N, L) prefix integrals of every lane (:func:`prefix_integrals`)
    lane : (M,) lane of each step
    j0 : (M,) first sample of each step
    n : (M,) samples in the step (≥ 1), T = n Δt
    leg : (M,) assumed leg length l (m)
    dt : float

    Returns
    -------
    velocity (M,) m/s, hip_rise (M,) m (clipped to [0, l]), clipped (M,) bool
    """
    jm = j0 + n // 2
    jn = np.minimum(jm + 1, c1.shape[-1] - 1)
    theta = 0.5 * (n % 2)
    c1s, c1m, c1n = c1[lane, j0], c1[lane, jm], c1[lane, jn]
    # ∫_{j0}^{jm} a and ∫_{j0}^{jm}∫_{j0}^{t} a from the prefix integrals
    single = c1m - c1s
    double = (c2[lane, jm] - c2[lane, j0]) - c1s * (jm - j0) * dt
    c1_half = c1m + theta * (c1n - c1m)
    single = single + (c1_half - c1m)
    double = double + theta * dt * (0.5 * (c1m + c1_half) - c1s)
    T = n * dt
    h = -single * (0.5 * T) + double
    clipped = (h < 0) | (h > leg)
    h = np.clip(h, 0.0, leg)
    return 2.0 * np.sqrt(2.0 * leg * h - h * h) / T, h, clipped


# --------------------------------------------------------------------------- the core
class WaistStepCore:
    """N lanes of the waist environment stepping together."""

    def __init__(self, config: WaistStepConfig, num_envs: int, env_name: str) -> None:
        if not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer ≥ 1, got {num_envs!r}")
        self.config = config
        self.n = n = int(num_envs)
        self.env_name = env_name
        self.k = config.interval_samples
        self.dt = 1.0 / config.rate_hz
        self.cap = cap = config.max_samples + self.k + 1
        self.grid_cap = (cap - 1) // self.k + 2
        self.kf = StepFusionKF(config.filter, n)
        self.det_cfg = StepDetectorConfig(g=config.g)
        # Per-lane episode buffers (padding: standing still, no new information).
        self.f_norm = np.full((n, cap), config.g)
        self.c1 = np.zeros((n, cap))
        self.c2 = np.zeros((n, cap))
        self.ins = np.zeros((n, cap, 2))
        self.yaw = np.zeros((n, cap))
        self.bm_noise = np.zeros((n, cap))
        self.near_true = np.zeros((n, cap), dtype=bool)
        self.truth_grid = np.zeros((n, self.grid_cap, 2))
        self.dist_grid = np.zeros((n, self.grid_cap))
        self.length = np.ones(n, dtype=np.int64)  # samples L
        self.cursor = np.zeros(n, dtype=np.int64)  # last sample processed
        self.intervals = np.zeros(n, dtype=np.int64)
        self.leg = np.ones(n)
        self.leg_true = np.ones(n)
        self.grade = ["" for _ in range(n)]
        # Detector, filter-side state and knobs.
        self.det_armed = np.zeros(n, dtype=bool)
        self.det_since = np.full(n, np.inf)
        self.last_b = np.zeros(n, dtype=np.int64)  # sample of the last step boundary
        self.action = np.zeros((n, ACTION_DIM))
        self.knobs = np.zeros((n, ACTION_DIM))
        self.clipped = np.zeros(n, dtype=np.int64)
        self.step_last_s = np.zeros(n)
        self.step_avg_s = np.zeros(n)
        self.nis_last = np.zeros(n)
        self.bm_last = np.zeros(n)
        self.ins_speed_last = np.zeros(n)
        self.h_last = np.zeros(n)
        self.last_est = np.zeros((n, 2))
        self.last_error = np.zeros(n)
        self.lanes = np.arange(n)
        self.ar_k = np.arange(self.k)
        self.obs = np.zeros((n, len(OBS_FEATURES) + ACTION_DIM), dtype=np.float32)
        self.obs_low = np.array(
            [lo for _, lo, _ in OBS_FEATURES] + [-1.0] * ACTION_DIM, dtype=np.float32
        )
        self.obs_high = np.array(
            [hi for _, _, hi in OBS_FEATURES] + [1.0] * ACTION_DIM, dtype=np.float32
        )

    # ------------------------------------------------------------------ reset
    def reset_lanes(self, lanes: NDArray[np.integer], rngs: list[np.random.Generator]) -> None:
        """Start new episodes in ``lanes``, each drawn from its own generator."""
        lanes = np.asarray(lanes, dtype=np.int64)
        c = self.config
        for lane, rng in zip(lanes, rngs, strict=True):
            ep = generate_episode(c, rng)
            L = ep.f_norm.shape[0]
            pad = slice(L, min(L + self.k + 1, self.cap))  # the only padding ever read
            self.f_norm[lane, :L] = ep.f_norm
            self.f_norm[lane, pad] = c.g
            c1, c2 = prefix_integrals(ep.a_up, self.dt)
            self.c1[lane, :L], self.c2[lane, :L] = c1, c2
            self.c1[lane, pad], self.c2[lane, pad] = c1[-1], c2[-1]
            self.ins[lane, :L] = ep.ins_pos
            self.ins[lane, pad] = ep.ins_pos[-1]
            self.yaw[lane, :L] = ep.yaw
            self.yaw[lane, pad] = ep.yaw[-1]
            self.bm_noise[lane, :L] = ep.bm_noise
            self.bm_noise[lane, pad] = 0.0
            # A detection counts as true within ±0.03 s of a footfall / start / stop.
            tb = ep.true_boundary.astype(np.int64)
            w = max(1, int(round(TRUE_DETECTION_WINDOW_S * c.rate_hz)))
            cs = np.concatenate(([0], np.cumsum(tb)))
            i = np.arange(L)
            self.near_true[lane, :L] = cs[np.minimum(i + w + 1, L)] - cs[np.maximum(i - w, 0)] > 0
            self.near_true[lane, pad] = False
            grid = np.minimum(np.arange(self.grid_cap) * self.k, L - 1)
            self.truth_grid[lane] = ep.pos_n[grid]
            self.dist_grid[lane] = ep.distance_m[grid]
            self.length[lane] = L
            self.leg[lane] = ep.leg_length_assumed
            self.leg_true[lane] = ep.leg_length
            self.grade[lane] = ep.sensor_grade
        kf, fc = self.kf, c.filter
        kf.x[lanes] = np.asarray(fc.initial_estimate)
        kf.P[lanes] = fc.P0
        kf.pos[lanes] = 0.0
        kf.x_prior[lanes] = kf.x[lanes]
        kf.P_prior[lanes] = kf.P[lanes]
        kf.y[lanes] = 0.0
        kf.S[lanes] = 0.0
        kf.K[lanes] = 0.0
        kf.repairs[lanes] = 0
        kf.steps[lanes] = 0
        kf.diverged[lanes] = False
        self.det_armed[lanes] = False
        self.det_since[lanes] = np.inf
        self.last_b[lanes] = 0
        self.cursor[lanes] = 0
        self.intervals[lanes] = 0
        self.action[lanes] = 0.0
        self.clipped[lanes] = 0
        for arr in (self.step_last_s, self.step_avg_s, self.nis_last, self.bm_last):
            arr[lanes] = 0.0
        self.ins_speed_last[lanes] = 0.0
        self.h_last[lanes] = 0.0
        self.last_est[lanes] = 0.0
        self.last_error[lanes] = 0.0
        self._apply_action(lanes)
        self.obs[lanes] = self._features(lanes, None)

    # ------------------------------------------------------------------ action
    def validate_action(self, action: Any) -> Array:
        """Shape ``(N, 5)`` and finiteness check; returns float64."""
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"{self.env_name}: action is not numeric: {action!r}") from None
        want = (self.n, ACTION_DIM)
        if a.shape != want:
            raise ValueError(f"{self.env_name}: actions must have shape {want}, got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{self.env_name}: action contains NaN or inf: {a.tolist()}")
        return a

    def _apply_action(self, lanes: NDArray[np.integer]) -> None:
        a = self.action[lanes]
        for i, knob in enumerate(ACTION_KNOBS):
            self.knobs[lanes, i] = knob.value(a[:, i])

    def knob_values(self) -> dict[str, Array]:
        """Current physical value of every knob, per lane."""
        return {knob.name: self.knobs[:, i].copy() for i, knob in enumerate(ACTION_KNOBS)}

    # ------------------------------------------------------------------ filter
    def _filter_update(
        self,
        sel: NDArray[np.int64],
        v_ins: Array,
        vb: Array,
        T: Array,
        F: Array,
        Q: Array,
        R: Array,
    ) -> Array:
        """One step update (paper 004 eqs 3–6) in lanes ``sel``; returns log(1 + NIS).

        The operations of :meth:`StepFusionKF.step` (Φ from
        :func:`schuler_transition`, the engine's :func:`kf_predict`,
        :func:`kf_update`, :func:`repair_covariance`) on the subset's rows only —
        the same numbers, bit for bit (tested), without the masked work on the
        other lanes. ``F``, ``Q``, ``R`` are Φ(T), Q·q_scale and R·r_scale."""
        kf = self.kf
        c = kf.config
        x_prior, P_prior = kf_predict(kf.x[sel], kf.P[sel], F, Q)
        vbar_corr = v_ins - x_prior[..., 0]  # eq (5)
        z = (v_ins - vb)[..., None]  # eq (3)
        x_post, P_post, y, S, _ = kf_update(x_prior, P_prior, z, H_DV, R)
        P_post, repaired = repair_covariance(P_post, c.repair_tol, c.eig_floor)
        ok = np.all(np.isfinite(x_post), axis=(1, 2)) & np.all(np.isfinite(P_post), axis=(1, 2, 3))
        kf.x[sel], kf.P[sel] = x_post, P_post
        y, S = y[..., 0], S[..., 0, 0]
        kf.y[sel], kf.S[sel] = y, S  # (priors and gains are not kept: the env never reads them)
        kf.pos[sel] = kf.pos[sel] + T[:, None] * vbar_corr  # eq (6)
        kf.repairs[sel] += np.any(repaired, axis=1)
        kf.steps[sel] += 1
        kf.diverged[sel] |= ~ok
        nis = np.sum(y * y / S, axis=1)
        return np.log1p(np.where(np.isfinite(nis), nis, 1e12))

    def _close_steps(self, boundary: NDArray[np.bool_], first: NDArray[np.int64]) -> Array:
        """Process the interval's step boundaries: the measurements of all detected
        steps at once, then the filter updates in order (round j = every lane's
        j-th boundary). Returns the sum of log(1 + NIS) per lane."""
        n, dt = self.n, self.dt
        counts = boundary.sum(axis=1)
        nis_sum = np.zeros(n)
        if not counts.any():
            return nis_sum
        lane_e, pos_e = np.nonzero(boundary)  # events sorted by lane, then time
        j1 = first[lane_e] + pos_e
        start = np.cumsum(counts) - counts  # index of each lane's first event
        rank = np.arange(lane_e.size) - start[lane_e]
        j0 = np.empty_like(j1)
        j0[1:] = j1[:-1]
        j0 = np.where(rank == 0, self.last_b[lane_e], j0)
        nk = j1 - j0
        T = nk * dt
        v_ins = (self.ins[lane_e, j1] - self.ins[lane_e, j0]) / T[:, None]
        v_bm, h, _ = pendulum_step_velocity(self.c1, self.c2, lane_e, j0, nk, self.leg[lane_e], dt)
        v_bm = v_bm + self.bm_noise[lane_e, (j0 + j1) // 2]
        psi = self.yaw[lane_e, j1]
        vb = v_bm[:, None] * np.stack((np.cos(psi), np.sin(psi)), axis=1)
        fc = self.kf.config
        F = schuler_transition(T[:, None], fc.g, fc.earth_radius, CHANNEL_SIGN[None, :])
        Q = fc.Q * self.knobs[lane_e, 4][:, None, None, None]
        R = fc.R * (self.knobs[lane_e, 3] ** 2)[:, None, None, None]
        for j in range(int(counts.max())):
            sel = np.flatnonzero(counts > j)
            e = start[sel] + j
            log_nis = self._filter_update(sel, v_ins[e], vb[e], T[e], F[e], Q[e], R[e])
            nis_sum[sel] += log_nis
            self.nis_last[sel] = log_nis
            prev = self.step_avg_s[sel]
            self.step_avg_s[sel] = np.where(prev > 0, 0.8 * prev + 0.2 * T[e], T[e])
        has = np.flatnonzero(counts)
        e = start[has] + counts[has] - 1  # each lane's last event
        self.last_b[has] = j1[e]
        self.step_last_s[has] = T[e]
        self.bm_last[has] = v_bm[e]
        self.ins_speed_last[has] = np.hypot(v_ins[e, 0], v_ins[e, 1])
        self.h_last[has] = h[e]
        return nis_sum

    def position_estimate(self, at: NDArray[np.int64]) -> Array:
        """Horizontal position estimate at sample ``at`` (≥ the last boundary), (N, 2).

        Ê(last boundary) plus the INS displacement since, corrected by the
        extrapolated error HΦ(τ)x̂ = δV̂ − s g τ β̂ per channel (eqs 5–6 over the
        open step, τ = time since the boundary)."""
        kf = self.kf
        tau = (at - self.last_b) * self.dt
        corr = kf.x[:, :, 0] - CHANNEL_SIGN * kf.config.g * tau[:, None] * kf.x[:, :, 1]
        disp = self.ins[self.lanes, at] - self.ins[self.lanes, self.last_b]
        return kf.pos + disp - tau[:, None] * corr

    # ------------------------------------------------------------------ step
    def step(self, action: Any) -> tuple[Array, Array, NDArray[np.bool_], NDArray[np.bool_], dict]:
        """Advance every lane by one decision interval."""
        a = self.validate_action(action)
        self.clipped += np.any(np.abs(a) > 1.0, axis=1)
        self.action = np.clip(a, -1.0, 1.0)
        self._apply_action(self.lanes)
        n, k = self.n, self.k
        used = np.clip(self.length - 1 - self.cursor, 0, k)
        first = self.cursor + 1  # samples first … first + k − 1
        idx = first[:, None] + self.ar_k[None, :]
        fn = self.f_norm[self.lanes[:, None], idx]
        chunk = np.zeros((n, k, 3))
        chunk[..., 0] = fn
        state = StepDetectorState(self.det_armed, self.det_since)
        boundary, state = detect_steps(
            chunk,
            self.dt,
            self.det_cfg,
            state,
            threshold=self.knobs[:, 0],
            hysteresis=self.knobs[:, 1],
            min_step_duration=self.knobs[:, 2],
        )
        self.det_armed, self.det_since = state.armed, state.since_last
        inside = self.ar_k[None, :] < used[:, None]
        boundary &= inside
        counts = boundary.sum(axis=1)
        true_det = (boundary & self.near_true[self.lanes[:, None], idx]).sum(axis=1)
        updates0 = self.kf.steps.copy()
        nis_sum = self._close_steps(boundary, first)
        self.cursor += used
        self.intervals += used > 0
        est = self.position_estimate(self.cursor)
        ok = np.all(np.isfinite(est), axis=1)
        est = np.where(ok[:, None], est, self.last_est)
        self.last_est = est
        grid = self.intervals
        truth = self.truth_grid[self.lanes, grid]
        err = np.hypot(est[:, 0] - truth[:, 0], est[:, 1] - truth[:, 1])
        dist = self.dist_grid[self.lanes, grid]
        c = self.config
        bound = c.divergence_error_m + c.divergence_error_fraction * dist
        terminated = self.kf.diverged | ~ok | (err > bound)
        truncated = (self.cursor >= self.length - 1) & ~terminated
        nav = np.maximum(self.length - 1, 1)
        weight = used / nav
        # On divergence the final error is held for the rest of the walk, so that
        # stopping early never pays: the return stays minus the time-average.
        tail = np.maximum(self.length - 1 - self.cursor, 0) / nav
        reward = -err * (weight + np.where(terminated, tail, 0.0))
        self.last_error = err
        updates = self.kf.steps - updates0
        interval = {
            "fn": fn,
            "used": used,
            "counts": counts,
            "nis_mean": np.where(updates > 0, nis_sum / np.maximum(updates, 1), 0.0),
        }
        self.obs = self._features(self.lanes, interval)
        info = {
            "pos_true": truth.copy(),
            "pos_est": est.copy(),
            "error": err,
            "distance": dist.copy(),
            "step_detections": counts,
            "true_step_detections": true_det,
            "false_step_detections": counts - true_det,
            "filter_updates": updates,
            "clipped_actions": self.clipped.copy(),
            "covariance_repairs": self.kf.repairs.copy(),
            "diverged": self.kf.diverged | ~ok,
            "reward_error": -err * weight,
        }
        return self.obs.copy(), reward, terminated, truncated, info

    # ------------------------------------------------------------------ observation
    def _features(self, lanes: NDArray[np.integer], interval: dict | None) -> NDArray[np.float32]:
        b = len(lanes)
        out = np.zeros((b, len(OBS_FEATURES)))
        g = self.config.g
        if interval is not None:
            x = interval["fn"] - g
            used = interval["used"]
            if np.all(used == self.k):
                out[:, 0] = x.mean(1)
                out[:, 1] = x.std(1)
                out[:, 2] = x.max(1)
                out[:, 3] = x.min(1)
                out[:, 4] = (x >= self.knobs[:, 0:1]).mean(1)
            else:
                mask = self.ar_k[None, :] < np.maximum(used, 1)[:, None]
                cnt = mask.sum(1)
                mean = np.where(mask, x, 0.0).sum(1) / cnt
                out[:, 0] = mean
                out[:, 1] = np.sqrt(np.where(mask, (x - mean[:, None]) ** 2, 0.0).sum(1) / cnt)
                out[:, 2] = np.where(mask, x, -np.inf).max(1)
                out[:, 3] = np.where(mask, x, np.inf).min(1)
                out[:, 4] = (mask & (x >= self.knobs[:, 0:1])).sum(1) / cnt
            out[:, 5] = interval["counts"]
            out[:, 10] = interval["nis_mean"]
        kf = self.kf
        out[:, 6] = self.step_last_s[lanes]
        out[:, 7] = self.step_avg_s[lanes]
        out[:, 8] = (self.cursor[lanes] - self.last_b[lanes]) * self.dt
        out[:, 9] = self.nis_last[lanes]
        out[:, 11:13] = kf.y[lanes]
        P = kf.P[lanes]
        out[:, 13:15] = np.sqrt(np.maximum(P[:, :, 0, 0], 0.0))
        out[:, 15] = 0.5 * np.log10(np.maximum(P[:, :, 1, 1].max(1), 1e-30))
        out[:, 16] = 0.5 * np.log10(np.maximum(P[:, :, 2, 2].max(1), 1e-30))
        out[:, 17] = self.bm_last[lanes]
        out[:, 18] = self.ins_speed_last[lanes]
        out[:, 19] = self.h_last[lanes]
        obs = np.concatenate((out, self.action[lanes]), axis=1)
        obs = np.where(np.isfinite(obs), obs, self.obs_high)
        return np.clip(obs, self.obs_low, self.obs_high).astype(np.float32)
