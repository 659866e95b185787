"""Batched episode engine behind ``pednav/WaistStep-v0`` (scalar and vector).

One implementation for any number of lanes: the scalar environment is this
core with N = 1, the native vector environment the same core with
N = ``num_envs``. Each lane owns its episode (walk, sensor record, seed); all
lanes step together through paper 004's step detector and step-fusion
Kalman filter (:func:`pednav_env.nav.waist_dr.detect_steps`,
:class:`pednav_env.nav.step_fusion_kf.StepFusionKF`) in one numpy call chain.
Spaces and settings are in :mod:`pednav_env.envs.waist_config`, the episode
draw in :mod:`pednav_env.envs.waist_episode`.

Episode (papers 000 and 004): a walker with a belt-level IMU walks a chain of
inverted-pendulum steps (:mod:`pednav_env.gait.pendulum`) with turns, stops,
slopes and gait changes (:mod:`pednav_env.gait.waist_walk`). Sensors
(:mod:`pednav_env.sensors.waist_record`):

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
:func:`pednav_env.nav.step_velocity.pendulum_step_velocity`) with the filter's
assumed leg length l, plus the walker's step-to-step irregularity n (paper
004: V̄^BM = V̄ + n); projected on the INS heading; then the filter's eqs (3)–(6).
Between boundaries the position estimate runs on the INS velocity corrected by
the extrapolated error, V^INS − HΦ(τ)x̂ (eq 5 over the open step), so that at
each boundary it equals eq (6).

A decision interval is ``decision_interval_s`` of sensor data (default 0.5 s,
50 samples at 100 Hz). The action sets the detector and filter knobs for the
next interval; a = 0 is paper 004's configuration
(:data:`pednav_env.envs.waist_config.ACTION_KNOBS`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from pednav_env.envs.spec import obs_bounds, validate_action
from pednav_env.envs.waist_config import (
    ACTION_DIM,
    ACTION_KNOBS,
    CONTEXT_FIELDS,
    OBS_FEATURES,
    WaistStepConfig,
)
from pednav_env.envs.waist_episode import generate_episode
from pednav_env.nav.step_fusion_kf import StepFusionKF
from pednav_env.nav.step_velocity import pendulum_step_velocity, prefix_integrals
from pednav_env.nav.waist_dr import StepDetectorConfig, StepDetectorState, detect_steps
from pednav_env.sensors.ins_error import CHANNEL_SIGN

Array = NDArray[np.float64]

#: A detected boundary within this time of a simulated footfall, start or stop
#: counts as a true detection (info only).
TRUE_DETECTION_WINDOW_S = 0.03


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
        #: The privileged episode context (CONTEXT_FIELDS), per lane.
        self.context = np.zeros((n, len(CONTEXT_FIELDS)))
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
        self.obs_low, self.obs_high = obs_bounds(OBS_FEATURES, ACTION_DIM)

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
            c1, c2 = prefix_integrals(ep.a_up, self.dt, "delta_v")  # O(1) per step later
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
            grades = c.sensor_grades
            self.context[lane] = (
                grades.index(ep.sensor_grade) if ep.sensor_grade in grades else -1,
                ep.accel_noise_scale,
                ep.bm_noise_scale,
                ep.vibration_amplitude_mps2,
            )
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
        """Shape ``(N, 5)``, numeric and finite (:func:`spec.validate_action`); float64."""
        return validate_action(action, (self.n, ACTION_DIM), self.env_name)

    def _apply_action(self, lanes: NDArray[np.integer]) -> None:
        a = self.action[lanes]
        for i, knob in enumerate(ACTION_KNOBS):
            self.knobs[lanes, i] = knob.value(a[:, i])
        self.kf.q_scale = self.knobs[:, 4]  # Q × scale
        self.kf.r_scale = self.knobs[:, 3] ** 2  # R = σ_n² × scale²

    def knob_values(self) -> dict[str, Array]:
        """Current physical value of every knob, per lane."""
        return {knob.name: self.knobs[:, i].copy() for i, knob in enumerate(ACTION_KNOBS)}

    # ------------------------------------------------------------------ filter
    def _close_steps(self, boundary: NDArray[np.bool_], first: NDArray[np.int64]) -> Array:
        """Process the interval's step boundaries: the measurements of all detected
        steps at once, then the filter updates in order
        (:meth:`StepFusionKF.step_sequence`: round j = every lane's j-th
        boundary). Returns the sum of log(1 + NIS) per lane."""
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
        y, S = self.kf.step_sequence(lane_e, v_ins, vb, T)  # eqs (3)–(6)
        nis = np.sum(y * y / S, axis=1)
        log_nis_e = np.log1p(np.where(np.isfinite(nis), nis, 1e12))
        for j in range(int(counts.max())):
            sel = np.flatnonzero(counts > j)
            e = start[sel] + j
            nis_sum[sel] += log_nis_e[e]
            prev = self.step_avg_s[sel]
            self.step_avg_s[sel] = np.where(prev > 0, 0.8 * prev + 0.2 * T[e], T[e])
        has = np.flatnonzero(counts)
        e = start[has] + counts[has] - 1  # each lane's last event
        self.last_b[has] = j1[e]
        self.nis_last[has] = log_nis_e[e]
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
        self.last_error = err.copy()  # info["error"] must not change when a lane resets
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
