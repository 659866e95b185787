"""Error measures of a filtered recording against its reference (docs/REAL_DATA.md).

Heading is unobservable at the start (paper 003 sets ψ = 0), so the
reference frame and the filter's navigation frame differ by an unknown
rotation about the vertical; both tracks are referred to their position at
the start of navigation t₀ (end of the alignment) and the reference is
rotated by the angle φ that minimises the summed squared horizontal error
(closed form, 2-D Procrustes without scale):

    φ = atan2( Σ (p × p̂)_z , Σ p̂·p )   (horizontal components),
    e_h(t) = p̂_h(t) − R(φ) p_h(t).

With k = t₀ … T the navigation samples that have a reference:

- ``armse_m`` = (1/K) Σ_k |e_h(k)| — the time average of the horizontal
  error norm (the replay environment's return is minus this, up to the
  rotation, which the env fixes per trial from a reference run);
- ``armse_pyshoe_m`` = PyShoe's ``compute_error(…, '2d')``: over *all*
  samples (alignment included, both tracks from their first sample),
  (1/T) Σ_k sqrt( (e_x² + e_y²) / 2 ), after the same best rotation
  (PyShoe's script rotates at the first sample 0.8 m from the start
  instead: :func:`pyshoe_rotation`);
- ``final_error_m`` = |e_h(T)|;
- ``loop_closure_m`` = |p̂(T) − p̂(t₀)| in 3-D, for walks that end where
  they started (no reference needed);
- footprint errors (:func:`footprint_errors`), for a reference known only at
  footfalls: the same best rotation over the footprints only, both sets
  referred to the first footprint.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def best_rotation(est_h: Array, ref_h: Array) -> float:
    """Angle φ (rad) minimising Σ |est − R(φ) ref|² for ``(K, 2)`` tracks."""
    ok = np.isfinite(est_h).all(axis=1) & np.isfinite(ref_h).all(axis=1)
    a, b = est_h[ok], ref_h[ok]
    cross = float(np.sum(b[:, 0] * a[:, 1] - b[:, 1] * a[:, 0]))
    dot = float(np.sum(a * b))
    return math.atan2(cross, dot) if (cross or dot) else 0.0


def pyshoe_rotation(est_h: Array, ref_h: Array, dist: float = 0.8) -> float:
    """PyShoe's ``align_plots``: the angle that turns the reference onto the
    estimate at the first sample whose estimated displacement reaches ``dist``
    (sample 300 if never)."""
    d = np.linalg.norm(est_h - est_h[0], axis=1)
    idx = int(np.argmax(d >= dist)) if np.any(d >= dist) else min(300, len(d) - 1)
    a, b = est_h[idx] - est_h[0], ref_h[idx] - ref_h[0]
    return math.atan2(b[0] * a[1] - b[1] * a[0], float(a @ b))


def rotate_h(xy: Array, phi: float) -> Array:
    c, s = math.cos(phi), math.sin(phi)
    return np.stack((c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]), axis=1)


def distance_walked(pos: Array) -> float:
    """Length of a track ``(T, 3)`` (m), horizontal and vertical."""
    d = np.diff(pos, axis=0)
    return float(np.sum(np.linalg.norm(d[np.isfinite(d).all(axis=1)], axis=1)))


def track_errors(
    pos_est: Array, truth: Array, start: int, leave_out: NDArray[np.bool_] | None = None
) -> dict[str, float]:
    """The measures of the module docstring for one lane.

    Parameters
    ----------
    pos_est : (T, 3) estimate (navigation frame, 0 at ``start``).
    truth : (T, 3) reference (its own frame), NaN rows allowed.
    start : first navigation sample t₀ (alignment length).
    leave_out : (T,) optional; samples left out of the two ARMSE averages only (the
        rotations and origins are still fitted on every referenced sample; e.g. the
        reference's tracking glitches, ``benchmarks/truth_glitch_armse.py``).
    """
    est = np.asarray(pos_est, dtype=float)
    ref = np.asarray(truth, dtype=float)
    t0 = start
    ok0 = np.isfinite(ref[t0:]).all(axis=1)
    if not ok0.any():
        raise ValueError("the reference has no finite sample after the alignment")
    first = t0 + int(np.argmax(ok0))
    e_nav = est[t0:, :2] - est[first, :2]
    r_nav = ref[t0:, :2] - ref[first, :2]
    phi = best_rotation(e_nav, r_nav)
    err = e_nav - rotate_h(r_nav, phi)
    en = np.linalg.norm(err, axis=1)
    good = np.isfinite(en)
    last = int(np.flatnonzero(good)[-1])
    # PyShoe: all samples, both tracks from their first sample.
    okp = np.isfinite(ref).all(axis=1)
    i0 = int(np.argmax(okp))
    ep, rp = est[:, :2] - est[i0, :2], ref[:, :2] - ref[i0, :2]
    errp = ep - rotate_h(rp, best_rotation(ep, rp))
    rms_axes = np.sqrt(np.mean(errp**2, axis=1))
    kept, kept_p = good, np.isfinite(rms_axes)
    if leave_out is not None:
        kept, kept_p = kept & ~leave_out[t0:], kept_p & ~leave_out
    return {
        "armse_m": float(np.mean(en[kept])),
        "armse_pyshoe_m": float(np.mean(rms_axes[kept_p])),
        "final_error_m": float(en[last]),
        "heading_offset_rad": float(phi),
    }


def aligned_reference(pos_est: Array, truth: Array, start: int) -> Array:
    """The reference ``(T, 2)`` in the estimate's frame as :func:`track_errors` compares
    them: turned by its φ and placed at the estimate's first referenced position
    (NaN rows stay NaN) — for drawing."""
    est = np.asarray(pos_est, dtype=float)
    ref = np.asarray(truth, dtype=float)
    ok = np.isfinite(ref[start:]).all(axis=1)
    if not ok.any():
        raise ValueError("the reference has no finite sample after the alignment")
    first = start + int(np.argmax(ok))
    phi = best_rotation(est[start:, :2] - est[first, :2], ref[start:, :2] - ref[first, :2])
    return est[first, :2] + rotate_h(ref[:, :2] - ref[first, :2], phi)


def pyshoe_armse_as_published(pos_est: Array, truth: Array) -> float:
    """PyShoe's ARMSE with its own rotation (:func:`pyshoe_rotation`), for comparison."""
    ok = np.isfinite(truth).all(axis=1)
    i0 = int(np.argmax(ok))
    ep, rp = pos_est[:, :2] - pos_est[i0, :2], truth[:, :2] - truth[i0, :2]
    errp = ep - rotate_h(rp, pyshoe_rotation(ep[ok], rp[ok]))
    rms = np.sqrt(np.mean(errp**2, axis=1))
    return float(np.mean(rms[np.isfinite(rms)]))


def footprint_errors(pos_at_footfalls: Array, footprints_h: Array) -> dict[str, float]:
    """Errors at the footfalls, for truth known only there (docs/REAL_DATA.md).

    Both sets are referred to their first footprint (the origin) and the
    footprints are turned about the vertical by the angle φ that minimises the
    summed squared horizontal error (:func:`best_rotation`, the closed-form 2-D
    Kabsch/Umeyama rotation without scale): e_k = p̂_k − R(φ) g_k.

    Parameters
    ----------
    pos_at_footfalls : (K, ≥2) the filter's position at each footfall sample (m).
    footprints_h : (K, 2) the footprints (m), their own frame.

    Returns ``footprints`` (K), ``footprint_mean_error_m`` (mean of |e_k| over
    the K footprints, the origin's 0 included), ``footprint_final_error_m``
    (|e_K|), ``footprint_final_error_pct`` (100 |e_K| / the length of the
    polyline through the footprints) and ``footprint_heading_offset_rad`` (φ).
    """
    est = np.asarray(pos_at_footfalls, dtype=float)[:, :2]
    ref = np.asarray(footprints_h, dtype=float)
    if est.shape != ref.shape or est.shape[0] < 2:
        raise ValueError(
            f"need ≥ 2 footfalls with one estimate each, got {est.shape} and {ref.shape}"
        )
    est = est - est[0]
    ref = ref - ref[0]
    phi = best_rotation(est, ref)
    err = np.linalg.norm(est - rotate_h(ref, phi), axis=1)
    path_m = float(np.sum(np.linalg.norm(np.diff(ref, axis=0), axis=1)))
    return {
        "footprints": int(est.shape[0]),
        "footprint_mean_error_m": float(err.mean()),
        "footprint_final_error_m": float(err[-1]),
        "footprint_final_error_pct": 100.0 * float(err[-1]) / path_m if path_m > 0 else math.nan,
        "footprint_heading_offset_rad": float(phi),
    }


def loop_closure(pos_est: Array, start: int) -> float:
    """|p̂(T) − p̂(t₀)| (m), 3-D."""
    return float(np.linalg.norm(pos_est[-1] - pos_est[start]))
