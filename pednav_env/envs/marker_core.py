"""Batched episode engine behind ``pednav/MarkerTrack-v0`` (scalar and vector).

One implementation for any number of lanes: the scalar environment is this
core with N = 1, the native vector environment the same core with
N = ``num_envs``. Each lane owns its episode (walk, UWB record, seed); all
lanes step through the marker EKF of paper 001 together, one UWB sample at a
time, in one numpy call chain through the one marker filter of the package,
:class:`pednav_env.nav.marker_ekf.MarkerEkfEngine` (which also serves the
paper-001 reproduction), repaired once per decision interval.

Episode: a walk of the heel–knee model (thesis eqs 4.1–4.11,
:mod:`pednav_env.gait.heel_knee`) seen by a UWB sensor
(:mod:`pednav_env.sensors.uwb`), both drawn from the lane's generator. A
decision interval is ``decision_interval_s`` of UWB data (default 0.5 s =
5 samples at 10 Hz). The action sets the filter's knobs for the next interval
as ``base · span ** a`` (log scale; a = 0 is the paper's EKF).

Two things the thesis does not need for its 10 s walks are handled here:

- **Time origin (kT term).** The EKF's model (eq 4.10) multiplies the rate
  parameters by the elapsed time kT, so in a long walk the Jacobian columns of
  Δc_x and Δω (eq 5.3) grow without bound and a gait change can no longer be
  followed. The engine therefore writes the model about a per-lane anchor
  (t_a, X_a): x₁ = X_a + c_x (t − t_a) + A_x sin(ω (t − t_a)), the other
  coordinates likewise (eq 4.10 with kT → t − t_a). Once t − t_a exceeds
  ``reanchor_after_s`` (end of a decision interval), the anchor moves to the
  latest time t_a' ≤ t − ``reanchor_keep_s`` at which the estimated phase
  ω̂ (t − t_a) is a whole number of cycles, and X_a' = X_a + ĉ_x (t_a' − t_a).
  For the current estimate this is an exact reparametrisation — the
  estimated marker tracks are unchanged at every time — but the rate
  parameters now pivot about t_a': the position and phase uncertainty
  accumulated before t_a' is dropped (the paper's 6-state has no place for
  it). The paper scenario never re-anchors (its walks are the thesis's 10 s).
- **Lock loss.** The thesis's EKF can lock onto another cycle of the gait
  harmonic or lose the trend (docs/REPRODUCTION_001.md, mechanism E); it
  does not recover. A lane terminates (divergence) when its state or
  covariance is not finite, when its cadence estimate ω̂ = ω₀ + Δω̂ leaves
  ``cadence_bounds`` × ω₀, or when the interval's RMS marker error exceeds
  ``divergence_error_m`` (lock loss).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from pednav_env.gait.heel_knee import (
    I_CX,
    I_OMEGA,
    HeelKneeConfig,
    HeelKneeNominal,
    simulate_heel_knee,
)
from pednav_env.nav.marker_ekf import DIM_X, DIM_Z, MarkerEkfConfig, MarkerEkfEngine
from pednav_env.sensors.uwb import UwbSpec, measure_uwb

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Knobs set by the action: (name, paper base value, span, unit). The Q scales
#: multiply the diagonal of Γ Q Γᵀ (eqs 5.2, 5.4) of their parameter group, the
#: R scale the diagonal of R = σ² I (eq 5.5); base 1 is the thesis's filter.
ACTION_KNOBS: tuple[tuple[str, float, float, str], ...] = (
    ("q_amplitude_scale", 1.0, 1000.0, "1"),
    ("q_trend_scale", 1.0, 1000.0, "1"),
    ("q_cadence_scale", 1.0, 1000.0, "1"),
    ("r_scale", 1.0, 100.0, "1"),
)
#: Q group (index into ACTION_KNOBS) of each state component, eq 4.9 order
#: [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω]: amplitudes, trend, cadence.
Q_GROUP: tuple[int, ...] = (0, 0, 1, 1, 0, 2)
#: Coordinates of a marker record, in the order of eq 4.12.
COORDS: tuple[str, ...] = ("heel_x", "heel_z", "knee_x", "knee_z")
_PARAMS = ("A_x", "A_z", "c_x", "c_z", "A", "omega")

#: Observation entries: (name, low, high); documented in the env docstring.
OBS_FEATURES: tuple[tuple[str, float, float], ...] = (
    ("dropped_fraction", 0.0, 1.0),
    ("log_nis_mean", 0.0, 30.0),
    ("log_nis_max", 0.0, 30.0),
    ("nis_gate_fraction", 0.0, 1.0),
    *((f"nu_rms_{c}", 0.0, 100.0) for c in COORDS),
    *((f"nu_mean_{c}", -100.0, 100.0) for c in COORDS),
    *((f"log10_rel_std_{p}", -8.0, 4.0) for p in _PARAMS),
    *((f"rel_dev_{p}", -10.0, 10.0) for p in _PARAMS),
    ("time_since_anchor", 0.0, 3600.0),
)

#: Error (× ``divergence_error_m``) booked for a lane whose estimate is not finite.
NONFINITE_ERROR_FACTOR = 10.0

#: χ² 99 % quantiles of the NIS by degrees of freedom (valid coordinates 0–4).
CHI2_99 = np.array([np.inf, *chi2.ppf(0.99, [1, 2, 3, 4])])


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


def _is_range(v: Any, positive: bool = True) -> bool:
    try:
        lo, hi = (float(x) for x in v)
    except (TypeError, ValueError):
        return False
    ok = math.isfinite(lo) and math.isfinite(hi) and lo <= hi
    return ok and (lo > 0 if positive else True)


@dataclass(frozen=True)
class MarkerTrackConfig:
    """Settings of the marker environment (all lanes share them).

    ``scenario``: ``"random"`` (domain randomisation) or ``"paper"`` (paper
    001's setup: eq 4.10 taken literally, 10 s walks, σ = 0.1 m, 10 Hz; the
    reproduction's headline scenario, docs/REPRODUCTION_001.md).
    """

    scenario: str = "random"
    decision_interval_s: float = 0.5  # DESIGN.md default
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
        if self.scenario not in ("random", "paper"):
            raise ValueError(f"scenario must be 'random' or 'paper', got {self.scenario!r}")
        if not (isinstance(self.rate_hz, int | float) and math.isfinite(self.rate_hz)):
            raise ValueError(f"rate_hz must be > 0, got {self.rate_hz!r}")
        if self.rate_hz <= 0:
            raise ValueError(f"rate_hz must be > 0, got {self.rate_hz!r}")
        d = self.decision_interval_s
        if not (isinstance(d, int | float) and math.isfinite(d) and d > 0):
            raise ValueError(f"decision_interval_s must be > 0, got {d!r}")
        if round(d * self.rate_hz) < 1:
            raise ValueError(f"decision_interval_s={d!r} is shorter than one UWB sample")
        if not _is_range(self.duration_s) or round(self.duration_s[0] * self.rate_hz) < 2:
            raise ValueError(
                f"duration_s must be (lo, hi) covering ≥ 2 samples, got {self.duration_s!r}"
            )
        p = self.paper_duration_s
        if not (isinstance(p, int | float) and math.isfinite(p) and round(p * self.rate_hz) >= 2):
            raise ValueError(f"paper_duration_s must cover ≥ 2 samples, got {p!r}")
        t = self.truth_corr_time_s
        if not (isinstance(t, int | float) and math.isfinite(t) and t > 0):
            raise ValueError(f"truth_corr_time_s must be > 0, got {t!r}")
        g = self.gait_change_rate_hz
        if not (isinstance(g, int | float) and math.isfinite(g) and g >= 0):
            raise ValueError(f"gait_change_rate_hz must be ≥ 0, got {g!r}")
        for name in ("cadence_factor_range", "stride_factor_range", "noise_factor_range"):
            if not _is_range(getattr(self, name)):
                raise ValueError(
                    f"{name} must be (lo, hi) with 0 < lo ≤ hi, got {getattr(self, name)!r}"
                )
        if not self.uwb_conditions:
            raise ValueError("uwb_conditions must name at least one condition")
        for c in self.uwb_conditions:
            if c not in UWB_CONDITIONS:
                raise ValueError(
                    f"uwb_conditions: unknown condition {c!r}; known: {UWB_CONDITIONS}"
                )
        w = np.asarray(self.uwb_condition_weights, dtype=float)
        if (
            w.shape != (len(self.uwb_conditions),)
            or not np.all(np.isfinite(w))
            or np.any(w < 0)
            or w.sum() <= 0
        ):
            raise ValueError(f"uwb_condition_weights invalid: {self.uwb_condition_weights!r}")
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
        if not (isinstance(k, int | float) and math.isfinite(k) and k >= 0):
            raise ValueError(f"reanchor_keep_s must be ≥ 0, got {k!r}")
        if not (isinstance(a, int | float) and not math.isnan(a) and a > k):
            raise ValueError(f"reanchor_after_s must be > reanchor_keep_s={k!r}, got {a!r}")
        e = self.divergence_error_m
        if not (isinstance(e, int | float) and math.isfinite(e) and e > 0):
            raise ValueError(f"divergence_error_m must be > 0, got {e!r}")
        if (
            not _is_range(self.cadence_bounds)
            or not self.cadence_bounds[0] < 1.0 < self.cadence_bounds[1]
        ):
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
    def interval_samples(self) -> int:
        return int(round(self.decision_interval_s * self.rate_hz))

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


# --------------------------------------------------------------------------- episodes


@dataclass
class Episode:
    """One lane's walk: UWB record and the truth used for reward and info."""

    z: Array  # (K, 4) reports [heel x, heel z, knee x, knee z] (m)
    valid: BoolArray  # (K, 2) per marker
    truth: Array  # (K, 4) true positions (m)
    uwb_condition: str


@functools.lru_cache(maxsize=16)
def _condition_cdf(weights: tuple[float, ...]) -> Array:
    """Cumulative UWB condition weights, normalised (computed once per weights)."""
    return np.cumsum(weights) / np.sum(weights)


def generate_episode(
    config: MarkerTrackConfig, rng: np.random.Generator, gait: HeelKneeConfig | None = None
) -> Episode:
    """Draw one episode from ``rng``.

    Draw order (random scenario): duration, UWB condition (one uniform against
    the cumulative weights), σ factor, the walk
    (:func:`simulate_heel_knee`), the UWB errors
    (:func:`~pednav_env.sensors.uwb.measure_uwb`).
    Paper scenario: the walk and the UWB noise only. ``gait`` may pass
    ``config.truth_gait`` precomputed.
    """
    gait = gait or config.truth_gait
    rate = config.rate_hz
    if config.scenario == "paper":
        k = round(config.paper_duration_s * rate)
        condition = "paper"
        spec = UwbSpec.paper(rate)
    else:
        k = max(2, round(rng.uniform(*config.duration_s) * rate))
        cdf = _condition_cdf(tuple(config.uwb_condition_weights))
        pick = min(int(np.searchsorted(cdf, rng.random(), side="right")), len(cdf) - 1)
        condition = config.uwb_conditions[pick]
        spec = uwb_spec(condition, rate, rng.uniform(*config.noise_factor_range))
    walk = simulate_heel_knee(gait, k, [rng])
    markers = walk.markers[0]
    uwb = measure_uwb(spec, markers[None], [rng])
    return Episode(uwb.z[0].reshape(k, DIM_Z), uwb.valid[0], markers.reshape(k, DIM_Z), condition)


# --------------------------------------------------------------------------- filter engine


class Engine(Protocol):
    """What the core needs from a batched marker filter (lane axis last):
    :class:`~pednav_env.nav.marker_ekf.MarkerEkfEngine`, or the benchmark's
    filterpy reference (``pednav_env.testing.reference_marker.FilterpyMarkerEngine``)."""

    x: Array  # (6, N)
    P: Array  # (6, 6, N)
    q: Array  # (6, N) diagonal of Γ Q Γᵀ in force
    r: Array  # (4, N) diagonal of R in force
    t_anchor: Array  # (N,)
    x_anchor: Array  # (N,)
    repairs: NDArray[np.int64]

    def reset(self, lanes: NDArray[np.integer]) -> None: ...
    def predict(self) -> None: ...
    def update(self, z: Array, valid: BoolArray, t: Array) -> Array: ...
    def markers(self, t: Array, x: Array | None = None) -> Array: ...
    def repair(self) -> BoolArray: ...


EngineFactory = Callable[[MarkerEkfConfig, int], Engine]


def _sum_in_order(a: Array) -> Array:
    """Σ over the first axis, added strictly in order (the same numbers for any
    lane count; numpy's pairwise reductions may associate differently)."""
    out = a[0].copy()
    for row in a[1:]:
        out += row
    return out


# --------------------------------------------------------------------------- episode core


class MarkerTrackCore:
    """N lanes of the marker environment stepping together.

    ``engine_factory`` builds the filter (default
    :class:`~pednav_env.nav.marker_ekf.MarkerEkfEngine`);
    the benchmark's reference passes a filterpy-backed one.
    """

    def __init__(
        self,
        config: MarkerTrackConfig,
        num_envs: int,
        env_name: str,
        engine_factory: EngineFactory | None = None,
    ) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be ≥ 1, got {num_envs!r}")
        self.config = config
        self.n = n = int(num_envs)
        self.env_name = env_name
        self.k = config.interval_samples
        self.T = config.sample_period
        self.gait = config.truth_gait
        self.engine: Engine = (engine_factory or MarkerEkfEngine)(config.filter, n)
        # Episode data live in circular buffers over global sample time, (N, C, 4):
        # lane i's episode starts at global sample ep_start[i], and every step all
        # lanes read the same k slots — a plain slice, no gather. C is a multiple
        # of k (an interval never wraps) and holds the longest walk plus k.
        self.C = -(-(config.max_samples + self.k) // self.k) * self.k
        self.zbuf = np.zeros((n, self.C, DIM_Z))
        self.vbuf = np.zeros((n, self.C, DIM_Z), dtype=bool)
        self.tbuf = np.zeros((n, self.C, DIM_Z))
        self.g = 0  # global sample index of the next step's first sample
        self.ep_start = np.zeros(n, dtype=np.int64)
        self.x_start = np.zeros(n)  # heel x at the episode's first sample
        self.length = np.ones(n, dtype=np.int64)
        self.cursor = np.zeros(n, dtype=np.int64)
        self.distance = np.zeros(n)
        self.condition = np.full(n, "", dtype=object)
        self.action = np.zeros((n, config.action_dim))
        self.clipped = np.zeros(n, dtype=np.int64)
        self.reanchors = np.zeros(n, dtype=np.int64)
        self.last_error = np.zeros(n)
        self.lanes = np.arange(n)
        self.obs_low = np.array(
            [lo for _, lo, _ in OBS_FEATURES] + [-1.0] * config.action_dim, dtype=np.float32
        )
        self.obs_high = np.array(
            [hi for _, _, hi in OBS_FEATURES] + [1.0] * config.action_dim, dtype=np.float32
        )
        self.obs = np.zeros((n, len(OBS_FEATURES) + config.action_dim), dtype=np.float32)
        self._obs_low64 = self.obs_low.astype(np.float64)[:, None]
        self._obs_high64 = self.obs_high.astype(np.float64)[:, None]
        self._prior_obs: NDArray[np.float32] | None = None
        self._abs_p0 = np.abs(config.filter.nominal.vector)[:, None]
        self._log10_abs_p0 = np.log10(self._abs_p0)
        self._qgroup = np.asarray(Q_GROUP)
        self._knob_base = np.array([base for _, base, _, _ in ACTION_KNOBS])
        self._knob_log_span = np.log([span for _, _, span, _ in ACTION_KNOBS])
        # q and r of action 0 (what _apply_action sets for a lane after reset)
        rest = self._knob_base * np.exp(np.zeros(config.action_dim) * self._knob_log_span)
        self._q_rest = self.engine.q0 * rest[self._qgroup]
        self._r_rest = self.engine.r0 * rest[3]
        self._scale_buf = np.empty((config.action_dim, n))
        #: The last interval, (k, 4, N): estimates, truth, innovations, validity.
        self.interval_est = np.zeros((self.k, DIM_Z, n))
        self.interval_truth = np.zeros((self.k, DIM_Z, n))
        self.interval_active = np.zeros((self.k, n), dtype=bool)

    # ------------------------------------------------------------------ reset
    def reset_lanes(self, lanes: NDArray[np.integer], rngs: list[np.random.Generator]) -> None:
        """Start new episodes in ``lanes``, each drawn from its own generator."""
        lanes = np.asarray(lanes, dtype=np.int64)
        g0 = self.g % self.C
        for lane, rng in zip(lanes, rngs, strict=True):
            ep = generate_episode(self.config, rng, self.gait)
            t = ep.z.shape[0]
            head = min(t, self.C - g0)  # the walk wraps around the buffer's end
            for buf, data in (
                (self.zbuf, ep.z),
                (self.vbuf, np.repeat(ep.valid, 2, axis=1)),  # per marker → per coordinate
                (self.tbuf, ep.truth),
            ):
                buf[lane, g0 : g0 + head] = data[:head]
                if head < t:
                    buf[lane, : t - head] = data[head:]
            self.x_start[lane] = ep.truth[0, 0]
            self.length[lane] = t
            self.condition[lane] = ep.uwb_condition
        self.engine.reset(lanes)
        self.ep_start[lanes] = self.g
        self.cursor[lanes] = 0
        self.distance[lanes] = 0.0
        self.action[lanes] = 0.0
        self.clipped[lanes] = 0
        self.reanchors[lanes] = 0
        self.last_error[lanes] = 0.0
        self.engine.q[:, lanes] = self._q_rest[:, None]  # _apply_action(lanes) at action 0
        self.engine.r[:, lanes] = self._r_rest
        if self._prior_obs is None:  # the same for every lane: no data, prior P, action 0
            self._prior_obs = self._features(lanes[:1], None)[0]
        self.obs[lanes] = self._prior_obs

    # ------------------------------------------------------------------ action
    def validate_action(self, action: Any) -> Array:
        """Shape ``(N, k)`` and finiteness check; returns float64."""
        a = np.asarray(action, dtype=np.float64)
        want = (self.n, self.config.action_dim)
        if a.shape != want:
            raise ValueError(f"{self.env_name}: actions must have shape {want}, got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{self.env_name}: action contains NaN or inf: {a.tolist()}")
        return a

    def _scales(self, lanes: NDArray[np.integer] | slice) -> Array:
        """Knob values base · span**a = base · exp(a ln span), ``(k, B)``."""
        return (self._knob_base * np.exp(self.action[lanes] * self._knob_log_span)).T

    def _apply_action(self) -> None:
        """Set every lane's Q and R diagonals from its action (knob-major, so that
        each operation runs along the lanes: the numbers of :meth:`_scales`)."""
        e = self.engine
        scales = self._scale_buf
        scales[...] = self.action.T
        scales *= self._knob_log_span[:, None]
        np.exp(scales, out=scales)
        scales *= self._knob_base[:, None]
        np.multiply(e.q0[:, None], scales[self._qgroup], out=e.q)
        np.multiply(e.r0, scales[3], out=e.r)

    def knob_values(self) -> dict[str, Array]:
        """Current physical value of every knob, per lane."""
        scales = self._scales(slice(None))
        return {name: scales[i] for i, (name, *_) in enumerate(ACTION_KNOBS)}

    # ------------------------------------------------------------------ step
    def step(self, action: Any) -> tuple[Array, Array, BoolArray, BoolArray, dict]:
        """Advance every lane by one decision interval."""
        a = self.validate_action(action)
        self.clipped += np.any(np.abs(a) > 1.0, axis=1)
        self.action = np.clip(a, -1.0, 1.0)
        self._apply_action()
        e, k, c = self.engine, self.k, self.config
        base = self.g - self.ep_start  # episode sample index of the first slot
        used = np.clip(self.length - base, 0, k)
        sl = slice(self.g % self.C, self.g % self.C + k)
        self.g += k
        sidx = base[None, :] + np.arange(k)[:, None]  # (k, N)
        active = (sidx < self.length) & (sidx >= 0)
        z = np.ascontiguousarray(self.zbuf[:, sl].transpose(1, 2, 0))  # (k, 4, N)
        truth = self.interval_truth  # (k, 4, N), the last interval's truth
        truth[...] = self.tbuf[:, sl].transpose(1, 2, 0)
        valid = np.empty((k, DIM_Z, self.n), dtype=bool)
        np.logical_and(self.vbuf[:, sl].transpose(1, 2, 0), active[:, None, :], out=valid)
        times = sidx * self.T  # kT
        fresh = np.flatnonzero(base == 0)
        nu = np.empty((k, DIM_Z, self.n))
        xs = np.empty((DIM_X, k, self.n))  # posterior after each sample
        with np.errstate(all="ignore"):  # diverging lanes are detected below
            for j in range(k):
                e.predict()
                if j == 0 and fresh.size:  # an episode's first sample: the prior
                    e.reset(fresh)
                nu[j] = e.update(z[j], valid[j], times[j])  # copies the engine's buffer
                xs[:, j] = e.x
            # estimated markers h(x̂ₖ) of all the interval's samples at once (the
            # anchor only moves between intervals)
            est = e.markers(times, xs).transpose(1, 0, 2)  # (k, 4, N)
            self.interval_est[:] = est
            nonfinite = e.repair()
            sq = (est - truth) ** 2 * active[:, None, :]  # (k, 4, N)
            coord_ms = _sum_in_order(sq) / np.maximum(used, 1)  # (4, N)
            err = np.sqrt(coord_ms.mean(axis=0))
        self.interval_active[:] = active
        err = np.where(used > 0, err, self.last_error)
        self.cursor += used
        last = np.maximum(self.cursor - 1, 0)
        j_last = np.maximum(used - 1, 0)
        lanes = self.lanes
        self.distance = np.where(
            used > 0,
            truth[j_last, 0, lanes] - self.x_start,
            self.distance,
        )
        # divergence and lock loss (module docstring)
        omega = e.p0[I_OMEGA, 0] + e.x[I_OMEGA]
        lo, hi = c.cadence_bounds
        nominal_omega = e.p0[I_OMEGA, 0]
        finite = ~nonfinite & np.isfinite(e.x).all(axis=0)
        diverged = ~finite | ~((omega > lo * nominal_omega) & (omega < hi * nominal_omega))
        lock_lost = ~(err <= c.divergence_error_m)
        terminated = diverged | lock_lost
        truncated = (self.cursor >= self.length) & ~terminated
        self._reanchor(last, ~terminated)
        weight = used / self.length
        # On divergence the final error is held for the rest of the walk, so that
        # stopping early never pays: the return stays minus the time-average.
        tail = np.maximum(self.length - self.cursor, 0) / self.length
        err_safe = np.where(np.isfinite(err), err, NONFINITE_ERROR_FACTOR * c.divergence_error_m)
        reward = -err_safe * (weight + np.where(terminated, tail, 0.0))
        self.last_error = err_safe.copy()
        interval = {"nu": nu, "valid": valid, "used": used}
        self.obs = self._features(slice(None), interval)
        info = {
            "markers_true": truth[j_last, :, lanes],
            "markers_est": est[j_last, :, lanes],
            "error": err_safe,
            "error_by_coord": np.sqrt(coord_ms.T),
            "distance": self.distance.copy(),
            "samples": used,
            # active coordinates not valid: 4 per active sample minus the valid ones
            "dropped_samples": (4 * active.sum(axis=0) - valid.sum(axis=(0, 1))) // 2,
            "reanchors": self.reanchors.copy(),
            "clipped_actions": self.clipped.copy(),
            "covariance_repairs": e.repairs.copy(),
            "diverged": diverged,
            "lock_lost": lock_lost & ~diverged,
            "reward_error": -err_safe * weight,
        }
        return self.obs.copy(), reward, terminated, truncated, info

    def _reanchor(self, last: NDArray[np.int64], ok: BoolArray) -> None:
        """Move the time origin of long-anchored lanes (module docstring)."""
        c, e = self.config, self.engine
        if not math.isfinite(c.reanchor_after_s):
            return
        t_now = last * self.T
        due = ok & (t_now - e.t_anchor > c.reanchor_after_s)
        if not due.any():
            return
        idx = np.flatnonzero(due)  # the same operations as over all lanes, on these
        omega = e.p0[I_OMEGA, 0] + e.x[I_OMEGA, idx]  # > 0 for lanes not diverged
        t_anchor = e.t_anchor[idx]
        span = t_now[idx] - c.reanchor_keep_s - t_anchor
        with np.errstate(all="ignore"):
            cycles = np.floor(omega * span / (2.0 * math.pi))
            shift = 2.0 * math.pi * cycles / omega
        moved = (cycles >= 1) & (shift > 0)
        idx, shift = idx[moved], shift[moved]
        c_x = e.p0[I_CX, 0] + e.x[I_CX, idx]
        e.x_anchor[idx] += c_x * shift
        e.t_anchor[idx] = t_anchor[moved] + shift
        self.reanchors[idx] += 1

    # ------------------------------------------------------------------ observation
    def _features(
        self, lanes: NDArray[np.integer] | slice, interval: dict | None
    ) -> NDArray[np.float32]:
        """Observation rows of ``lanes`` (see OBS_FEATURES and the env docstring)."""
        e = self.engine
        b = self.n if isinstance(lanes, slice) else len(lanes)
        out = np.zeros((len(OBS_FEATURES) + self.config.action_dim, b))  # features × lanes
        with np.errstate(all="ignore"):
            if interval is not None:  # right after reset: no data yet (zeros)
                nu, valid, used = interval["nu"], interval["valid"], interval["used"]
                nu2 = nu * nu  # (k, 4, N); ν = 0 where skipped
                nvalid = valid.sum(axis=1)  # (k, N)
                nis = nu2.sum(axis=1)
                lnis = np.log1p(nis)  # 0 where no update
                n_upd = np.maximum((nvalid > 0).sum(axis=0), 1)
                cnt = valid.sum(axis=0)  # (4, N)
                out[0] = 1.0 - cnt.sum(axis=0) / np.maximum(4 * used, 1)
                out[1] = _sum_in_order(lnis) / n_upd
                out[2] = lnis.max(axis=0)
                out[3] = (nis > CHI2_99[nvalid]).sum(axis=0) / n_upd  # χ²(0) = inf
                cnt = np.maximum(cnt, 1)
                out[4:8] = np.sqrt(_sum_in_order(nu2) / cnt)
                out[8:12] = _sum_in_order(nu) / cnt
            diag = e.P.reshape(DIM_X * DIM_X, -1)[:: DIM_X + 1][:, lanes]
            out[12:18] = 0.5 * np.log10(diag) - self._log10_abs_p0
            out[18:24] = e.x[:, lanes] / self._abs_p0
            t_last = np.maximum(self.cursor[lanes] - 1, 0) * self.T
            out[24] = t_last - e.t_anchor[lanes]
            out[25:] = self.action[lanes].T
            # Clip to the bounds, NaN → 0: what nan_to_num and then clipping the
            # float32 cast gives (±inf end at a bound either way, 0 is inside every
            # range; the bounds are float32 numbers and rounding keeps the order).
            np.maximum(out, self._obs_low64, out=out)  # NaN stays NaN
            np.minimum(out, self._obs_high64, out=out)
            nan = np.isnan(out)
            if nan.any():
                out[nan] = 0.0
        return out.T.astype(np.float32)


__all__ = [
    "ACTION_KNOBS",
    "CHI2_99",
    "COORDS",
    "OBS_FEATURES",
    "Q_GROUP",
    "UWB_CONDITIONS",
    "Episode",
    "MarkerTrackConfig",
    "MarkerTrackCore",
    "generate_episode",
    "uwb_spec",
]
