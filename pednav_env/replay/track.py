"""The estimated track as a table: ``pednav run --out track.csv``.

One line per sample of the filter's uniform grid (gaps filled, a settling
start left out), after the sample:

- ``time (s)``: the recording's first time + (k + samples left out) / rate;
- ``pos_x/y/z (m)``: position of the IMU in the navigation frame
  (east-north-up, x along the heading at the start), 0 at the start of
  navigation;
- ``vel_x/y/z (m/s)``: velocity in the navigation frame;
- ``yaw``, ``pitch``, ``roll (rad)``: attitude ψ, θ, γ of body → navigation
  (paper 003's 3-2-1 Euler angles; body x forward, y left, z up after the
  mounting rotation);
- ``stance`` (0/1): the detector declared stance at the sample;
- ``navigating`` (0/1): 0 during the still start used for the alignment
  (the state is held at the initial one);
- ``var_pos_x/y/z (m^2)``, ``var_vel_x/y/z (m^2/s^2)``, ``var_pitch``,
  ``var_roll``, ``var_yaw (rad^2)``: the diagonal of the state covariance.

The covariance is the one a ZUPT at that sample would use as its prior
(:func:`pednav_env.replay.runner.state_covariance`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pednav_env.files import writing
from pednav_env.replay.runner import RecordingRun
from pednav_env.replay.stream import StreamStates

TRACK_COLUMNS = (
    "time (s)",
    "pos_x (m)",
    "pos_y (m)",
    "pos_z (m)",
    "vel_x (m/s)",
    "vel_y (m/s)",
    "vel_z (m/s)",
    "yaw (rad)",
    "pitch (rad)",
    "roll (rad)",
    "stance",
    "navigating",
    "var_pos_x (m^2)",
    "var_pos_y (m^2)",
    "var_pos_z (m^2)",
    "var_vel_x (m^2/s^2)",
    "var_vel_y (m^2/s^2)",
    "var_vel_z (m^2/s^2)",
    "var_pitch (rad^2)",
    "var_roll (rad^2)",
    "var_yaw (rad^2)",
)


def run_states(run: RecordingRun, first_time_s: float, lane: int = 0) -> StreamStates:
    """Lane ``lane`` of a run made with ``track=True`` as :class:`StreamStates`;
    ``first_time_s`` is the recording's first time stamp."""
    if run.states is None or run.covariance_diag is None:
        raise ValueError("the run has no track: run it with track=True")
    prep = run.prepared
    m = prep.num_samples
    sample = np.arange(m, dtype=np.int64)
    x = run.states[lane]
    return StreamStates(
        sample,
        first_time_s + (prep.skipped + sample) / prep.rate_hz,
        x[:, 0:3],
        x[:, 3:6],
        x[:, [8, 6, 7]],
        run.stance[lane],
        sample >= prep.n_align,
        run.covariance_diag[lane],
    )


def write_track_csv(states: StreamStates, path: str | Path) -> Path:
    """Write states with their covariance diagonal as CSV (module docstring)."""
    path = Path(path)
    if states.covariance_diag is None:
        raise ValueError("the states have no covariance: use track=True / covariance=True")
    data = np.column_stack(
        (
            states.time_s,
            states.position_m,
            states.velocity_mps,
            states.euler_rad,
            states.stance.astype(int),
            states.navigating.astype(int),
            states.covariance_diag,
        )
    )
    fmt = ["%.6f"] + ["%.9g"] * 9 + ["%d", "%d"] + ["%.6g"] * 9
    with writing(path):
        np.savetxt(path, data, delimiter=",", header=",".join(TRACK_COLUMNS), comments="", fmt=fmt)
    return path
