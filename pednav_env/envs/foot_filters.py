"""The filter families of the foot environments: which filter action 0 is and
what the action's knobs set.

Both families run through the same engine (:class:`pednav_env.nav.zupt_ukf.ZuptUkf`
and its compiled kernel); they differ in the stance detector, in when ZUPTs
are applied and in the knobs:

- ``"paper"`` — paper 003's filter (Bolotin & Fatehrad 2015): the eq (5)
  detector on |ω'| and the vertical specific force, ZUPTs at stance start and
  end. Knobs (:data:`PAPER_KNOBS`): ω_max, Δf_max, process-noise scale, ZUPT
  noise scale around paper 003's values.
- ``"shoe"`` — the filter foot-mounted systems run (PyShoe, OpenShoe): the
  SHOE / GLRT detector (Skog et al. 2010 eq 11) and a ZUPT at every stance
  sample. Action 0 is ``real-fixed`` (:func:`pednav_env.replay.setup.real_fixed_setup`,
  read from ``real_fixed.json``); knobs (:func:`shoe_knobs`): log γ, the
  statistic's window, process- and ZUPT-noise scales around its values.

Both families may add the minimum stance duration as a fifth knob
(:data:`MIN_STANCE_MAX_S`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from pednav_env.envs.spec import Knob
from pednav_env.nav.detectors import ShoeDetectorConfig, ThresholdDetectorConfig, shoe_statistic_at
from pednav_env.nav.zupt_config import ZuptUkfConfig

Array = NDArray[np.float64]

#: Filter families, in the order the docs list them.
FILTER_FAMILIES = ("paper", "shoe")
#: The family the learned tuners use by default (the one whose constant
#: transfers from simulation to recordings, docs/SIM_TO_REAL.md).
LEARNED_FAMILY = "shoe"

#: Knobs of the paper family (log mapping, base · span ** a). ω_max and Δf_max
#: bases are paper 003's simulation thresholds (see ThresholdDetectorConfig);
#: the noise scales multiply the paper's Q and R.
PAPER_KNOBS: tuple[Knob, ...] = (
    Knob("omega_max", "log", 0.22, 10.0, "rad/s"),
    Knob("delta_f_max", "log", 0.33, 10.0, "m/s²"),
    Knob("process_noise_scale", "log", 1.0, 100.0, "1"),
    Knob("zupt_noise_scale", "log", 1.0, 100.0, "1"),
)
#: Spans of the shoe family's knobs: γ over four decades, the window from a
#: quarter to four times its base, the noise scales over four decades.
SHOE_SPANS = {"shoe_threshold": 100.0, "shoe_window_s": 4.0, "noise": 100.0}
#: Optional fifth knob of both families: minimum stance duration =
#: MIN_STANCE_MAX_S · max(a, 0) (a ≤ 0 keeps "no minimum").
MIN_STANCE_MAX_S = 0.15


def require_family(family: str) -> str:
    """``family`` if it is a known filter family, else a ValueError naming the parameter."""
    if family not in FILTER_FAMILIES:
        raise ValueError(f"filter: must be one of {FILTER_FAMILIES}, got {family!r}")
    return family


def family_filter(family: str, scenario: str) -> ZuptUkfConfig:
    """The filter at action 0 of ``family``: paper 003's (with its real-data gyro-bias
    calibration at rest except in the paper scenario, whose simulation has none),
    or ``real-fixed``'s, computed with the sigma points' angle-sum forms
    (``angle_sums``: the same filter, other rounding, less kernel time;
    docs/PERFORMANCE.md)."""
    if require_family(family) == "paper":
        return ZuptUkfConfig(calibrate_gyro_bias=scenario != "paper")
    from pednav_env.replay.setup import real_fixed_setup

    return replace(real_fixed_setup().filter, angle_sums=True)


def shoe_knobs(filt: ZuptUkfConfig) -> tuple[Knob, ...]:
    """The shoe family's knobs around the SHOE filter ``filt`` (its values at a = 0)."""
    det = filt.detector
    if not isinstance(det, ShoeDetectorConfig):
        raise ValueError(
            "filter='shoe' needs a SHOE detector (ShoeDetectorConfig) in config.filter"
        )
    return (
        Knob("shoe_threshold", "log", det.threshold, SHOE_SPANS["shoe_threshold"], "1"),
        Knob("shoe_window_s", "log", det.window_s, SHOE_SPANS["shoe_window_s"], "s"),
        Knob("process_noise_scale", "log", filt.process_noise_scale, SHOE_SPANS["noise"], "1"),
        Knob("zupt_noise_scale", "log", filt.zupt_noise_scale, SHOE_SPANS["noise"], "1"),
    )


def family_knobs(family: str, filt: ZuptUkfConfig) -> tuple[Knob, ...]:
    """The four knobs of ``family`` for its action-0 filter ``filt``."""
    if require_family(family) == "paper":
        if not isinstance(filt.detector, ThresholdDetectorConfig):
            raise ValueError("filter='paper' needs the eq (5) detector (ThresholdDetectorConfig)")
        return PAPER_KNOBS
    return shoe_knobs(filt)


def check_family_filter(family: str, filt: ZuptUkfConfig) -> None:
    """ValueError when the filter ``filt`` does not belong to ``family``."""
    family_knobs(family, filt)


class ShoeStatistic:
    """The SHOE statistic of a decision interval for lanes with their own windows.

    For lane i the statistic at sample m averages samples max(0, m − W_i + 1) … m
    of its record (the causal window of :func:`pednav_env.nav.detectors.shoe_statistic`,
    Skog et al. 2010 eq 11), with W_i = ``window_s`` · rate in samples (≥ 1);
    ``rate_hz`` is one rate or each lane's, ``(N,)``.
    """

    def __init__(self, detector: ShoeDetectorConfig, rate_hz: float | Array) -> None:
        self.detector = detector
        self.rate_hz = rate_hz

    def window_samples(self, window_s: Array) -> NDArray[np.int64]:
        """Windows in samples (round half to even, at least 1), as
        :func:`pednav_env.nav.detectors.window_samples`."""
        return np.maximum(1, np.round(np.asarray(window_s) * self.rate_hz)).astype(np.int64)

    def interval(
        self, omega: Array, f: Array, first: NDArray[np.integer], k: int, window_s: Array
    ) -> Array:
        """Statistic ``(N, k)`` at samples first … first + k − 1 of the lanes'
        records ``omega``, ``f`` ``(N, T, 3)`` (T ≥ first + k)."""
        return shoe_statistic_at(
            omega, f, np.asarray(first), k, self.window_samples(window_s), self.detector
        )
