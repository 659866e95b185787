"""Fit the gait-adaptive SHOE rule (:mod:`agents.gait_rule`) on recorded walks.

The simulator's rule (:mod:`agents.gait_rule_search`) learns on simulated walks
only. This module fits the same five parameters on recordings with truth, with
``pednav run``'s code path: for each recording the replay core plays the rule
(one lane per candidate), its knob schedule is recorded and the recording is
filtered with that schedule (:func:`pednav_env.replay.runner.run_prepared`), so
the error of a candidate here is the error ``pednav run --policy FILE`` prints.

Error of a recording: PyShoe's ARMSE (``armse_pyshoe_m``, the time average of
the RMS over axes after one horizontal rotation; docs/REAL_DATA.md) when it has
a truth track, else the mean footprint error (``footprint_mean_error_m``) when
it has footprints; a recording with neither cannot be scored (ValueError).

Objective of a candidate: the mean over *groups* of the mean over the group's
recordings of log10(error). A group is a data set (by default the directory a
recording comes from), so a set of 23 short trials does not outweigh one of 8
long walks; the logarithm lets a walk that runs away count as a large error,
not as all of the objective. Search: CMA-ES in x ∈ [−1, 1]⁵ with
c = :func:`agents.gait_rule_search.to_params` (x), started from the shipped
simulated ``tuned`` constant with slope 0 (a start that has seen no recording).
The replay is deterministic, so there is no evaluation noise to average; the
in-sample objective is biased low only by the fit itself, which is what
:func:`cross_validate` measures: each recording's error from a fit that did not
see it.

    pednav fit-rule RECORDING|DIR ... --out DIR [--folds K] [--generations G]
        [--popsize P] [--seed S] [--json]
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from agents.gait_rule import FAMILY, N_PARAMS, GaitRuleParams, rule_actions
from agents.gait_rule_search import rule_errors, to_params, tuned_start
from agents.run_recording import knob_schedule
from pednav_env.io import Recording, find_recordings, load_recording
from pednav_env.replay.metrics import footprint_errors, track_errors
from pednav_env.replay.runner import run_prepared
from pednav_env.seeds import search_seeds

#: Decision interval of the replay (s), as ``pednav run``.
INTERVAL_S = 0.5
ARMSE_KEY = "armse_pyshoe_m"
#: The group of the simulated walks in the objective.
SIMULATED_GROUP = "simulated"
FOOTPRINT_KEY = "footprint_mean_error_m"
#: Index of the slope c1 in the rule's parameters (held at 0 by ``constant``).
SLOPE_INDEX = 1


@dataclass(frozen=True)
class FitRecording:
    """One recording of the fit: its group (data set) and the error it is scored by."""

    name: str
    group: str
    recording: Recording
    metric: str  # ARMSE_KEY or FOOTPRINT_KEY


def scored_recording(rec: Recording, group: str, source: str | Path = "") -> FitRecording:
    """``rec`` with the error it is scored by; ValueError naming ``source`` when
    the recording has neither a truth track nor footprints."""
    if rec.has_truth:
        metric = ARMSE_KEY
    elif rec.footprints is not None:
        metric = FOOTPRINT_KEY
    else:
        raise ValueError(
            f"{source or rec.name}: no truth track and no footprints: a fit needs one of them"
        )
    return FitRecording(rec.name, group, rec, metric)


def load_fit_recordings(paths: Sequence[str | Path]) -> list[FitRecording]:
    """Recordings of ``paths`` (files, or directories of recordings); the group of
    each is the name of the directory it is in. ValueError naming the path when
    a path does not exist, a directory holds no recording, or a file cannot be
    scored; also when two paths name the same file or two files hold the same samples."""
    files: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            found = find_recordings(p)
            if not found:
                raise ValueError(f"{p}: no recordings (.mat, .csv) found")
            files += found
        elif p.is_file():
            files.append(p)
        else:
            raise ValueError(f"{p}: no such file or directory")
    seen: set[Path] = set()
    samples: dict[bytes, Path] = {}
    out = []
    for f in files:
        key = f.resolve()
        if key in seen:
            raise ValueError(f"{f}: given twice")
        seen.add(key)
        rec = load_recording(f)
        same = _sample_key(rec)
        if same in samples:
            raise ValueError(
                f"{f}: the same samples as {samples[same]} (one walk twice?): "
                "give one of them, or the walk counts twice"
            )
        samples[same] = f
        out.append(scored_recording(rec, f.resolve().parent.name, f))
    return out


def _sample_key(rec: Recording) -> bytes:
    """The first 200 angular-rate samples (to 1e-9 rad/s): equal for one walk saved
    in two formats (e.g. a vendor CSV and its .mat) or cut to two lengths."""
    return np.round(rec.omega_b[:200], 9).tobytes()


def recording_errors(fr: FitRecording, cs: np.ndarray, base: GaitRuleParams) -> np.ndarray:
    """The error of ``fr`` (its metric, m) for each parameter row of ``cs`` (P, 5)."""
    cs = np.atleast_2d(np.asarray(cs, dtype=np.float64))
    prep, schedule = knob_schedule(
        fr.recording,
        FAMILY,
        len(cs),
        lambda obs: rule_actions(obs, cs, base).astype(np.float64),
        INTERVAL_S,
        "pednav fit-rule",
    )
    run = run_prepared(prep, num_lanes=len(cs), schedule=schedule, interval_s=INTERVAL_S)
    out = np.empty(len(cs))
    for j in range(len(cs)):
        if fr.metric == ARMSE_KEY:
            out[j] = track_errors(run.pos[j], prep.truth_pos, prep.n_align)[ARMSE_KEY]
        else:
            fp = prep.footprints
            out[j] = footprint_errors(run.pos[j][fp.sample], fp.pos)[FOOTPRINT_KEY]
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{fr.name}: the error is not finite for some candidate")
    return out


def errors_matrix(
    recs: Sequence[FitRecording],
    cs: np.ndarray,
    base: GaitRuleParams,
    simulated_seeds: Sequence[int] = (),
) -> np.ndarray:
    """Errors (P candidates, R recordings + S simulated walks): the recordings',
    then the time-averaged error of ``pednav/FootZupt-v0`` (shoe family,
    calibrated scenario) on the episodes of ``simulated_seeds`` (training seeds),
    :func:`agents.gait_rule_search.rule_errors`."""
    cols = [recording_errors(fr, cs, base) for fr in recs]
    if len(simulated_seeds):
        cols.append(rule_errors(np.atleast_2d(cs), list(simulated_seeds), base))
    return np.column_stack(cols)


def objective(errors: np.ndarray, groups: Sequence[str]) -> np.ndarray:
    """Mean over groups of the group's mean log10 error, per candidate row."""
    groups = np.asarray(groups)
    logs = np.log10(np.atleast_2d(errors))
    return np.mean([logs[:, groups == g].mean(axis=1) for g in np.unique(groups)], axis=0)


