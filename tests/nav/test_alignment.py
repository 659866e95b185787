"""Static alignment (paper 003 eq 4): tilt from the mean specific force."""

import numpy as np
import pytest

from pednav_env.nav.alignment import align_static
from pednav_env.nav.strapdown import integrate
from pednav_env.rotations import euler_to_dcm


def test_alignment_recovers_tilt():
    euler = np.array([[0.0, 0.10, 0.13], [0.0, -0.4, 0.2]])  # paper 003's real-data 0.10, 0.13
    f = np.einsum("nji,j->ni", euler_to_dcm(euler), [0, 0, 9.80665])
    np.testing.assert_allclose(align_static(f), euler, atol=1e-12)
    rng = np.random.default_rng(0)
    noisy = f[:, None, :] + rng.normal(scale=0.1, size=(2, 100, 3))
    # averaging 100 samples of σ = 0.1 m/s²: tilt error ≈ 0.01/g rad per axis
    np.testing.assert_allclose(align_static(noisy), euler, atol=5 * 0.01 / 9.8)


def test_alignment_rejects_bad_input():
    with pytest.raises(ValueError, match="NaN"):
        align_static(np.array([[np.nan, 0, 9.8]]))
    with pytest.raises(ValueError, match="f_b"):
        align_static(np.zeros((2, 2, 2, 3)))
    with pytest.raises(ValueError, match="g"):
        align_static(np.array([[0, 0, 9.8]]), g=0.0)
    with pytest.raises(ValueError, match="dt"):
        integrate(
            np.array([[1.0, 0, 0, 0]]),
            np.zeros((1, 3)),
            np.zeros((1, 3)),
            np.zeros((1, 5, 3)),
            np.zeros((1, 5, 3)),
            0.0,
        )
