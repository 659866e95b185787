"""Batched episode engine behind ``pednav/FootZuptReplay-v0``: recorded trials.

The simulated foot environment's core (:class:`FootZuptCore`) with its
episodes replaced by recorded trials: the same filter, action knobs,
observation features, reward, termination and info, so that a tuner trained
in simulation runs here unchanged. Only the episode source differs.

Per trial (cached per env after its first use):

- the recording is loaded and prepared as :func:`pednav_env.replay.runner.prepare`
  does (uniform grid, mounting, still start of its own length);
- the truth is moved into the filter's navigation frame: referred to its
  position at the end of the alignment and turned about the vertical by the
  angle that best fits (least squares) the track of a *reference run* — the
  filter with the ``reference`` setup (``real-fixed``) over the whole trial.
  The angle is fixed per trial, whatever the agent does: heading is
  unobservable at the start and this removes it the same way for every policy;
- NaN truth rows are linearly interpolated from their neighbours;
- the truth stance labels (for ``true_stance_detections``) are the data's
  own when present (PyShoe's ``zv_vicon_opt``), else samples whose truth
  speed (0.05 s mean) is below 0.15 m/s;
- distance walked: the path length of the truth smoothed over 0.05 s.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from pednav_env.envs.foot_context import grade_code
from pednav_env.envs.foot_core import FootZuptConfig, FootZuptCore
from pednav_env.envs.foot_filters import family_knobs, require_family
from pednav_env.envs.spec import require_nonnegative, require_positive
from pednav_env.io.load import find_recordings, load_recording
from pednav_env.io.recording import Recording
from pednav_env.io.validate import LoadOptions
from pednav_env.nav.detectors import (
    ShoeDetectorConfig,
    causal_moving_mean,
    detector_window,
    window_samples,
)
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.replay.metrics import best_rotation, rotate_h
from pednav_env.replay.runner import PreparedRecording, prepare, run_prepared
from pednav_env.replay.setup import RealFilterSetup, named_setup, real_fixed_setup

Array = NDArray[np.float64]

#: Truth-speed threshold for stance labels when the data have none (m/s).
TRUTH_STANCE_SPEED = 0.15
#: Smoothing of the truth for speed and distance (s).
TRUTH_SMOOTHING_S = 0.05
#: How episodes choose their trial (:class:`FootReplayConfig`).
TRIAL_ORDERS = ("random", "sequential")


def family_setup(family: str) -> RealFilterSetup:
    """Action 0 of ``family`` = the simulated env's action-0 filter: paper — eq (5)
    at 0.22 rad/s / 0.33 m/s², gyro-bias calibration (FootZuptConfig, random
    scenario); shoe — the ``real-fixed`` setup with the angle-sum forms
    (:func:`pednav_env.envs.foot_filters.family_filter`)."""
    if require_family(family) == "paper":
        return RealFilterSetup(filter=ZuptUkfConfig(calibrate_gyro_bias=True))
    setup = real_fixed_setup()
    return replace(setup, filter=replace(setup.filter, angle_sums=True))


@dataclass(frozen=True)
class FootReplayConfig:
    """Settings of the replay environment.

    ``data_dir``: a directory of recordings with truth (``.mat``/``.csv``,
    see :mod:`pednav_env.io`), each played at its own rate, whose decision
    interval is the same number of samples for all; required by the
    environments (the core can also replay in-memory recordings).
    ``filter_family`` (``gym.make`` argument ``filter``): ``"paper"`` or
    ``"shoe"`` (:mod:`pednav_env.envs.foot_filters`).
    ``setup``: the filter at action 0 and the real-data steps (None: the
    family's, :func:`family_setup`); its detector must be the family's (eq 5
    or SHOE: the knobs set its thresholds). ``reference``: the named setup
    whose run fixes the truth heading (``real-fixed``).
    ``trial_order``: ``"random"`` (training) — each episode draws its trial
    uniformly from the lane's generator; ``"sequential"`` (evaluation, what
    ``pednav evaluate`` sets) — the episode of reset seed s plays trial
    (s − ``first_trial_seed``) mod n of the n recordings sorted by name, and a
    lane's next episode (reset without a seed, or autoreset) the next trial, so
    n consecutive seeds play every recording once.
    """

    data_dir: str | None = None
    decision_interval_s: float = 0.5
    filter_family: str = "paper"
    setup: RealFilterSetup | None = None
    reference: str = "real-fixed"
    tune_min_stance: bool = False
    divergence_error_m: float = 25.0
    divergence_error_fraction: float = 0.25
    load_options: LoadOptions = field(default_factory=LoadOptions)
    trial_order: str = "random"
    first_trial_seed: int = 0

    def __post_init__(self) -> None:
        if self.data_dir is not None and not Path(self.data_dir).is_dir():
            raise ValueError(f"FootReplayConfig.data_dir: {self.data_dir!r} is not a directory")
        if self.setup is None:
            object.__setattr__(self, "setup", family_setup(self.filter_family))
        try:
            family_knobs(self.filter_family, self.setup.filter)
        except ValueError as exc:
            raise ValueError(f"FootReplayConfig.setup: {exc}") from None
        if self.setup.gravity != "standard":
            raise ValueError("FootReplayConfig.setup.gravity must be 'standard' (one g per batch)")
        # Not an EnvConfig: the recordings set the rate and there is no scenario;
        # the settings it shares with the other envs get the same checks.
        require_positive("decision_interval_s", self.decision_interval_s)
        require_positive("divergence_error_m", self.divergence_error_m)
        require_nonnegative("divergence_error_fraction", self.divergence_error_fraction)
        named_setup(self.reference)  # validates the name
        if self.trial_order not in TRIAL_ORDERS:
            raise ValueError(
                f"FootReplayConfig.trial_order must be one of {TRIAL_ORDERS}, "
                f"got {self.trial_order!r}"
            )
        if isinstance(self.first_trial_seed, bool) or not isinstance(
            self.first_trial_seed, int | np.integer
        ):
            raise ValueError(
                f"FootReplayConfig.first_trial_seed must be an integer, "
                f"got {self.first_trial_seed!r}"
            )


@dataclass
class Trial:
    """One prepared trial with its truth in the navigation frame."""

    name: str
    prepared: PreparedRecording
    pos_n: Array  # (M+1, 3) truth after c samples, nav frame, 0 at the alignment end
    stance: NDArray[np.bool_]  # (M,)
    distance_m: Array  # (M+1,)
    heading_offset_rad: float


def _fill_nan(truth: Array) -> Array:
    ok = np.isfinite(truth).all(axis=1)
    if ok.all():
        return truth
    idx = np.arange(len(truth))
    return np.stack([np.interp(idx, idx[ok], truth[ok, c]) for c in range(3)], axis=1)


def build_trial(rec: Recording, config: FootReplayConfig, require_truth: bool = True) -> Trial:
    """Prepare one trial (see the module docstring). Without truth (allowed when
    ``require_truth`` is False) the truth track is zero and no reference run is made."""
    if not rec.has_truth:
        if require_truth:
            raise ValueError(f"{rec.name}: the replay environment needs recordings with truth")
        prep = prepare(rec, config.setup)
        m = prep.num_samples
        zeros = np.zeros((m + 1, 3))
        return Trial(rec.name, prep, zeros, np.zeros(m, dtype=bool), np.zeros(m + 1), 0.0)
    prep = prepare(rec, config.setup)
    truth = _fill_nan(np.asarray(prep.truth_pos, dtype=float))
    ref_setup = replace(named_setup(config.reference), mounting=config.setup.mounting)
    ref_setup = replace(
        ref_setup,
        alignment_max_s=config.setup.alignment_max_s,
        alignment_min_s=config.setup.alignment_min_s,
    )
    ref = run_prepared(prepare(rec, ref_setup), interval_s=config.decision_interval_s)
    na = prep.n_align
    start = truth[na - 1]
    est_h = ref.pos[0, na:, :2]
    phi = best_rotation(est_h, truth[na:, :2] - start[:2])
    rel = truth - start
    pos_samples = np.concatenate((rotate_h(rel[:, :2], phi), rel[:, 2:3]), axis=1)
    pos_n = np.concatenate((pos_samples[:1], pos_samples), axis=0)
    rate = prep.rate_hz
    n = window_samples(TRUTH_SMOOTHING_S, rate)
    smooth = causal_moving_mean(pos_samples[None], n)[0]
    step = np.linalg.norm(np.diff(smooth[:, :2], axis=0), axis=1)
    dist_samples = np.concatenate(([0.0], np.cumsum(step)))
    distance = np.concatenate(([0.0], dist_samples))
    labels = rec.metadata.get("reference_stance")
    m = prep.num_samples
    if labels is not None and len(labels) == m and not prep.uniform.filled.any():
        stance = np.asarray(labels, dtype=bool)
    else:
        speed = np.concatenate(([0.0], step * rate))
        stance = causal_moving_mean(speed[None], n)[0] < TRUTH_STANCE_SPEED
    return Trial(rec.name, prep, pos_n, stance, distance, float(phi))


class FootReplayCore(FootZuptCore):
    """N lanes of the replay environment stepping together."""

    def __init__(
        self,
        config: FootReplayConfig,
        num_envs: int,
        env_name: str,
        recordings: list[Recording] | None = None,
    ) -> None:
        """Trials from ``config.data_dir``, or the in-memory ``recordings``
        (which may lack truth: then the error and reward are meaningless)."""
        self.replay_config = config
        self.recordings = recordings
        if recordings is not None:
            self.paths = [Path(r.name) for r in recordings]
        elif config.data_dir is None:
            raise ValueError(
                f"{env_name}: data_dir is required: a directory of recordings with truth, "
                "e.g. ../shared/data/pyshoe-vicon-dev"
            )
        else:
            self.paths = find_recordings(config.data_dir)
        if not self.paths:
            raise ValueError(f"{config.data_dir}: no recordings (.mat, .csv) found")
        self.trials: dict[int, Trial] = {}
        peeks = [self._peek(i, env_name) for i in range(len(self.paths))]
        rate = peeks[0][0]
        self.capacity = max(samples for _, samples in peeks)
        for i, (rec_rate, _) in enumerate(peeks):
            self._check_rate(i, rec_rate, rate, env_name)
        foot = FootZuptConfig(
            decision_interval_s=config.decision_interval_s,
            rate_hz=rate,
            filter_family=config.filter_family,
            filter=config.setup.filter,
            tune_min_stance=config.tune_min_stance,
            divergence_error_m=config.divergence_error_m,
            divergence_error_fraction=config.divergence_error_fraction,
        )
        super().__init__(foot, num_envs, env_name)
        n, cap = self.n, self.capacity + self.k + 1
        self.omega = np.zeros((n, cap, 3))
        self.f = np.zeros((n, cap, 3))
        self.pos = np.zeros((n, cap + 1, 3))
        self.true_stance = np.zeros((n, cap), dtype=bool)
        self.distance = np.zeros((n, cap + 1))
        self.lane_align = np.full(n, self.n_align, dtype=np.int64)
        self.trial_index = np.zeros(n, dtype=np.int64)
        self.trial_name = ["" for _ in range(n)]
        self.heading_offset = np.zeros(n)
        #: Sequential order: the trial each lane plays next.
        self.next_trial = np.zeros(n, dtype=np.int64)

    def _peek(self, i: int, env_name: str) -> tuple[float, int]:
        """(rate, uniform samples) of recording i without the reference run; a
        recording of ``data_dir`` without a truth track is refused here, naming it."""
        from pednav_env.io.uniform import grid_steps

        rec = self._recording(i)
        if self.recordings is None and not rec.has_truth:
            what = "it has footprints only" if rec.footprints is not None else "it has none"
            raise ValueError(
                f"{env_name}: {self.paths[i]}: no truth track ({what}); the reward needs the "
                "truth at every sample. Footprint walks are scored by `pednav run DIR` "
                "(footprint errors)"
            )
        nominal, steps = grid_steps(rec.time)
        return 1.0 / nominal, int(steps.sum()) + 1

    def _check_rate(self, i: int, rec_rate: float, rate: float, env_name: str) -> None:
        """Recording i plays at its own rate (the filter's sample interval per lane),
        but the lanes step together: a decision interval must be the same number of
        samples as recording 0's, and so must the eq-5 detector window; ValueError
        naming both recordings and their rates otherwise."""
        cfg = self.replay_config
        k0, k = (max(1, round(cfg.decision_interval_s * r)) for r in (rate, rec_rate))
        det = cfg.setup.filter.detector
        same_window = isinstance(det, ShoeDetectorConfig) or detector_window(
            det, rec_rate
        ) == detector_window(det, rate)
        if k != k0 or not same_window:
            raise ValueError(
                f"{env_name}: recordings at different rates: {self.paths[0].name} "
                f"{rate:.1f} Hz, {self.paths[i].name} {rec_rate:.1f} Hz (a decision "
                f"interval of {cfg.decision_interval_s:g} s is {k0} and {k} samples; the "
                "lanes step by one number of samples): put them in separate folders"
            )

    def _recording(self, i: int) -> Recording:
        if self.recordings is not None:
            return self.recordings[i]
        return load_recording(self.paths[i], options=self.replay_config.load_options)

    def _trial(self, i: int) -> Trial:
        if i not in self.trials:
            self.trials[i] = build_trial(
                self._recording(i), self.replay_config, require_truth=self.recordings is None
            )
        return self.trials[i]

    @property
    def num_trials(self) -> int:
        return len(self.paths)

    def seed_trials(self, lanes: NDArray[np.integer], seeds: list[int]) -> None:
        """Sequential order: the next episode of ``lanes[j]`` plays trial
        (``seeds[j]`` − ``first_trial_seed``) mod n (no effect in random order)."""
        if self.replay_config.trial_order == "sequential":
            first = self.replay_config.first_trial_seed
            for lane, seed in zip(lanes, seeds, strict=True):
                self.next_trial[lane] = (int(seed) - first) % self.num_trials

    def reset_lanes(self, lanes: NDArray[np.integer], rngs: list[np.random.Generator]) -> None:
        """Start new episodes in ``lanes``: trial drawn from each lane's generator, or
        in sequential order the lane's next trial (:class:`FootReplayConfig`)."""
        lanes = np.asarray(lanes, dtype=np.int64)
        sequential = self.replay_config.trial_order == "sequential"
        for lane, rng in zip(lanes, rngs, strict=True):
            if sequential:
                i = int(self.next_trial[lane])
                self.next_trial[lane] = (i + 1) % self.num_trials
            else:
                i = int(rng.integers(self.num_trials))
            tr = self._trial(i)
            p = tr.prepared
            self.load_lane(lane, p.omega_b, p.f_b, tr.pos_n, tr.stance, tr.distance_m)
            self.grade[lane] = "recorded"
            self.grade_code[lane] = grade_code("recorded")
            self.engine.set_rate(np.array([lane]), p.rate_hz)  # its own sample interval
            self.trial_index[lane] = i
            self.trial_name[lane] = tr.name
            self.heading_offset[lane] = tr.heading_offset_rad
            self.lane_align[lane] = p.n_align
            mask = np.zeros(self.n, dtype=bool)
            mask[lane] = True
            na = p.n_align
            self.engine.initialize(
                self.f[lane : lane + 1, :na], mask, omega_align_b=self.omega[lane : lane + 1, :na]
            )
            self.cursor[lane] = na
            self.nav_samples[lane] = max(p.num_samples - na, 1)
        self._restart_episodes(lanes)
        for lane in lanes:  # the reset features describe each lane's own alignment window
            self.n_align = int(self.lane_align[lane])
            self.obs[lane] = self._features(np.array([lane]), None)[0]
