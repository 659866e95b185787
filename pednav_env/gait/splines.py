"""Clamped cubic splines for many short segments at once.

``scipy.interpolate.CubicSpline(bc_type="clamped")`` solves one spline per
call; a walk has hundreds of swing segments, each with the same few knots,
and building them one by one dominated episode resets. This solves the same
C² system (zero end slopes) for all segments in one batched linear solve and
returns ``scipy.interpolate.PPoly`` coefficients; the tests check it against
``CubicSpline``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def clamped_cubic_coefficients(knots_t: Array, knots_y: Array) -> Array:
    """PPoly coefficients of clamped C² cubic splines, one per segment.

    Parameters
    ----------
    knots_t : (S, n+1) strictly increasing knot times of S segments
    knots_y : (S, n+1, D) values at the knots

    Returns
    -------
    c : (4, S·n, D) coefficients, highest power first, pieces in segment order
        (the layout of ``PPoly.c``).
    """
    y, h, delta, slopes = _clamped_slopes(knots_t, knots_y)
    return _hermite(y, h, delta, slopes)


def monotone_clamped_cubic_coefficients(knots_t: Array, knots_y: Array) -> Array:
    """As :func:`clamped_cubic_coefficients` (zero end slopes), with each interior
    knot's slope limited so that every piece is monotone between its two knots:
    the slope is set to 0 where the secants on either side differ in sign (or one
    is 0) and otherwise kept between 0 and 3·min(|δ_{j−1}|, |δ_j|) with their sign,
    a sufficient condition for a monotone cubic Hermite piece (Fritsch & Carlson
    1980, SIAM J. Numer. Anal. 17(2):238–246, the square 0 ≤ α, β ≤ 3 inside their
    monotonicity region; the limiter of Hyman 1983, SIAM J. Sci. Stat. Comput.
    4(4):645–654). No piece then leaves the range of its knots' values. C¹; C²
    wherever no slope is limited. Same arguments and layout."""
    y, h, delta, slopes = _clamped_slopes(knots_t, knots_y)
    if h.shape[1] > 1:
        left, right = delta[:, :-1], delta[:, 1:]
        sign = np.sign(left) * (left * right > 0)
        bound = 3.0 * np.minimum(np.abs(left), np.abs(right))
        slopes[:, 1:-1] = sign * np.clip(sign * slopes[:, 1:-1], 0.0, bound)
    return _hermite(y, h, delta, slopes)


def _clamped_slopes(knots_t: Array, knots_y: Array) -> tuple[Array, Array, Array, Array]:
    """Values, knot spacings h, secants δ and the clamped C² spline's knot slopes."""
    t = np.asarray(knots_t, dtype=float)
    y = np.asarray(knots_y, dtype=float)
    if t.ndim != 2 or y.ndim != 3 or y.shape[:2] != t.shape or t.shape[1] < 2:
        raise ValueError(f"knots_t (S, n+1) and knots_y (S, n+1, D) mismatch: {t.shape}, {y.shape}")
    h = np.diff(t, axis=1)  # (S, n)
    if np.any(h <= 0):
        raise ValueError("knots_t must be strictly increasing within each segment")
    delta = np.diff(y, axis=1) / h[..., None]  # (S, n, D)
    s, n = h.shape
    slopes = np.zeros_like(y)  # clamped: zero at both ends
    if n > 1:
        # interior j = 1 … n−1:  h_j m_{j−1} + 2(h_{j−1}+h_j) m_j + h_{j−1} m_{j+1}
        #                         = 3 (h_j δ_{j−1} + h_{j−1} δ_j)
        A = np.zeros((s, n - 1, n - 1))
        j = np.arange(n - 1)
        A[:, j, j] = 2 * (h[:, :-1] + h[:, 1:])
        A[:, j[1:], j[:-1]] = h[:, 2:]
        A[:, j[:-1], j[1:]] = h[:, :-2]
        rhs = 3 * (h[:, 1:, None] * delta[:, :-1] + h[:, :-1, None] * delta[:, 1:])
        slopes[:, 1:-1] = np.linalg.solve(A, rhs)
    return y, h, delta, slopes


def _hermite(y: Array, h: Array, delta: Array, slopes: Array) -> Array:
    """PPoly coefficients (4, S·n, D) of the cubic Hermite pieces with these knot slopes."""
    s, n = h.shape
    m0, m1 = slopes[:, :-1], slopes[:, 1:]
    hh = h[..., None]
    c = np.empty((4, s, n, y.shape[2]))
    c[0] = (m0 + m1 - 2 * delta) / hh**2
    c[1] = (3 * delta - 2 * m0 - m1) / hh
    c[2] = m0
    c[3] = y[:, :-1]
    return c.reshape(4, s * n, y.shape[2])
