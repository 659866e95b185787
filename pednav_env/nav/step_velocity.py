"""Step-mean velocities of a waist IMU (papers 000 and 004), batched over walkers.

- :func:`biomechanical_step_velocity` — V̄^BM = 2 sqrt(2 l h − h²)/T with h
  the doubly integrated vertical acceleration over the first half step
  (paper 000, V̄^МОД; paper 004, eq 7).
- :func:`pendulum_step_velocity` — the same V̄^BM evaluated from running
  integrals built once per record (:func:`prefix_integrals`), O(1) per step.
- :func:`nested_trapezoid_mean_velocity` — paper 000's V̄^ЧП, the step-mean
  velocity by double integration of the acceleration.

Integration rule (paper 000). The printed double integrals ∫₀ᵀ∫₀ᵀ a dt dt are
read as nested running integrals, V(t) = V(0) + ∫₀ᵗ a, then ∫₀ᵀ V(t) dt, each
by the trapezoid rule on the samples t = 0, Δt, …, T (both ends included) —
the reading that reproduces paper 000's printed V̄ = 1.39994406 and
1.39999891 m/s to all eight digits (docs/REPRODUCTION.md (papers 000/002/004)).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.checks import require_positive

Array = NDArray[np.float64]


def prefix_integrals(
    acc: Array, dt: float, rule: Literal["trapezoid", "delta_v"]
) -> tuple[Array, Array]:
    """Running single and double integrals C1, C2 of ``acc`` (..., T) from sample 0.

    ``trapezoid``: C1 = cumtrapz(a), C2 = cumtrapz(C1) (point samples).
    ``delta_v``: C1[j] = Δt Σ_{i≤j, i≥1} a_i (a_i = mean over (t_{i−1}, t_i]),
    C2 = cumtrapz(C1). Built once per record, they give every step's
    integrals in O(1) (:func:`pendulum_step_velocity`).
    """
    if rule == "trapezoid":
        c1 = np.concatenate(
            (np.zeros(acc.shape[:-1] + (1,)), np.cumsum(0.5 * (acc[..., 1:] + acc[..., :-1]), -1)),
            axis=-1,
        )
    elif rule == "delta_v":
        c1 = np.concatenate((np.zeros(acc.shape[:-1] + (1,)), np.cumsum(acc[..., 1:], -1)), -1)
    else:
        raise ValueError(f"rule must be 'trapezoid' or 'delta_v', got {rule!r}")
    c1 = c1 * dt
    c2 = np.concatenate(
        (np.zeros(acc.shape[:-1] + (1,)), np.cumsum(0.5 * (c1[..., 1:] + c1[..., :-1]), -1)),
        axis=-1,
    )
    return c1, c2 * dt


def _window_integrals(
    c1: Array, c2: Array, j0: NDArray[np.int64], j1: NDArray[np.int64], dt: float
) -> tuple[Array, Array]:
    """∫_{t_j0}^{t_j1} a and ∫_{t_j0}^{t_j1} ∫_{t_j0}^{t} a from the prefix integrals."""
    a0 = np.take_along_axis(c1, j0, axis=-1)
    a1 = np.take_along_axis(c1, j1, axis=-1)
    b0 = np.take_along_axis(c2, j0, axis=-1)
    b1 = np.take_along_axis(c2, j1, axis=-1)
    return a1 - a0, (b1 - b0) - a0 * (j1 - j0) * dt


def nested_trapezoid_mean_velocity(
    acc: ArrayLike, dt: float, v0: ArrayLike, step_edges: ArrayLike
) -> Array:
    """Paper 000's V̄^ЧП = V(0) + (1/T) ∫₀ᵀ ∫₀ᵗ a dτ dt, nested trapezoid rule.

    Parameters
    ----------
    acc : (N, T_samples) m/s²
        Point samples of the acceleration along the axis of interest.
    dt : float
    v0 : (N, K) m/s
        Velocity at each step's first sample.
    step_edges : (N, K+1) int
        Step k spans samples edges[k] … edges[k+1] (both included).

    Returns
    -------
    vbar : (N, K) m/s
    """
    require_positive("dt", dt)
    dt = float(dt)
    a = np.asarray(acc, dtype=float)
    e = np.asarray(step_edges, dtype=np.int64)
    c1, c2 = prefix_integrals(a, dt, "trapezoid")
    _, dbl = _window_integrals(c1, c2, e[:, :-1], e[:, 1:], dt)
    T = (e[:, 1:] - e[:, :-1]) * dt
    return np.asarray(v0, dtype=float) + dbl / T


@dataclass(frozen=True)
class BiomechanicalVelocity:
    """Output of :func:`biomechanical_step_velocity`, arrays (N, K)."""

    velocity: Array  #: V̄^BM along the walking surface × cos(slope) (m/s)
    hip_rise: Array  #: h (m), clipped to [0, l]
    step_period: Array  #: T_k (s)
    clipped: NDArray[np.bool_]  #: h fell outside [0, l] and was clipped


def biomechanical_step_velocity(
    acc_up: ArrayLike,
    dt: float,
    step_edges: ArrayLike,
    leg_length: ArrayLike,
    v_up0: ArrayLike | Literal["apex", "zero"] = "apex",
    rule: Literal["trapezoid", "delta_v"] = "trapezoid",
    slope: ArrayLike = 0.0,
) -> BiomechanicalVelocity:
    """Pendulum step velocity V̄^BM = 2 sqrt(2 l h − h²)/T · cos α (papers 000, 004).

    h is the hip rise over the first half step (paper 000, V̄^МОД)::

        h = V_up(0) T/2 + ∫₀^{T/2} ∫₀^{t} a_up dτ dt

    integrated by ``rule`` over the first n_k/2 sample intervals, n_k =
    edges[k+1] − edges[k], T = n_k Δt (for odd n_k the last half interval uses
    the running integral interpolated linearly within the sample).

    Parameters
    ----------
    acc_up : (N, T_samples) m/s²
        Vertical (navigation-frame up) acceleration, gravity removed.
    dt : float
    step_edges : (N, K+1) int
        From :func:`boundaries_to_steps` or known step times.
    leg_length : (N,) or (N, K) m
    v_up0 : (N, K) array, "apex" or "zero"
        Vertical velocity at the step's start. An array: known (paper 000,
        "at known initial conditions"). ``"apex"``: from V_up(T/2) = 0 — the
        pendulum hip is at the top of its arc at mid-step (paper 000 eq 16
        at φ = π/2) — i.e. V_up(0) = −∫₀^{T/2} a_up, needing nothing but the
        first half step. ``"zero"``: paper 004's eq (7) literally, without the
        V_up(0) T/2 term (yields h < 0, clipped, on the pendulum).
    rule : "trapezoid" or "delta_v"
        ``trapezoid`` for point samples (papers 000/004); ``delta_v`` for
        interval means over (t_{i−1}, t_i] (IMU delta-velocities, paper 002's
        finite differences), for which V is reconstructed exactly by sums.
    slope : (N, K) rad
        Surface slope α for the horizontal projection (paper 000).

    Returns
    -------
    BiomechanicalVelocity
    """
    require_positive("dt", dt)
    dt = float(dt)
    a = np.asarray(acc_up, dtype=float)
    if a.ndim != 2:
        raise ValueError(f"acc_up must be (N, T), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("acc_up contains NaN or inf")
    e = np.asarray(step_edges)
    if e.ndim != 2 or e.shape[0] != a.shape[0] or e.shape[1] < 2:
        raise ValueError(f"step_edges must be (N, K+1) with N = {a.shape[0]}, got {e.shape}")
    e = e.astype(np.int64)
    if np.any(np.diff(e, axis=1) < 0) or e.min() < 0 or e.max() >= a.shape[1]:
        raise ValueError("step_edges must be non-decreasing sample indices within acc_up")
    n_k = e[:, 1:] - e[:, :-1]
    l_ = np.asarray(leg_length, dtype=float)
    try:
        l_ = np.broadcast_to(l_[:, None] if l_.ndim == 1 else l_, n_k.shape)
    except ValueError:
        raise ValueError(f"leg_length must be (N,) or (N, K), got {l_.shape}") from None
    if not np.all(np.isfinite(l_)) or np.any(l_ <= 0):
        raise ValueError(f"leg_length must be finite and > 0, got {leg_length!r}")
    j0 = e[:, :-1]
    jm = j0 + n_k // 2
    theta = 0.5 * (n_k % 2)  # odd n: the half step ends mid-sample
    half = 0.5 * n_k * dt
    T = n_k * dt
    c1, c2 = prefix_integrals(a, dt, rule)
    single, double = _window_integrals(c1, c2, j0, jm, dt)
    # Odd n: extend by θ·Δt, C1 linear between samples, C2 by the trapezoid of C1.
    jn = np.minimum(jm + 1, a.shape[1] - 1)
    c1m, c1n = np.take_along_axis(c1, jm, axis=-1), np.take_along_axis(c1, jn, axis=-1)
    c1_half = c1m + theta * (c1n - c1m)
    c1_start = np.take_along_axis(c1, j0, axis=-1)
    single = single + (c1_half - c1m)
    double = double + theta * dt * (0.5 * (c1m + c1_half) - c1_start)
    if isinstance(v_up0, str):
        if v_up0 == "apex":
            v0 = -single
        elif v_up0 == "zero":
            v0 = np.zeros_like(single)
        else:
            raise ValueError(f"v_up0 must be an array, 'apex' or 'zero', got {v_up0!r}")
    else:
        v0 = np.broadcast_to(np.asarray(v_up0, dtype=float), single.shape)
        if not np.all(np.isfinite(v0)):
            raise ValueError("v_up0 contains NaN or inf")
    h = v0 * half + double
    clipped = (h < 0) | (h > l_)
    h = np.clip(h, 0.0, l_)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(T > 0, 2.0 * np.sqrt(2.0 * l_ * h - h * h) / np.where(T > 0, T, 1.0), 0.0)
    v = v * np.cos(np.asarray(slope, dtype=float))
    return BiomechanicalVelocity(velocity=v, hip_rise=h, step_period=T, clipped=clipped)


def pendulum_step_velocity(
    c1: Array,
    c2: Array,
    lane: NDArray[np.integer],
    j0: NDArray[np.integer],
    n: NDArray[np.integer],
    leg: Array,
    dt: float,
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """V̄^BM = 2 sqrt(2 l h − h²)/T for steps starting at samples ``j0`` (papers 000/004).

    Evaluates :func:`biomechanical_step_velocity` (apex closure V_up(T/2) = 0,
    rule ``delta_v``, level ground) from prefix integrals: h = V_up(0)·T/2 +
    ∫₀^{T/2}∫₀^t a_up over the first n/2 sample intervals (odd n: the last half
    interval interpolated within the sample).

    Parameters
    ----------
    c1, c2 : (N, L) prefix integrals of every lane (:func:`prefix_integrals`, ``delta_v``)
    lane : (M,) lane of each step
    j0 : (M,) first sample of each step
    n : (M,) samples in the step (≥ 1), T = n Δt
    leg : (M,) assumed leg length l (m)
    dt : float

    Returns
    -------
    velocity (M,) m/s, hip_rise (M,) m (clipped to [0, l]), clipped (M,) bool
    """
    jm = j0 + n // 2
    jn = np.minimum(jm + 1, c1.shape[-1] - 1)
    theta = 0.5 * (n % 2)
    c1s, c1m, c1n = c1[lane, j0], c1[lane, jm], c1[lane, jn]
    # ∫_{j0}^{jm} a and ∫_{j0}^{jm}∫_{j0}^{t} a from the prefix integrals
    single = c1m - c1s
    double = (c2[lane, jm] - c2[lane, j0]) - c1s * (jm - j0) * dt
    c1_half = c1m + theta * (c1n - c1m)
    single = single + (c1_half - c1m)
    double = double + theta * dt * (0.5 * (c1m + c1_half) - c1s)
    T = n * dt
    h = -single * (0.5 * T) + double
    clipped = (h < 0) | (h > leg)
    h = np.clip(h, 0.0, leg)
    return 2.0 * np.sqrt(2.0 * leg * h - h * h) / T, h, clipped
