"""A SHOE configuration of the ZUPT-UKF chosen on simulated walks only.

What the calibrated simulator is for (docs/SIM_TO_REAL.md): a configuration
chosen in simulation should work on real walks. :func:`choose_on_simulation`
simulates walks with a simulator model of :mod:`pednav_env.calibration.compare`
(by default the calibrated one: its stance dynamics, walker timing and the
MicroStrain 3DM-GX5-25 grade), every stride's speed in
:data:`SIM_SPEED_MPS`, turns and stops, and runs on them the SHOE part of
``real-fixed``'s search (:func:`pednav_env.replay.search.search` over
:func:`pednav_env.replay.search.shoe_families`: threshold γ, process and ZUPT
noise scales, update mode; refined around the winner) with the real-data
runner of ``pednav run`` and PyShoe's ARMSE against the simulated truth. The
result's ``setup`` is a :class:`pednav_env.replay.setup.RealFilterSetup`
dictionary, the layout of ``real_fixed.json``.

``benchmarks/choose_shoe_on_sim.py`` runs it and scores the choice on
recordings.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pednav_env.calibration.compare import MODELS, SimModel
from pednav_env.calibration.sources import recording_from_simulation
from pednav_env.io import Recording
from pednav_env.replay.metrics import track_errors
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.search import search, shoe_families
from pednav_env.replay.setup import RealFilterSetup

#: Speeds (m/s) of the simulated strides.
SIM_SPEED_MPS = (0.3, 3.0)
#: Length of a simulated walk (s), its 2 s still start and 1 s end included.
SIM_DURATION_S = (30.0, 60.0)


def simulated_recordings(
    model: SimModel,
    walks: int,
    seed: int,
    speed_mps: tuple[float, float] = SIM_SPEED_MPS,
    duration_s: tuple[float, float] = SIM_DURATION_S,
) -> list[Recording]:
    """``walks`` simulated walks of ``model`` as recordings with truth (walk i from
    ``default_rng([seed, i])``; :meth:`SimModel.batch`)."""
    if walks < 1:
        raise ValueError(f"walks must be ≥ 1, got {walks}")
    truth, imu = model.batch(speed_mps, walks, seed, duration_s)
    return [
        recording_from_simulation(truth, imu, i, f"{model.name}-{seed}-{i}") for i in range(walks)
    ]


def choose_on_simulation(
    model: SimModel | None = None, walks: int = 24, seed: int = 0
) -> dict[str, Any]:
    """The SHOE search on ``walks`` simulated walks of ``model`` (default: the
    calibrated one); :func:`pednav_env.replay.search.search`'s result."""
    recordings = simulated_recordings(model or MODELS["calibrated"], walks, seed)
    return search(recordings, shoe_families())


def armse_by_recording(setup: RealFilterSetup, recordings: Sequence[Recording]) -> dict[str, float]:
    """PyShoe's ARMSE (m) of ``setup`` on each recording with truth (inf if the
    filter diverged)."""
    out = {}
    for rec in recordings:
        prep = prepare(rec, setup)
        run = run_prepared(prep, 1)
        out[rec.name] = (
            np.inf
            if run.diverged[0]
            else float(track_errors(run.pos[0], prep.truth_pos, prep.n_align)["armse_pyshoe_m"])
        )
    return out
