"""How the foot turns during the swing, in three axes, from the IMU alone
(docs/SIM_TO_REAL.md, "The swing in three axes").

A swing (the non-stance runs of :mod:`pednav_env.calibration.swing_phases`: stance from
the walk's labels or the simulator's truth, :data:`~pednav_env.calibration.swing_phases.
MIN_SWING_S` to :data:`~pednav_env.calibration.swing_phases.MAX_SWING_S`) is short enough
to integrate the IMU over it without any reference: a strapdown from the stance that ends
it to the stance that follows.

- **Start attitude.** The tilt from the mean specific force of the last
  :data:`TILT_WINDOW_S` of the stance before the swing (pitch θ = asin(−f_x/|f|), roll
  γ = atan2(f_y, f_z), paper 003 eq 4), yaw 0.
- **Attitude.** C_nb integrated sample by sample, C ← C · exp([ω Δt]×) (Rodrigues).
- **Heading of the stride.** The velocity integrated from the specific force
  (v ← v + (C f − g e_z) Δt) and pulled to zero at both ends by a linear correction
  (a zero-velocity update at each end); the horizontal displacement's direction h.
  Swings whose displacement is shorter than :data:`MIN_DISPLACEMENT_M` are left out:
  their heading is not defined.
- **The turn.** ΔC = C_k C_0ᵀ, the foot's rotation in the navigation frame since the
  stance (the sensor's mounting in the shoe cancels), seen in the stride's frame
  (x along h, z up): A_k = R_z(h)ᵀ ΔC R_z(h), split into yaw ψ, pitch θ and roll γ in the
  3-2-1 order of :mod:`pednav_env.rotations` (paper 003 eq 1; positive pitch turns the
  toes down). On a straight stride these are the foot's Euler angles relative to its
  heading, as the simulator draws them (:func:`pednav_env.gait.foot.build_schedule`);
  on a stride that turns, the foot's heading leaves the stride's direction and pitch
  and roll mix by the difference. The yaw at the end of the swing is the stride's
  turn. The same function on recorded and simulated walks compares like with like.

Left and right feet mirror each other about the sagittal plane (yaw and roll change
sign), so a walk's yaw and roll are signed to make the walk's median roll over the middle
of its swings (phases 0.4–0.6) non-negative. At the end of a swing the foot stands flat
again: the end pitch and roll (``end_tilt_rad``) measure how well the integration and the
stance labels hold.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from pednav_env.calibration.stats import (
    StanceSource,
    WalkSamples,
    log10_shoe,
    runs,
    walking_stance,
)
from pednav_env.calibration.swing_phases import MAX_SWING_S, MIN_SWING_S
from pednav_env.rotations import dcm_to_euler

Array = NDArray[np.float64]

#: Stance time (s) before a swing whose mean specific force gives the start tilt.
TILT_WINDOW_S = 0.05
#: Shortest horizontal displacement (m) of a swing whose heading is used.
MIN_DISPLACEMENT_M = 0.2


class SwingAttitudes(NamedTuple):
    """A walk's swing samples (module docstring): per sample ``(K,)`` its phase in the
    swing and the foot's yaw, pitch and roll (rad) relative to the stance before, in
    the stride's frame; per swing ``(S,)`` the end tilt (rad, √(θ² + γ²) at the last
    sample) and the swing's mean horizontal speed (m/s, from the integration)."""

    phase: Array
    yaw_rad: Array
    pitch_rad: Array
    roll_rad: Array
    end_tilt_rad: Array
    swing_speed_mps: Array


def _rodrigues(rotvec: Array) -> Array:
    """exp([r]×) for one rotation vector ``(3,)``."""
    angle = float(np.sqrt(rotvec @ rotvec))
    if angle < 1e-12:
        return np.eye(3)
    k = rotvec / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * (kx @ kx)


def _start_attitude(f_mean: Array) -> Array:
    """C_nb with yaw 0 and the tilt of a foot at rest whose specific force is ``f_mean``."""
    norm = float(np.linalg.norm(f_mean))
    pitch = float(np.arcsin(np.clip(-f_mean[0] / norm, -1.0, 1.0)))
    roll = float(np.arctan2(f_mean[1], f_mean[2]))
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    return np.array([[cp, sp * sr, sp * cr], [0.0, cr, -sr], [-sp, cp * sr, cp * cr]])


