"""IMU mounting: rotate the sensor's axes into the body convention.

The filter wants body axes with z up at rest (x forward, y left; paper 003's
eq 4 alignment assumes a roughly level IMU: its arcsin form cannot express a
sensor mounted upside down). A foot IMU is mounted any way: PyShoe's reads
−9.4 m/s² on z at rest, x-io's has its axes tilted by about 34°. A fixed
rotation ``C_bs`` (sensor → body) is applied to every sample,
``ω_b = C_bs ω_s``, ``f_b = C_bs f_s``:

- ``"auto"``: the smallest rotation that turns the mean static specific
  force onto +z (rotation about the horizontal axis ``f̄ × e_z``). The body
  x axis is then the sensor's x axis tilted into the level plane; heading
  is unobservable anyway (paper 003: ψ = 0 at the start defines the frame).
- ``"none"``: the sensor axes are already x forward, y left, z up.
- a signed axis permutation such as ``"x,-y,-z"``: body x, y, z given as
  sensor axes (PyShoe's MicroStrain: ``"x,-y,-z"``, z down → up). It must be
  a proper rotation (determinant +1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

_AXES = {"x": 0, "y": 1, "z": 2}


def level_rotation(f_static: Array) -> Array:
    """``C_bs`` (3, 3): the smallest rotation taking the direction of the
    static specific force ``f_static`` (3,) (or a window (W, 3)) onto +z."""
    f = np.asarray(f_static, dtype=float)
    if f.ndim == 2:
        f = f.mean(axis=0)
    norm = np.linalg.norm(f)
    if f.shape != (3,) or not np.isfinite(norm) or norm == 0:
        raise ValueError(f"f_static must be a finite non-zero 3-vector, got {f_static!r}")
    u = f / norm
    c = float(u[2])
    v = np.array([u[1], -u[0], 0.0])  # u × e_z
    s2 = float(v @ v)
    if s2 < 1e-24:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K * ((1.0 - c) / s2)


def axes_rotation(spec: str) -> Array:
    """``C_bs`` from a signed axis list such as ``"x,-y,-z"`` (body x, y, z as sensor axes)."""
    parts = [p.strip().lower() for p in spec.split(",")]
    if len(parts) != 3:
        raise ValueError(f"mounting {spec!r}: give three signed axes, e.g. 'x,-y,-z'")
    C = np.zeros((3, 3))
    for row, p in enumerate(parts):
        sign = -1.0 if p.startswith("-") else 1.0
        axis = p.lstrip("+-")
        if axis not in _AXES:
            raise ValueError(f"mounting {spec!r}: {p!r} is not one of ±x, ±y, ±z")
        C[row, _AXES[axis]] = sign
    if not np.isclose(np.linalg.det(C), 1.0):
        raise ValueError(
            f"mounting {spec!r} is not a proper rotation (determinant {np.linalg.det(C):+.0f}): "
            "a right-handed sensor maps to right-handed body axes"
        )
    return C


def mounting_rotation(spec: str, f_static: Array | None = None) -> Array:
    """``C_bs`` for ``"auto"`` (needs ``f_static``), ``"none"`` or an axis list."""
    if spec == "auto":
        if f_static is None:
            raise ValueError("mounting 'auto' needs the static specific force")
        return level_rotation(f_static)
    if spec == "none":
        return np.eye(3)
    return axes_rotation(spec)


def rotate_samples(C_bs: Array, x_s: Array) -> Array:
    """Samples ``(..., 3)`` in sensor axes → body axes."""
    return np.asarray(x_s, dtype=float) @ np.asarray(C_bs, dtype=float).T
