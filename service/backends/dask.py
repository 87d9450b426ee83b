"""Dask distributed as the job backend (``RCSERVICE_DASK_SCHEDULER=tcp://host:8786`` or
``local``).

The job skeleton runs on a thread of the service (lease, heartbeat, fenced final write); only the
work's compute half goes to the cluster: the service reads the job's rows (``load``), submits them
with the task (a large frame, such as a diagnosis's half year, is scattered to a worker first), and
the worker fits without ever opening a database connection — hundreds of tasks make no connection
storm. The result comes back to the service, which stores it and decides promotion in the
transaction that ends the job.

A worker lost mid-task (killed, out of memory, host gone) is the scheduler's business: it runs the
task again on another worker (up to ``distributed.scheduler.allowed-failures`` times, then the
job fails with ``KilledWorker``). Whichever run answers, the service stores the one result once:
each job still ends with exactly one decision.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable
from concurrent.futures import CancelledError, Executor, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import dask
from distributed import Client, LocalCluster

from .. import calibration, diagnosis
from ..core.db import Database
from ..models import JobRecord
from ..pool import WORKER_NICENESS, warm_up

# The compute half of each kind's work, by its work function (service.jobs.kinds).
SPLIT: dict[Callable[..., Any], tuple[Callable[..., Any], Callable[..., Any]]] = {
    calibration.work: (calibration.load, calibration.compute),
    diagnosis.work: (diagnosis.load, diagnosis.compute),
}
# Inputs above this size are scattered to a worker rather than carried in the task. [bytes]
SCATTER_BYTES = 1_000_000
# Jobs in flight per worker thread: one computes while the service reads the next one's rows
# and stores the last one's result.
IN_FLIGHT_PER_THREAD = 2
# Jobs in flight per service process at most: each holds a thread and, while it reads or
# writes, one of the engine's 30 database connections (service.core.db), which the API and the
# heartbeats share. Past this, add replicas: they share the queue.
MAX_SERVICE_THREADS = 24
CONNECT_TIMEOUT_S = 30.0


class DaskBackend:
    """A client of a Dask scheduler (``local``: a LocalCluster of one single-threaded worker
    process per core of this machine, or ``n_workers``)."""

    name = "dask"

    def __init__(self, address: str, n_workers: int | None = None):
        self.address = address
        self._cluster: LocalCluster | None = None
        if address == "local":
            # One thread per worker process: the fits hold the GIL between numpy calls. Tasks go
            # to the workers as soon as they are submitted (at most two per worker thread are
            # in flight): a worker starts its next fit without a round trip to the scheduler.
            with dask.config.set({"distributed.scheduler.worker-saturation": float("inf")}):
                self._cluster = LocalCluster(
                    n_workers=n_workers or os.cpu_count() or 1,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=":0",  # a free port: several services may run one each
                )
            address = self._cluster.scheduler_address
        try:
            self.client = Client(address, timeout=CONNECT_TIMEOUT_S)
        except OSError as exc:
            raise RuntimeError(
                f"cannot reach the Dask scheduler at {address!r} ({exc}); start one with "
                "`dask scheduler` and workers with `dask worker ADDRESS` (docs/fleet.md)"
            ) from exc
        try:  # every worker imports the engine now, not in its first fit
            self.client.run(warm_up)
            if self._cluster is not None:  # on the service's machine: the API wins the CPU
                self.client.run(lower_priority)
        except ImportError as exc:
            self.close()
            raise RuntimeError(
                f"the Dask workers at {address!r} cannot import the service ({exc}): install "
                "this project with its service extra where each worker runs (docs/fleet.md)"
            ) from exc

    def new_executor(self) -> Executor:
        return ThreadPoolExecutor(max_workers=self.slots(), thread_name_prefix="dask-job")

    def call(
        self, db: Database, entry: Callable[..., Any], first: Any, work: Any, *rest: Any
    ) -> tuple[Callable[..., Any], tuple[Any, ...]]:
        return entry, (db, first, self.remote(work), *rest)

    def remote(self, work: Callable[..., Any]) -> RemoteWork:
        if work not in SPLIT:
            raise ValueError(f"{work!r} has no load/compute halves to run on Dask")
        load, compute = SPLIT[work]
        return RemoteWork(self.client, load, compute)

    def threads(self) -> int:
        """Worker threads of the cluster now (workers may join or leave later)."""
        return max(sum(self.client.nthreads().values()), 1)

    def slots(self) -> int:
        return min(self.threads() * IN_FLIGHT_PER_THREAD, MAX_SERVICE_THREADS)

    def cores(self) -> int:
        return self.threads()

    def close(self) -> None:
        self.client.close()
        if self._cluster is not None:
            self._cluster.close()


@dataclass(frozen=True)
class RemoteWork:
    """A kind's work with its compute half on the cluster; called by the job skeleton on a
    service thread, like any work function."""

    client: Client
    load: Callable[..., Any]
    compute: Callable[..., Any]

    def __call__(self, db: Database, job: JobRecord, options: Any) -> Any:
        inputs = self.load(db, job, options)
        if _frame_bytes(inputs) > SCATTER_BYTES:
            inputs = self.client.scatter(inputs, hash=False)
        key = f"{job.kind}-{job.id}-{uuid.uuid4().hex[:8]}"
        future = self.client.submit(self.compute, inputs, options, key=key, pure=False)
        try:
            return future.result()
        except CancelledError as exc:  # the scheduler went away or restarted
            raise RuntimeError(
                f"the Dask task {key} was cancelled (scheduler {self.client.scheduler.address} "
                "lost or restarted)"
            ) from exc


def lower_priority() -> None:
    """Every thread of this worker process at the pool's lower CPU priority (Linux niceness is
    per thread; threads started later inherit it from their creator)."""
    tasks = Path("/proc/self/task")
    for tid in [int(t.name) for t in tasks.iterdir()] if tasks.exists() else [0]:
        try:
            current = os.getpriority(os.PRIO_PROCESS, tid)
            os.setpriority(os.PRIO_PROCESS, tid, min(current + WORKER_NICENESS, 19))
        except OSError:  # the thread ended meanwhile
            continue


def _frame_bytes(inputs: Any) -> int:
    """The size of the rows a job sends (its frame: the bulk of what it carries). [bytes]"""
    frame = getattr(inputs, "frame", None)
    return 0 if frame is None else int(frame.memory_usage(index=True).sum())
