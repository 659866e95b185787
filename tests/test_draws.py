"""pednav_env.draws: the same numbers as numpy's Generator.choice, from the same stream."""

import numpy as np
import pytest

from pednav_env.draws import choice_cdf, choice_index


@pytest.mark.parametrize(
    "weights",
    [(0.2, 0.4, 0.25, 0.15), (0.4, 0.3, 0.3), (0.0, 1.0, 0.0, 0.0), (1.0,), (3.0, 0.0, 1e-9, 7.0)],
)
def test_choice_index_is_generator_choice(weights):
    w = np.asarray(weights, dtype=float)
    p = w / w.sum()
    cdf = choice_cdf(p)
    ours, numpys = np.random.default_rng(11), np.random.default_rng(11)
    drawn = [choice_index(ours, cdf) for _ in range(5000)]
    expected = [int(numpys.choice(len(p), p=p)) for _ in range(5000)]
    assert drawn == expected
    assert ours.bit_generator.state == numpys.bit_generator.state  # one draw each, same stream
    assert set(drawn) <= {i for i, x in enumerate(weights) if x > 0}


@pytest.mark.parametrize("p", [(), ((0.5, 0.5),), (0.5, np.nan), (-0.1, 1.1), (0.0, 0.0)])
def test_choice_cdf_rejects_bad_weights(p):
    with pytest.raises(ValueError, match="p must"):
        choice_cdf(p)
