"""Paper 002 reproduction: uncorrected waist strapdown on the walking robot.

Contract rows (docs/CONTRACTS.md): the printed scheme (9)–(17) — Euler-angle
integration at T = 0.025 s with the kinematic matrix of eq (14) evaluated at
the previous attitude — on the continuous-time robot of
:mod:`pednav_env.gait.robot`, ideal sensors:

- ``no_oscillation``: ``end_miss`` R (m) and ``end_miss_pct`` (R/S, %).
- ``roll_only`` / ``pitch_only`` / ``yaw_only``: least-squares line R(a) =
  slope·a + intercept over a sweep of the amplitude a (degrees), plus
  ``end_miss_at_0.5deg`` (the paper quotes 3.5 m for roll and 23.5 m for pitch).

Extra rows (suffixed config names), each a documented hypothesis or variant,
not the printed scheme: ``:grid_aligned`` (stops and turns fall on sample
instants), ``:delayed_projection`` (C_nb(i−1) in eq 15), ``:kinematic_transpose``
(Mᵀ instead of M⁻¹ in eq 14), ``:grid_aligned_transpose`` (both) and
``:quaternion`` (paper 003's quaternion
mechanisation, :mod:`pednav_env.nav.strapdown`, on the same sensor data).
Mechanisms: docs/REPRODUCTION.md (papers 000/002/004).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from pednav_env.constants import STANDARD_GRAVITY
from pednav_env.files import save_figure
from pednav_env.gait.robot import RobotConfig, RobotWalk, simulate_robot
from pednav_env.nav.waist_dr import euler_dead_reckoning
from pednav_env.reproduce import ReproductionResult, ReproductionRow
from pednav_env.sensors.imu import ideal_imu

#: Paper 002's published figures.
PAPER = {
    ("no_oscillation", "end_miss"): 0.57,
    ("no_oscillation", "end_miss_pct"): 3.5,
    ("roll_only", "slope"): 6.806,
    ("roll_only", "intercept"): 0.1155,
    ("roll_only", "end_miss_at_0.5deg"): 3.5,
    ("pitch_only", "slope"): 45.85,
    ("pitch_only", "intercept"): 0.335,
    ("pitch_only", "end_miss_at_0.5deg"): 23.5,
}

AXES = {"roll_only": "roll_amplitude", "pitch_only": "pitch_amplitude", "yaw_only": "yaw_amplitude"}


def _end_miss(walk: RobotWalk, pos_est: np.ndarray) -> np.ndarray:
    """Horizontal distance between estimate and truth at the route's end (m), (N,)."""
    rows = np.arange(pos_est.shape[0])
    err = pos_est[rows, walk.end_index, :2] - walk.pos_n[rows, walk.end_index, :2]
    return np.hypot(err[:, 0], err[:, 1])


def _dead_reckon(walk: RobotWalk, method: str, g: float) -> np.ndarray:
    omega_b, f_b = ideal_imu(walk.euler, walk.euler_rate, walk.acc_n_mean, g)
    e0, v0, p0 = walk.euler[:, 0], walk.vel_n[:, 0], walk.pos_n[:, 0]
    if method == "quaternion":
        from pednav_env.nav.strapdown import integrate
        from pednav_env.rotations import euler_to_quat

        # Sample i of the robot covers (t_{i−1}, t_i]; strapdown sample m covers [t_m, t_{m+1}].
        _, _, p = integrate(euler_to_quat(e0), v0, p0, omega_b[:, 1:], f_b[:, 1:], walk.dt, g)
        return p
    kw: dict[str, Any] = {}
    if method == "delayed_projection":
        kw["projection"] = "previous"
    elif method == "kinematic_transpose":
        kw["kinematics"] = "transpose"
    dr = euler_dead_reckoning(omega_b, f_b, walk.dt, e0, v0, p0, g=g, **kw)
    return dr.pos_n


def sweep(
    amplitudes_deg: np.ndarray,
    method: str = "printed",
    aligned: bool = False,
    dt: float = 0.025,
    g: float = STANDARD_GRAVITY,
) -> dict[str, np.ndarray]:
    """End misses for no oscillation and for each single-axis amplitude sweep.

    Returns ``{"no_oscillation": (1,), "roll_only": (A,), "pitch_only": (A,),
    "yaw_only": (A,)}`` in metres, one batched simulation and dead reckoning.
    """
    base = RobotConfig.no_oscillation()
    configs = [base]
    for field in AXES.values():
        configs += [base.with_(**{field: math.radians(a)}) for a in amplitudes_deg]
    walk = simulate_robot(configs, dt, align_to_grid=aligned)
    R = _end_miss(walk, _dead_reckon(walk, method, g))
    a = len(amplitudes_deg)
    out = {"no_oscillation": R[:1]}
    for j, name in enumerate(AXES):
        out[name] = R[1 + j * a : 1 + (j + 1) * a]
    return out


