"""The heel strike of ``StanceMotion.heel_rocker``: the heel lands at rest on its
footfall and the foot rolls down about it (:func:`heel_rocker_coefficients`).

Without it (the default) each moving phase of :func:`pednav_env.gait.foot.build_schedule`
is one clamped C² cubic through stance, toe-off, mid-swing, heel strike and the
next stance, all six rows alike: the heel is on the footfall at the heel-strike
knot but still moving, runs a few cm past it while dipping below the ground, and
slides back while the foot flattens (``benchmarks/slow_speed_bias.py``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from pednav_env.gait.splines import (
    clamped_cubic_coefficients,
    monotone_clamped_cubic_coefficients,
)

Array = NDArray[np.float64]


def heel_rocker_coefficients(knots_t: Array, knots_y: Array) -> Array:
    """The moving phases of ``StanceMotion.heel_rocker``: (4, S, 4, 6) coefficients
    of the pieces between the five realistic knots (stance, toe-off, mid-swing,
    heel strike, next stance; ``knots_y`` (S, 5, 6) heel x, y, z, ψ, θ, γ).

    The angles keep the clamped C² cubic through all five knots, so the foot
    still pitches toes-up to the heel-strike knot and rolls down to flat after
    it. The heel's position is a clamped cubic through the first four knots only
    (:func:`pednav_env.gait.splines.monotone_clamped_cubic_coefficients`: zero
    velocity at both ends, monotone between knots, C¹), so it comes to rest on
    the footfall at the heel-strike knot without passing it or the ground, and
    is held there until the next stance: the foot rotates about the heel, the
    heel rocker of the loading response (Perry & Burnfield, Gait Analysis:
    Normal and Pathological Function, 2nd ed. 2010). Lanshammar & Strandberg
    (Biomechanics VIII-B, 1982, pp. 1123–1128) found the heel moving slightly
    backward at heel strike in most steps (69 of the 82 with a horizontal force
    peak): landing at rest is the middle ground, running on is not.
    """
    n_str = knots_t.shape[0]
    c = np.zeros((4, n_str, 4, 6))
    c[..., 3:] = clamped_cubic_coefficients(knots_t, knots_y[..., 3:]).reshape(4, n_str, 4, 3)
    heel = monotone_clamped_cubic_coefficients(knots_t[:, :4], knots_y[:, :4, :3])
    c[:, :, :3, :3] = heel.reshape(4, n_str, 3, 3)
    c[3, :, 3, :3] = knots_y[:, 3, :3]  # held on the footfall through the heel strike
    return c
