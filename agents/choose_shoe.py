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
from numpy.typing import NDArray

from pednav_env.calibration.compare import MODELS
from pednav_env.calibration.sim_model import SimModel
from pednav_env.calibration.sources import recording_from_simulation
from pednav_env.io import Recording
from pednav_env.nav.detectors import ShoeDetectorConfig
from pednav_env.replay.metrics import footprint_errors, track_errors
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.search import search, shoe_families
from pednav_env.replay.setup import RealFilterSetup

Array = NDArray[np.float64]

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
    turn_per_stride_rad: tuple[float, float] | None = None,
) -> list[Recording]:
    """``walks`` simulated walks of ``model`` as recordings with truth (walk i from
    ``default_rng([seed, i])``; :meth:`SimModel.batch`, with ``turn_per_stride_rad``
    every leg on a circle)."""
    if walks < 1:
        raise ValueError(f"walks must be ≥ 1, got {walks}")
    truth, imu = model.batch(speed_mps, walks, seed, duration_s, turn_per_stride_rad)
    return [
        recording_from_simulation(truth, imu, i, f"{model.name}-{seed}-{i}") for i in range(walks)
    ]


def standing_still_armse(recordings: Sequence[Recording], setup: RealFilterSetup) -> Array:
    """PyShoe's ARMSE (m) of a track that stays at its start, per recording: what
    not navigating scores, the cap of a configuration's score on a walk."""
    out = []
    for rec in recordings:
        prep = prepare(rec, setup)
        still = np.zeros_like(prep.truth_pos)
        out.append(track_errors(still, prep.truth_pos, prep.n_align)["armse_pyshoe_m"])
    return np.array(out)


def choose_on_simulation(
    model: SimModel | None = None, walks: int = 24, seed: int = 0
) -> dict[str, Any]:
    """The SHOE search on ``walks`` simulated walks of ``model`` (default: the
    calibrated one); :func:`pednav_env.replay.search.search`'s result, with each
    walk's score capped at :func:`standing_still_armse` (a configuration that
    diverges on a walk, or does worse than standing still, scores as standing
    still there: one hopeless walk does not make every mean infinite) and the
    caps under ``"standing_still_armse_m"``."""
    recordings = simulated_recordings(model or MODELS["calibrated"], walks, seed)
    families = shoe_families()
    cap = standing_still_armse(recordings, families[0].setup)
    result = search(recordings, families, cap)
    result["standing_still_armse_m"] = dict(
        zip([r.name for r in recordings], cap.tolist(), strict=True)
    )
    return result


def lane_errors(recording: Recording, setup: RealFilterSetup, knobs: dict[str, Array]) -> Array:
    """The error of each lane of ``knobs`` (name → (N,) values) on ``recording``
    (m): PyShoe's ARMSE against its truth, else the mean footprint error
    (:func:`pednav_env.replay.metrics.footprint_errors`); inf where the filter
    diverged."""
    n = len(next(iter(knobs.values()))) if knobs else 1
    prep = prepare(recording, setup)
    if prep.truth_pos is None and prep.footprints is None:
        raise ValueError(f"{recording.name}: no truth and no footprints to score against")
    run = run_prepared(prep, n, knobs=knobs)
    out = np.full(n, np.inf)
    for j in range(n):
        if run.diverged[j]:
            continue
        if prep.truth_pos is not None:
            out[j] = track_errors(run.pos[j], prep.truth_pos, prep.n_align)["armse_pyshoe_m"]
        else:
            fp = prep.footprints
            out[j] = footprint_errors(run.pos[j][fp.sample], fp.pos)["footprint_mean_error_m"]
    return out


def errors_by_recording(
    setup: RealFilterSetup, recordings: Sequence[Recording]
) -> dict[str, float]:
    """:func:`lane_errors` of ``setup`` alone on each recording (m)."""
    return {rec.name: float(lane_errors(rec, setup, {})[0]) for rec in recordings}


def threshold_sweep(
    setup: RealFilterSetup, recordings: Sequence[Recording], thresholds: Sequence[float]
) -> Array:
    """(recordings, thresholds) errors of ``setup`` with each SHOE threshold γ (its
    other values kept): the search for the best single γ."""
    knobs = threshold_knobs(setup, thresholds)
    return np.array([lane_errors(rec, setup, knobs) for rec in recordings])


def threshold_knobs(setup: RealFilterSetup, thresholds: Sequence[float]) -> dict[str, Array]:
    """One lane per SHOE threshold γ, ``setup``'s noise scales on every lane: the
    knobs of ``run_prepared`` for a threshold sweep."""
    if not isinstance(setup.filter.detector, ShoeDetectorConfig):
        raise ValueError("threshold_sweep needs a SHOE detector setup")
    knobs = {"shoe_threshold": np.asarray(thresholds, dtype=float)}
    for name in ("process_noise_scale", "zupt_noise_scale"):
        knobs[name] = np.full(len(thresholds), getattr(setup.filter, name))
    return knobs
