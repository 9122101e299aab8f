"""Run independent, seeded tasks across processes or a Ray cluster, results in task order.

Every task carries its own seed, so what a task returns does not depend on which worker ran it
or when: :func:`run_sweep` gives the same list for ``workers=1``, ``workers=N`` and Ray. The
caller sees progress through ``on_result(index, result)``, called in the parent process as
results arrive (in completion order), e.g. to update a progress bar with the running counts.

Back ends:

- ``workers=1``: in this process (no pickling; what tests and debuggers want);
- ``workers=N``: a :class:`concurrent.futures.ProcessPoolExecutor` of ``N`` spawned processes,
  each limited to one BLAS / OpenCV thread so that ``N`` workers use ``N`` cores;
- ``ray="auto" | ADDRESS | "local"``: Ray (the ``symloc[ray]`` extra): ``"local"`` starts a
  private local instance with ``workers`` CPUs, ``"auto"`` joins a running cluster, anything else
  is a cluster address. The same task function runs there as a remote function.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from multiprocessing import get_context
from typing import Any, TypeVar

from symloc.errors import ConfigurationError

__all__ = ["default_workers", "run_sweep"]

T = TypeVar("T")
R = TypeVar("R")

#: prctl option: the signal a process gets when its parent dies (linux/prctl.h).
_PR_SET_PDEATHSIG = 1
_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def default_workers() -> int:
    """All cores this process may use (``os.sched_getaffinity`` where available)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS
        return max(1, os.cpu_count() or 1)


def _worker_init(parent: int) -> None:
    """Worker initializer: die with the sweep, one thread for BLAS and OpenCV."""
    _die_with_parent(parent)
    _single_threaded()


def _die_with_parent(parent: int) -> None:
    """Linux: SIGTERM this worker when the sweep's process dies, so that a sweep killed from
    outside (``kill``, a closed terminal, a batch scheduler) leaves no orphan computing its
    remaining tasks; elsewhere the pool's own shutdown is all there is."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
        except (OSError, AttributeError):  # pragma: no cover - no usable libc
            pass
    if os.getppid() != parent:  # the sweep died before the signal was armed
        os._exit(1)


def _single_threaded() -> None:
    """One thread per worker for BLAS and OpenCV."""
    for var in _THREAD_VARS:
        os.environ[var] = "1"
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:  # pragma: no cover - OpenCV is a dependency
        pass


def run_sweep(
    func: Callable[[T], R],
    tasks: Sequence[T],
    *,
    workers: int | None = None,
    ray: str | None = None,
    on_result: Callable[[int, R], None] | None = None,
) -> list[R]:
    """``[func(t) for t in tasks]``, computed in parallel; the list is in task order.

    Parameters
    ----------
    func : callable
        A module-level function (it is pickled for the workers) of one task.
    tasks : sequence
        Picklable task descriptions, each with its own seed.
    workers : int, optional
        Processes (default: all cores); with ``ray="local"`` the CPUs of the local instance.
    ray : str, optional
        ``"local"``, ``"auto"`` or a Ray cluster address; None uses processes.
    on_result : callable, optional
        ``on_result(index, result)`` in the calling process as each result arrives.

    Raises
    ------
    ConfigurationError
        ``workers`` < 1, or Ray asked for but not installed.
    """
    n_workers = default_workers() if workers is None else workers
    if isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1:
        raise ConfigurationError(f"workers: expected an integer >= 1, got {workers!r}")
    items = list(tasks)
    results: list[Any] = [None] * len(items)

    def done(i: int, r: R) -> None:
        results[i] = r
        if on_result is not None:
            on_result(i, r)

    if ray is not None:
        _run_ray(func, items, n_workers, ray, done)
    elif n_workers == 1 or len(items) <= 1:
        for i, t in enumerate(items):
            done(i, func(t))
    else:
        _run_processes(func, items, n_workers, done)
    return results


def _run_processes(
    func: Callable[[T], R], items: list[T], n_workers: int, done: Callable[[int, R], None]
) -> None:
    ctx = get_context("spawn")
    with ProcessPoolExecutor(
        max_workers=min(n_workers, len(items)),
        mp_context=ctx,
        initializer=_worker_init,
        initargs=(os.getpid(),),
    ) as pool:
        pending: dict[Future[R], int] = {pool.submit(func, t): i for i, t in enumerate(items)}
        try:
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    done(pending.pop(fut), fut.result())
        except BaseException:
            for fut in pending:
                fut.cancel()
            raise


def _run_ray(
    func: Callable[[T], R],
    items: list[T],
    n_workers: int,
    address: str,
    done: Callable[[int, R], None],
) -> None:
    try:
        import ray
    except ImportError as err:
        raise ConfigurationError(
            "ray: Ray is not installed; install the extra with pip install 'symloc[ray]'"
        ) from err
    started_here = not ray.is_initialized()
    if started_here:
        env = {"env_vars": dict.fromkeys(_THREAD_VARS, "1")}
        if address == "local":
            ray.init(
                num_cpus=n_workers,
                include_dashboard=False,
                log_to_driver=False,
                runtime_env=env,
            )
        else:
            ray.init(address=address, log_to_driver=False, runtime_env=env)
    try:
        remote = ray.remote(num_cpus=1)(func)
        refs = {remote.remote(t): i for i, t in enumerate(items)}
        while refs:
            ready, _ = ray.wait(list(refs), num_returns=1)
            for ref in ready:
                done(refs.pop(ref), ray.get(ref))
    finally:
        if started_here:
            ray.shutdown()
