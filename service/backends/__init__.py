"""Where jobs run: the in-process pool (default) or Dask distributed (``RCSERVICE_DASK_SCHEDULER``).

Both plug into the one job skeleton of ``service.jobs``: a backend is asked for the executor on
which an *entry* of the skeleton runs (``jobs.execute`` for one job, ``jobs.drain`` for "claim and
run queued jobs until none is left") and for the call that runs it there:

- :class:`PoolBackend` runs the whole entry in a worker process of ``service.pool`` with its own
  database engine, as the service always did;
- ``DaskBackend`` (``service.backends.dask``) runs the entry on a thread of the service, which
  reads the job's data, sends it to a Dask task that fits (no database connection on the
  workers), and stores the result itself: the service alone decides promotion.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import Executor
from typing import Any, Protocol

from ..core.config import Settings
from ..core.db import Database
from ..pool import make_executor, warm_up


class Backend(Protocol):
    """Executor and call of a job-skeleton entry ``entry(db, first, work, *rest)``."""

    name: str

    def new_executor(self) -> Executor: ...

    def call(
        self, db: Database, entry: Callable[..., Any], first: Any, work: Any, *rest: Any
    ) -> tuple[Callable[..., Any], tuple[Any, ...]]:
        """``(fn, args)`` to submit to the executor for ``entry(db, first, work, *rest)``."""
        ...

    def slots(self) -> int:
        """Entries worth running at once (drains of the queue)."""
        ...

    def cores(self) -> int:
        """Cores the work runs on (for buildings per core-hour)."""
        ...

    def close(self) -> None: ...


class PoolBackend:
    """``settings.workers`` spawned processes (or one thread of the server when 0)."""

    name = "pool"

    def __init__(self, settings: Settings):
        self.workers = settings.workers
        self.log_level = settings.log_level

    def new_executor(self) -> Executor:
        executor = make_executor(self.workers, self.log_level)
        if self.workers > 0:
            executor.submit(warm_up)
        return executor

    def call(
        self, db: Database, entry: Callable[..., Any], first: Any, work: Any, *rest: Any
    ) -> tuple[Callable[..., Any], tuple[Any, ...]]:
        # A worker process opens its own engine: connections never cross a fork or a spawn.
        return in_worker, (db.url, entry, first, work, *rest)

    def slots(self) -> int:
        return max(self.workers, 1)

    def cores(self) -> int:
        return min(self.slots(), os.cpu_count() or 1)

    def close(self) -> None:
        return None


def in_worker(database_url: str, entry: Callable[..., Any], *args: Any) -> Any:
    """Worker entry: its own database engine, then ``entry(db, *args)``."""
    db = Database(database_url)
    try:
        return entry(db, *args)
    finally:
        db.dispose()


def make_backend(settings: Settings, dask_scheduler: str | None = None) -> Backend:
    """The Dask backend when a scheduler is given (argument or setting), else the pool."""
    address = dask_scheduler or settings.dask_scheduler
    if address is None:
        return PoolBackend(settings)
    from .dask import DaskBackend  # distributed is imported only when asked for

    return DaskBackend(address)