def fit(
    recs: Sequence[FitRecording],
    generations: int = 12,
    popsize: int = 10,
    sigma0: float = 0.3,
    seed: int = 1,
    base: GaitRuleParams | None = None,
    progress: Callable[[int, float], None] | None = None,
    simulated_episodes: int = 0,
    episode_set: int = 0,
    constant: bool = False,
) -> tuple[GaitRuleParams, dict[str, Any]]:
    """CMA-ES over the rule's parameters on ``recs`` (module docstring); returns
    the parameters and the fit's record. ``simulated_episodes`` > 0 adds a group of
    that many calibrated simulated training walks (search episode set
    ``episode_set``, :func:`pednav_env.seeds.search_seeds`), which covers gaits the
    recordings may lack (running). ``constant``: the slope c1 is held at 0 and
    CMA-ES searches the other four parameters: the best constant SHOE
    configuration (γ, window, Q, R) by the same objective, the comparator that
    says what adapting γ to the gait adds."""
    import cma

    if not recs:
        raise ValueError("recordings: at least one is required")
    if generations < 1 or popsize < 2 or not (math.isfinite(sigma0) and sigma0 > 0):
        raise ValueError("generations ≥ 1, popsize ≥ 2 and sigma0 > 0 are required")
    if simulated_episodes < 0:
        raise ValueError(f"simulated_episodes: must be ≥ 0, got {simulated_episodes}")
    base = base or GaitRuleParams(c=(0.0,) * N_PARAMS)
    sim = search_seeds(episode_set, simulated_episodes) if simulated_episodes else []
    groups = [r.group for r in recs] + [SIMULATED_GROUP] * len(sim)
    x0 = tuned_start()  # slope x1 = 0
    free = np.array([i for i in range(N_PARAMS) if not (constant and i == SLOPE_INDEX)])

    def full(x: np.ndarray) -> np.ndarray:
        """Search points in the free coordinates → all five (the slope at x0's 0)."""
        out = np.tile(x0, (len(x), 1))
        out[:, free] = x
        return out

    es = cma.CMAEvolutionStrategy(
        x0[free], sigma0, {"bounds": [-1.0, 1.0], "popsize": popsize, "seed": seed, "verbose": -9}
    )
    start, history = time.perf_counter(), []
    for g in range(generations):
        xs_free = np.clip(np.asarray(es.ask()), -1.0, 1.0)
        xs = full(xs_free)
        scores = objective(errors_matrix(recs, to_params(xs), base, sim), groups)
        es.tell(list(xs_free), scores.tolist())
        history.append(float(scores.min()))
        if progress is not None:
            progress(g + 1, float(scores.min()))
    best = full(np.clip(np.asarray(es.result.xbest), -1.0, 1.0)[None, :])[0]
    both = errors_matrix(recs, to_params(np.stack([best, x0])), base, sim)
    scores = objective(both, groups)
    kept_start = bool(scores[1] < scores[0])  # the start itself is not a CMA-ES candidate
    j = int(kept_start)
    c = to_params(np.stack([best, x0])[j])
    record = {
        "fitted_on": [r.name for r in recs],
        "groups": sorted(set(groups)),
        "objective_log10_m": float(scores[j]),
        "start_objective_log10_m": float(scores[1]),
        "kept_start": kept_start,
        "errors_m": dict(
            zip([r.name for r in recs], both[j, : len(recs)].round(5).tolist(), strict=True)
        ),
        "simulated_episode_seeds": [sim[0], sim[-1]] if sim else [],
        "simulated_errors_m": both[j, len(recs) :].round(4).tolist(),
        "evaluations": int(es.result.evaluations),
        "generations": generations,
        "popsize": popsize,
        "sigma0": sigma0,
        "cma_seed": seed,
        "constant": constant,
        "initial_c": to_params(x0).tolist(),
        "best_per_generation_log10_m": history,
        "seconds": round(time.perf_counter() - start, 1),
    }
    return replace(base, c=tuple(float(v) for v in c)), record


