"""The development search that chose ``real-fixed`` (docs/REAL_DATA.md).

Grid search of one fixed configuration over development recordings with a
reference. Each *family* fixes what the engine shares across lanes (detector
type and window, update mode); its grid varies the per-lane knobs
(thresholds, noise scales), all lanes of a family running together through
one batched filter per recording. The score of a configuration is the mean
over the recordings of PyShoe's ARMSE (``armse_pyshoe_m``), the figure the
issue's target compares with; ties are irrelevant at the printed precision.

Stages (:func:`select`): stage 1 is the grid of :func:`default_families`;
each further stage is a finer grid around the current winner
(:func:`refine_family`: thresholds × 0.5…1.5, noise scales × 0.1…3), and the
choice is over all stages so far. Refinement goes on while the winner comes
from the newest grid and sits on its edge in some knob (the optimum may lie
beyond it), at most :data:`MAX_REFINEMENTS` times.

Honesty check: the trials (sorted by name) are split into two folds (even
and odd positions); the whole selection, refinements included, is run on one
fold and its choice scored on the other. The shipped configuration is the
one chosen on all trials.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.files import writing
from pednav_env.io.recording import Recording
from pednav_env.nav.detectors import ShoeDetectorConfig, ThresholdDetectorConfig
from pednav_env.nav.zupt_config import UpdateMode, ZuptUkfConfig
from pednav_env.replay.metrics import track_errors
from pednav_env.replay.runner import prepare, run_prepared
from pednav_env.replay.setup import RealFilterSetup

#: PyShoe's SHOE noise figures for the MicroStrain (its INS(sigma_a, sigma_w))
#: and window (W = 5 samples at 200 Hz): thresholds are then in PyShoe's units.
PYSHOE_SHOE = ShoeDetectorConfig(
    threshold=1e7, window_s=0.025, accel_noise_std=0.00098, gyro_noise_std=8.7266463e-5
)


@dataclass(frozen=True)
class Family:
    """Engine-wide choices and the per-lane knob grid of one search family."""

    name: str
    setup: RealFilterSetup
    grid: dict[str, tuple[float, ...]]

    def lanes(self) -> list[dict[str, float]]:
        keys = list(self.grid)
        return [dict(zip(keys, v, strict=True)) for v in itertools.product(*self.grid.values())]


def default_families() -> list[Family]:
    """The documented search space (docs/REAL_DATA.md, "The real-fixed search")."""
    noise = {"process_noise_scale": (0.1, 1.0, 10.0), "zupt_noise_scale": (0.1, 1.0, 10.0)}
    fams = []
    for mode in (UpdateMode.EVERY_STANCE_SAMPLE, UpdateMode.STANCE_BOUNDARIES):
        shoe = RealFilterSetup(
            filter=ZuptUkfConfig(detector=PYSHOE_SHOE, calibrate_gyro_bias=True, update_mode=mode)
        )
        fams.append(
            Family(
                f"shoe/{mode}",
                shoe,
                {"shoe_threshold": (2e6, 5e6, 1e7, 2e7, 5e7, 1e8), **noise},
            )
        )
        thr = RealFilterSetup(
            filter=ZuptUkfConfig(
                detector=ThresholdDetectorConfig.real_data(),
                calibrate_gyro_bias=True,
                update_mode=mode,
            )
        )
        fams.append(
            Family(
                f"threshold/{mode}",
                thr,
                {
                    "omega_max": (0.1, 0.3, 1.0),
                    "delta_f_max": (0.3, 1.0, 3.0),
                    **noise,
                },
            )
        )
    return fams


def shoe_families() -> list[Family]:
    """The SHOE families of :func:`default_families` (PyShoe's detector and units;
    threshold γ, process and ZUPT noise scales; both update modes)."""
    return [f for f in default_families() if f.name.startswith("shoe/")]


#: Stage-2 factors around the stage-1 winner: thresholds and noise scales.
REFINE_THRESHOLD = (0.5, 0.75, 1.0, 1.5)
REFINE_SCALE = (0.1, 0.3, 1.0, 3.0)


#: Most refinement stages after stage 1.
MAX_REFINEMENTS = 4


def refine_family(family: Family, lane: dict[str, float], stage: int) -> Family:
    """A finer grid around ``lane`` of ``family`` (same engine choices), named by the
    stage-1 family, the stage and the centre."""
    grid = {
        k: tuple(v * f for f in (REFINE_SCALE if k.endswith("noise_scale") else REFINE_THRESHOLD))
        for k, v in lane.items()
    }
    centre = ",".join(f"{v:.3g}" for v in lane.values())
    base = family.name.split("/stage")[0]
    return Family(f"{base}/stage{stage}({centre})", family.setup, grid)


def on_edge(family: Family, lane: dict[str, float]) -> bool:
    """Whether ``lane`` takes the smallest or largest grid value of some knob."""
    return any(lane[k] in (min(v), max(v)) for k, v in family.grid.items())


def score_family(
    recordings: Sequence[Recording], family: Family, cap: np.ndarray | None = None
) -> np.ndarray:
    """``armse_pyshoe_m`` per (recording, lane); diverged lanes get +inf, or the
    recording's ``cap`` (m) when given (every score is then at most its cap)."""
    lanes = family.lanes()
    knobs = {k: np.array([ln[k] for ln in lanes]) for k in family.grid}
    out = np.full((len(recordings), len(lanes)), np.inf)
    for i, rec in enumerate(recordings):
        prep = prepare(rec, family.setup)
        run = run_prepared(prep, len(lanes), knobs=knobs)
        for j in range(len(lanes)):
            if not run.diverged[j]:
                out[i, j] = track_errors(run.pos[j], prep.truth_pos, prep.n_align)["armse_pyshoe_m"]
    if cap is not None:
        out = np.minimum(out, np.asarray(cap, dtype=float)[:, None])
    return out


