"""The ZUPT-UKF online: feed IMU samples as they arrive, get the state after each.

:class:`ZuptStream` runs the filter of :mod:`pednav_env.replay.runner` on a
stream instead of a whole recording::

    from pednav_env.replay.stream import ZuptStream

    stream = ZuptStream(rate_hz=200.0)              # setup "real-fixed" by default
    for omega, f in sensor_blocks():                # (K, 3) rad/s and m/s², sensor axes
        out = stream.feed(omega, f)                 # states of the samples now done
        if len(out):
            print(out.time_s[-1], out.position_m[-1], out.stance[-1])
    out = stream.close()                            # a stream shorter than the still start

Samples must come at ``rate_hz``, in order, without gaps (fill them first, as
:func:`pednav_env.io.to_uniform` does for a recording). The walker must
stand still at the start: the stream holds its samples until the still span
for the alignment is known (:mod:`pednav_env.replay.start`: at most
``alignment_max_s`` plus 0.1 s, longer when the IMU moves at the very start),
then aligns (paper 003 eq 4), fixes the mounting rotation and the gravity as
the offline runner does, and from then on returns every sample's state as
soon as it is fed. Samples before the still span (a settling foot) and those
of the still span are returned with the initial state and ``navigating``
False.

Each call returns a :class:`StreamStates` with one row per sample that became
available: stream sample index, time (index / rate + ``start_time_s``),
position, velocity (navigation frame, east-north-up, 0 at the start of
navigation), attitude (ψ, θ, γ: yaw, pitch, roll, paper 003's 3-2-1 Euler
angles of body → navigation), detected stance, and with ``covariance=True``
the diagonal of the state covariance (:func:`pednav_env.replay.runner.
state_covariance`; the filter then advances one sample per call, about
0.3 ms of CPU per sample). The knobs (:data:`pednav_env.replay.runner.KNOBS`) may be
changed between calls (:meth:`ZuptStream.set_knobs`).

Fed the samples of a recording in blocks of any size, the stream gives the
offline run's track to rounding (tests/replay/test_stream.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pednav_env.nav.detectors import shoe_statistic, window_samples
from pednav_env.nav.mounting import mounting_rotation, rotate_samples
from pednav_env.nav.zupt_model import STATE_DIM
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.replay.runner import set_knob, state_covariance, with_gravity_of
from pednav_env.replay.setup import RealFilterSetup, named_setup
from pednav_env.replay.start import find_still_start

Array = NDArray[np.float64]


@dataclass(frozen=True)
class StreamStates:
    """States of K consecutive stream samples (arrays of length K).

    ``euler_rad`` is (ψ, θ, γ) = (yaw, pitch, roll); ``covariance_diag`` is in
    the filter's state order (position, velocity, pitch, roll, yaw) or None.
    """

    sample: NDArray[np.int64]
    time_s: Array
    position_m: Array
    velocity_mps: Array
    euler_rad: Array
    stance: NDArray[np.bool_]
    navigating: NDArray[np.bool_]
    covariance_diag: Array | None

    def __len__(self) -> int:
        return int(self.sample.size)


def _states(
    first: int,
    rate_hz: float,
    start_time_s: float,
    x: Array,
    stance: NDArray[np.bool_],
    navigating: NDArray[np.bool_],
    cov: Array | None,
) -> StreamStates:
    k = x.shape[0]
    sample = np.arange(first, first + k, dtype=np.int64)
    return StreamStates(
        sample,
        start_time_s + sample / rate_hz,
        x[:, 0:3].copy(),
        x[:, 3:6].copy(),
        x[:, [8, 6, 7]].copy(),
        np.asarray(stance, dtype=bool),
        np.asarray(navigating, dtype=bool),
        cov,
    )


class ZuptStream:
    """The ZUPT-UKF on a stream of IMU samples (module docstring).

    Parameters
    ----------
    rate_hz : Hz, the sample rate.
    setup : a :class:`RealFilterSetup` or a shipped setup's name
        (``"real-fixed"``, ``"paper"``).
    covariance : also return the diagonal of the state covariance per sample.
    start_time_s : s, time of stream sample 0.
    """

    def __init__(
        self,
        rate_hz: float,
        setup: RealFilterSetup | str = "real-fixed",
        covariance: bool = False,
        start_time_s: float = 0.0,
    ) -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz must be a finite number > 0, got {rate_hz!r}")
        self.rate_hz = float(rate_hz)
        self.setup = named_setup(setup) if isinstance(setup, str) else setup
        self.covariance = bool(covariance)
        self.start_time_s = float(start_time_s)
        self.engine: ZuptUkf | None = None
        self.C_bs: Array | None = None
        #: Samples left out before the still span, and the still span's length.
        self.skipped = 0
        self.n_align = 0
        self._raw_w: list[Array] = []
        self._raw_f: list[Array] = []
        self._fed = 0
        self._done = 0
        self._knobs: dict[str, float] = {}
        self._tail_w = np.zeros((0, 3))
        self._tail_f = np.zeros((0, 3))
        self._last: StreamStates | None = None

    # ------------------------------------------------------------------ queries
    @property
    def aligned(self) -> bool:
        """True once the still span is known and the filter runs."""
        return self.engine is not None

    @property
    def samples_fed(self) -> int:
        return self._fed

    @property
    def state(self) -> StreamStates | None:
        """The latest sample's state (a one-row :class:`StreamStates`), or None."""
        return self._last

    # ------------------------------------------------------------------ control
    def set_knobs(self, **values: float) -> None:
        """Set filter knobs (names in :data:`pednav_env.replay.runner.KNOBS`) from
        the next sample on; before the alignment they are kept until it."""
        for name, value in values.items():
            self._knobs[name] = float(value)
            if self.engine is not None:
                set_knob(self.engine, name, np.array([float(value)]))

    def feed(self, omega_b: Array, f_b: Array) -> StreamStates:
        """Feed samples ``(K, 3)`` (or one ``(3,)``): angular rate (rad/s) and
        specific force (m/s²) in the sensor's axes. Returns the states of the
        samples that became available (none while the still span is not known)."""
        w = np.atleast_2d(np.asarray(omega_b, dtype=float))
        f = np.atleast_2d(np.asarray(f_b, dtype=float))
        if w.ndim != 2 or w.shape[1] != 3 or f.shape != w.shape:
            raise ValueError(f"omega_b and f_b must be (K, 3) alike, got {w.shape}, {f.shape}")
        if not (np.isfinite(w).all() and np.isfinite(f).all()):
            k = int(np.flatnonzero(~(np.isfinite(w).all(1) & np.isfinite(f).all(1)))[0])
            raise ValueError(f"stream sample {self._fed + k} has a NaN or inf value")
        self._fed += w.shape[0]
        if self.engine is not None:
            return self._filter(w, f)
        self._raw_w.append(w)
        self._raw_f.append(f)
        return self._try_align(final=False)

    def close(self) -> StreamStates:
        """End of the stream: align on what was fed if that was not done yet
        (``ValueError`` if the IMU was never still, or nothing followed the still
        span); returns the states not returned yet."""
        if self.engine is not None:
            return self._empty()
        if self._fed == 0:
            raise ValueError("the stream ended before any sample was fed")
        out = self._try_align(final=True)
        if self._done < self._fed or self.engine is None:
            raise ValueError(
                f"the stream ended after {self._fed} samples "
                f"({self._fed / self.rate_hz:.2f} s), within the still start used for the "
                "alignment: a walk must follow it"
            )
        return out

    # ------------------------------------------------------------------ internals
    def _empty(self) -> StreamStates:
        none = np.zeros(0, dtype=bool)
        cov = np.zeros((0, STATE_DIM)) if self.covariance else None
        x = np.zeros((0, STATE_DIM))
        return _states(self._done, self.rate_hz, self.start_time_s, x, none, none, cov)

    def _try_align(self, final: bool) -> StreamStates:
        w = np.concatenate(self._raw_w)
        f = np.concatenate(self._raw_f)
        s = self.setup
        found = find_still_start(
            w, f, self.rate_hz, s.alignment_max_s, s.alignment_min_s, final=final
        )
        if found is None:
            return self._empty()
        skip, na = found
        if final and len(w) <= skip + na:
            return self._empty()
        self.skipped, self.n_align = skip, na
        self.C_bs = mounting_rotation(s.mounting, f[skip : skip + na])
        wb = rotate_samples(self.C_bs, w[skip:])
        fb = rotate_samples(self.C_bs, f[skip:])
        self.setup = with_gravity_of(s, fb[:na])
        e = ZuptUkf(self.setup.filter, self.rate_hz, 1)
        for name, value in self._knobs.items():
            set_knob(e, name, np.array([value]))
        e.initialize(fb[None, :na], omega_align_b=wb[None, :na])
        self.engine = e
        self._raw_w, self._raw_f = [], []
        self._tail_w, self._tail_f = wb[:na], fb[:na]
        x0 = np.broadcast_to(e.mean_state()[0], (skip + na, STATE_DIM))
        x0 = np.where(np.arange(skip + na)[:, None] < skip, 0.0, x0)
        cov0 = None
        if self.covariance:
            cov0 = np.broadcast_to(np.diagonal(e.P[0]), (skip + na, STATE_DIM)).copy()
        quiet = np.zeros(skip + na, dtype=bool)
        head = _states(0, self.rate_hz, self.start_time_s, x0, quiet, quiet, cov0)
        self._done = skip + na
        self._last = _row(head, -1)
        rest = self._filter(wb[na:], fb[na:], rotated=True)
        return _concat(head, rest)

    def _filter(self, w: Array, f: Array, rotated: bool = False) -> StreamStates:
        """Advance the filter through new samples (sensor axes unless ``rotated``)."""
        e = self.engine
        k = w.shape[0]
        if k == 0:
            return self._empty()
        if not rotated:
            w, f = rotate_samples(self.C_bs, w), rotate_samples(self.C_bs, f)
        shoe = None
        if e.uses_shoe:
            det = self.setup.filter.detector
            n = window_samples(det.window_s, self.rate_hz)
            tw = np.concatenate((self._tail_w, w))
            tf = np.concatenate((self._tail_f, f))
            shoe = shoe_statistic(tw[None], tf[None], det, self.rate_hz)[:, -k:]
            keep = max(n - 1, 0)
            self._tail_w, self._tail_f = tw[len(tw) - keep :], tf[len(tf) - keep :]
        if self.covariance:
            x = np.empty((k, STATE_DIM))
            cov = np.empty((k, STATE_DIM))
            stance = np.empty(k, dtype=bool)
            for j in range(k):
                res = e.advance(
                    w[None, j : j + 1],
                    f[None, j : j + 1],
                    None if shoe is None else shoe[:, j : j + 1],
                    record="state",
                )
                x[j], stance[j] = res.states[0, 0], res.stance[0, 0]
                cov[j] = state_covariance(e, diagonal=True)[0]
        else:
            res = e.advance(w[None], f[None], shoe, record="state")
            x, stance, cov = res.states[0], res.stance[0], None
        out = _states(
            self._done, self.rate_hz, self.start_time_s, x, stance, np.ones(k, dtype=bool), cov
        )
        self._done += k
        self._last = _row(out, -1)
        return out


def _row(states: StreamStates, i: int) -> StreamStates:
    """Row ``i`` of ``states`` as a one-row :class:`StreamStates`."""
    sl = slice(i, i + 1 if i != -1 else None)
    return _map(states, lambda a: a[sl])


def _concat(a: StreamStates, b: StreamStates) -> StreamStates:
    if len(b) == 0:
        return a
    return StreamStates(
        *(
            None if x is None else np.concatenate((x, y))
            for x, y in zip(_fields(a), _fields(b), strict=True)
        )
    )


def _fields(s: StreamStates) -> tuple:
    return (
        s.sample,
        s.time_s,
        s.position_m,
        s.velocity_mps,
        s.euler_rad,
        s.stance,
        s.navigating,
        s.covariance_diag,
    )


def _map(s: StreamStates, fn) -> StreamStates:
    return StreamStates(*(None if x is None else fn(x) for x in _fields(s)))
