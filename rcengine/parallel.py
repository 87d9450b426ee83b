"""Worker processes for independent calibrations, one BLAS thread each.

Each worker runs small dense linear algebra (the least-squares polish factorises a tall Jacobian
at every step). Several processes that each start a multi-threaded BLAS on the same cores
oversubscribe them: the BLAS threads spin-wait for one another and a diagnosis on two cores runs
2–3× slower than with one thread per process. The pool's processes are the parallelism, and the
parent's own small factorisations run faster on one thread too.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Protocol, TypeVar

from threadpoolctl import threadpool_limits


def one_blas_thread() -> threadpool_limits:
    """Limit BLAS/OpenMP to one thread (for good, or within a ``with`` block)."""
    return threadpool_limits(limits=1)


def can_start_processes() -> bool:
    """Whether this process may start worker processes: a daemonic one (a Dask worker, a
    multiprocessing.Pool worker) may not, and must do its share of the work itself."""
    return not multiprocessing.current_process().daemon


def _start_worker(initializer: Callable[..., None] | None, initargs: tuple[Any, ...]) -> None:
    one_blas_thread()
    if initializer is not None:
        initializer(*initargs)


def process_pool(
    workers: int,
    initializer: Callable[..., None] | None = None,
    initargs: tuple[Any, ...] = (),
) -> ProcessPoolExecutor:
    """``workers`` processes limited to one BLAS/OpenMP thread each, then ``initializer``."""
    return ProcessPoolExecutor(workers, initializer=_start_worker, initargs=(initializer, initargs))


T = TypeVar("T", covariant=True)


class Job(Protocol[T]):
    """Independent work that a worker process can run (picklable, with its arguments)."""

    def run(self) -> T: ...


def _run(job: Job[T]) -> T:
    return job.run()


def run_jobs(jobs: Sequence[Job[T]], workers: int) -> list[T]:
    """Each job's result, in order, run on up to ``workers`` processes (1, or where this process
    may not start any, ``can_start_processes``: in this process)."""
    if workers <= 1 or len(jobs) <= 1 or not can_start_processes():
        return [job.run() for job in jobs]
    with process_pool(min(workers, len(jobs))) as pool:
        return list(pool.map(_run, jobs))
