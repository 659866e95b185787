"""Where independent units of work run: in this process, or as tasks on a Ray cluster.

Evaluation batches (one policy on up to 128 consecutive seeds), CMA-ES
candidates of one generation, and the runs of a multi-seed training are
independent of each other; each unit's result depends only on its own inputs
(seeds, policy, configuration) and, for a network's last bits, on PyTorch's
thread setting, which Ray workers take from this process (training runs on one
thread, :func:`one_torch_thread`). A backend maps a function over such units and
returns the results in the units' order, so the serial and the Ray backend give
identical results.

- :class:`SerialBackend`: one unit after the other, in this process.
- :class:`RayBackend`: one Ray task per unit (``num_cpus=1`` each). Without an
  address it starts a local Ray instance on this machine (``num_cpus`` CPUs,
  default all); with one (``"auto"``, ``"HOST:6379"``, ``"ray://HOST:10001"``)
  it joins that cluster and ships this project's packages to its workers
  (Ray ``runtime_env`` ``py_modules``), which need the dependencies
  installed (``pip install 'pednav[ray]'`` installs them all).

Ray is an optional dependency (``pip install 'pednav[ray]'``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, Protocol

BACKENDS = ("serial", "ray")


@contextmanager
def one_torch_thread() -> Iterator[None]:
    """Run the body with PyTorch on one CPU thread (restored after).

    With several threads PyTorch may split a matrix product, and the number of
    threads can then change the order of its sums. Training runs in this context,
    so that its weights do not depend on the machine's core count and parallel
    runs do not oversubscribe the cores; one thread is also the fast choice for
    the small MLPs of these tuners. (Playing a learned policy keeps the process's
    threads, so evaluation figures stay what they were; Ray workers get this
    process's thread setting, see :func:`_thread_env`.)
    """
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)


class Backend(Protocol):
    """``map(fn, items, on_done)`` → ``[fn(item) for item in items]``, in item order;
    ``on_done(i)`` is called when item i is done (in any order)."""

    name: str
    #: Units that run at the same time (CPUs of the cluster; 1 when serial).
    workers: int

    def map(
        self,
        fn: Callable[[Any], Any],
        items: Sequence[Any],
        on_done: Callable[[int], None] | None = None,
    ) -> list[Any]: ...


class SerialBackend:
    """Every unit in this process, in order."""

    name = "serial"
    workers = 1

    def map(
        self,
        fn: Callable[[Any], Any],
        items: Sequence[Any],
        on_done: Callable[[int], None] | None = None,
    ) -> list[Any]:
        out = []
        for i, item in enumerate(items):
            out.append(fn(item))
            if on_done is not None:
                on_done(i)
        return out


class RayBackend:
    """One Ray task per unit, on a local Ray instance or the cluster at ``address``."""

    name = "ray"

    def __init__(self, address: str | None = None, num_cpus: int | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise ValueError(
                "the ray backend needs Ray: pip install 'pednav[ray]' (or pip install ray)"
            ) from None
        if address is not None and num_cpus is not None:
            raise ValueError("num_cpus applies to a local Ray instance, not to --ray-address")
        if num_cpus is not None and num_cpus < 1:
            raise ValueError(f"num_cpus must be ≥ 1, got {num_cpus}")
        self._ray = ray
        if not ray.is_initialized():
            runtime_env: dict[str, Any] = {"env_vars": _thread_env()}
            kwargs: dict[str, Any] = {
                "include_dashboard": False,
                "logging_level": "error",
                "log_to_driver": False,
            }
            if address is None:
                kwargs["num_cpus"] = num_cpus
            else:
                kwargs["address"] = address
                runtime_env["py_modules"] = _project_packages()
            kwargs["runtime_env"] = runtime_env
            try:
                ray.init(**kwargs)
            except ConnectionError as exc:
                raise ValueError(f"--ray-address {address!r}: {exc}") from None
        self.workers = max(1, int(ray.cluster_resources().get("CPU", 1)))

    def map(
        self,
        fn: Callable[[Any], Any],
        items: Sequence[Any],
        on_done: Callable[[int], None] | None = None,
    ) -> list[Any]:
        ray = self._ray
        task = ray.remote(num_cpus=1)(fn)
        refs = [task.remote(item) for item in items]
        index = {ref: i for i, ref in enumerate(refs)}
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    ray.get(ref)  # raise a failed task's error now
                    if on_done is not None:
                        on_done(index[ref])
            return ray.get(refs)
        except ray.exceptions.RayTaskError as exc:
            for ref in pending:
                ray.cancel(ref)
            cause = exc.cause if isinstance(exc.cause, Exception) else exc
            raise cause from None


def _thread_env() -> dict[str, str]:
    """This process's thread counts for the workers' OpenMP/MKL runtimes, and one
    numba thread per worker.

    Ray starts each worker with ``OMP_NUM_THREADS=1``; PyTorch's CPU kernels started
    that way round a network's outputs and training differently (in the last bits)
    from a process started with several threads, even when both train on one
    thread (:func:`one_torch_thread`). Workers get this process's setting instead.
    Each task reserves one CPU, so the foot env's compiled kernel, which runs its
    walkers on as many threads as numba is given, runs on one thread in a worker
    (``NUMBA_NUM_THREADS=1``; its results do not depend on the thread count,
    :mod:`pednav_env.nav.kernel_threads`).
    """
    import torch

    threads = str(torch.get_num_threads())
    return {"OMP_NUM_THREADS": threads, "MKL_NUM_THREADS": threads, "NUMBA_NUM_THREADS": "1"}


def _project_packages() -> list[Any]:
    """The project's packages, for a remote cluster's workers."""
    import agents
    import baselines
    import pednav_env

    return [pednav_env, baselines, agents]


def make_backend(
    name: str = "serial", address: str | None = None, num_cpus: int | None = None
) -> Backend:
    """``"serial"`` or ``"ray"``; an ``address`` implies Ray."""
    if address is not None and name == "serial":
        name = "ray"
    if name == "serial":
        if num_cpus is not None:
            raise ValueError("num_cpus applies to the ray backend")
        return SerialBackend()
    if name == "ray":
        return RayBackend(address, num_cpus)
    raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {name!r}")