def integrate_swing(
    omega_b: Array, f_b: Array, f_rest: Array, rate_hz: float, g: float
) -> tuple[Array, Array, float]:
    """One swing's strapdown (module docstring): the ``(n, 3)`` (ψ, θ, γ) of each sample
    relative to the start, in the stride's frame, the horizontal displacement ``(2,)``
    (m) and its heading h (rad). ``omega_b`` and ``f_b`` are the swing's ``(n, 3)``
    samples, ``f_rest`` the mean specific force of the stance before it."""
    n = omega_b.shape[0]
    dt = 1.0 / rate_hz
    c0 = _start_attitude(f_rest)
    c = np.empty((n + 1, 3, 3))
    c[0] = c0
    for k in range(n):
        c[k + 1] = c[k] @ _rodrigues(omega_b[k] * dt)
    accel = np.einsum("kij,kj->ki", c[:n], f_b) - np.array([0.0, 0.0, g])
    v = np.concatenate((np.zeros((1, 3)), np.cumsum(accel * dt, axis=0)))
    v -= np.linspace(0.0, 1.0, n + 1)[:, None] * v[-1]
    disp = np.sum(0.5 * (v[1:] + v[:-1]), axis=0)[:2] * dt
    h = float(np.arctan2(disp[1], disp[0]))
    ch, sh = np.cos(h), np.sin(h)
    rz = np.array([[ch, -sh, 0.0], [sh, ch, 0.0], [0.0, 0.0, 1.0]])
    delta = c[1:] @ c0.T
    stride_frame = rz.T @ delta @ rz
    return dcm_to_euler(stride_frame), disp, h


def swing_attitudes(samples: WalkSamples) -> SwingAttitudes:
    """The walk's swings in three axes (module docstring); ValueError when the walk's
    stance comes from the detector rule (no labels, no truth stance)."""
    s = samples
    rate = float(s.rate_hz)
    log_t = log10_shoe(s.omega_b, s.f_b, rate, s.g)
    source, stance, walking = walking_stance(s, log_t)
    if source == StanceSource.DETECTOR:
        raise ValueError(f"{s.name}: swing attitudes need stance labels or truth stance")
    window = max(1, int(round(TILT_WINDOW_S * rate)))
    phases, angles, end_tilt, speed = [], [], [], []
    for a, b in zip(*runs(walking & ~stance), strict=True):
        n = int(b - a)
        if not (MIN_SWING_S * rate <= n <= MAX_SWING_S * rate) or a < window:
            continue
        if not stance[a - window : a].all():
            continue
        f_rest = s.f_b[a - window : a].mean(axis=0)
        euler, disp, _ = integrate_swing(s.omega_b[a:b], s.f_b[a:b], f_rest, rate, s.g)
        if float(np.hypot(*disp)) < MIN_DISPLACEMENT_M:
            continue
        phases.append((np.arange(n) + 0.5) / n)
        angles.append(euler)
        end_tilt.append(float(np.hypot(euler[-1, 1], euler[-1, 2])))
        speed.append(float(np.hypot(*disp)) * rate / n)
    if not phases:
        return SwingAttitudes(*(np.zeros(0) for _ in range(6)))
    phase, euler = np.concatenate(phases), np.concatenate(angles)
    yaw, pitch, roll = euler[:, 0], euler[:, 1], euler[:, 2]
    middle = (phase > 0.4) & (phase < 0.6)
    if middle.any() and np.median(roll[middle]) < 0:
        yaw, roll = -yaw, -roll
    return SwingAttitudes(phase, yaw, pitch, roll, np.array(end_tilt), np.array(speed))


def pooled(walks: Sequence[WalkSamples]) -> SwingAttitudes:
    """The swing attitudes of ``walks`` end to end."""
    parts = [swing_attitudes(w) for w in walks]
    return SwingAttitudes(
        *(np.concatenate([p[i] for p in parts]) if parts else np.zeros(0) for i in range(6))
    )


def attitude_profile(walks: Sequence[WalkSamples], bins: int = 10) -> dict[str, Any]:
    """Per phase bin (``bins`` equal bins of [0, 1)) over the swings of ``walks``: the
    median, 25th and 75th percentile of yaw, pitch and roll (rad) and the median
    off-sagittal angle √(ψ² + γ²) (lists, None where a bin is empty), with
    ``bin_edges``, ``swings``, ``swing_samples`` and the swings' median end tilt (rad)."""
    if bins < 1:
        raise ValueError(f"bins must be ≥ 1, got {bins}")
    every = pooled(walks)
    index = np.minimum((every.phase * bins).astype(int), bins - 1)
    off = np.hypot(every.yaw_rad, every.roll_rad)
    out: dict[str, Any] = {
        "bin_edges": np.linspace(0.0, 1.0, bins + 1).tolist(),
        "swings": int(every.end_tilt_rad.size),
        "swing_samples": int(every.phase.size),
        "end_tilt_median_rad": (
            float(np.median(every.end_tilt_rad)) if every.end_tilt_rad.size else None
        ),
    }
    series = {"yaw": every.yaw_rad, "pitch": every.pitch_rad, "roll": every.roll_rad}
    for name in series:
        for stat in ("median", "p25", "p75"):
            out[f"{name}_{stat}_rad"] = []
    out["off_sagittal_median_rad"] = []
    for k in range(bins):
        m = index == k
        for name, values in series.items():
            for stat, q in (("median", 50), ("p25", 25), ("p75", 75)):
                out[f"{name}_{stat}_rad"].append(
                    float(np.percentile(values[m], q)) if m.any() else None
                )
        out["off_sagittal_median_rad"].append(float(np.median(off[m])) if m.any() else None)
    return out
