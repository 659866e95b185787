"""Batched episode engine behind ``pednav/FootZupt-v0`` (scalar and vector).

One implementation for any number of lanes: the scalar environment is this
core with N = 1, the native vector environment the same core with
N = ``num_envs``. Each lane owns its episode (walk, IMU record, seed); all
lanes go through the ZUPT-UKF together, a whole decision interval per call
(:meth:`pednav_env.nav.zupt_ukf.ZuptUkf.advance`), in one numpy call chain.

Episode: a walk drawn from the lane's generator (route with turns, stops and
gait changes; IMU grade and its errors), a 1 s alignment at rest, then
navigation. A decision interval is ``decision_interval_s`` of IMU data
(default 0.5 s). The action sets the filter's knobs for the next interval as
``base · span ** a`` (log scale; a = 0 is the paper configuration).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from pednav_env.draws import choice_cdf, choice_index
from pednav_env.envs.foot_context import grade_code, interval_context
from pednav_env.envs.foot_features import (
    masked,
    masked_moments,
    update_stance_average,
    vector_norms,
)
from pednav_env.envs.foot_filters import (
    MIN_STANCE_MAX_S,
    PAPER_KNOBS,
    ShoeStatistic,
    family_filter,
    family_knobs,
    require_family,
)
from pednav_env.envs.spec import (
    EnvConfig,
    Knob,
    ObsFeature,
    obs_bounds,
    require_weights,
    validate_action,
)
from pednav_env.gait.foot import FootSimConfig, simulate_foot
from pednav_env.gait.foot_route import (
    RouteRandomization,
    paper_stride_shape,
    random_route,
    square_route,
)
from pednav_env.gait.speed_route import SpeedRouteConfig, speed_route
from pednav_env.gait.stance_motion import StanceRandomization
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.sensors.imu import IMU_GRADES, grade_spec, simulate_imu

Array = NDArray[np.float64]

#: Knobs of the paper family (re-exported; the families: :mod:`pednav_env.envs.foot_filters`).
ACTION_KNOBS = PAPER_KNOBS

#: Observation entries; documented in the env docstring.
OBS_FEATURES: tuple[ObsFeature, ...] = (
    ObsFeature("gyro_norm_mean", 0.0, 50.0, "rad/s"),
    ObsFeature("gyro_norm_std", 0.0, 50.0, "rad/s"),
    ObsFeature("gyro_norm_max", 0.0, 50.0, "rad/s"),
    ObsFeature("accel_excess_mean", -20.0, 200.0, "m/s²"),
    ObsFeature("accel_excess_std", 0.0, 200.0, "m/s²"),
    ObsFeature("accel_excess_absmax", 0.0, 200.0, "m/s²"),
    ObsFeature("stance_fraction", 0.0, 1.0, "1"),
    ObsFeature("stance_starts", 0.0, 50.0, "1"),
    ObsFeature("stance_duration_avg", 0.0, 20.0, "s"),
    ObsFeature("time_since_zupt", 0.0, 200.0, "s"),
    ObsFeature("log_nis_last", 0.0, 30.0, "1"),
    ObsFeature("log_nis_interval", 0.0, 30.0, "1"),
    ObsFeature("log10_trace_p_pos", -12.0, 8.0, "log m²"),
    ObsFeature("log10_trace_p_vel", -12.0, 8.0, "log (m/s)²"),
    ObsFeature("log10_trace_p_att", -12.0, 8.0, "log rad²"),
    ObsFeature("zupt_rejected_fraction", 0.0, 1.0, "1"),
)


@dataclass(frozen=True)
class FootZuptConfig(EnvConfig):
    """Settings of the foot environment (all lanes share them).

    ``scenario``: ``"random"`` (domain randomisation), ``"paper"`` (paper
    003's square walk, 1 m strides, its IMU) or ``"calibrated"`` (the
    simulator calibrated on recordings: walks of ``speed_route``, walker
    stance dynamics of :meth:`StanceRandomization.calibrated`, the IMU grades
    ``calibrated_imu_grades``); None = ``"calibrated"`` for the shoe filter
    family, ``"random"`` for the paper family. ``filter_family`` (``gym.make``
    argument ``filter``): ``"paper"`` or ``"shoe"``
    (:mod:`pednav_env.envs.foot_filters`). ``rate_hz`` None = 200 Hz in the
    calibrated scenario (the recordings' rate), else 100 Hz (paper 003).
    """

    SCENARIOS: ClassVar[tuple[str, ...]] = ("random", "paper", "calibrated")
    scenario: str | None = None
    decision_interval_s: float = 0.5
    rate_hz: float | None = None
    route: RouteRandomization = field(default_factory=RouteRandomization)
    #: Calibrated scenario: every stride's speed in 0.3–3 m/s, a new speed per
    #: leg, turns between legs, stops of 1–8 s before a quarter of the legs.
    speed_route: SpeedRouteConfig = field(
        default_factory=lambda: SpeedRouteConfig(
            speed_mps=(0.3, 3.0), duration_s=(60.0, 120.0), stop_probability=0.25, stop_s=(1.0, 8.0)
        )
    )
    calibrated_imu_grades: tuple[str, ...] = ("microstrain_gx5",)
    #: IMU grades drawn per episode and their weights (random scenario).
    imu_grades: tuple[str, ...] = ("paper003", "adis16470", "consumer")
    imu_grade_weights: tuple[float, ...] = (0.4, 0.3, 0.3)
    #: The filter family: "paper" (eq 5, ZUPTs at stance boundaries) or "shoe"
    #: (SHOE detector, a ZUPT at every stance sample).
    filter_family: str = "paper"
    #: The filter at action 0; None = the family's (foot_filters.family_filter):
    #: paper 003's IMU model and thresholds, in the random scenario with its
    #: real-data gyro-bias calibration at rest (the paper's simulation has none),
    #: or real-fixed's configuration.
    filter: ZuptUkfConfig | None = None
    tune_min_stance: bool = False
    #: Divergence: horizontal error beyond this + fraction × distance walked.
    divergence_error_m: float = 25.0
    divergence_error_fraction: float = 0.25

    def __post_init__(self) -> None:
        require_family(self.filter_family)
        if self.scenario is None:
            scenario = "calibrated" if self.filter_family == "shoe" else "random"
            object.__setattr__(self, "scenario", scenario)
        if self.rate_hz is None:
            object.__setattr__(self, "rate_hz", 200.0 if self.scenario == "calibrated" else 100.0)
        self.check_env_settings(sample="IMU sample")
        if self.filter is None:
            object.__setattr__(self, "filter", family_filter(self.filter_family, self.scenario))
        family_knobs(self.filter_family, self.filter)  # the filter fits the family
        for g in (*self.imu_grades, *self.calibrated_imu_grades):
            if g not in IMU_GRADES:
                raise ValueError(f"imu_grades: unknown grade {g!r}; known: {sorted(IMU_GRADES)}")
        require_weights("imu_grade_weights", self.imu_grade_weights, len(self.imu_grades))
        if not self.calibrated_imu_grades:
            raise ValueError("calibrated_imu_grades: give at least one IMU grade")

    @property
    def knobs(self) -> tuple[Knob, ...]:
        """The family's four knobs around ``filter`` (the minimum stance apart)."""
        return family_knobs(self.filter_family, self.filter)

    @property
    def action_dim(self) -> int:
        return len(self.knobs) + int(self.tune_min_stance)

    @property
    def max_samples(self) -> int:
        """Capacity of the per-lane buffers (longest possible walk)."""
        if self.scenario == "paper":
            return int(math.ceil(paper_route().duration_s * self.rate_hz)) + 1
        # the routes stop before exceeding the drawn duration; +1 s margin
        longest = (
            self.speed_route.duration_s[1]
            if self.scenario == "calibrated"
            else self.route.duration_s[1]
        )
        return int(math.ceil((longest + 1.0) * self.rate_hz)) + 1


def paper_route():
    """Paper 003's square (5 m side, 1 m strides)."""
    return square_route(5.0, paper_stride_shape(1.0))


@dataclass
class Episode:
    """One lane's walk: IMU record and the truth used for reward and info."""

    omega_b: Array  # (T, 3)
    f_b: Array  # (T, 3)
    pos_n: Array  # (T+1, 3) truth
    stance: NDArray[np.bool_]  # (T,) truth
    distance_m: Array  # (T+1,)
    imu_grade: str


#: The calibrated walker population (stance dynamics, gait timing, swing vigour).
CALIBRATED_WALKERS = StanceRandomization.calibrated()


def generate_episode(config: FootZuptConfig, rng: np.random.Generator) -> Episode:
    """Draw one episode from ``rng`` (fixed draw order: route, grade, IMU errors;
    calibrated scenario: walker, route, grade, IMU errors). The random
    scenario's grade is drawn by :func:`pednav_env.draws.choice_index`, the
    number ``rng.choice(len(w), p=w / w.sum())`` gives."""
    sim = FootSimConfig(rate_hz=config.rate_hz)
    if config.scenario == "paper":
        route = paper_route()
        grade = "paper003"
    elif config.scenario == "calibrated":
        walker = CALIBRATED_WALKERS.draw(rng)
        route = speed_route(rng, replace(config.speed_route, stance_motion=walker))
        grades = config.calibrated_imu_grades
        grade = grades[int(rng.integers(len(grades)))] if len(grades) > 1 else grades[0]
    else:
        route = random_route(rng, config.route)
        w = np.asarray(config.imu_grade_weights, dtype=float)
        grade = config.imu_grades[choice_index(rng, choice_cdf(w / w.sum()))]
    truth = simulate_foot(route, sim, full_state=False)
    imu = simulate_imu(
        truth.omega_b,
        truth.f_b,
        config.rate_hz,
        grade_spec(grade),
        [rng],
        gait_step_index=truth.gait_step,
    )
    return Episode(
        imu.omega_b[0], imu.f_b[0], truth.pos_n[0], truth.stance[0], truth.distance_m[0], grade
    )


class FootZuptCore:
    """N lanes of the foot environment stepping together."""

    def __init__(self, config: FootZuptConfig, num_envs: int, env_name: str) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be ≥ 1, got {num_envs!r}")
        self.config = config
        self.n = int(num_envs)
        self.env_name = env_name
        self.k = config.interval_samples
        self.dt = 1.0 / config.rate_hz
        self.n_align = max(1, int(round(config.filter.alignment_s * config.rate_hz)))
        self.engine = ZuptUkf(config.filter, config.rate_hz, self.n)
        #: Each lane's sample interval (s), the engine's (a recording's own rate).
        self.lane_dt = self.engine.walker_dt
        cap = config.max_samples + self.k
        n = self.n
        self.omega = np.zeros((n, cap, 3))
        self.f = np.zeros((n, cap, 3))
        self.f[..., 2] = config.filter.g  # padding: standing still
        self.pos = np.zeros((n, cap + 1, 3))
        self.true_stance = np.zeros((n, cap), dtype=bool)
        self.distance = np.zeros((n, cap + 1))
        self.length = np.zeros(n, dtype=np.int64)
        self.cursor = np.zeros(n, dtype=np.int64)
        self.nav_samples = np.ones(n, dtype=np.int64)
        self.grade = ["" for _ in range(n)]
        self.grade_code = np.zeros(n, dtype=np.int64)
        #: Privileged context of the coming interval (foot_context.CONTEXT_FIELDS).
        self.context = np.zeros((n, 3))
        self.action = np.zeros((n, config.action_dim))
        self.clipped = np.zeros(n, dtype=np.int64)
        self.stance_avg_s = np.zeros(n)
        self.stance_len = np.zeros(n, dtype=np.int64)
        self.obs = np.zeros((n, len(OBS_FEATURES) + config.action_dim), dtype=np.float32)
        self.last_error = np.zeros(n)
        self.lanes = np.arange(n)
        self.obs_low, self.obs_high = obs_bounds(OBS_FEATURES, config.action_dim)
        self.knobs = config.knobs
        det = config.filter.detector
        rates = self.engine.walker_rate_hz  # per lane (the same array)
        self.shoe = ShoeStatistic(det, rates) if self.engine.uses_shoe else None
        #: SHOE statistic window of each lane (s), set by the shoe family's knob.
        self.shoe_window_s = np.full(n, getattr(det, "window_s", np.nan))

    # ------------------------------------------------------------------ reset
    def load_lane(
        self,
        lane: int,
        omega_b: Array,
        f_b: Array,
        pos_n: Array,
        stance: NDArray[np.bool_],
        distance_m: Array,
    ) -> None:
        """Copy one walk's IMU record ``(T, 3)`` and truth (positions and distance
        ``(T+1, ·)``, stance ``(T,)``) into ``lane``'s buffers; past the end the
        lane stands still at its last position."""
        t = omega_b.shape[0]
        self.omega[lane, :t] = omega_b
        self.omega[lane, t:] = 0.0
        self.f[lane, :t] = f_b
        self.f[lane, t:] = 0.0
        self.f[lane, t:, 2] = self.config.filter.g
        self.pos[lane, : t + 1] = pos_n
        self.pos[lane, t + 1 :] = pos_n[-1]
        self.true_stance[lane, :t] = stance
        self.true_stance[lane, t:] = True
        self.distance[lane, : t + 1] = distance_m
        self.distance[lane, t + 1 :] = distance_m[-1]
        self.length[lane] = t

    def reset_lanes(self, lanes: NDArray[np.integer], rngs: list[np.random.Generator]) -> None:
        """Start new episodes in ``lanes``, each drawn from its own generator."""
        lanes = np.asarray(lanes, dtype=np.int64)
        c = self.config
        for lane, rng in zip(lanes, rngs, strict=True):
            ep = generate_episode(c, rng)
            self.load_lane(lane, ep.omega_b, ep.f_b, ep.pos_n, ep.stance, ep.distance_m)
            self.grade[lane] = ep.imu_grade
            self.grade_code[lane] = grade_code(ep.imu_grade)
        mask = np.zeros(self.n, dtype=bool)
        mask[lanes] = True
        self.engine.initialize(
            self.f[lanes, : self.n_align], mask, omega_align_b=self.omega[lanes, : self.n_align]
        )
        self.cursor[lanes] = self.n_align
        self.nav_samples[lanes] = np.maximum(self.length[lanes] - self.n_align, 1)
        self._restart_episodes(lanes)
        self.obs[lanes] = self._features(lanes, None)

    def _restart_episodes(self, lanes: NDArray[np.integer]) -> None:
        """Action 0 (the family's filter), cleared counters and stance statistics,
        and the context of the first interval, for lanes whose new episode is
        loaded and whose filter is initialised."""
        self._update_context(lanes)
        self.action[lanes] = 0.0
        self.clipped[lanes] = 0
        self.stance_avg_s[lanes] = 0.0
        self.stance_len[lanes] = 0
        self.last_error[lanes] = 0.0
        self._apply_action(lanes)

    def _update_context(self, lanes: NDArray[np.integer]) -> None:
        self.context[lanes] = interval_context(
            self.distance,
            lanes,
            self.cursor[lanes],
            self.length[lanes],
            self.k,
            self.lane_dt[lanes],
            self.grade_code[lanes],
        )

    # ------------------------------------------------------------------ action
    def validate_action(self, action: Any) -> Array:
        """Shape ``(N, k)``, numeric and finite (:func:`spec.validate_action`); float64."""
        return validate_action(action, (self.n, self.config.action_dim), self.env_name)

    def _apply_action(self, lanes: NDArray[np.integer]) -> None:
        a = self.action[lanes]
        e = self.engine
        values = {knob.name: knob.value(a[:, i]) for i, knob in enumerate(self.knobs)}
        if self.shoe is None:
            e.omega_max[lanes], e.delta_f_max[lanes] = values["omega_max"], values["delta_f_max"]
        else:
            e.shoe_threshold[lanes] = values["shoe_threshold"]
            self.shoe_window_s[lanes] = values["shoe_window_s"]
        e.process_noise_scale[lanes] = values["process_noise_scale"]
        e.zupt_noise_scale[lanes] = values["zupt_noise_scale"]
        if self.config.tune_min_stance:
            e.min_stance_s[lanes] = MIN_STANCE_MAX_S * np.maximum(a[:, 4], 0.0)

    def knob_values(self) -> dict[str, Array]:
        """Current physical value of every knob, per lane."""
        e = self.engine
        if self.shoe is None:
            out = {"omega_max": e.omega_max.copy(), "delta_f_max": e.delta_f_max.copy()}
        else:
            out = {
                "shoe_threshold": e.shoe_threshold.copy(),
                "shoe_window_s": self.shoe_window_s.copy(),
            }
        out["process_noise_scale"] = e.process_noise_scale.copy()
        out["zupt_noise_scale"] = e.zupt_noise_scale.copy()
        if self.config.tune_min_stance:
            out["min_stance_s"] = e.min_stance_s.copy()
        return out

    # ------------------------------------------------------------------ step
    def step(self, action: Any) -> tuple[Array, Array, NDArray[np.bool_], NDArray[np.bool_], dict]:
        """Advance every lane by one decision interval."""
        a = self.validate_action(action)
        clipped = np.any(np.abs(a) > 1.0, axis=1)
        self.clipped += clipped
        self.action = np.clip(a, -1.0, 1.0)
        self._apply_action(self.lanes)
        e = self.engine
        k = self.k
        remaining = self.length - self.cursor
        used = np.clip(remaining, 0, k)
        # rows of the interval in the lanes' buffers seen as one (N·cap, ·) array:
        # np.take of them copies the same values as a two-index gather, 4× faster
        rows = (self.lanes * self.omega.shape[1] + self.cursor)[:, None] + np.arange(k)
        omega = np.take(self.omega.reshape(-1, 3), rows, axis=0)  # (N, K, 3)
        f = np.take(self.f.reshape(-1, 3), rows, axis=0)
        updates0, rejected0 = e.updates.copy(), e.rejected.copy()
        shoe = None
        if self.shoe is not None:
            shoe = self.shoe.interval(self.omega, self.f, self.cursor, k, self.shoe_window_s)
        res = e.advance(omega, f, shoe, valid=used)  # the whole interval in one call
        in_walk = np.arange(k)[None, :] < used[:, None]
        start, end = res.start & in_walk, res.end & in_walk
        starts = start.sum(axis=1)
        true_starts = (start & np.take(self.true_stance.reshape(-1), rows)).sum(axis=1)
        self.stance_avg_s, self.stance_len = update_stance_average(
            self.stance_avg_s, self.stance_len, res.stance, end, self.lane_dt
        )
        est_end = res.position
        self.cursor += used
        truth = self.pos[self.lanes, self.cursor]
        err = np.linalg.norm(est_end[:, :2] - truth[:, :2], axis=1)
        dist = self.distance[self.lanes, self.cursor]
        bound = self.config.divergence_error_m + self.config.divergence_error_fraction * dist
        terminated = e.diverged | (err > bound)
        truncated = (self.cursor >= self.length) & ~terminated
        weight = used / self.nav_samples
        # On divergence the final error is held for the rest of the walk, so that
        # stopping early never pays: the return stays minus the time-average.
        tail = np.maximum(self.length - self.cursor, 0) / self.nav_samples
        reward = -err * (weight + np.where(terminated, tail, 0.0))
        self.last_error = err.copy()  # info["error"] must not change when a lane resets
        new_updates = e.updates - updates0
        interval = {
            "omega": omega,
            "f": f,
            "used": used,
            "detected": res.stance,
            "starts": starts,
            "nis_mean": np.where(
                res.accepted > 0, res.nis_log_sum / np.maximum(res.accepted, 1), 0.0
            ),
        }
        self.obs = self._features(self.lanes, interval)
        self._update_context(self.lanes)
        info = {
            "pos_true": truth.copy(),
            "pos_est": est_end,
            "error": err,
            "distance": dist,
            "stance_detections": starts,
            "true_stance_detections": true_starts,
            "false_stance_detections": starts - true_starts,
            "zupts": new_updates,
            "zupts_rejected": e.rejected - rejected0,
            "clipped_actions": self.clipped.copy(),
            "covariance_repairs": e.repairs.copy(),
            "diverged": e.diverged.copy(),
            "reward_error": -err * weight,
        }
        return self.obs.copy(), reward, terminated, truncated, info

    # ------------------------------------------------------------------ observation
    def _features(self, lanes: NDArray[np.integer], interval: dict | None) -> NDArray[np.float32]:
        e = self.engine
        g = self.config.filter.g
        b = len(lanes)
        out = np.zeros((b, len(OBS_FEATURES)))
        if interval is None:  # right after reset: statistics of the alignment window
            omega = self.omega[lanes, : self.n_align]
            f = self.f[lanes, : self.n_align]
            mask = np.ones(omega.shape[:2], dtype=bool)
            detected = np.zeros(omega.shape[:2], dtype=bool)
            starts = np.zeros(b)
            nis_mean = np.zeros(b)
        else:
            omega, f = interval["omega"], interval["f"]
            mask = np.arange(omega.shape[1])[None, :] < np.maximum(interval["used"], 1)[:, None]
            detected, starts, nis_mean = (
                interval["detected"],
                interval["starts"],
                interval["nis_mean"],
            )
        cnt = mask.sum(axis=1)
        full = bool(mask.all())
        wn = vector_norms(omega)
        an = vector_norms(f) - g
        out[:, 0], out[:, 1] = masked_moments(wn, mask, cnt, full)
        out[:, 3], out[:, 4] = masked_moments(an, mask, cnt, full)
        out[:, 2] = masked(wn, mask, full).max(1)
        out[:, 5] = masked(np.abs(an), mask, full).max(1)
        out[:, 6] = masked(detected, mask, full).sum(1) / cnt
        out[:, 7] = starts
        out[:, 8] = self.stance_avg_s[lanes]
        out[:, 9] = e.time_since_update_s[lanes]
        out[:, 10] = np.log1p(e.last_nis[lanes])
        out[:, 11] = nis_mean
        P = e.P[lanes]
        diag = np.diagonal(P, axis1=1, axis2=2)
        for col, sl in ((12, slice(0, 3)), (13, slice(3, 6)), (14, slice(6, 9))):
            out[:, col] = np.log10(np.maximum(diag[:, sl].sum(1), 1e-12))
        total = e.updates[lanes] + e.rejected[lanes]
        out[:, 15] = np.where(total > 0, e.rejected[lanes] / np.maximum(total, 1), 0.0)
        obs = np.concatenate((out, self.action[lanes]), axis=1)
        return np.clip(obs, self.obs_low, self.obs_high).astype(np.float32)
