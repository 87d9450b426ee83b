"""The executor that runs jobs (calibrations, diagnoses) off the request path.

Worker processes are started with ``spawn`` (no copy of the server's threads, locks or database
connections), at low CPU priority so that the API answers first when both want a core, and with
one BLAS thread each. This module imports nothing heavy: the worker sets its environment before
the engine (numpy) is imported by the first job.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor

# Added to the worker's nice value: the API process wins the CPU when both are busy.
WORKER_NICENESS = 10
_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def make_executor(workers: int, log_level: str) -> Executor:
    """``workers`` spawned processes, or one thread of this process when ``workers`` is 0."""
    if workers == 0:
        return ThreadPoolExecutor(max_workers=1, thread_name_prefix="job")
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_init_worker,
        initargs=(log_level,),
    )


def warm_up() -> None:
    """Import the engine in a worker ahead of the first job."""
    from . import calibration, diagnosis  # noqa: F401


def _init_worker(log_level: str) -> None:
    for name in _THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    # Ctrl-C in the terminal stops the server; a job in progress finishes and is stored.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.nice(WORKER_NICENESS)
    from .core.logging import configure_logging

    configure_logging(log_level)
