"""``pednav/FootZuptReplay-v0``: the FootZupt contract over recorded trials."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from pednav_env.envs.foot_replay_core import FootReplayConfig, FootReplayCore
from pednav_env.envs.foot_zupt import FootZuptEnv, FootZuptVectorEnv

ENV_ID = "pednav/FootZuptReplay-v0"


class ReplayFront:
    """What the replay env's scalar and vector classes add to the foot env's:
    the replay core and config. After construction ``config`` is the core's
    filter-side :class:`~pednav_env.envs.foot_core.FootZuptConfig` (what the
    foot env's code reads) and ``replay_config`` the :class:`FootReplayConfig`."""

    env_id = ENV_ID
    core_cls = FootReplayCore
    config_cls = FootReplayConfig
    arguments = (
        "data_dir",
        "filter",
        "decision_interval_s",
        "tune_min_stance",
        "trial_order",
        "first_trial_seed",
    )
    core: FootReplayCore

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.replay_config: FootReplayConfig = self.config
        self.config = self.core.config

    def reset(self, *, seed: Any = None, options: dict | None = None):
        """The env's reset; in sequential trial order the seed also picks the trial
        (lane i of a vector env: seed s + i, as for the episode draw)."""
        if seed is not None:
            n = int(getattr(self, "num_envs", 1))
            if isinstance(seed, int | np.integer):
                seeds: list[Any] = [int(seed) + i for i in range(n)]
            else:
                seeds = list(seed)
            lanes = [i for i, s in enumerate(seeds) if s is not None]
            if len(seeds) == n:  # a wrong length is the vector env's error
                self.core.seed_trials(np.array(lanes), [seeds[i] for i in lanes])
        return super().reset(seed=seed, options=options)  # type: ignore[misc]

    @classmethod
    def build_config(cls, config: Any, arguments: dict[str, Any]) -> Any:
        data_dir = arguments.get("data_dir")
        if data_dir is not None:  # a path-like is kept as its string
            arguments = {**arguments, "data_dir": str(data_dir)}
        return super().build_config(config, arguments)  # type: ignore[misc]

    @staticmethod
    def with_family(config: FootReplayConfig, family: str) -> FootReplayConfig:
        """``config`` with filter family ``family`` and that family's setup."""
        return replace(config, filter_family=family, setup=None)

    def action_dim(self) -> int:
        return int(self.core.config.action_dim)


class FootZuptReplayEnv(ReplayFront, FootZuptEnv):
    """
    ## Description
    :class:`pednav_env.envs.foot_zupt.FootZuptEnv` with recorded walks in
    place of simulated ones: a foot-mounted IMU recording with a reference
    track (e.g. the PyShoe VICON trials) is played through the same
    ZUPT-UKF, and the agent retunes it every ``decision_interval_s`` of data.
    Action space, observation space, reward, termination and info are those
    of ``pednav/FootZupt-v0`` (see its docstring), so a tuner trained in
    simulation runs here unchanged, and action 0 is the same filter as there
    (eq 5 at 0.22 rad/s and 0.33 m/s², paper 003's noise model, gyro-bias
    calibration on the still start).

    An episode is one whole trial, chosen by the reset seed (uniformly) from
    the recordings in ``data_dir`` (``.mat`` PyShoe trials or CSV files with
    truth columns, :mod:`pednav_env.io`; each at its own rate, with the same
    number of samples per decision interval; a recording
    without a truth track, e.g. a footprint-only hallway walk, is refused
    naming it). With ``trial_order="sequential"`` the episode of seed s plays
    trial (s − ``first_trial_seed``) mod n of the n recordings sorted by name,
    and a lane's next episode the next one (``pednav evaluate`` plays every
    recording once this way). Before the
    filter sees them the samples are put on a uniform grid, rotated so that
    the still start's specific force points up, and the still start (at most
    1 s) is the alignment window (paper 003 eq 4).

    ## Action Space
    ``Box(-1, 1, (4,), float32)`` (``(5,)`` with ``tune_min_stance=True``),
    per filter family (``filter="paper"`` or ``"shoe"``) exactly as in
    ``pednav/FootZupt-v0``: ω_max, Δf_max, process-noise scale, ZUPT-noise
    scale (paper; action 0 as above), or γ, SHOE window, process- and
    ZUPT-noise scales (shoe; action 0 = ``real-fixed``).

    ## Observation Space
    ``Box(low, high, (16 + k,), float32)``, the features of
    ``pednav/FootZupt-v0`` computed from the recorded IMU and the filter.

    ## Rewards
    ``−e · Δ / D`` per step as in ``pednav/FootZupt-v0``; e is the horizontal
    distance between the estimate and the reference, with the reference
    turned about the vertical by an angle fixed per trial (fitted to a run of
    the ``real-fixed`` filter; heading is unobservable at the start). The
    return is minus the time-averaged horizontal error.

    ## Starting State
    The still start of the trial (0.1–1 s): alignment and gyro-bias
    calibration; navigation starts at its end, at position 0.

    ## Episode End
    Truncation at the end of the trial; termination on divergence as in
    ``pednav/FootZupt-v0``.

    ## Arguments
    ``gymnasium.make("pednav/FootZuptReplay-v0", data_dir=DIR, filter="paper",
    decision_interval_s=0.5, tune_min_stance=False, trial_order="random",
    first_trial_seed=0, config=None, render_mode=None)``; ``config`` is a full
    :class:`pednav_env.envs.foot_replay_core.FootReplayConfig` (filter setup,
    reference setup, load options, divergence bounds). ``data_dir`` is required.

    ## Vectorized environment
    ``gymnasium.make_vec("pednav/FootZuptReplay-v0", num_envs=N,
    vectorization_mode="vector_entry_point", data_dir=DIR)``: one batched
    filter, SAME_STEP autoreset; lane i reset with seed s plays the trials
    that this env plays reset with seed s + i.

    ## Info
    That of ``pednav/FootZupt-v0`` (``imu_grade`` is ``"recorded"``; the
    ``context`` speed is the reference's, smoothed over 0.05 s), plus
    ``trial`` (the recording's name) and ``heading_offset`` (rad, the fixed
    rotation of the reference). ``true_stance_detections`` counts detected
    stance starts inside reference stance labels.

    ## Version History
    - v0: initial version.
    """

    def lane_info(self) -> dict[str, Any]:
        return {
            **super().lane_info(),
            "trial": self.core.trial_name[0],
            "heading_offset": float(self.core.heading_offset[0]),
        }


class FootZuptReplayVectorEnv(ReplayFront, FootZuptVectorEnv):
    """Native vector version of :class:`FootZuptReplayEnv` (see its docstring):
    one batched filter for all ``num_envs`` trials, SAME_STEP autoreset."""

    def lane_info(self) -> dict[str, np.ndarray]:
        info = super().lane_info()
        info["trial"] = np.array(self.core.trial_name, dtype=object)
        info["heading_offset"] = self.core.heading_offset.copy()
        return info


__all__ = ["ENV_ID", "FootZuptReplayEnv", "FootZuptReplayVectorEnv"]
