"""Shared fixtures: small paper-003 walks, simulated once per session; three recordings
of different lengths for the replay env."""

from __future__ import annotations

import numpy as np
import pytest
from testdata import write_pyshoe_excerpts

from pednav_env.gait.foot import FootTrajectory, simulate_foot
from pednav_env.gait.foot_route import paper_stride_shape, random_route, square_route


@pytest.fixture(scope="session")
def paper_walk() -> FootTrajectory:
    """Paper 003 scenario: a 3 m square of 1 m strides (noiseless truth)."""
    return simulate_foot(square_route(3.0, paper_stride_shape(1.0)))


@pytest.fixture(scope="session")
def realistic_walk() -> FootTrajectory:
    """A short randomised walk with turns, gait changes and stance micro-motion."""
    from pednav_env.gait.foot_route import RouteRandomization

    rng = np.random.default_rng(12345)
    return simulate_foot(random_route(rng, RouteRandomization(duration_s=(25.0, 25.0))))


@pytest.fixture(scope="session")
def three_recordings(tmp_path_factory):
    """A folder of three PyShoe excerpts, ``a.mat`` (7 s), ``b.mat`` (6 s), ``c.mat`` (5 s)."""
    return write_pyshoe_excerpts(
        tmp_path_factory.mktemp("recordings"), {"a": 7.0, "b": 6.0, "c": 5.0}
    )
