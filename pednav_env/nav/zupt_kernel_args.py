"""The argument tuples of the compiled ZUPT-UKF kernel of paper 003
(:mod:`pednav_env.nav.zupt_kernel`) and their constructors.

Numba passes NamedTuples of arrays and scalars to compiled code as they are; the
kernel takes a walker's arrays out of them before its sample loop.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

#: Kinds of ZUPT in the update log: stance start, stance end, stance sample.
KIND_START, KIND_END, KIND_STANCE = 0, 1, 2


class KernelSettings(NamedTuple):
    """Constants shared by all walkers."""

    g: float  # m/s², gravity of the strapdown
    detector_g: float  # m/s², the g of eq (5)
    gate_nis: float  # χ² gate on the NIS of a ZUPT (inf: no gate)
    uses_shoe: bool  # stance condition given per sample (SHOE), not eq (5)
    boundaries_only: bool  # ZUPTs at stance start and end (paper 003), else at every stance sample
    spread: float  # L + λ of the sigma points
    speed_max: float  # m/s, divergence speed of the central sigma point
    angle_sums: bool  # sigma-point angles by angle-sum forms (pednav_env.nav.sigma_angles)


class WalkerKnobs(NamedTuple):
    """Per-walker settings, arrays over N walkers (the agent's knobs among them)."""

    dt: np.ndarray  # (N,) s, sample interval (each walker's own rate: recordings)
    omega_max: np.ndarray  # (N,) rad/s, eq (5)
    delta_f_max: np.ndarray  # (N,) m/s², eq (5)
    min_stance_samples: np.ndarray  # (N,) int, minimum stance duration
    process_noise_scale: np.ndarray  # (N,) multiplies Q
    zupt_var_height: np.ndarray  # (N,) m², R entry of x₃
    zupt_var_velocity: np.ndarray  # (N,) m²/s², R entries of v
    height_ref: np.ndarray  # (N,) m, x₃(t₀) of the ZUPT measurement
    gyro_bias: np.ndarray  # (N, 3) rad/s, subtracted from every sample


class UkfModel(NamedTuple):
    """The filter's fixed model: Q(τ) = Σ_p τᵖ q_basis_p, sigma-point weights."""

    q_basis: np.ndarray  # (4, 9, 9)
    Wm: np.ndarray  # (S,) mean weights
    Wc: np.ndarray  # (S,) covariance weights


class WalkerFilters(NamedTuple):
    """The filter state of N walkers, updated in place."""

    sig_C: np.ndarray  # (N, S, 3, 3) sigma-point attitudes C_nb
    sig_v: np.ndarray  # (N, S, 3) m/s
    sig_p: np.ndarray  # (N, S, 3) m
    x: np.ndarray  # (N, 9) last posterior mean
    P: np.ndarray  # (N, 9, 9) last posterior covariance
    elapsed_s: np.ndarray  # (N,) s since the last sigma-point draw
    counters: np.ndarray  # (N, 3) int: [updates, rejected, covariance repairs]
    last_nis: np.ndarray  # (N,) NIS of the last ZUPT


class DetectorState(NamedTuple):
    """Causal detector state of N walkers, updated in place."""

    history: np.ndarray  # (N, W−1, 2) last eq-(5) window inputs (|ω'|, f'_x3), oldest first
    count: np.ndarray  # (N,) int, samples seen, capped at the window length W
    run: np.ndarray  # (N,) int, samples the condition has held
    in_stance: np.ndarray  # (N,) bool


class BlockInput(NamedTuple):
    """A block of K samples of N walkers."""

    omega: np.ndarray  # (N, K, 3) rad/s, body rate
    f: np.ndarray  # (N, K, 3) m/s², specific force
    shoe_cond: np.ndarray  # (N, K) bool SHOE condition; (N, 0) for eq (5)
    valid: np.ndarray  # (N,) int, samples before the end of each record (later: no ZUPT)
    frozen: np.ndarray  # (N,) bool, diverged walkers (not moved)


class BlockOutput(NamedTuple):
    """What :func:`advance_block` reports (arrays filled in place)."""

    stance: np.ndarray  # (N, K) bool, detected stance after each sample
    start: np.ndarray  # (N, K) bool, stance declared at the sample
    end: np.ndarray  # (N, K) bool, stance ended at the sample
    accepted: np.ndarray  # (N,) int, ZUPTs applied in the block
    nis_log_sum: np.ndarray  # (N,) Σ log(1 + NIS) of those ZUPTs
    position: np.ndarray  # (N, 3) m, mean position after each walker's valid samples
    diverged_at: np.ndarray  # (N,) int, state index of divergence (K + 1: none)
    last_accepted: np.ndarray  # (N,) int, sample of the last accepted ZUPT (−1: none)
    positions: np.ndarray  # (N, K, 3) m, mean position after every sample, or (0, 0, 3)
    states: np.ndarray  # (N, K, 9) mean state after every sample, or (0, 0, 9)


class UpdateLog(NamedTuple):
    """Every ZUPT of the block (rows 0 … returned count − 1), or empty arrays."""

    index: np.ndarray  # (M, 4) int: [walker, sample, kind, accepted]
    x: np.ndarray  # (M, 2, 9) prior and posterior mean
    P: np.ndarray  # (M, 2, 9, 9) prior and posterior covariance
    nis: np.ndarray  # (M,)


def new_detector_state(num_walkers: int, window: int) -> DetectorState:
    """Detector state of walkers that have seen no sample, window W = ``window``."""
    n = num_walkers
    return DetectorState(
        np.zeros((n, window - 1, 2)),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=bool),
    )


def new_block_output(
    num_walkers: int, num_samples: int, positions: bool, states: bool
) -> BlockOutput:
    """Output arrays of a block; per-sample positions and states only when asked."""
    n, k = num_walkers, num_samples
    return BlockOutput(
        np.zeros((n, k), dtype=bool),
        np.zeros((n, k), dtype=bool),
        np.zeros((n, k), dtype=bool),
        np.zeros(n, dtype=np.int64),
        np.zeros(n),
        np.empty((n, 3)),
        np.empty(n, dtype=np.int64),
        np.empty(n, dtype=np.int64),
        np.empty((n, k, 3) if positions else (0, 0, 3)),
        np.empty((n, k, 9) if states else (0, 0, 9)),
    )


def new_update_log(rows: int) -> UpdateLog:
    """An update log with room for ``rows`` ZUPTs (0: no logging)."""
    return UpdateLog(
        np.zeros((rows, 4), dtype=np.int64),
        np.empty((rows, 2, 9)),
        np.empty((rows, 2, 9, 9)),
        np.empty(rows),
    )
