"""Paper 000 reproduction: the inverted-pendulum test motion over one step.

Paper 000's check: l = 0.7 m, T = 0.5 s (T_I-III = T_III-V), φ_min = π/3,
x_C(0) = 2 l cos φ_min, y_C(0) = 0, α = 0, accelerometer rate 100 Hz. The
accelerations of eqs (20)–(21) are sampled at t = 0, 0.01, …, 0.5 s and
integrated numerically from the known initial conditions.

Integration rule: nested running integrals by the trapezoid rule on the 51
samples of the closed step (V = V(0) + cumtrapz(a), then trapz(V)), the
reading that reproduces the printed V̄^ЧП = 1.39994406 and V̄^МОД =
1.39999891 m/s to all eight digits. Config ``paper`` rows (docs/CONTRACTS.md):
``vbar_true``, ``vbar_from_ax``, ``vbar_from_h`` (m/s), ``max_velocity_error``
(m/s) and ``max_position_error`` (m) — the largest deviation of the
numerically integrated velocity / position of the hip (both axes, all
samples of the step) from eqs (14), (16) / (12), (13); the paper gives
"of the order of 1e-5", recorded as 1e-5. Extra rows: ``paper:rectangle_rule``
(left-rectangle nested sums, to show the digits single out the trapezoid
rule) and ``paper:apex_closure`` (V̄ from the h-formula without the known
V_y(0): V_y(0) from V_y(T/2) = 0).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from pednav_env.files import save_figure
from pednav_env.gait.pendulum import PendulumSteps, step_kinematics
from pednav_env.nav.step_velocity import biomechanical_step_velocity, nested_trapezoid_mean_velocity
from pednav_env.reproduce import ReproductionResult, ReproductionRow

#: Paper 000's printed values.
PAPER = {
    "vbar_true": 1.4,
    "vbar_from_ax": 1.39994406,
    "vbar_from_h": 1.39999891,
    "max_velocity_error": 1e-5,
    "max_position_error": 1e-5,
}


def _cumtrapz(a: np.ndarray, dt: float) -> np.ndarray:
    return np.concatenate(([0.0], np.cumsum(0.5 * (a[1:] + a[:-1])) * dt))


def run(
    runs: int | None = None,
    seed: int = 0,
    *,
    leg_length: float = 0.7,
    phi_min: float = math.pi / 3,
    step_period: float = 0.5,
    rate_hz: float = 100.0,
    plot_dir: str | Path | None = None,
) -> ReproductionResult:
    """Reproduce paper 000's one-step check (deterministic: ``runs``/``seed`` unused)."""
    del runs, seed
    start = time.perf_counter()
    steps = PendulumSteps(
        leg_length=np.full((1, 1), leg_length), phi_min=phi_min, step_period=step_period
    )
    dt = 1.0 / rate_hz
    n = int(round(step_period * rate_hz))
    if abs(n * dt - step_period) > 1e-9:
        raise ValueError(f"step_period·rate_hz must be an integer, got {step_period * rate_hz!r}")
    t = np.arange(n + 1) * dt  # closed step [0, T]
    x, y, vx, vy, ax, ay = step_kinematics(t, leg_length, phi_min, step_period)
    x = x + 2.0 * leg_length * math.cos(phi_min)  # x_C(0) = 2 l cos φ_min

    vbar_true = float(steps.mean_velocity[0, 0])
    edges = np.array([[0, n]])
    vbar_ax = float(nested_trapezoid_mean_velocity(ax[None], dt, [[vx[0]]], edges)[0, 0])
    bm = biomechanical_step_velocity(ay[None], dt, edges, leg_length, v_up0=[[vy[0]]])
    vbar_h = float(bm.velocity[0, 0])
    apex = biomechanical_step_velocity(ay[None], dt, edges, leg_length, v_up0="apex")

    vx_num = vx[0] + _cumtrapz(ax, dt)
    vy_num = vy[0] + _cumtrapz(ay, dt)
    x_num = x[0] + _cumtrapz(vx_num, dt)
    y_num = y[0] + _cumtrapz(vy_num, dt)
    max_v = float(max(np.abs(vx_num - vx).max(), np.abs(vy_num - vy).max()))
    max_p = float(max(np.abs(x_num - x).max(), np.abs(y_num - y).max()))

    # Left-rectangle nested sums over the same samples, for contrast.
    v_rect = vx[0] + np.concatenate(([0.0], np.cumsum(ax[:-1]) * dt))
    vbar_ax_rect = float(np.sum(v_rect[:-1]) * dt / step_period)
    m = n // 2
    vy_rect = np.concatenate(([0.0], np.cumsum(ay[:m]) * dt))
    h_rect = vy[0] * 0.5 * step_period + float(np.sum(vy_rect[:-1]) * dt)
    vbar_h_rect = 2.0 * math.sqrt(2 * leg_length * h_rect - h_rect**2) / step_period

    rows = [
        ReproductionRow("paper", "vbar_true", "m/s", PAPER["vbar_true"], vbar_true),
        ReproductionRow("paper", "vbar_from_ax", "m/s", PAPER["vbar_from_ax"], vbar_ax),
        ReproductionRow("paper", "vbar_from_h", "m/s", PAPER["vbar_from_h"], vbar_h),
        ReproductionRow("paper", "max_velocity_error", "m/s", PAPER["max_velocity_error"], max_v),
        ReproductionRow("paper", "max_position_error", "m", PAPER["max_position_error"], max_p),
        ReproductionRow(
            "paper:rectangle_rule", "vbar_from_ax", "m/s", PAPER["vbar_from_ax"], vbar_ax_rect
        ),
        ReproductionRow(
            "paper:rectangle_rule", "vbar_from_h", "m/s", PAPER["vbar_from_h"], vbar_h_rect
        ),
        ReproductionRow(
            "paper:apex_closure",
            "vbar_from_h",
            "m/s",
            PAPER["vbar_from_h"],
            float(apex.velocity[0, 0]),
        ),
    ]
    notes = [
        f"one step, {n + 1} samples t = 0 … {step_period} s at {rate_hz:g} Hz; nested trapezoid "
        f"rule; vbar_from_ax = {vbar_ax:.8f}, vbar_from_h = {vbar_h:.8f}",
        "paper's max errors are 'of the order of 1e-5' (its Figs. 5–6), recorded as 1e-5",
    ]
    if plot_dir is not None:
        _plot(Path(plot_dir), t, ax, ay, vx_num - vx, vy_num - vy, x_num - x, y_num - y)
    return ReproductionResult("000", time.perf_counter() - start, rows, notes)


def _plot(out: Path, t: np.ndarray, *series: np.ndarray) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    ax_, ay_, evx, evy, ex, ey = series
    fig, axes = plt.subplots(3, 1, figsize=(6, 7), sharex=True)
    axes[0].plot(t, ax_, label="a_x")
    axes[0].plot(t, ay_, label="a_y")
    axes[0].set_ylabel("m/s²")
    axes[1].plot(t, evx, label="V_x error")
    axes[1].plot(t, evy, label="V_y error")
    axes[1].set_ylabel("m/s")
    axes[2].plot(t, ex, label="x error")
    axes[2].plot(t, ey, label="y error")
    axes[2].set_ylabel("m")
    axes[2].set_xlabel("t (s)")
    for a in axes:
        a.legend()
    save_figure(fig, out / "paper000_step.png", dpi=100)
    plt.close(fig)