def choose(scores: dict[str, np.ndarray], rows: np.ndarray) -> tuple[str, int, float]:
    """(family, lane, mean score) with the lowest mean over recordings ``rows``."""
    best = ("", -1, np.inf)
    for name, s in scores.items():
        m = s[rows].mean(axis=0)
        j = int(np.argmin(m))
        if m[j] < best[2]:
            best = (name, j, float(m[j]))
    return best


def setup_for(family: Family, lane: dict[str, float]) -> RealFilterSetup:
    """The single configuration of ``lane`` as a :class:`RealFilterSetup`."""
    f = family.setup.filter
    det = f.detector
    if isinstance(det, ShoeDetectorConfig):
        det = replace(det, threshold=lane["shoe_threshold"])
    else:
        det = replace(det, omega_max=lane["omega_max"], delta_f_max=lane["delta_f_max"])
    filt = replace(
        f,
        detector=det,
        process_noise_scale=lane["process_noise_scale"],
        zupt_noise_scale=lane["zupt_noise_scale"],
    )
    return replace(family.setup, filter=filt)


def select(
    recordings: Sequence[Recording],
    scores: dict[str, np.ndarray],
    by_name: dict[str, Family],
    stage1: Sequence[str],
    rows: np.ndarray,
    cap: np.ndarray | None = None,
) -> tuple[str, int, float, list[dict[str, Any]]]:
    """Choose on recordings ``rows``: stage 1 over the families ``stage1``, then
    refinements around the winner while it sits on the edge of the newest grid.
    New families are scored on all recordings and cached in ``scores``/``by_name``.
    Returns (family, lane, mean score on ``rows``, the winner of every stage)."""
    candidates = list(stage1)
    fam, lane, mean = choose({n: scores[n] for n in candidates}, rows)
    path = [{"family": fam, "lane": by_name[fam].lanes()[lane], "mean_armse_pyshoe_m": mean}]
    for stage in range(2, 2 + MAX_REFINEMENTS):
        if fam != candidates[-1] and stage > 2:
            break  # the newest grid did not win: its centre is the optimum
        if stage > 2 and not on_edge(by_name[fam], by_name[fam].lanes()[lane]):
            break
        refined = refine_family(by_name[fam], by_name[fam].lanes()[lane], stage)
        if refined.name not in scores:
            scores[refined.name] = score_family(recordings, refined, cap)
            by_name[refined.name] = refined
        candidates.append(refined.name)
        fam, lane, mean = choose({n: scores[n] for n in candidates}, rows)
        path.append(
            {"family": fam, "lane": by_name[fam].lanes()[lane], "mean_armse_pyshoe_m": mean}
        )
    return fam, lane, mean, path


def search(
    recordings: Sequence[Recording],
    families: Sequence[Family] | None = None,
    cap: np.ndarray | None = None,
) -> dict[str, Any]:
    """Run the search; returns the chosen setup, its stages, the fold check and the
    best configurations. ``cap`` (m, one per recording): the most a recording's
    score counts (:func:`score_family`); None for the ``real-fixed`` search."""
    families = list(families or default_families())
    scores = {f.name: score_family(recordings, f, cap) for f in families}
    by_name = {f.name: f for f in families}
    stage1 = [f.name for f in families]
    n = len(recordings)
    all_rows = np.arange(n)
    fam, lane, mean, stages = select(recordings, scores, by_name, stage1, all_rows, cap)
    folds = []
    for a, b in ((all_rows[0::2], all_rows[1::2]), (all_rows[1::2], all_rows[0::2])):
        fa, la, ma, fold_stages = select(recordings, scores, by_name, stage1, a, cap)
        folds.append(
            {
                "select_on": [recordings[i].name for i in a],
                "family": fa,
                "lane": by_name[fa].lanes()[la],
                "stages": len(fold_stages),
                "score_on_selection": ma,
                "score_on_other_fold": float(scores[fa][b, la].mean()),
                "all_trials_config_on_other_fold": float(scores[fam][b, lane].mean()),
            }
        )
    chosen = setup_for(by_name[fam], by_name[fam].lanes()[lane])
    table = [
        {
            "family": name,
            "lane": by_name[name].lanes()[j],
            "mean_armse_pyshoe_m": float(s[:, j].mean()),
            "max_armse_pyshoe_m": float(s[:, j].max()),
        }
        for name, s in scores.items()
        for j in range(s.shape[1])
    ]
    table.sort(key=lambda r: r["mean_armse_pyshoe_m"])
    return {
        "setup": chosen.to_dict(),
        "stages": stages,
        "chosen": {"family": fam, "lane": by_name[fam].lanes()[lane], "mean_armse_pyshoe_m": mean},
        "per_trial_armse_pyshoe_m": dict(
            zip([r.name for r in recordings], scores[fam][:, lane].tolist(), strict=True)
        ),
        "folds": folds,
        "trials": [r.name for r in recordings],
        "top": table[:20],
    }


def write(result: dict[str, Any], path: Path) -> None:
    """Write the search result as the shipped ``real_fixed.json``."""
    with writing(path):
        path.write_text(json.dumps(result, indent=1, default=float) + "\n")
