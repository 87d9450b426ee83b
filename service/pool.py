"""The executor that runs jobs (calibrations, diagnoses) off the request path.

Worker processes are started with ``spawn`` (no copy of the server's threads, locks or database
connections), at low CPU priority so that the API answers first when both want a core, and with
one BLAS thread each. This module imports nothing heavy: the worker sets its environment before
the engine (numpy) is imported by the first job.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor

# Added to the worker's nice value: the API process wins the CPU when both are busy.
WORKER_NICENESS = 10
# prctl option: the signal a process gets when its parent dies (linux/prctl.h).
_PR_SET_PDEATHSIG = 1
# How often a worker checks that the server that started it is alive. [s]
PARENT_POLL_S = 0.5
_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def make_executor(workers: int, log_level: str) -> Executor:
    """``workers`` spawned processes, or one thread of this process when ``workers`` is 0."""
    if workers == 0:
        return ThreadPoolExecutor(max_workers=1, thread_name_prefix="job")
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_init_worker,
        initargs=(log_level, os.getpid()),
    )


def warm_up() -> None:
    """Import the engine in a worker ahead of the first job."""
    from . import calibration, diagnosis  # noqa: F401


def _init_worker(log_level: str, parent_pid: int) -> None:
    _die_with_parent(parent_pid)
    for name in _THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    # Ctrl-C in the terminal stops the server; a job in progress finishes and is stored.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.nice(WORKER_NICENESS)
    from .core.logging import configure_logging

    configure_logging(log_level)


def _die_with_parent(parent_pid: int) -> None:
    """A worker never outlives the server, nor do the processes it starts (the engine's own
    pools): the worker leads a process group of its own, and the whole group is killed when the
    server dies — on the kernel's parent-death signal (Linux) or, should the worker's main thread
    be busy in C code, by a thread watching the parent's pid. A job cut short this way is failed
    by the next server once its lease expires; its own late writes are fenced off."""
    os.setpgid(0, 0)
    signal.signal(signal.SIGTERM, _kill_group)
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    if os.getppid() != parent_pid:  # the parent died before the signal was asked for
        _kill_group()
    threading.Thread(target=_watch_parent, args=(parent_pid,), name="parent", daemon=True).start()


def _watch_parent(parent_pid: int) -> None:
    while os.getppid() == parent_pid:
        time.sleep(PARENT_POLL_S)
    _kill_group()


def _kill_group(*_: object) -> None:
    os.killpg(os.getpgid(0), signal.SIGKILL)
