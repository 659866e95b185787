"""What the threads of the compiled ZUPT kernel need (:mod:`pednav_env.nav.zupt_kernel`).

:func:`pednav_env.nav.zupt_kernel.advance_block` runs its walkers on numba's
threads (:func:`thread_parts`: ``NUMBA_NUM_THREADS``, default all cores, or
:func:`numba.set_num_threads`). Each thread takes the next walker from a shared
counter (:func:`fetch_add`) until none is left, so a thread held up by other
work on its core leaves more walkers to the others. Each thread has its own
scratch arrays, a :class:`SampleScratch` and a :class:`ZuptScratch`, which serve
its walkers one after the other. A walker writes each entry before it reads it (its
preintegrals restart at its first anchor, a ZUPT fills its arrays before it
uses them; the Cholesky factor's upper triangle stays zero), so no value passes
from one walker to the next: a walker's arithmetic does not depend on which
thread runs it or on which walker ran before (tests/nav/test_kernel_threads.py:
one thread and two give identical outputs; lanes equal scalar envs bit for bit).

The update log is filled walker by walker in the serial kernel. With threads,
walker i writes its rows from row i·K on (K samples in the block, at most one
ZUPT per sample), and :func:`compact_log` closes the gaps afterwards, which
gives the serial kernel's rows in the serial kernel's order.

The threads are numba's own work queue (threading layer ``workqueue``) unless
``NUMBA_THREADING_LAYER`` or ``numba.config.THREADING_LAYER`` names another by the
time this module is imported: its idle threads sleep, where those of
GNU OpenMP (numba's first choice on Linux without TBB) spin, which on a busy
machine made the kernel slower on two threads than on one (docs/PERFORMANCE.md);
it is also safe under ``fork``, GNU OpenMP is not. The layer is chosen for the
whole process at its first parallel call.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from pednav_env.nav.preintegration import AnchorSums, Preintegral
from pednav_env.nav.zupt_algebra import AlgebraScratch, new_algebra_scratch

if numba.config.THREADING_LAYER == "default":  # no choice made (module docstring)
    numba.config.THREADING_LAYER = "workqueue"


def thread_parts(num_walkers: int) -> int:
    """Threads the walkers are run on: numba's thread count, at most one per
    walker; 1 means the serial kernel."""
    return max(1, min(int(num_walkers), numba.get_num_threads()))


@intrinsic
def fetch_add(typingctx: object, counter: types.Type, by: types.Type) -> tuple:
    """``counter[0] += by`` as one atomic operation (int64 array); returns the value
    before. Threads that take work from a shared counter each get different values.
    numba's own analysis does not see this write: a function that reads
    ``counter[0]`` after the parallel loop may get the value from before it (seen
    with numba 0.68), so read the counter only through this function."""
    sig = types.int64(types.Array(types.int64, 1, "C"), types.int64)

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: tuple) -> Any:
        array_type = signature.args[0]
        array = context.make_array(array_type)(context, builder, args[0])
        zero = context.get_constant(types.intp, 0)
        ptr = cgutils.get_item_pointer(context, builder, array_type, array, [zero])
        return builder.atomic_rmw("add", ptr, args[1], "monotonic")

    return sig, codegen


@njit(cache=True)
def compact_log(
    index: np.ndarray,
    x: np.ndarray,
    P: np.ndarray,
    nis: np.ndarray,
    logged: np.ndarray,
    region: int,
) -> int:
    """Walker i's ``logged[i]`` log rows, written from row i·``region`` on, moved up
    so that they follow each other walker by walker (the serial kernel's order);
    ``index``, ``x``, ``P``, ``nis`` are the arrays of an update log. Returns the
    number of rows. A row moves to a row at or above its own, after every row
    before it has moved, so none is overwritten before it is read."""
    n_log = 0
    for i in range(logged.shape[0]):
        for row in range(i * region, i * region + logged[i]):
            if row != n_log:
                for c in range(index.shape[1]):
                    index[n_log, c] = index[row, c]
                for h in range(2):
                    for r in range(9):
                        x[n_log, h, r] = x[row, h, r]
                        for c in range(9):
                            P[n_log, h, r, c] = P[row, h, r, c]
                nis[n_log] = nis[row]
            n_log += 1
    return n_log


class SampleScratch(NamedTuple):
    """Scratch arrays of the per-sample steps (paper 003 eq 3 increments and preintegrals)."""

    w: np.ndarray  # (3,) rad/s, bias-corrected rate
    f_j: np.ndarray  # (3,) m/s², the sample's specific force
    dC: np.ndarray  # (3, 3) C(Δq) of the sample
    f_mid: np.ndarray  # (3,) m/s², specific force in mid-interval axes
    F: np.ndarray  # (3,) m/s², the same in anchor axes
    pre: Preintegral
    sums: AnchorSums
    v_c: np.ndarray  # (3,) m/s, central point's velocity
    p_c: np.ndarray  # (3,) m, central point's position
    p_mean: np.ndarray  # (3,) m, mean position


@njit(cache=True)
def new_sample_scratch() -> SampleScratch:
    """Scratch arrays for the per-sample steps of
    :func:`pednav_env.nav.zupt_kernel.advance_walker`."""
    return SampleScratch(
        np.empty(3),
        np.empty(3),
        np.empty((3, 3)),
        np.empty(3),
        np.empty(3),
        Preintegral(np.empty((3, 3)), np.empty(3), np.empty(3)),
        AnchorSums(np.empty((3, 3)), np.empty(3), np.empty(3)),
        np.empty(3),
        np.empty(3),
        np.empty(3),
    )


class ZuptScratch(NamedTuple):
    """Scratch arrays of a ZUPT (and of a recorded mean state)."""

    chi: np.ndarray  # (S, 9) moved sigma states
    C_moved: np.ndarray  # (S, 3, 3) their attitudes
    dev: np.ndarray  # (S, 9) residuals from the mean
    x: np.ndarray  # (9,) prior, then posterior mean
    P: np.ndarray  # (9, 9) prior, then posterior covariance
    alg: AlgebraScratch  # the update's and the draw's work arrays
    powers: np.ndarray  # (4,) τᵖ · process-noise scale
    R_diag: np.ndarray  # (4,)


@njit(cache=True)
def new_zupt_scratch(num_sigmas: int, num_powers: int) -> ZuptScratch:
    """Scratch arrays for :func:`pednav_env.nav.zupt_kernel.zupt`."""
    return ZuptScratch(
        np.empty((num_sigmas, 9)),
        np.empty((num_sigmas, 3, 3)),
        np.empty((num_sigmas, 9)),
        np.empty(9),
        np.empty((9, 9)),
        new_algebra_scratch(),
        np.empty(num_powers),
        np.empty(4),
    )
