"""Run the ZUPT-UKF on a :class:`pednav_env.io.Recording`.

Steps (docs/REAL_DATA.md):

1. the samples on a uniform grid (:func:`pednav_env.io.to_uniform`: gaps
   interpolated, jitter ignored), at the recording's own rate;
2. the still span at the start (:mod:`pednav_env.nav.static_start`, at most
   ``alignment_max_s``), which must exist; when the IMU moves at the very
   start (a foot settling), the first still span within
   :data:`pednav_env.replay.start.STILL_SEARCH_S` is used instead and the samples before it are left
   out (``PreparedRecording.skipped``); at least one sample must follow it;
3. the mounting rotation into body axes (:mod:`pednav_env.nav.mounting`),
   from that span's mean specific force when ``"auto"``;
4. gravity: standard, or that span's mean |f|;
5. paper 003's static alignment (eq 4) and gyro-bias calibration on the
   span, then the filter over the rest, sample by sample, in decision
   intervals; knobs may change from one interval to the next (a schedule,
   e.g. recorded from a policy in the replay environment).

N lanes can run the same recording at once with different knob values
(the development search does that).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.io.footprints import Footprints
from pednav_env.io.recording import Recording
from pednav_env.io.uniform import UniformSamples, to_uniform
from pednav_env.nav.detectors import shoe_statistic_at
from pednav_env.nav.mounting import mounting_rotation, rotate_samples
from pednav_env.nav.zupt_model import (
    STATE_DIM,
    dcm_to_state,
    process_noise,
    state_mean,
    state_residual,
)
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.replay.setup import RealFilterSetup
from pednav_env.replay.start import find_still_start

Array = NDArray[np.float64]

#: Engine attributes a schedule may set (per lane, per interval).
#: The SHOE statistic's window (s) in a schedule (the foot envs' shoe family):
#: the statistic is then computed per interval with each lane's window.
WINDOW_KNOB = "shoe_window_s"
KNOBS = (
    "omega_max",
    "delta_f_max",
    "shoe_threshold",
    "min_stance_s",
    "process_noise_scale",
    "zupt_noise_scale",
)


@dataclass(frozen=True)
class PreparedRecording:
    """A recording ready for the filter: uniform, body axes, alignment window.

    ``omega_b``/``f_b`` ``(M, 3)`` in body axes; ``truth_pos`` ``(M, 3)`` in
    the recording's frame or None; ``n_align`` samples of still start;
    ``footprints`` on this grid (their ``sample`` index these M samples) or
    None; ``skipped`` grid samples left out before the still start (0 unless
    the IMU moved at the very start; the M samples begin after them).
    """

    name: str
    rate_hz: float
    omega_b: Array
    f_b: Array
    truth_pos: Array | None
    n_align: int
    C_bs: Array
    g: float
    setup: RealFilterSetup
    uniform: UniformSamples
    footprints: Footprints | None = None
    skipped: int = 0

    @property
    def navigation_start_s(self) -> float:
        """Time of t₀ (end of the alignment) after the first recorded sample (s)."""
        return (self.skipped + self.n_align) / self.rate_hz

    @property
    def num_samples(self) -> int:
        return int(self.omega_b.shape[0])

    @property
    def duration_s(self) -> float:
        return self.num_samples / self.rate_hz


def with_gravity_of(setup: RealFilterSetup, f_align_b: Array) -> RealFilterSetup:
    """Step 4: with ``gravity="static"``, the setup with g = the mean |f| of the
    still span ``(W, 3)`` (body axes); else ``setup`` unchanged."""
    if setup.gravity != "static":
        return setup
    return setup.with_gravity(float(np.linalg.norm(f_align_b, axis=1).mean()))


def prepare(rec: Recording, setup: RealFilterSetup) -> PreparedRecording:
    """Steps 1–4 of the module docstring; the setup returned has the gravity used."""
    u = to_uniform(rec)
    try:
        skip, n_align = find_still_start(
            u.omega_b, u.f_b, u.rate_hz, setup.alignment_max_s, setup.alignment_min_s
        )
    except ValueError as exc:
        raise ValueError(f"{rec.name}: {exc}") from None
    footprints = None
    if rec.footprints is not None:
        grid = u.grid_index(rec.footprints.sample)
        if grid[0] < skip:
            raise ValueError(
                f"{rec.name}: the IMU is not still before the first footprint (sample "
                f"{int(rec.footprints.sample[0])}); no start for the alignment"
            )
        footprints = rec.footprints.reindexed(grid - skip)
    if skip:
        u = u.cropped(skip)
    if u.num_samples <= n_align:
        raise ValueError(
            f"{rec.name}: {u.num_samples} samples ({u.num_samples / u.rate_hz:.2f} s), all of "
            "them the still start used for the alignment: a walk must follow it"
        )
    C_bs = mounting_rotation(setup.mounting, u.f_b[:n_align])
    omega_b = rotate_samples(C_bs, u.omega_b)
    f_b = rotate_samples(C_bs, u.f_b)
    setup = with_gravity_of(setup, f_b[:n_align])
    g = setup.filter.g
    return PreparedRecording(
        rec.name, u.rate_hz, omega_b, f_b, u.truth_pos, n_align, C_bs, g, setup, u, footprints, skip
    )


@dataclass(frozen=True)
class RecordingRun:
    """The filter's output on one prepared recording, per lane.

    ``pos`` ``(N, M, 3)``: estimated position after each sample (held at 0
    during alignment); ``stance`` ``(N, M)`` detected stance; ``stances``
    ``(N,)`` number of detected stance phases; ``zupts`` accepted updates.
    With ``track=True``: ``states`` ``(N, M, 9)`` the mean state after each
    sample (position, velocity, pitch, roll, yaw — paper 003's order) and
    ``covariance_diag`` ``(N, M, 9)`` the diagonal of its covariance
    (:func:`state_covariance`); both hold the initial state during alignment.
    """

    prepared: PreparedRecording
    pos: Array
    stance: NDArray[np.bool_]
    stances: NDArray[np.int64]
    zupts: NDArray[np.int64]
    rejected: NDArray[np.int64]
    repairs: NDArray[np.int64]
    diverged: NDArray[np.bool_]
    states: Array | None = None
    covariance_diag: Array | None = None

    @property
    def start_sample(self) -> int:
        return self.prepared.n_align


def run_prepared(
    prep: PreparedRecording,
    num_lanes: int = 1,
    knobs: Mapping[str, Array] | None = None,
    schedule: Mapping[str, Array] | None = None,
    interval_s: float = 0.5,
    track: bool = False,
) -> RecordingRun:
    """Filter a prepared recording on ``num_lanes`` lanes.

    ``track=True`` also records the state and its covariance after every
    sample; the filter then advances one sample per call (the same filter up
    to rounding, :meth:`pednav_env.nav.zupt_ukf.ZuptUkf.advance`), about
    0.3 ms of CPU per sample.

    Parameters
    ----------
    knobs : name → ``(N,)`` constant knob values (names in :data:`KNOBS`).
    schedule : name → ``(K, N)`` knob values for decision interval k (the
        last row holds for later intervals); applied at the start of each
        interval of ``interval_s``. Besides :data:`KNOBS`, ``shoe_window_s``
        (:data:`WINDOW_KNOB`): the SHOE statistic is then computed per interval
        with each lane's window, as the foot envs' shoe family does.
    """
    n = int(num_lanes)
    e = ZuptUkf(prep.setup.filter, prep.rate_hz, n)
    for name, value in (knobs or {}).items():
        set_knob(e, name, np.broadcast_to(np.asarray(value, dtype=float), (n,)))
    w = np.broadcast_to(prep.omega_b, (n,) + prep.omega_b.shape)
    f = np.broadcast_to(prep.f_b, (n,) + prep.f_b.shape)
    na = prep.n_align
    e.initialize(f[:, :na], omega_align_b=w[:, :na])
    m = prep.num_samples
    pos = np.zeros((n, m, 3))
    stance = np.zeros((n, m), dtype=bool)
    states = cov = None
    if track:
        states = np.empty((n, m, STATE_DIM))
        cov = np.empty((n, m, STATE_DIM))
        states[:, :na] = e.mean_state()[:, None]
        cov[:, :na] = np.diagonal(e.P, axis1=1, axis2=2)[:, None]
    shoe = e.stance_statistic(w[:1], f[:1])  # the lanes share the recording
    if shoe is not None:
        shoe = np.broadcast_to(shoe, (n, m))
    k = max(1, int(round(interval_s * prep.rate_hz)))
    windows = (schedule or {}).get(WINDOW_KNOB)
    if windows is not None and shoe is None:
        raise ValueError(f"schedule: {WINDOW_KNOB!r} needs a SHOE detector")
    if windows is not None:
        shoe = np.zeros((n, m))  # filled interval by interval
    for interval, s0 in enumerate(range(na, m, k)):
        s1 = min(s0 + k, m)
        if schedule:
            for name, table in schedule.items():
                table = np.asarray(table, dtype=float)
                row = table[min(interval, table.shape[0] - 1)]
                if name == WINDOW_KNOB:  # the statistic of this interval, lane windows
                    lanes = window_samples_of(np.broadcast_to(row, (n,)), prep.rate_hz)
                    first = np.full(n, s0)
                    det = e.config.detector
                    shoe[:, s0:s1] = shoe_statistic_at(w, f, first, s1 - s0, lanes, det)
                else:
                    set_knob(e, name, np.broadcast_to(row, (n,)))
        if not track:
            res = e.advance(
                w[:, s0:s1],
                f[:, s0:s1],
                None if shoe is None else shoe[:, s0:s1],
                record="position",
            )
            pos[:, s0:s1] = res.positions
            stance[:, s0:s1] = res.stance
            continue
        for j in range(s0, s1):
            res = e.advance(
                w[:, j : j + 1],
                f[:, j : j + 1],
                None if shoe is None else shoe[:, j : j + 1],
                record="state",
            )
            states[:, j] = res.states[:, 0]
            cov[:, j] = state_covariance(e, diagonal=True)
            stance[:, j] = res.stance[:, 0]
        pos[:, s0:s1] = states[:, s0:s1, :3]
    return RecordingRun(prep, pos, stance, e.stance_starts.copy(), *e.tallies(), states, cov)


def state_covariance(e: ZuptUkf, diagonal: bool = False) -> Array:
    """Covariance ``(N, 9, 9)`` of each walker's state now (its diagonal ``(N, 9)``
    with ``diagonal``): the spread of the sigma points, moved by the strapdown
    since their last redraw, plus the process noise Q of that interval — the
    prior a ZUPT at this sample would use (right after a ZUPT, the posterior)."""
    sig = dcm_to_state(e.sig_C, e.sig_v, e.sig_p)
    d = state_residual(sig, state_mean(sig, e.weights.Wm)[:, None])
    if diagonal:
        tau = e.elapsed_s[:, None] ** np.arange(1, 5) * e.process_noise_scale[:, None]
        q = tau @ np.diagonal(e.model.q_basis, axis1=1, axis2=2)
        return np.einsum("s,nsi->ni", e.weights.Wc, d * d) + q
    spread = np.einsum("s,nsi,nsj->nij", e.weights.Wc, d, d)
    q = process_noise(
        e.config.assumed_imu, e.rate_hz, e.elapsed_s, e.process_noise_scale, e.model.q_basis
    )
    return spread + q


def window_samples_of(window_s: Array, rate_hz: float) -> NDArray[np.int64]:
    """SHOE windows (s) in samples, at least 1 (as :func:`window_samples`)."""
    return np.maximum(1, np.round(np.asarray(window_s) * rate_hz)).astype(np.int64)


def set_knob(e: ZuptUkf, name: str, value: Array) -> None:
    """Set knob ``name`` (:data:`KNOBS`) of every walker of ``e`` to ``value`` ``(N,)``."""
    if name not in KNOBS:
        raise ValueError(f"unknown knob {name!r}; knobs: {', '.join(KNOBS)}")
    if not np.all(np.isfinite(value)) or np.any(value < 0):
        raise ValueError(f"knob {name!r} must be finite and ≥ 0, got {value!r}")
    getattr(e, name)[:] = value


def run_recording(
    rec: Recording,
    setup: RealFilterSetup,
    schedule: Mapping[str, Array] | None = None,
    interval_s: float = 0.5,
) -> RecordingRun:
    """Prepare and filter one recording on one lane."""
    return run_prepared(prepare(rec, setup), 1, schedule=schedule, interval_s=interval_s)