def run(
    runs: int | None = None,
    seed: int = 0,
    *,
    dt: float = 0.025,
    g: float = STANDARD_GRAVITY,
    variants: bool = True,
    plot_dir: str | Path | None = None,
) -> ReproductionResult:
    """Reproduce paper 002's figures.

    Parameters
    ----------
    runs : int, optional
        Number of amplitudes in each sweep, evenly spaced over 0.1°–1.2°
        (default 12: 0.1°, 0.2°, …, 1.2°). The model is deterministic
        (ideal sensors), so ``seed`` is unused.
    dt : float
        Sample period T (s); paper: 0.025.
    g : float
        Gravity (m/s²); the paper prints none.
    variants : bool
        Also compute the suffixed hypothesis/variant rows.
    plot_dir : path, optional
        Write ``paper002_trajectory.png`` and ``paper002_sweep.png`` there.
    """
    del seed
    start = time.perf_counter()
    n_amp = 12 if runs is None else int(runs)
    if n_amp < 2:
        raise ValueError(f"runs (sweep points) must be ≥ 2, got {runs!r}")
    amps = np.round(np.linspace(0.1, 1.2, n_amp), 10)
    amps = np.unique(np.concatenate((amps, [0.5])))
    S = RobotConfig().route_length
    modes = [("", "printed", False)]
    if variants:
        modes += [
            (":grid_aligned", "printed", True),
            (":delayed_projection", "delayed_projection", False),
            (":kinematic_transpose", "kinematic_transpose", False),
            (":grid_aligned_transpose", "kinematic_transpose", True),
            (":quaternion", "quaternion", False),
        ]
    rows: list[ReproductionRow] = []
    results = {}
    for suffix, method, aligned in modes:
        res = sweep(amps, method, aligned, dt, g)
        results[suffix] = res
        cfg = "no_oscillation" + suffix
        R0 = float(res["no_oscillation"][0])
        rows.append(
            ReproductionRow(cfg, "end_miss", "m", PAPER[("no_oscillation", "end_miss")], R0)
        )
        rows.append(
            ReproductionRow(
                cfg, "end_miss_pct", "%", PAPER[("no_oscillation", "end_miss_pct")], 100 * R0 / S
            )
        )
        for name in AXES:
            slope, intercept = np.polyfit(amps, res[name], 1)
            at_half = float(res[name][np.argmin(np.abs(amps - 0.5))])
            for metric, unit, value in (
                ("slope", "m/deg", slope),
                ("intercept", "m", intercept),
                ("end_miss_at_0.5deg", "m", at_half),
            ):
                rows.append(
                    ReproductionRow(
                        name + suffix, metric, unit, PAPER.get((name, metric)), float(value)
                    )
                )
    notes = [
        f"sweep amplitudes (deg): {', '.join(f'{a:g}' for a in amps)}; dt = {dt} s; "
        "ideal sensors; R = |estimate − truth| at the first sample after the route's end",
        "contract rows: printed scheme (9)–(17) on the continuous-time robot; suffixed rows are "
        "hypotheses/variants, not the printed scheme (docs/REPRODUCTION.md (papers 000/002/004))",
    ]
    if plot_dir is not None:
        _plots(Path(plot_dir), amps, results, dt, g)
    return ReproductionResult("002", time.perf_counter() - start, rows, notes)


def _plots(out: Path, amps: np.ndarray, results: dict, dt: float, g: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    base = RobotConfig.no_oscillation()
    walk = simulate_robot([base, base.with_(pitch_amplitude=math.radians(0.5))], dt)
    p = _dead_reckon(walk, "printed", g)
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(walk.pos_n[0, :, 0], walk.pos_n[0, :, 1], "k-", label="truth")
    ax.plot(p[0, :, 0], p[0, :, 1], "b--", label="DR, no oscillation")
    ax.plot(p[1, :, 0], p[1, :, 1], "r:", label="DR, pitch 0.5°")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal")
    ax.legend()
    save_figure(fig, out / "paper002_trajectory.png", dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4))
    for suffix, res in results.items():
        for name, style in (("roll_only", "-"), ("pitch_only", "--")):
            ax.plot(amps, res[name], style, label=f"{name}{suffix}")
    ax.plot(amps, 6.806 * amps + 0.1155, "k-", lw=2, label="paper roll fit")
    ax.plot(amps, 45.85 * amps + 0.335, "k--", lw=2, label="paper pitch fit")
    ax.set_xlabel("amplitude (deg)")
    ax.set_ylabel("end miss R (m)")
    ax.set_yscale("log")
    ax.legend(fontsize=6)
    save_figure(fig, out / "paper002_sweep.png", dpi=100)
    plt.close(fig)
