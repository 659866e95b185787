"""Static alignment, paper 003 eq (4).

At rest f_b = B_zx (0, 0, g₀), hence f₁ = −g₀ sin θ and f₂ = g₀ cos θ sin γ:

    θ = arcsin(−f₁/g₀),   γ = arcsin(f₂ / (g₀ cos θ)),   ψ = 0,   x = v = 0.

Heading is not observable by low-grade gyros, so ψ = 0 defines the frame.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.constants import STANDARD_GRAVITY

Array = NDArray[np.float64]


def align_static(f_b: Array, g: float = STANDARD_GRAVITY) -> Array:
    """Euler angles ``(N, 3)`` = (ψ=0, θ, γ) from static specific force.

    Parameters
    ----------
    f_b : (N, W, 3) or (N, 3)
        Specific force (m/s²) while at rest; a window is averaged first.
    g : float
        Gravity magnitude g₀ used by eq (4).
    """
    f = np.asarray(f_b, dtype=float)
    if f.ndim == 3:
        f = f.mean(axis=1)
    if f.ndim != 2 or f.shape[-1] != 3:
        raise ValueError(f"f_b must be (N, W, 3) or (N, 3), got {np.shape(f_b)}")
    if not np.all(np.isfinite(f)):
        raise ValueError("f_b contains NaN or inf")
    if not g > 0:
        raise ValueError(f"g must be > 0, got {g!r}")
    pitch = np.arcsin(np.clip(-f[:, 0] / g, -1.0, 1.0))
    roll = np.arcsin(np.clip(f[:, 1] / (g * np.cos(pitch)), -1.0, 1.0))
    return np.stack((np.zeros_like(pitch), pitch, roll), axis=-1)
