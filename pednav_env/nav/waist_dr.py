"""Waist-IMU dead reckoning and step detection of papers 002 and 004, batched over walkers.

- :func:`euler_dead_reckoning` — paper 002's uncorrected strapdown scheme,
  steps 6–9, eqs (14)–(17), written in our frames (docs/CONVENTIONS.md) (the mapping of
  the paper's axes is in :mod:`pednav_env.gait.robot`).
- :func:`detect_steps` — step boundaries as upward crossings of |f| − g
  (paper 004: "the moment of transition through zero of the difference of
  the accelerometer vector modulus and g"), with a threshold, a hysteresis
  and a minimum step duration (seconds) as tunable parameters; streamable.
- :func:`boundaries_to_steps` — consecutive boundaries as step edges.

The step-velocity maths (paper 000's V̄^ЧП and the pendulum velocity V̄^BM of
papers 000/004) are in :mod:`pednav_env.nav.step_velocity`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.checks import require_positive
from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.rotations import euler_to_dcm

Array = NDArray[np.float64]


# --------------------------------------------------------------------------- paper 002
def euler_rates_from_body(euler: ArrayLike, omega_b: ArrayLike) -> Array:
    """[ψ̇, θ̇, γ̇] from body rates: the inverse of paper 002's eq (9) matrix.

    In our axes (paper 002's a_x, a_y, a_z = our y, z, x)::

        ψ̇ = (ω_y sin γ + ω_z cos γ) / cos θ
        θ̇ = ω_y cos γ − ω_z sin γ
        γ̇ = ω_x + ψ̇ sin θ

    which is the paper's [[cos ϑ sin γ, cos γ, 0], [cos ϑ cos γ, −sin γ, 0],
    [−sin ϑ, 0, 1]]⁻¹ applied to (ω_x, ω_y, ω_z)_paper, in closed form.
    """
    e = np.asarray(euler, dtype=float)
    w = np.asarray(omega_b, dtype=float)
    sp, cp = np.sin(e[..., 1]), np.cos(e[..., 1])
    sr, cr = np.sin(e[..., 2]), np.cos(e[..., 2])
    psi_dot = (w[..., 1] * sr + w[..., 2] * cr) / cp
    return np.stack(
        (psi_dot, w[..., 1] * cr - w[..., 2] * sr, w[..., 0] + psi_dot * sp),
        axis=-1,
    )


def euler_rates_transpose_hypothesis(euler: ArrayLike, omega_b: ArrayLike) -> Array:
    """Mᵀ ω instead of M⁻¹ ω in eq (14) — a *hypothesis* about paper 002's code.

    M of eq (9) is orthogonal when ϑ = 0, so its transpose is a tempting
    "inverse"; with pitch it is not: in our axes ::

        ψ̇' = cos θ sin γ ω_y + cos θ cos γ ω_z − sin θ ω_x
        θ̇' = ω_y cos γ − ω_z sin γ
        γ̇' = ω_x

    so a pitched body turning in yaw accumulates a roll error −∫ψ̇ sin θ dt.
    Not the printed scheme (docs/REPRODUCTION.md (papers 000/002/004)).
    """
    e = np.asarray(euler, dtype=float)
    w = np.asarray(omega_b, dtype=float)
    sp, cp = np.sin(e[..., 1]), np.cos(e[..., 1])
    sr, cr = np.sin(e[..., 2]), np.cos(e[..., 2])
    return np.stack(
        (
            cp * sr * w[..., 1] + cp * cr * w[..., 2] - sp * w[..., 0],
            w[..., 1] * cr - w[..., 2] * sr,
            w[..., 0],
        ),
        axis=-1,
    )


@dataclass(frozen=True)
class DeadReckoning:
    """Output of :func:`euler_dead_reckoning`, arrays (N, T, 3) at the input samples."""

    euler: Array
    vel_n: Array
    pos_n: Array


def euler_dead_reckoning(
    omega_b: ArrayLike,
    f_b: ArrayLike,
    dt: float,
    euler0: ArrayLike,
    vel0: ArrayLike,
    pos0: ArrayLike,
    g: float = STANDARD_GRAVITY,
    projection: Literal["current", "previous"] = "current",
    kinematics: Literal["inverse", "transpose"] = "inverse",
) -> DeadReckoning:
    """Paper 002's uncorrected strapdown scheme, eqs (14)–(17), for i = 1 … T−1.

    ::

        (14) [ψ, θ, γ](i) = [ψ, θ, γ](i−1) + M⁻¹(θ(i−1), γ(i−1)) ω̃(i) Δt
        (15) f_n(i) = C_nb(ψ(i), θ(i), γ(i)) f̃(i)
        (16) V(i) = V(i−1) + (f_n(i) − g e_up) Δt
        (17) x(i) = x(i−1) + V(i) Δt

    The kinematic matrix of (14) is evaluated with the attitude of the
    previous step — the one-step attitude delay the paper describes (the
    angles in use lag the rates just received). The paper integrates only
    the horizontal channels in (16)–(17); the vertical one is integrated the
    same way here and can be ignored. ``projection="previous"`` uses
    C_nb(i−1) in (15) instead — a variant (a further step of delay), not the
    printed scheme; ``kinematics="transpose"`` replaces M⁻¹ by Mᵀ
    (:func:`euler_rates_transpose_hypothesis`), also not the printed scheme.

    Parameters
    ----------
    omega_b, f_b : (N, T, 3)
        Sensor rates (rad/s) and specific force (m/s²); sample 0 is not used.
    dt : float
        Δt (s). Paper 002: 0.025 s.
    euler0, vel0, pos0 : (N, 3)
        Initial [ψ, θ, γ] (rad), velocity (m/s) and position (m).
    g : float
        Gravity (m/s²) removed from the vertical channel.

    Returns
    -------
    DeadReckoning
        Attitude, velocity and position at samples 0 … T−1.
    """
    require_positive("dt", dt)
    dt = float(dt)
    w = np.asarray(omega_b, dtype=float)
    f = np.asarray(f_b, dtype=float)
    if w.ndim != 3 or w.shape[-1] != 3 or w.shape != f.shape:
        raise ValueError(f"omega_b and f_b must both be (N, T, 3), got {w.shape} and {f.shape}")
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(f))):
        raise ValueError("omega_b/f_b contain NaN or inf")
    if projection not in ("current", "previous"):
        raise ValueError(f"projection must be 'current' or 'previous', got {projection!r}")
    if kinematics not in ("inverse", "transpose"):
        raise ValueError(f"kinematics must be 'inverse' or 'transpose', got {kinematics!r}")
    rates = euler_rates_from_body if kinematics == "inverse" else euler_rates_transpose_hypothesis
    n, t, _ = w.shape
    init = []
    for name, v in (("euler0", euler0), ("vel0", vel0), ("pos0", pos0)):
        a = np.asarray(v, dtype=float)
        try:
            a = np.broadcast_to(a, (n, 3))
        except ValueError:
            raise ValueError(f"{name} must be (N, 3) = ({n}, 3), got {a.shape}") from None
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} contains NaN or inf")
        init.append(a)
    euler = np.empty((n, t, 3))
    vel = np.empty((n, t, 3))
    pos = np.empty((n, t, 3))
    euler[:, 0], vel[:, 0], pos[:, 0] = init
    gvec = np.array([0.0, 0.0, g])
    for i in range(1, t):
        euler[:, i] = euler[:, i - 1] + rates(euler[:, i - 1], w[:, i]) * dt
        C = euler_to_dcm(euler[:, i] if projection == "current" else euler[:, i - 1])
        f_n = np.einsum("nij,nj->ni", C, f[:, i])
        vel[:, i] = vel[:, i - 1] + (f_n - gvec) * dt
        pos[:, i] = pos[:, i - 1] + vel[:, i] * dt
    return DeadReckoning(euler=euler, vel_n=vel, pos_n=pos)


# --------------------------------------------------------------------------- paper 004
@dataclass(frozen=True)
class StepDetectorConfig:
    """Step-boundary detector on d = |f| − g (paper 004). Defaults are the paper's
    pure zero crossing (threshold 0, no hysteresis, no minimum duration).

    A boundary is declared at the first sample where d ≥ ``threshold`` after
    d has been below ``threshold − hysteresis`` (armed), provided at least
    ``min_step_duration`` seconds have passed since the previous accepted
    boundary; a crossing that comes too early is consumed (the detector must
    re-arm). The upward crossing marks double support: during single support
    the pendulum hip accelerates downward (|f| < g, paper 000 eq 17), at the
    footfall the vertical velocity reverses (|f| > g).

    Attributes
    ----------
    threshold : float  (m/s²), any finite value
    hysteresis : float (m/s²), ≥ 0
    min_step_duration : float (s), ≥ 0
    g : float (m/s²), > 0
    """

    threshold: float = 0.0
    hysteresis: float = 0.0
    min_step_duration: float = 0.0
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        for name in ("threshold", "hysteresis", "min_step_duration", "g"):
            v = getattr(self, name)
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"StepDetectorConfig.{name} must be a finite number, got {v!r}")
        for name in ("hysteresis", "min_step_duration"):
            if getattr(self, name) < 0:
                raise ValueError(
                    f"StepDetectorConfig.{name} must be ≥ 0, got {getattr(self, name)!r}"
                )
        if self.g <= 0:
            raise ValueError(f"StepDetectorConfig.g must be > 0, got {self.g!r}")


@dataclass(frozen=True)
class StepDetectorState:
    """Carry-over between chunks: ``armed`` (N,) bool and ``since_last`` (N,) s,
    the time from the last accepted boundary to the last sample processed."""

    armed: NDArray[np.bool_]
    since_last: Array

    @classmethod
    def initial(cls, n: int) -> StepDetectorState:
        """Not armed; the first boundary is allowed at once."""
        return cls(armed=np.zeros(n, dtype=bool), since_last=np.full(n, np.inf))


def detect_steps(
    f_b: ArrayLike,
    dt: float,
    config: StepDetectorConfig | None = None,
    state: StepDetectorState | None = None,
    threshold: ArrayLike | None = None,
    hysteresis: ArrayLike | None = None,
    min_step_duration: ArrayLike | None = None,
) -> tuple[NDArray[np.bool_], StepDetectorState]:
    """Step boundaries from upward crossings of |f| − g (paper 004).

    Parameters
    ----------
    f_b : (N, T, 3)
        Specific force (m/s²), any axes (only the norm is used).
    dt : float
        Sample period (s).
    config : StepDetectorConfig, optional
    state : StepDetectorState, optional
        From the previous chunk (streaming); default :meth:`StepDetectorState.initial`.
    threshold, hysteresis, min_step_duration : (N,) arrays, optional
        Per-walker overrides of the config values (an agent's action).

    Returns
    -------
    boundary : (N, T) bool
        True at the samples where a step boundary is declared.
    state : StepDetectorState
    """
    require_positive("dt", dt)
    dt = float(dt)
    f = np.asarray(f_b, dtype=float)
    if f.ndim != 3 or f.shape[-1] != 3:
        raise ValueError(f"f_b must be (N, T, 3), got {f.shape}")
    if not np.all(np.isfinite(f)):
        raise ValueError("f_b contains NaN or inf")
    cfg = config if config is not None else StepDetectorConfig()
    n, t, _ = f.shape

    def per_walker(name: str, value: ArrayLike | None, lo: float) -> Array:
        v = getattr(cfg, name) if value is None else value
        a = np.broadcast_to(np.asarray(v, dtype=float), (n,))
        if not np.all(np.isfinite(a)) or np.any(a < lo):
            raise ValueError(f"{name} must be finite and ≥ {lo}, got {a!r}")
        return a

    thr = per_walker("threshold", threshold, -math.inf)
    hys = per_walker("hysteresis", hysteresis, 0.0)
    min_d = per_walker("min_step_duration", min_step_duration, 0.0)
    st = state if state is not None else StepDetectorState.initial(n)
    if st.armed.shape != (n,) or st.since_last.shape != (n,):
        raise ValueError(f"state is for {st.armed.shape[0]} walkers, data has {n}")

    d = np.sqrt(np.sum(f * f, axis=-1)) - cfg.g
    # Schmitt trigger, vectorised: +1 fire level, −1 arm level, 0 hold; forward-fill.
    level = np.where(d >= thr[:, None], 1, np.where(d < (thr - hys)[:, None], -1, 0))
    prev = np.where(st.armed, -1, 1)[:, None]
    full = np.concatenate((prev, level), axis=1)
    idx = np.where(full != 0, np.arange(t + 1)[None, :], 0)
    np.maximum.accumulate(idx, axis=1, out=idx)
    filled = np.take_along_axis(full, idx, axis=1)
    filled[:, 0] = prev[:, 0]
    candidate = (filled[:, 1:] == 1) & (filled[:, :-1] == -1)  # (N, T)

    # Minimum duration: sequential over the candidates only (not over samples).
    boundary = np.zeros((n, t), dtype=bool)
    counts = candidate.sum(axis=1)
    # Time of the last accepted boundary relative to this chunk's sample 0.
    last = -(st.since_last + dt)
    if counts.max(initial=0) > 0:
        kmax = int(counts.max())
        order = np.argsort(~candidate, axis=1, kind="stable")[:, :kmax]  # candidate samples first
        valid = np.arange(kmax)[None, :] < counts[:, None]
        last = last.copy()
        rows = np.arange(n)
        for j in range(kmax):
            s = order[:, j]
            ts = s * dt
            ok = valid[:, j] & (ts - last >= min_d - 1e-12)
            boundary[rows[ok], s[ok]] = True
            last = np.where(ok, ts, last)
    since_last = (t - 1) * dt - last if t > 0 else st.since_last
    new_state = StepDetectorState(armed=filled[:, -1] == -1, since_last=since_last)
    return boundary, new_state


def boundaries_to_steps(boundary: NDArray[np.bool_]) -> tuple[NDArray[np.int64], NDArray[np.bool_]]:
    """Consecutive boundary pairs as steps.

    Parameters
    ----------
    boundary : (N, T) bool

    Returns
    -------
    edges : (N, K+1) int
        Boundary sample indices, padded with the last index (``valid`` says which
        steps exist); step k spans samples edges[k] … edges[k+1].
    valid : (N, K) bool
    """
    b = np.asarray(boundary)
    if b.ndim != 2 or b.dtype != bool:
        raise ValueError(f"boundary must be an (N, T) bool array, got {b.dtype} {b.shape}")
    n = b.shape[0]
    counts = b.sum(axis=1)
    kmax = max(int(counts.max(initial=0)), 1)
    order = np.argsort(~b, axis=1, kind="stable")[:, :kmax]
    present = np.arange(kmax)[None, :] < counts[:, None]
    last = np.take_along_axis(order, np.maximum(counts - 1, 0)[:, None], axis=1)
    edges = np.where(present, order, last).astype(np.int64)
    valid = present[:, 1:] & present[:, :-1]
    if kmax == 1:
        return edges, np.zeros((n, 0), dtype=bool)
    return edges, valid
