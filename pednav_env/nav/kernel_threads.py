"""What the threads of the compiled ZUPT kernel need (:mod:`pednav_env.nav.zupt_kernel`).

:func:`pednav_env.nav.zupt_kernel.advance_block` runs its walkers on the calling
thread and helper threads together (:func:`thread_parts` of them in all:
numba's thread count, ``NUMBA_NUM_THREADS``, default all cores, or
:func:`numba.set_num_threads`). Each thread runs the compiled
:func:`pednav_env.nav.zupt_kernel.advance_share` without the GIL and takes the
next walker from a shared counter (:func:`fetch_add`) until none is left, so a
thread held up by other work on its core leaves more walkers to the others.
Each thread has its own scratch arrays, a :class:`SampleScratch` and a
:class:`ZuptScratch`, which serve its walkers one after the other. A walker
writes each entry before it reads it (its preintegrals restart at its first
anchor, a ZUPT fills its arrays before it uses them; the Cholesky factor's upper
triangle stays zero), so no value passes from one walker to the next: a walker's
arithmetic does not depend on which thread runs it or on which walker ran before
(tests/nav/test_kernel_threads.py: one thread and two give identical outputs;
lanes equal scalar envs bit for bit).

The update log is filled walker by walker in the serial kernel. With threads,
walker i writes its rows from row i·K on (K samples in the block, at most one
ZUPT per sample), and :func:`compact_log` closes the gaps afterwards, which
gives the serial kernel's rows in the serial kernel's order.

Why the calling thread works too (:class:`SharedRun`), rather than a numba
``prange`` loop on numba's thread pool, which this module used before: a
parallel region's caller only waits, and on this project's 2-core virtual
machine a pool thread that has slept through the env's serial work between two
kernel calls often starts late, by milliseconds, or not before the others have
finished; the paper family's kernel then gained nothing from two threads in the
env (docs/PERFORMANCE.md). The caller starts at once, so a late helper costs at
most the time of the serial kernel. The helpers are Python threads started on
first use (again after a ``fork``), waiting for work on a queue; one run at a
time uses them (:meth:`SharedRun.acquire`), another caller meanwhile runs the
serial kernel.

numba's threading layer is set to its own work queue (``workqueue``) unless
``NUMBA_THREADING_LAYER`` or ``numba.config.THREADING_LAYER`` names another by
the time this module is imported: the kernel no longer uses numba's threads,
but other parallel code in the process would, and GNU OpenMP's idle threads spin.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Callable
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


class SharedRun:
    """The calling thread and helper threads running one compiled function's shares
    of a block together (module docstring)."""

    def __init__(self) -> None:
        self.pid = -1
        self.start()

    def start(self) -> None:
        """No helpers yet, fresh queues and lock (also in a forked child, which
        inherits none of the parent's threads)."""
        self.pid = os.getpid()
        self.lock = threading.Lock()
        self.jobs: queue.SimpleQueue = queue.SimpleQueue()
        self.done: queue.SimpleQueue = queue.SimpleQueue()
        self.helpers: list[threading.Thread] = []

    def acquire(self) -> bool:
        """Take the helpers for one run; False when another run has them."""
        if self.pid != os.getpid():
            self.start()
        return self.lock.acquire(blocking=False)

    def release(self) -> None:
        self.lock.release()

    def run(self, share: Callable[..., Any], args: tuple, parts: int) -> int:
        """``share(*args, taken, logged)`` (:func:`pednav_env.nav.zupt_kernel.advance_share`)
        on this thread and ``parts − 1`` helpers, all drawing walkers from one counter;
        then the update log closed up (:func:`compact_log`). Returns its row count.
        ``args`` are :func:`~pednav_env.nav.zupt_kernel.advance_block`'s."""
        block, log = args[0], args[-1]
        n, k = block.omega.shape[0], block.omega.shape[1]
        region = k if log.index.shape[0] > 0 else 0
        logged = np.zeros(n, dtype=np.int64)
        taken = np.zeros(1, dtype=np.int64)  # walkers handed out so far
        job = (*args, taken, logged)
        while len(self.helpers) < parts - 1:
            helper = threading.Thread(target=serve, args=(self.jobs, self.done), daemon=True)
            helper.start()
            self.helpers.append(helper)
        for _ in range(parts - 1):
            self.jobs.put((share, job))
        errors = []
        try:
            share(*job)
        finally:  # the helpers write into the arrays until they report
            errors = [e for e in (self.done.get() for _ in range(parts - 1)) if e is not None]
        if errors:
            raise errors[0]
        return compact_log(log.index, log.x, log.P, log.nis, logged, region)


def serve(jobs: queue.SimpleQueue, done: queue.SimpleQueue) -> None:
    """A helper thread: run each ``(function, arguments)`` of ``jobs``, then put None
    (or the exception raised) on ``done``."""
    while True:
        share, job = jobs.get()
        try:
            share(*job)
        except BaseException as exc:  # reported to the caller, which raises it
            done.put(exc)
        else:
            done.put(None)


#: The process's helper threads of the ZUPT kernel.
SHARED_RUN = SharedRun()


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
