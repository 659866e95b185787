"""The compiled ZUPT kernel on several threads (nav.zupt_kernel, nav.kernel_threads):
one thread (the serial kernel) and two give the same outputs bit for bit, and the
update log lists the same ZUPTs in the same order (walker by walker); so do two
engines advanced from two Python threads at once, and a forked child process."""

import multiprocessing
import os
import threading
from dataclasses import fields

import numba
import numpy as np
import pytest
from simulated import FOOT_RATE_HZ, foot_imu

from pednav_env.envs.foot_filters import family_filter
from pednav_env.nav.kernel_threads import compact_log, fetch_add, thread_parts
from pednav_env.nav.zupt_config import ZuptUkfConfig
from pednav_env.nav.zupt_kernel_args import new_update_log
from pednav_env.nav.zupt_ukf import ZuptUkf
from pednav_env.sensors.imu import ImuSpec

FILTERS = {"paper": ZuptUkfConfig(), "shoe": family_filter("shoe", "calibrated")}
WALKERS = 7


def run_with_threads(threads, family, omega, f):
    """A whole run of WALKERS walkers (per-sample states recorded, every ZUPT
    logged) with ``threads`` numba threads; the engine and its run."""
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        assert thread_parts(WALKERS) == threads  # 1: the serial kernel
        eng = ZuptUkf(FILTERS[family], FOOT_RATE_HZ, WALKERS, record_updates=True)
        if family == "paper":  # loose thresholds on some walkers: stances flicker
            eng.omega_max[:] = np.linspace(0.2, 2.0, WALKERS)
        return eng, eng.run(omega, f, block_samples=50)
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("family", FILTERS)
def test_two_threads_give_the_serial_kernels_outputs(paper_walk, family):
    assert numba.config.NUMBA_NUM_THREADS >= 2, "needs NUMBA_NUM_THREADS ≥ 2 (default: all cores)"
    imu = foot_imu(paper_walk, WALKERS, seed=3, spec=ImuSpec.consumer())
    omega, f = imu.omega_b.copy(), imu.f_b.copy()
    f[WALKERS - 1, 400:, 0] += 1e5  # the last walker diverges and is frozen
    (serial, run1), (threaded, run2) = (run_with_threads(t, family, omega, f) for t in (1, 2))
    if os.environ.get("NUMBA_THREADING_LAYER", "default") == "default":
        assert numba.threading_layer() == "workqueue"  # the kernel's choice (nav.kernel_threads)
    assert run1.diverged.tolist() == [False] * (WALKERS - 1) + [True]
    for field in fields(run1):
        np.testing.assert_array_equal(getattr(run2, field.name), getattr(run1, field.name))
    for name in ("sig_C", "sig_v", "sig_p", "x", "P", "elapsed_s", "last_nis"):
        np.testing.assert_array_equal(getattr(threaded, name), getattr(serial, name), name)
    # the log: the same ZUPTs, walker by walker within each block, as the serial kernel
    assert len(serial.history) >= 2 * 12 * (WALKERS - 1)  # two ZUPTs or more per stance
    assert len(threaded.history) == len(serial.history)
    for one, two in zip(serial.history, threaded.history, strict=True):
        for field in fields(one):
            np.testing.assert_array_equal(getattr(two, field.name), getattr(one, field.name))


def test_compact_log_closes_the_gaps_in_walker_order():
    """Rows written from row i·K on for walker i come out contiguous, walker by
    walker, each walker's rows in their order; rows past the count are not read."""
    k, logged = 4, np.array([2, 0, 4, 1])
    log = new_update_log(len(logged) * k)
    log.index[:] = -1
    expected = []
    for i, count in enumerate(logged):
        for r in range(count):
            row, tag = i * k + r, 100 * i + r
            log.index[row] = [i, r, tag % 3, 1]
            log.x[row] = tag
            log.P[row] = -tag
            log.nis[row] = tag / 7
            expected.append(tag)
    n = compact_log(log.index, log.x, log.P, log.nis, logged, k)
    assert n == logged.sum() == len(expected)
    tags = np.array(expected)
    np.testing.assert_array_equal(log.index[:n, 0], tags // 100)
    np.testing.assert_array_equal(log.index[:n, 1], tags % 100)
    np.testing.assert_array_equal(log.x[:n, 1, 4], tags)
    np.testing.assert_array_equal(log.P[:n, 0, 8, 2], -tags)
    np.testing.assert_array_equal(log.nis[:n], tags / 7)


@numba.njit(parallel=True)
def claim_all(n, parts):
    """Every thread takes indices from one counter until n are taken; how often
    each index was taken, and the counter."""
    taken, count = np.zeros(1, dtype=np.int64), np.zeros(n, dtype=np.int8)
    for _ in numba.prange(parts):
        i = fetch_add(taken, 1)
        while i < n:
            count[i] += 1
            i = fetch_add(taken, 1)
    return count, taken


def test_threads_take_each_walker_once():
    """The walkers' counter is atomic: two threads claiming 20 million indices as
    fast as they can (a plain load and store would hand some out twice) take each
    index exactly once."""
    n = 20_000_000
    before = numba.get_num_threads()
    numba.set_num_threads(2)
    try:
        count, taken = claim_all(n, 2)
    finally:
        numba.set_num_threads(before)
    assert count.min() == count.max() == 1
    assert taken[0] == n + 2  # each thread's last claim finds none left


def _two_thread_run(family, omega, f):
    eng, run = run_with_threads(2, family, omega, f)
    return run.x, eng.P, len(eng.history)


def test_two_engines_from_two_python_threads_at_once(paper_walk):
    """The kernel runs without the GIL: two engines advanced from two Python threads
    at the same time (one has the helper threads, the other runs serially while they
    are taken, or after) give each its own sequential run's outputs."""
    imu = foot_imu(paper_walk, WALKERS, seed=5, spec=ImuSpec.consumer())
    inputs = [
        (imu.omega_b.copy(), imu.f_b.copy()),
        (imu.omega_b[::-1].copy(), imu.f_b[::-1].copy()),
    ]
    alone = [_two_thread_run("shoe", o, f) for o, f in inputs]
    together: list = [None, None]

    def work(j):
        together[j] = _two_thread_run("shoe", *inputs[j])

    threads = [threading.Thread(target=work, args=(j,)) for j in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for one, two in zip(alone, together, strict=True):
        np.testing.assert_array_equal(two[0], one[0])
        np.testing.assert_array_equal(two[1], one[1])
        assert two[2] == one[2] > 0


def _child(conn, family, omega, f):
    x, P, count = _two_thread_run(family, omega, f)
    conn.send((x, P, count))


def test_a_forked_child_runs_the_threaded_kernel(paper_walk):
    """After a fork (the helper threads are not inherited) the child starts its own
    and gives the parent's outputs."""
    imu = foot_imu(paper_walk, WALKERS, seed=6, spec=ImuSpec.consumer())
    omega, f = imu.omega_b.copy(), imu.f_b.copy()
    x, P, count = _two_thread_run("paper", omega, f)  # the parent's helpers exist
    parent, child = multiprocessing.get_context("fork").Pipe()
    proc = multiprocessing.get_context("fork").Process(
        target=_child, args=(child, "paper", omega, f)
    )
    proc.start()
    assert parent.poll(120), "the forked child did not answer"
    x2, P2, count2 = parent.recv()
    proc.join(30)
    np.testing.assert_array_equal(x2, x)
    np.testing.assert_array_equal(P2, P)
    assert count2 == count
