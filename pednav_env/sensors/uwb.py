"""UWB marker position measurements (paper 001, thesis chapter 3 and eq 5.5).

A DecaWave DW1000 two-way-ranging system reports each tag's position; the
thesis models the reported coordinates as the truth plus independent Gaussian
errors of σ = 0.1 m per axis (its indoor accuracy "of the order of 10 cm",
eq 5.5). That is :meth:`UwbSpec.paper`.

The realistic option (:meth:`UwbSpec.realistic`) adds, per marker:

- non-line-of-sight bursts: a two-state Markov chain (Gilbert–Elliott) per
  marker, entered at ``nlos_start_rate_hz`` starts per second of line of
  sight and left after ``nlos_mean_duration`` on average (per-sample
  probabilities 1 − exp(−rate·T) and T/duration, so the statistics do not
  depend on the sample rate); during a burst the position carries a bias
  drawn once per burst, N(0, ``nlos_bias_std``²) per axis, and the noise is
  inflated by ``nlos_noise_scale``;
- outliers: with probability ``outlier_prob`` a sample gets an extra
  N(0, ``outlier_std``²) error per axis;
- dropped samples: with probability ``drop_prob`` (``nlos_drop_prob`` inside
  a burst) the sample is missing.

Dropped samples are reported through the boolean ``valid`` mask, never as
NaN; the value array holds the last valid measurement of that marker there
(what a host that re-reads a stale position sees), or the first valid one
before any arrives, or 0 when a marker never reports. Consumers must use
``valid``. ``nlos`` and ``outlier`` are truth diagnostics for analysis and
must not be fed to a filter.

Walker i draws only from its own generator ``rngs[i]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pednav_env.checks import require_nonnegative, require_positive, require_probability

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class UwbSpec:
    """UWB position sensor.

    Attributes
    ----------
    rate_hz : float
        Position update rate (Hz). Not in the thesis; 10 Hz is the location
        rate of DecaWave's TWR RTLS firmware (DWM1001 PANS maximum).
    noise_std : float
        σ (m) of the position error per axis, thesis eq 5.5 (DecaWave 0.1 m).
    nlos_start_rate_hz : float
        Mean number of NLOS bursts starting per second of line of sight.
    nlos_mean_duration : float
        Mean NLOS burst length (s).
    nlos_bias_std : float
        σ (m) per axis of the bias held during one burst.
    nlos_noise_scale : float
        Factor ≥ 1 on ``noise_std`` during a burst.
    nlos_drop_prob : float
        Probability that a sample inside a burst is dropped.
    outlier_prob : float
        Probability per sample of an outlier.
    outlier_std : float
        σ (m) per axis of an outlier's extra error.
    drop_prob : float
        Probability that a line-of-sight sample is dropped.
    """

    rate_hz: float = 10.0  # ours: DecaWave TWR RTLS location rate (DWM1001 PANS max 10 Hz)
    noise_std: float = 0.1  # thesis eq 5.5 and §3.3: DecaWave indoor accuracy ≈ 10 cm
    nlos_start_rate_hz: float = 0.0  # thesis: no NLOS
    nlos_mean_duration: float = 1.0  # ours (realistic option)
    nlos_bias_std: float = 0.3  # ours: NLOS excess paths of tens of cm
    nlos_noise_scale: float = 2.0  # ours: weaker first path, noisier
    nlos_drop_prob: float = 0.0  # thesis: no dropped samples
    outlier_prob: float = 0.0  # thesis: no outliers
    outlier_std: float = 1.0  # ours (realistic option)
    drop_prob: float = 0.0  # thesis: no dropped samples

    def __post_init__(self) -> None:
        require_positive("UwbSpec.rate_hz", self.rate_hz)
        for name in ("noise_std", "nlos_bias_std", "outlier_std"):
            require_nonnegative(f"UwbSpec.{name}", getattr(self, name))
        require_nonnegative("UwbSpec.nlos_start_rate_hz", self.nlos_start_rate_hz)
        for name in ("nlos_drop_prob", "outlier_prob", "drop_prob"):
            require_probability(f"UwbSpec.{name}", getattr(self, name))
        require_nonnegative("UwbSpec.nlos_mean_duration", self.nlos_mean_duration)
        if self.nlos_mean_duration < self.sample_period:
            raise ValueError(
                "UwbSpec.nlos_mean_duration must be >= one sample period "
                f"({self.sample_period} s), got {self.nlos_mean_duration!r}"
            )
        require_nonnegative("UwbSpec.nlos_noise_scale", self.nlos_noise_scale)
        if self.nlos_noise_scale < 1:
            raise ValueError(
                f"UwbSpec.nlos_noise_scale must be >= 1, got {self.nlos_noise_scale!r}"
            )

    @property
    def sample_period(self) -> float:
        """T = 1/rate (s)."""
        return 1.0 / self.rate_hz

    def with_noise_std(self, noise_std: float) -> UwbSpec:
        """This spec with σ = ``noise_std`` (equal to ``replace(self, noise_std=...)``;
        only the new σ is checked, the other fields are this valid spec's)."""
        require_nonnegative("UwbSpec.noise_std", noise_std)
        out = object.__new__(UwbSpec)
        out.__dict__.update(self.__dict__)
        object.__setattr__(out, "noise_std", noise_std)
        return out

    @property
    def nlos_enter_prob(self) -> float:
        """Per-sample probability of starting a burst, 1 − exp(−rate·T)."""
        return -math.expm1(-self.nlos_start_rate_hz * self.sample_period)

    @property
    def nlos_exit_prob(self) -> float:
        """Per-sample probability of leaving a burst, T / mean duration."""
        return min(1.0, self.sample_period / self.nlos_mean_duration)

    @property
    def is_ideal(self) -> bool:
        """True when only the Gaussian noise is active (the thesis model)."""
        return self.nlos_start_rate_hz == 0.0 and self.outlier_prob == 0.0 and self.drop_prob == 0.0

    @classmethod
    def paper(cls, rate_hz: float = 10.0) -> UwbSpec:
        """Thesis model: Gaussian σ = 0.1 m per axis, nothing else (eq 5.5)."""
        return cls(rate_hz=rate_hz)

    @classmethod
    def realistic(cls, rate_hz: float = 10.0) -> UwbSpec:
        """Our indoor-walk error mix: NLOS bursts, outliers, dropped samples.

        0.2 bursts per second of line of sight lasting 1 s on average (≈ 17 %
        of the time in NLOS), 1 % outliers, 2 % drops in LOS and 30 % in NLOS.
        These are illustrative magnitudes, not fitted to any data set.
        """
        return cls(
            rate_hz=rate_hz,
            nlos_start_rate_hz=0.2,
            nlos_drop_prob=0.3,
            outlier_prob=0.01,
            drop_prob=0.02,
        )


@dataclass(frozen=True)
class UwbMeasurements:
    """UWB readings of a batch of walks.

    Attributes
    ----------
    z : ndarray, shape (N, K, 2, 2)
        Reported positions (m): marker (heel, knee), then (x, z). Finite
        everywhere; at dropped samples a held value (see module docstring).
    valid : ndarray of bool, shape (N, K, 2)
        False where the marker's sample was dropped.
    nlos : ndarray of bool, shape (N, K, 2)
        Truth diagnostic: sample inside an NLOS burst.
    outlier : ndarray of bool, shape (N, K, 2)
        Truth diagnostic: sample is an outlier.
    """

    z: Array
    valid: BoolArray
    nlos: BoolArray
    outlier: BoolArray


def _check_rngs(rngs: Sequence[np.random.Generator], n_walkers: int) -> None:
    if isinstance(rngs, np.random.Generator) or len(rngs) != n_walkers:
        raise ValueError(
            f"rngs must be a sequence of {n_walkers} numpy Generators (one per walker), "
            f"got {rngs!r}"
        )
    for i, rng in enumerate(rngs):
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rngs[{i}] must be a numpy.random.Generator, got {rng!r}")


def _take_samples(a: Array, idx: NDArray[np.intp]) -> Array:
    """``out[i, j, m] = a[i, idx[2i + m, j], m]`` for ``a`` of shape (N, K, 2, 2)
    and per-marker sample indices ``idx`` of shape (N·2, K) (:func:`_per_marker`).

    ``np.take_along_axis`` in effect, but gathers whole (x, z) pairs, each one
    16-byte item of ``a`` viewed as complex (an exact copy of the two floats), by
    flat row index, which is several times faster.
    """
    n, k = a.shape[:2]
    rows = idx * 2
    rows += (np.arange(n)[:, None] * (2 * k) + np.arange(2)).reshape(-1, 1)
    pairs = np.ascontiguousarray(a).reshape(-1, 2).view(np.complex128)[:, 0]
    out = _from_per_marker(pairs.take(rows), n)  # (N, K, 2)
    return out.view(np.float64).reshape(n, k, 2, 2)


def _per_marker(a: NDArray) -> NDArray:
    """``(N, K, 2)`` → ``(N·2, K)`` rows (one marker's samples per row), contiguous:
    the scans along time below then run over contiguous memory."""
    n, k = a.shape[:2]
    return np.ascontiguousarray(a.transpose(0, 2, 1)).reshape(n * 2, k)


def _last_index(flags: NDArray[np.bool_]) -> NDArray[np.intp]:
    """Per row of ``(M, K)`` ``flags``: the index of the latest True at or before
    each sample, −1 before the first."""
    idx = np.where(flags, np.arange(flags.shape[1]), -1)
    return np.maximum.accumulate(idx, axis=1, out=idx)


def _from_per_marker(a: NDArray, n: int) -> NDArray:
    """Inverse of :func:`_per_marker`: ``(N·2, K)`` rows → ``(N, K, 2)``, contiguous
    (two strided copies, much faster than numpy's transposing copy here)."""
    rows = a.reshape(n, 2, -1)
    out = np.empty((n, rows.shape[2], 2), dtype=a.dtype)
    out[:, :, 0] = rows[:, 0]
    out[:, :, 1] = rows[:, 1]
    return out


def hold_last_valid(z: ArrayLike, valid: ArrayLike) -> Array:
    """Replace dropped samples by the marker's last valid one.

    Parameters
    ----------
    z : array_like, shape (N, K, 2, 2)
        Positions (m).
    valid : array_like of bool, shape (N, K, 2)
        Per-marker validity.

    Returns
    -------
    ndarray, shape (N, K, 2, 2)
        ``z`` with each invalid sample replaced by the last valid one of its
        marker, or by the first valid one before any, or by 0 if none.
    """
    z = np.asarray(z, dtype=float)
    valid = np.asarray(valid, dtype=bool)
    rows = _per_marker(valid)
    idx = _last_index(rows)
    # before the first valid sample idx is −1: max(−1, first) = first; after it
    # idx ≥ first already (first = 0 when a marker never reports)
    np.maximum(idx, np.argmax(rows, axis=1)[:, None], out=idx)
    held = _take_samples(z, idx)
    never = ~rows.any(axis=1)  # (N·2,)
    if never.any():
        n = valid.shape[0]
        never = never.reshape(n, 2)
        held[np.broadcast_to(never[:, None, :, None], held.shape)] = 0.0
    return held


def nlos_states(u: Array, enter_prob: float, exit_prob: float) -> BoolArray:
    """States of the per-marker NLOS Markov chains, without a loop over samples.

    The chain starts in line of sight before the first sample; at sample j a
    marker in line of sight enters a burst when ``u[j] < enter_prob`` and one
    in a burst leaves it when ``u[j] < exit_prob``. With ``a = u < enter_prob``
    and ``b = u ≥ exit_prob``, sample j maps the previous state s to ``a``
    (s = 0) or ``b`` (s = 1): where a = b it sets the state, where a > b it
    toggles it, else it keeps it. So the state is the value of the last
    setting sample (0 if none) XOR the parity of the toggles since.

    Parameters
    ----------
    u : ndarray, shape (N, K, 2)
        Uniforms of the transitions, time on axis 1.
    enter_prob, exit_prob : float
        Per-sample probabilities of entering and of leaving a burst.

    Returns
    -------
    ndarray of bool, shape (N, K, 2)
        True inside a burst.
    """
    return _from_per_marker(_nlos_rows(_per_marker(u), enter_prob, exit_prob), u.shape[0])


def _nlos_rows(u: Array, enter_prob: float, exit_prob: float) -> BoolArray:
    """:func:`nlos_states` of ``(M, K)`` rows of uniforms (time along a row).

    With the parity c of the toggles up to each sample (an XOR scan) the state
    is c XOR (a XOR c) taken at the last setting sample (0 if none): a setting
    sample is not a toggle, so the parity since it is c XOR c there.
    """
    a = u < enter_prob
    b = ~(u < exit_prob)
    last_set = _last_index(a == b)
    parity = np.bitwise_xor.accumulate(a > b, axis=1)  # a > b: a toggle
    # a XOR c per row behind a leading 0 (no setting sample yet), gathered at
    # 1 + the last setting sample by flat index
    m, k = u.shape
    held = np.zeros((m, k + 1), dtype=bool)
    np.bitwise_xor(a, parity, out=held[:, 1:])
    last_set += (np.arange(m) * (k + 1) + 1)[:, None]
    held = held.ravel().take(last_set)
    held ^= parity
    return held


def _widen(flags: BoolArray) -> BoolArray:
    """Per-marker flags ``(N, K, 2)`` repeated over (x, z): ``(N, K, 2, 2)``."""
    return np.repeat(flags, 2, axis=-1).reshape((*flags.shape, 2))


def measure_uwb(
    spec: UwbSpec, markers: ArrayLike, rngs: Sequence[np.random.Generator]
) -> UwbMeasurements:
    """Simulate UWB position reports of the markers.

    Only the random draws loop (over walkers, one generator each); the NLOS
    chain (:func:`nlos_states`), the burst biases, outliers and drops are
    evaluated for all walkers and samples at once.

    Parameters
    ----------
    spec : UwbSpec
        Sensor model; ``markers`` must be sampled at ``spec.rate_hz``.
    markers : array_like, shape (N, K, 2, 2)
        True positions (m): marker, then (x, z).
    rngs : sequence of numpy.random.Generator, length N
        One generator per walker. Walker i draws, in order: the Gaussian noise
        (K, 2, 2); then, only with the realistic option, NLOS transitions
        (K, 2), burst biases (K, 2, 2), outlier flags (K, 2), outlier errors
        (K, 2, 2) and drop uniforms (K, 2).

    Returns
    -------
    UwbMeasurements
        z = truth + scale · noise + bias + outlier error, with scale
        ``nlos_noise_scale`` inside a burst (else 1) and the bias of the
        burst's first sample held through the burst; dropped samples hold the
        last valid report (:func:`hold_last_valid`).
    """
    truth = np.asarray(markers, dtype=float)
    if truth.ndim != 4 or truth.shape[2:] != (2, 2):
        raise ValueError(f"markers must have shape (N, K, 2, 2), got {truth.shape}")
    if not np.all(np.isfinite(truth)):
        raise ValueError("markers must be finite (found NaN or inf)")
    n, k = truth.shape[:2]
    _check_rngs(rngs, n)

    noise = np.empty((n, k, 2, 2))  # C-contiguous: rows are filled in place
    if spec.is_ideal:  # Gaussian noise only: the sum below with scale 1, no bias, no outliers
        for i, rng in enumerate(rngs):
            rng.standard_normal(out=noise[i])
        noise *= spec.noise_std
        z = truth + noise  # + 0.0 + 0.0 of the sum below: the same as one + 0.0
        z += 0.0
        no = np.zeros((n, k, 2), dtype=bool)
        return UwbMeasurements(z=z, valid=~no, nlos=no, outlier=no.copy())

    u_state = np.empty((n, k, 2))
    burst_bias = np.empty((n, k, 2, 2))
    u_out = np.empty((n, k, 2))
    out_err = np.empty((n, k, 2, 2))
    u_drop = np.empty((n, k, 2))
    for i, rng in enumerate(rngs):  # the draw order of the docstring
        rng.standard_normal(out=noise[i])
        rng.random(out=u_state[i])
        rng.standard_normal(out=burst_bias[i])
        rng.random(out=u_out[i])
        rng.standard_normal(out=out_err[i])
        rng.random(out=u_drop[i])
    noise *= spec.noise_std
    burst_bias *= spec.nlos_bias_std
    # z = truth + scale · noise + bias + extra, where the terms of error sources
    # this spec switches off are the scalars 1.0 / 0.0. Summed in that order, in
    # place; a factor 1.0 is exact and of two trailing + 0.0 one does the same.
    # Per-marker flags are widened to both axes ((N, K, 2) → (N, K, 2, 2)) before
    # they select, so that every elementwise operation runs over whole arrays.
    bias: Array | float = 0.0
    extra: Array | float = 0.0
    if spec.nlos_enter_prob > 0.0:
        rows = _nlos_rows(_per_marker(u_state), spec.nlos_enter_prob, spec.nlos_exit_prob)
        nlos = _from_per_marker(rows, n)
        # each burst keeps the bias drawn at its first sample
        entry = rows.copy()
        entry[:, 1:] &= ~rows[:, :-1]
        last_entry = np.maximum(_last_index(entry), 0)
        wide = _widen(nlos)
        bias = np.where(wide, _take_samples(burst_bias, last_entry), 0.0)
        noise *= np.where(wide, spec.nlos_noise_scale, 1.0)  # scale · noise
        dropped = u_drop < np.where(nlos, spec.nlos_drop_prob, spec.drop_prob)
    else:  # never enters a burst
        nlos = np.zeros((n, k, 2), dtype=bool)
        dropped = u_drop < spec.drop_prob
    outlier = u_out < spec.outlier_prob
    if spec.outlier_prob > 0.0:
        out_err *= spec.outlier_std
        extra = np.where(_widen(outlier), out_err, 0.0)
    z = truth + noise
    z += bias
    if not isinstance(extra, float):
        z += extra
    elif not isinstance(bias, float):
        z += 0.0
    valid = ~dropped
    if dropped.any():
        z = hold_last_valid(z, valid)
    return UwbMeasurements(z=z, valid=valid, nlos=nlos, outlier=outlier)
