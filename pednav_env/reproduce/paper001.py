"""Reproduction of paper 001: heel and knee UWB markers, EKF vs low-pass.

The thesis (chapter 6) simulates raw DecaWave positions of a heel and a knee
marker, filters them with its EKF (chapter 5) and with "the simplest low-pass
filter", and prints the RMS errors of x₁, z₁ (heel) and x₂, z₂ (knee):
EKF 0.0575, 0.0072, 0.0572, 0.0078 m; low-pass 0.0701, 0.0324, 0.0308,
0.0400 m; "the synthesised filter is 1.5 times more accurate".

Our scenario (every choice and its reason: docs/REPRODUCTION.md (paper 001)):

- truth: the thesis's own model, eq 4.10 literally with the deviations of
  eq 4.11 (``kinematics="paper"``), starting at the nominal values (eq 5.6);
  nominal values of §4.2 except the shank-angle amplitude A⁰ (printed 0,
  ours −asin(A_x⁰/2M) ≈ −0.41 rad);
- Q read as "stationary variance 0.03 × nominal²" (eqs 5.2, 5.4, 5.8);
- UWB at 10 Hz with σ = 0.1 m per axis (eq 5.5); walks of 10 s (K = 100);
- parameter correlation time τ = 10⁴ s (d = exp(−T/τ)): with eq 4.10 taken
  literally the elapsed time kT multiplies the parameters' sample-to-sample
  jitter, and τ ≥ 10⁴ s keeps the jitter this adds to the heel's velocity at
  the end of a 10 s walk within ~10 % of c_x⁰;
- the EKF of chapter 5 with the simulator's own p⁰, T, d, 0.03 and σ;
- low-pass: causal first-order Butterworth (RC) filter per coordinate, its
  cut-off minimising the predicted RMS error on the nominal gait
  (:func:`~pednav_env.nav.lowpass.lowpass_cutoff_for_gait`);
- RMS over all samples of all runs, per coordinate;
  ``improvement_ratio`` = Σ low-pass RMS / Σ EKF RMS over the four
  coordinates, ``ratio_<coord>`` = low-pass RMS / EKF RMS.

Runs are independent walkers; walker i uses the generators spawned from
``SeedSequence(seed).spawn(runs)[i]`` (one for the gait, one for the UWB).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from pednav_env.gait.heel_knee import HeelKneeConfig, simulate_heel_knee
from pednav_env.gait.heel_knee_model import I_OMEGA
from pednav_env.nav.lowpass import lowpass_cutoff_for_gait, lowpass_filter
from pednav_env.nav.marker_model import MarkerEkfConfig
from pednav_env.nav.marker_run import run_marker_ekf
from pednav_env.reproduce import ReproductionResult, ReproductionRow
from pednav_env.sensors.uwb import UwbSpec, measure_uwb

#: Coordinates in the order of the thesis's result vectors (chapter 6).
COORDS: tuple[str, ...] = ("heel_x", "heel_z", "knee_x", "knee_z")
#: Thesis chapter 6, EKF RMS errors (m).
PAPER_EKF: dict[str, float] = {
    "heel_x": 0.0575,
    "heel_z": 0.0072,
    "knee_x": 0.0572,
    "knee_z": 0.0078,
}
#: Thesis chapter 6, low-pass RMS errors (m).
PAPER_LOWPASS: dict[str, float] = {
    "heel_x": 0.0701,
    "heel_z": 0.0324,
    "knee_x": 0.0308,
    "knee_z": 0.0400,
}
#: Thesis chapter 6: "more accurate ... by 1.5 times" (no definition given).
PAPER_IMPROVEMENT = 1.5
#: Default number of simulated walks of :func:`run`.
DEFAULT_RUNS = 4000


@dataclass(frozen=True)
class Paper001Scenario:
    """Everything one reproduction run needs.

    Attributes
    ----------
    gait : HeelKneeConfig
        Truth simulator (its ``sample_period`` must be the UWB period).
    uwb : UwbSpec
        Sensor model.
    duration : float
        Length of each walk (s); K = round(duration · rate) samples.
    lowpass_cutoff_hz : float or None
        Cut-off of the low-pass; None picks
        :func:`~pednav_env.nav.lowpass.lowpass_cutoff_for_gait`.
    lowpass_zero_phase : bool
        Use the (non-causal) forward-backward low-pass instead.
    """

    gait: HeelKneeConfig = field(default_factory=HeelKneeConfig.paper)
    uwb: UwbSpec = field(default_factory=UwbSpec.paper)
    duration: float = 10.0  # ours: ≈ 14 gait cycles, a gait-lab walk
    lowpass_cutoff_hz: float | None = None  # ours: best first-order cut-off for p⁰
    lowpass_zero_phase: bool = False  # issue 5: causal baseline

    def __post_init__(self) -> None:
        if not math.isclose(self.gait.sample_period, self.uwb.sample_period, rel_tol=1e-12):
            raise ValueError(
                f"Paper001Scenario: gait.sample_period={self.gait.sample_period} must equal "
                f"1/uwb.rate_hz={self.uwb.sample_period}"
            )
        if not (isinstance(self.duration, (int, float)) and math.isfinite(self.duration)):
            raise ValueError(f"Paper001Scenario.duration must be finite, got {self.duration!r}")
        if self.duration * self.uwb.rate_hz < 2:
            raise ValueError(
                f"Paper001Scenario.duration must cover >= 2 samples, got {self.duration!r}"
            )
        if self.lowpass_cutoff_hz is not None and not (
            math.isfinite(self.lowpass_cutoff_hz)
            and 0 < self.lowpass_cutoff_hz < self.uwb.rate_hz / 2
        ):
            raise ValueError(
                "Paper001Scenario.lowpass_cutoff_hz must be in (0, rate/2), "
                f"got {self.lowpass_cutoff_hz!r}"
            )

    @property
    def num_samples(self) -> int:
        return round(self.duration * self.uwb.rate_hz)

    @property
    def cutoff_hz(self) -> float:
        """The low-pass cut-off actually used (Hz)."""
        if self.lowpass_cutoff_hz is not None:
            return self.lowpass_cutoff_hz
        return lowpass_cutoff_for_gait(
            self.gait.nominal,
            self.uwb.rate_hz,
            self.uwb.noise_std,
            self.duration,
            zero_phase=self.lowpass_zero_phase,
        )


#: Keyword overrides accepted by :func:`paper_scenario` and :func:`run`.
SCENARIO_KEYS = (
    "rate_hz",
    "duration",
    "param_corr_time",
    "param_var_ratio",
    "shank_angle_amplitude",
    "kinematics",
    "initial_deviation",
    "lowpass_cutoff_hz",
    "lowpass_zero_phase",
    "noise_std",
)


def paper_scenario(**overrides: Any) -> Paper001Scenario:
    """The paper-001 scenario, optionally with some settings changed.

    Parameters
    ----------
    **overrides
        Any of :data:`SCENARIO_KEYS`: ``rate_hz`` (UWB and simulation rate),
        ``noise_std`` (UWB σ), ``duration``, ``param_corr_time``,
        ``param_var_ratio``, ``shank_angle_amplitude``, ``kinematics``,
        ``initial_deviation``, ``lowpass_cutoff_hz``, ``lowpass_zero_phase``.
    """
    unknown = sorted(set(overrides) - set(SCENARIO_KEYS))
    if unknown:
        raise ValueError(f"paper 001: unknown setting(s) {unknown}; known: {list(SCENARIO_KEYS)}")
    base = Paper001Scenario()
    uwb = base.uwb
    if "rate_hz" in overrides or "noise_std" in overrides:
        uwb = UwbSpec(
            rate_hz=overrides.get("rate_hz", uwb.rate_hz),
            noise_std=overrides.get("noise_std", uwb.noise_std),
        )
    nominal = base.gait.nominal
    if "shank_angle_amplitude" in overrides:
        nominal = replace(nominal, shank_angle_amplitude=overrides["shank_angle_amplitude"])
    gait_kw = {
        k: overrides[k]
        for k in ("param_corr_time", "param_var_ratio", "kinematics", "initial_deviation")
        if k in overrides
    }
    gait = replace(base.gait, nominal=nominal, sample_period=uwb.sample_period, **gait_kw)
    scen_kw = {
        k: overrides[k]
        for k in ("duration", "lowpass_cutoff_hz", "lowpass_zero_phase")
        if k in overrides
    }
    return replace(base, gait=gait, uwb=uwb, **scen_kw)


@dataclass(frozen=True)
class Paper001Errors:
    """Scores of one scenario.

    Attributes
    ----------
    ekf, lowpass, raw : ndarray, shape (4,)
        RMS errors (m) over all samples of all walks, :data:`COORDS` order.
    ekf_walker_mse, lowpass_walker_mse : ndarray, shape (runs, 4)
        Mean squared error of each walk (m²), for Monte Carlo standard errors.
    cutoff_hz : float
        Low-pass cut-off used.
    mean_nis : float
        Mean EKF NIS over all updates after the first (4 if consistent).
    slip_fraction : float
        Share of walks whose final phase error |(ω₀ + Δω̂) kT − φ| exceeds π:
        the EKF has locked onto another cycle of the gait harmonic.
    repairs : int
        EKF covariance repairs summed over walks.
    runs, samples : int
        Walks and samples per walk.
    """

    ekf: np.ndarray
    lowpass: np.ndarray
    raw: np.ndarray
    ekf_walker_mse: np.ndarray
    lowpass_walker_mse: np.ndarray
    cutoff_hz: float
    mean_nis: float
    slip_fraction: float
    repairs: int
    runs: int
    samples: int


def _walker_rngs(
    seed: int, runs: int
) -> tuple[list[np.random.Generator], list[np.random.Generator]]:
    children = np.random.SeedSequence(seed).spawn(runs)
    pairs = [c.spawn(2) for c in children]
    return (
        [np.random.default_rng(p[0]) for p in pairs],
        [np.random.default_rng(p[1]) for p in pairs],
    )


def evaluate(scenario: Paper001Scenario, runs: int, seed: int) -> Paper001Errors:
    """Simulate ``runs`` walks and score the EKF, the low-pass and the raw data.

    RMS per coordinate over all samples of all walks (m).
    """
    if not isinstance(runs, (int, np.integer)) or runs < 1:
        raise ValueError(f"runs must be an integer >= 1, got {runs!r}")
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    gait_rngs, uwb_rngs = _walker_rngs(int(seed), int(runs))
    walk = simulate_heel_knee(scenario.gait, scenario.num_samples, gait_rngs)
    meas = measure_uwb(scenario.uwb, walk.markers, uwb_rngs)
    ekf_cfg = MarkerEkfConfig.matched(scenario.gait, scenario.uwb)
    est = run_marker_ekf(ekf_cfg, meas.z, meas.valid)
    cutoff = scenario.cutoff_hz
    low = lowpass_filter(
        meas.z,
        cutoff,
        scenario.uwb.rate_hz,
        valid=meas.valid,
        zero_phase=scenario.lowpass_zero_phase,
    )

    def walker_mse(estimate: np.ndarray) -> np.ndarray:
        err = (estimate - walk.markers).reshape(runs, scenario.num_samples, 4)
        return np.mean(err**2, axis=1)

    ekf_mse, low_mse = walker_mse(est.markers), walker_mse(low)
    t_end = walk.t[-1]
    phase_est = (scenario.gait.nominal.omega + est.x[:, -1, I_OMEGA]) * t_end
    phase_err = np.abs(phase_est - walk.phase[:, -1])
    return Paper001Errors(
        ekf=np.sqrt(ekf_mse.mean(axis=0)),
        lowpass=np.sqrt(low_mse.mean(axis=0)),
        raw=np.sqrt(walker_mse(meas.z).mean(axis=0)),
        ekf_walker_mse=ekf_mse,
        lowpass_walker_mse=low_mse,
        cutoff_hz=cutoff,
        mean_nis=float(np.mean(est.nis[:, 1:])),
        slip_fraction=float(np.mean(phase_err > np.pi)),
        repairs=int(est.repairs.sum()),
        runs=int(runs),
        samples=scenario.num_samples,
    )


def run(runs: int | None = None, seed: int = 0, **kw: Any) -> ReproductionResult:
    """Reproduce the thesis's chapter-6 table.

    Parameters
    ----------
    runs : int, optional
        Number of simulated walks (default :data:`DEFAULT_RUNS`).
    seed : int
        Root seed.
    **kw
        Scenario overrides (:func:`paper_scenario`), for sensitivity studies.

    Returns
    -------
    ReproductionResult
        Rows ``ekf`` / ``lowpass`` × ``heel_x``, ``heel_z``, ``knee_x``,
        ``knee_z`` (m) and ``summary`` × ``improvement_ratio`` and
        ``ratio_<coord>`` (dimensionless).
    """
    start = time.perf_counter()
    scenario = paper_scenario(**kw)
    n_runs = DEFAULT_RUNS if runs is None else runs
    res = evaluate(scenario, n_runs, seed)
    rows: list[ReproductionRow] = []
    for config, ours, paper in (
        ("ekf", res.ekf, PAPER_EKF),
        ("lowpass", res.lowpass, PAPER_LOWPASS),
    ):
        rows.extend(
            ReproductionRow(config, name, "m", paper[name], float(value))
            for name, value in zip(COORDS, ours, strict=True)
        )
    rows.append(
        ReproductionRow(
            "summary",
            "improvement_ratio",
            "",
            PAPER_IMPROVEMENT,
            float(res.lowpass.sum() / res.ekf.sum()),
        )
    )
    rows.extend(
        ReproductionRow("summary", f"ratio_{name}", "", None, float(lo / ek))
        for name, lo, ek in zip(COORDS, res.lowpass, res.ekf, strict=True)
    )
    paper_ratio = sum(PAPER_LOWPASS.values()) / sum(PAPER_EKF.values())
    g = scenario.gait
    notes = [
        f"{res.runs} walks x {res.samples} samples at {scenario.uwb.rate_hz:g} Hz "
        f"({scenario.duration:g} s), sigma = {scenario.uwb.noise_std:g} m, seed {seed}",
        f"truth kinematics={g.kinematics}, initial_deviation={g.initial_deviation}, "
        f"tau = {g.param_corr_time:g} s (d = {g.inertia:.8f}), 0.03 -> {g.param_var_ratio:g}, "
        f"A0 = {g.nominal.shank_angle_amplitude:.4f} rad",
        f"low-pass: {'zero-phase' if scenario.lowpass_zero_phase else 'causal'} first-order "
        f"Butterworth, cut-off {res.cutoff_hz:.3f} Hz",
        "raw UWB RMS (heel_x, heel_z, knee_x, knee_z): "
        + ", ".join(f"{v:.4f}" for v in res.raw)
        + " m",
        f"EKF mean NIS {res.mean_nis:.3f} (4 expected), covariance repairs {res.repairs}, "
        f"walks ending on a wrong phase cycle {100 * res.slip_fraction:.1f} %",
        "improvement_ratio = sum of the four low-pass RMS / sum of the four EKF RMS; "
        f"the thesis's own table gives {paper_ratio:.3f} by this definition (it says 1.5)",
    ]
    return ReproductionResult(
        paper="001", seconds=time.perf_counter() - start, rows=rows, notes=notes
    )