def folds(recs: Sequence[FitRecording], k: int) -> list[np.ndarray]:
    """k held-out index sets: within each group, recordings sorted by name and cut
    into k contiguous blocks (``np.array_split``); fold i holds out block i of
    every group. ValueError when a group has fewer than k recordings."""
    if k < 2:
        raise ValueError(f"folds: at least 2 are needed, got {k}")
    out: list[list[int]] = [[] for _ in range(k)]
    for g in sorted({r.group for r in recs}):
        idx = sorted((i for i, r in enumerate(recs) if r.group == g), key=lambda i: recs[i].name)
        if len(idx) < k:
            raise ValueError(f"folds: group {g!r} has {len(idx)} recordings, fewer than {k}")
        for i, block in enumerate(np.array_split(np.array(idx), k)):
            out[i] += block.tolist()
    return [np.array(sorted(f)) for f in out]


def cross_validate(
    recs: Sequence[FitRecording],
    held_out: Sequence[np.ndarray],
    **fit_kwargs: Any,
) -> dict[str, Any]:
    """Fit on all but each held-out set and score the held-out recordings with
    that fit: the held-out error of every recording (it must be held out once)."""
    counts = np.bincount(np.concatenate(held_out), minlength=len(recs))
    if np.any(counts != 1):
        raise ValueError("held_out: every recording must be held out exactly once")
    errors = np.full(len(recs), np.nan)
    fold_records = []
    for i, test in enumerate(held_out):
        train = [r for j, r in enumerate(recs) if j not in set(test.tolist())]
        params, record = fit(train, **fit_kwargs)
        errors[test] = errors_matrix([recs[j] for j in test], np.array([params.c]), params)[0]
        fold_records.append(
            {
                "fold": i,
                "held_out": [recs[j].name for j in test],
                "c": list(params.c),
                "fit": record,
            }
        )
    return {
        "held_out_errors_m": dict(zip([r.name for r in recs], errors.tolist(), strict=True)),
        "folds": fold_records,
    }
