"""How much of a walk's swing a too-high SHOE threshold calls stance
(docs/SIM_TO_REAL.md, "The threshold's response, simulated and recorded").

A zero-velocity detector declares stance where the SHOE statistic (Skog et al. 2010,
eq 11) is below its threshold γ; a γ above part of the swing's statistic makes false
zero-velocity updates there. Per walk and per γ, over the walking part
(:func:`pednav_env.calibration.stats.walking_part`, log10 SHOE with PyShoe's settings
as in :func:`pednav_env.calibration.stats.log10_shoe`):

- ``below``: the share of the non-stance samples whose log10 SHOE is below log10 γ,
  stance from the walk's own source (labels, the simulator's truth, else the
  detector rule), cleaned as the statistics clean labels;
- ``below_quiet_free``: the same share with "non-stance" the samples outside the
  label-free quiet phase (:func:`pednav_env.calibration.stats.quiet_phase`), the
  same rule on every walk;
- ``speed_weighted``: ``below`` weighted by the truth foot speed
  (:func:`pednav_env.calibration.stats.truth_speed`), i.e. the share of the swing's
  speed a false update would wipe; None without truth. Samples in a truth glitch
  (:func:`pednav_env.calibration.strides.truth_glitches`) or without a truth
  position are left out of the weighting.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pednav_env.calibration.stats import (
    WalkSamples,
    log10_shoe,
    quiet_phase,
    truth_speed,
    walking_stance,
)
from pednav_env.calibration.strides import truth_glitches


def _share(below: np.ndarray, weight: np.ndarray | None = None) -> float | None:
    """Share of True in ``below`` (weighted by ``weight``); None when empty."""
    if weight is None:
        return float(below.mean()) if below.size else None
    total = float(weight.sum())
    return float(weight[below].sum()) / total if total > 0 else None


def false_stance(samples: WalkSamples, log10_gammas: Sequence[float]) -> dict[str, Any]:
    """The walk's false-stance shares per threshold (module docstring): a dict with
    ``name``, ``stance_source``, ``walking_s``, ``nonstance_share`` (of the walking
    time), ``swing_speed_mps`` (mean truth speed over the non-stance samples, None
    without truth) and, one entry per ``log10_gammas`` value, lists ``below``,
    ``below_quiet_free`` and ``speed_weighted`` (entries None where undefined)."""
    s = samples
    rate = float(s.rate_hz)
    log_t = log10_shoe(s.omega_b, s.f_b, rate, s.g)
    source, stance, walking = walking_stance(s, log_t)
    swing = walking & ~stance
    quiet = np.zeros_like(walking)
    if walking.sum() >= 2:
        quiet[walking] = quiet_phase(log_t[walking], rate)
    loud = walking & ~quiet
    speed, log_speed = None, log_t[:0]
    if s.truth_pos is not None:
        v = truth_speed(s.truth_pos, rate)
        for a, b in truth_glitches(s.truth_pos, rate):
            v[a : b + 1] = np.nan
        ok = swing & np.isfinite(v)
        speed = v[ok]
        log_speed = log_t[ok]
    out: dict[str, Any] = {
        "name": s.name,
        "stance_source": str(source),
        "walking_s": float(walking.sum()) / rate,
        "nonstance_share": _share(swing[walking]),
        "swing_speed_mps": None if speed is None or not speed.size else float(speed.mean()),
        "below": [],
        "below_quiet_free": [],
        "speed_weighted": [],
    }
    for g in log10_gammas:
        out["below"].append(_share(log_t[swing] < g))
        out["below_quiet_free"].append(_share(log_t[loud] < g))
        out["speed_weighted"].append(None if speed is None else _share(log_speed < g, speed))
    return out
