"""Batched episode engine behind ``pednav/MarkerTrack-v0`` (scalar and vector).

One implementation for any number of lanes: the scalar environment is this
core with N = 1, the native vector environment the same core with
N = ``num_envs``. Each lane owns its episode (walk, UWB record, seed); all
lanes step through the marker EKF of paper 001 together, one UWB sample at a
time, in one numpy call chain through the one marker filter of the package,
:class:`pednav_env.nav.marker_ekf.MarkerEkfEngine` (which also serves the
paper-001 reproduction), repaired once per decision interval.

Episode (:mod:`pednav_env.envs.marker_episode`): a walk of the heel–knee
model (thesis eqs 4.1–4.11, :mod:`pednav_env.gait.heel_knee`) seen by a UWB
sensor (:mod:`pednav_env.sensors.uwb`), both drawn from the lane's generator;
settings in :mod:`pednav_env.envs.marker_config`. A decision interval is
``decision_interval_s`` of UWB data (default 0.5 s = 5 samples at 10 Hz). The
action sets the filter's knobs for the next interval as ``base · span ** a``
(log scale; a = 0 is the paper's EKF).

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
  harmonic or lose the trend (docs/REPRODUCTION.md, paper 001, mechanism E); it
  does not recover. A lane terminates (divergence) when its state or
  covariance is not finite, when its cadence estimate ω̂ = ω₀ + Δω̂ leaves
  ``cadence_bounds`` × ω₀, or when the interval's RMS marker error exceeds
  ``divergence_error_m`` (lock loss).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from pednav_env.envs.marker_config import ACTION_KNOBS, CONTEXT_FIELDS, MarkerTrackConfig
from pednav_env.envs.marker_episode import generate_episode
from pednav_env.envs.spec import ObsFeature, obs_bounds, validate_action
from pednav_env.gait.heel_knee_model import I_CX, I_OMEGA, PARAM_NAMES
from pednav_env.nav.marker_ekf import MarkerEkfEngine
from pednav_env.nav.marker_model import DIM_X, DIM_Z, MarkerEkfConfig

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Q group (index into ACTION_KNOBS) of each state component, eq 4.9 order
#: [ΔA_x, ΔA_z, Δc_x, Δc_z, ΔA, Δω]: amplitudes, trend, cadence.
Q_GROUP: tuple[int, ...] = (0, 0, 1, 1, 0, 2)
#: Coordinates of a marker record, in the order of eq 4.12.
COORDS: tuple[str, ...] = ("heel_x", "heel_z", "knee_x", "knee_z")

#: Observation entries; documented in the env docstring.
OBS_FEATURES: tuple[ObsFeature, ...] = (
    ObsFeature("dropped_fraction", 0.0, 1.0),
    ObsFeature("log_nis_mean", 0.0, 30.0),
    ObsFeature("log_nis_max", 0.0, 30.0),
    ObsFeature("nis_gate_fraction", 0.0, 1.0),
    *(ObsFeature(f"nu_rms_{c}", 0.0, 100.0) for c in COORDS),
    *(ObsFeature(f"nu_mean_{c}", -100.0, 100.0) for c in COORDS),
    *(ObsFeature(f"log10_rel_std_{p}", -8.0, 4.0) for p in PARAM_NAMES),
    *(ObsFeature(f"rel_dev_{p}", -10.0, 10.0) for p in PARAM_NAMES),
    ObsFeature("time_since_anchor", 0.0, 3600.0, "s"),
)

#: Error (× ``divergence_error_m``) booked for a lane whose estimate is not finite.
NONFINITE_ERROR_FACTOR = 10.0

#: χ² 99 % quantiles of the NIS by degrees of freedom (valid coordinates 0–4).
CHI2_99 = np.array([np.inf, *chi2.ppf(0.99, [1, 2, 3, 4])])


# --------------------------------------------------------------------------- filter engine


class Engine(Protocol):
    """What the core needs from a batched marker filter (lanes first):
    :class:`~pednav_env.nav.marker_ekf.MarkerEkfEngine`, or the benchmark's
    filterpy reference (``pednav_env.testing.reference_marker.FilterpyMarkerEngine``)."""

    x: Array  # (N, 6)
    P: Array  # (N, 6, 6)
    q: Array  # (N, 6) diagonal of Γ Q Γᵀ in force
    r: Array  # (N, 4) diagonal of R in force
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
    lane count and interval length; numpy's pairwise reductions associate
    differently from eight terms on)."""
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

    Everything the core takes and returns is lanes first, as the engine's
    state. The scratch arrays of one interval (``interval_est``,
    ``interval_truth``: ``(k, 4, N)``; ``interval_active``: ``(k, N)``) are
    sample- and coordinate-major, so that the interval's sums and features run
    along the lanes (numpy reduces a short last axis row by row, which is
    several times slower at N = 256).
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
        #: The privileged episode context (CONTEXT_FIELDS), per lane.
        self.context = np.zeros((n, len(CONTEXT_FIELDS)))
        self.action = np.zeros((n, config.action_dim))
        self.clipped = np.zeros(n, dtype=np.int64)
        self.reanchors = np.zeros(n, dtype=np.int64)
        self.last_error = np.zeros(n)
        self.lanes = np.arange(n)
        self.obs_low, self.obs_high = obs_bounds(OBS_FEATURES, config.action_dim)
        self.obs = np.zeros((n, len(OBS_FEATURES) + config.action_dim), dtype=np.float32)
        self._obs_low64 = self.obs_low.astype(np.float64)[:, None]
        self._obs_high64 = self.obs_high.astype(np.float64)[:, None]
        self._prior_obs: NDArray[np.float32] | None = None
        self._abs_p0 = np.abs(config.filter.nominal.vector)[:, None]
        self._log10_abs_p0 = np.log10(self._abs_p0)
        self._qgroup = np.asarray(Q_GROUP)
        self._knob_base = np.array([knob.base for knob in ACTION_KNOBS])
        self._knob_log_span = np.log([knob.span for knob in ACTION_KNOBS])
        # q and r of action 0 (what _apply_action sets for a lane after reset)
        rest = self._knob_base * np.exp(np.zeros(config.action_dim) * self._knob_log_span)
        self._q_rest = self.engine.q0 * rest[self._qgroup]
        self._r_rest = self.engine.r0 * rest[3]
        self._scale_buf = np.empty((n, config.action_dim))
        #: The last interval: estimates and truth (k, 4, N), samples in the walk (k, N).
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
            conditions = self.config.uwb_conditions
            index = conditions.index(ep.uwb_condition) if ep.uwb_condition in conditions else -1
            self.context[lane] = (index, ep.uwb_noise_factor)
        self.engine.reset(lanes)
        self.ep_start[lanes] = self.g
        self.cursor[lanes] = 0
        self.distance[lanes] = 0.0
        self.action[lanes] = 0.0
        self.clipped[lanes] = 0
        self.reanchors[lanes] = 0
        self.last_error[lanes] = 0.0
        self.engine.q[lanes] = self._q_rest  # _apply_action(lanes) at action 0
        self.engine.r[lanes] = self._r_rest
        if self._prior_obs is None:  # the same for every lane: no data, prior P, action 0
            self._prior_obs = self._features(lanes[:1], None)[0]
        self.obs[lanes] = self._prior_obs

    # ------------------------------------------------------------------ action
    def validate_action(self, action: Any) -> Array:
        """Shape ``(N, k)``, numeric and finite (:func:`spec.validate_action`); float64."""
        return validate_action(action, (self.n, self.config.action_dim), self.env_name)

    def _scales(self, lanes: NDArray[np.integer] | slice) -> Array:
        """Knob values base · span**a = base · exp(a ln span), ``(B, k)``."""
        return self._knob_base * np.exp(self.action[lanes] * self._knob_log_span)

    def _apply_action(self) -> None:
        """Set every lane's Q and R diagonals from its action (in place: the
        numbers of :meth:`_scales`)."""
        e = self.engine
        scales = self._scale_buf
        scales[...] = self.action
        scales *= self._knob_log_span
        np.exp(scales, out=scales)
        scales *= self._knob_base
        np.multiply(e.q0, scales[:, self._qgroup], out=e.q)
        np.multiply(e.r0, scales[:, 3:4], out=e.r)

    def knob_values(self) -> dict[str, Array]:
        """Current physical value of every knob, per lane."""
        scales = self._scales(slice(None))
        return {knob.name: scales[:, i] for i, knob in enumerate(ACTION_KNOBS)}

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
        xs = np.empty((k, self.n, DIM_X))  # posterior after each sample
        with np.errstate(all="ignore"):  # diverging lanes are detected below
            for j in range(k):
                e.predict()
                if j == 0 and fresh.size:  # an episode's first sample: the prior
                    e.reset(fresh)
                nu[j] = e.update(z[j].T, valid[j].T, times[j]).T  # copies the buffer
                xs[j] = e.x
            # estimated markers h(x̂ₖ) of all the interval's samples at once (the
            # anchor only moves between intervals)
            est = self.interval_est  # (k, 4, N)
            est[...] = e.markers(times.T, xs.transpose(1, 0, 2)).transpose(1, 2, 0)
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
        omega = e.p0[I_OMEGA] + e.x[:, I_OMEGA]
        lo, hi = c.cadence_bounds
        nominal_omega = e.p0[I_OMEGA]
        finite = ~nonfinite & np.isfinite(e.x).all(axis=1)
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
        omega = e.p0[I_OMEGA] + e.x[idx, I_OMEGA]  # > 0 for lanes not diverged
        t_anchor = e.t_anchor[idx]
        span = t_now[idx] - c.reanchor_keep_s - t_anchor
        with np.errstate(all="ignore"):
            cycles = np.floor(omega * span / (2.0 * math.pi))
            shift = 2.0 * math.pi * cycles / omega
        moved = (cycles >= 1) & (shift > 0)
        idx, shift = idx[moved], shift[moved]
        c_x = e.p0[I_CX] + e.x[idx, I_CX]
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
            diag = e.P.reshape(-1, DIM_X * DIM_X)[lanes, :: DIM_X + 1].T
            out[12:18] = 0.5 * np.log10(diag) - self._log10_abs_p0
            out[18:24] = e.x[lanes].T / self._abs_p0
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
    "CHI2_99",
    "COORDS",
    "OBS_FEATURES",
    "Q_GROUP",
    "MarkerTrackCore",
]
