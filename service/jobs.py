"""Jobs (calibrations and diagnoses): one skeleton for every kind, recovery after a restart, the
nightly batch.

A job's life: :class:`JobRunner` stores it queued and hands it to the executor; in a worker,
:func:`execute` marks it running, runs the work of its kind, and stores what the work made in
the transaction that marks it succeeded — or, when the work raises, marks it failed with the
reason, the building's current set and latest report untouched. A kind supplies only its work
function (``calibration.work``, ``diagnosis.work``): ``work(db, job, options)`` returns a
:class:`Product`.

A run holds its job by a lease (owner, fencing token, heartbeat, expiry; see
``repository.start_job``): a heartbeat thread renews it, and the run's final write must still
hold it, or nothing of the run is stored. Jobs whose lease expired (their process died with its
server) are failed at start-up and by a reaper thread, which moves the token on.

Several service processes can share one PostgreSQL database: a process runs a queued job only
by claiming it (``repository.claim_next_job``, ``FOR UPDATE SKIP LOCKED``, or ``start_job`` for a
named job — whoever marks it running first runs it), so the nightly batch queued by every
replica's scheduler is spread over them and each building is fitted once. Where the work runs
(the process pool or Dask) is the backend's choice (``service.backends``).
"""

from __future__ import annotations

import logging
import os
import queue
import socket
import threading
import time
from collections.abc import Callable
from concurrent.futures import Executor, Future
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any, Protocol

from sqlalchemy import select
from sqlalchemy.exc import SQLAlchemyError
from sqlalchemy.orm import Session

from rcengine.exceptions import RCEngineError

from . import adoption, calibration, diagnosis, repository
from .backends import Backend, make_backend
from .calibration import CalibrationOptions
from .core.config import Settings
from .core.db import Database
from .diagnosis import DiagnosisOptions, DiagnosisSpec
from .errors import ConflictError, LeaseLostError, ServiceError
from .models import (
    CALIBRATION,
    DIAGNOSIS,
    FAILED,
    RUNNING,
    SUCCEEDED,
    BuildingRecord,
    JobRecord,
    utc_now,
)

log = logging.getLogger(__name__)
INTERRUPTED = "interrupted: the server stopped before the job finished"
# Triggers of the nightly re-estimation (scheduler, retrain-all): re-run when interrupted.
NIGHTLY_TRIGGERS = ("schedule", "cli")


class Product(Protocol):
    """What a job's work made: ``outcome`` for the job record (promoted | rejected for a
    calibration), ``save`` to store it in the transaction that marks the job succeeded."""

    @property
    def outcome(self) -> str | None: ...

    def save(self, session: Session, job: JobRecord) -> dict[str, Any]:
        """Store the product; returns the job's ``details``."""
        ...


# A kind's work; a module-level function, so that the process pool can send it by name.
Work = Callable[[Database, JobRecord, Any], Product]


def kinds(settings: Settings) -> dict[str, tuple[Work, Any]]:
    """The work of each kind of job and the service settings it receives (picklable)."""
    return {
        CALIBRATION: (
            calibration.work,
            CalibrationOptions(
                settings.preset, settings.random_state, criterion=settings.criterion
            ),
        ),
        DIAGNOSIS: (
            diagnosis.work,
            DiagnosisOptions(settings.diagnosis_preset, settings.random_state),
        ),
    }


@dataclass(frozen=True)
class LeaseTerms:
    """Who runs a job (a server process) and for how long a lease lasts unrenewed. [s]"""

    owner: str = field(default_factory=lambda: f"{socket.gethostname()}:{os.getpid()}")
    seconds: float = 30.0


def execute(
    db: Database, job_id: int, work: Work, options: Any, terms: LeaseTerms | None = None
) -> str:
    """Run a queued job to its end under a lease; returns its final status. Never raises for
    failed work; LeaseLostError when the lease was taken over (nothing of this run is stored).
    """
    terms = terms or LeaseTerms()
    with db.write() as session:
        lease = repository.start_job(session, job_id, terms.owner, terms.seconds)
    return run_leased(db, lease, work, options, terms)


def drain(
    db: Database,
    kind: str,
    work: Work,
    options: Any,
    terms: LeaseTerms,
    building_ids: tuple[int, ...] = (),
) -> dict[int, str]:
    """Claim the oldest queued job of ``kind`` and run it, until none is left (other processes
    may be claiming from the same queue at the same time); {job id: final status}."""
    done: dict[int, str] = {}
    while (lease := _claim_next(db, kind, terms, building_ids)) is not None:
        try:
            done[lease.job_id] = run_leased(db, lease, work, options, terms)
        except LeaseLostError as exc:  # the job was failed when its lease expired
            log.warning("job run fenced off", extra={"job_id": lease.job_id, "error": str(exc)})
            done[lease.job_id] = FAILED
    return done


def _claim_next(
    db: Database, kind: str, terms: LeaseTerms, building_ids: tuple[int, ...]
) -> repository.Lease | None:
    with db.write() as session:
        return repository.claim_next_job(session, kind, terms.owner, terms.seconds, building_ids)


def run_leased(
    db: Database, lease: repository.Lease, work: Work, options: Any, terms: LeaseTerms
) -> str:
    """Run the job ``lease`` holds (see :func:`execute`)."""
    started = time.perf_counter()
    job_id = lease.job_id
    with db.session() as session:
        job = repository.get_job(session, job_id)
    context = {"job_id": job_id, "building_id": job.building_id, "lease": str(lease)}
    log.info("%s started", job.kind, extra=context)
    with _Heartbeat(db, lease, terms.seconds):
        try:
            product = work(db, job, options)
        except Exception as exc:  # every failure is stored with its reason
            error = describe(exc)
            with db.write() as session:
                repository.finish_job(session, job_id, FAILED, error=error, lease=lease)
            log.warning(
                "%s failed",
                job.kind,
                extra={**context, "error": error},
                exc_info=not isinstance(exc, RCEngineError | ServiceError),
            )
            return FAILED
        with db.write() as session:
            details = product.save(session, job)
            details["duration_s"] = round(time.perf_counter() - started, 3)
            # Fenced: a run whose lease was taken over raises here, and what it saved rolls back.
            repository.finish_job(
                session,
                job_id,
                SUCCEEDED,
                outcome=product.outcome,
                details=details,
                lease=lease,
                # The model fitted: a revert or an adoption while the job ran changes it.
                model=details.get("model"),
            )
    log.info(
        "%s finished",
        job.kind,
        extra={**context, "outcome": product.outcome, "details": details},
    )
    return SUCCEEDED


class _Heartbeat:
    """Renews a lease every third of its length on a thread while the work runs."""

    def __init__(self, db: Database, lease: repository.Lease, seconds: float):
        self.db, self.lease, self.seconds = db, lease, seconds
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, name="lease", daemon=True)

    def __enter__(self) -> _Heartbeat:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _beat(self) -> None:
        while not self._stop.wait(self.seconds / 3.0):
            try:
                with self.db.write() as session:
                    held = repository.renew_lease(session, self.lease, self.seconds)
            except SQLAlchemyError as exc:  # the database is away: the next beat tries again
                log.warning("lease not renewed", extra={"job_id": self.lease.job_id, "error": exc})
                continue
            if not held:
                log.warning("lease lost", extra={"job_id": self.lease.job_id})
                return


def describe(exc: BaseException) -> str:
    """A failure as one line for the job record."""
    return f"{type(exc).__name__}: {exc}"


class JobRunner:
    """Owns the backend and its executor; ``create_calibration`` and ``create_diagnosis`` queue
    a job and hand it over at once, ``drain`` runs what is queued. One executor runs every
    kind."""

    def __init__(self, settings: Settings, db: Database, backend: Backend | None = None):
        self.settings = settings
        self.db = db
        self.terms = LeaseTerms(seconds=settings.job_lease_s)
        self.backend = backend or make_backend(settings)
        self._kinds = kinds(settings)
        self._lock = threading.Lock()
        self._dispatcher = Dispatcher()
        self._executor = self._dispatcher.submit(self._new_executor).result()
        self._stop = threading.Event()
        self._reaper = threading.Thread(target=self._reap, name="lease-reaper", daemon=True)
        self._reaper.start()

    def create_calibration(
        self, building_id: int, model: str, days: int, trigger: str
    ) -> JobRecord:
        """Queue a calibration on ``days`` before the held-out day and submit it; ConflictError
        if the building has one active or has no measured data yet."""
        with self.db.write() as session:
            job = add_calibration(session, building_id, trigger, model, days)
        self.submit(job.id, CALIBRATION)
        return job

    def create_diagnosis(
        self, building_id: int, model: str, spec: DiagnosisSpec, trigger: str
    ) -> JobRecord:
        """Queue a diagnosis of the window ``spec`` asks for (fixed now) and submit it;
        ConflictError if the building has one active or has no measured data yet."""
        with self.db.write() as session:
            building = _measured_building(session, building_id)
            window = diagnosis.plan(
                spec,
                repository.building_summary(session, building_id).first_time,
                building.last_measured_at,
                building.step_s,
                self.settings.diagnosis_days,
            )
            asked = {} if spec.days in (None, window.days) else {"days_requested": spec.days}
            job = repository.add_job(
                session,
                building_id,
                trigger,
                model,
                window.days,
                DIAGNOSIS,
                {**window.to_dict(), **asked},
            )
        self.submit(job.id, DIAGNOSIS)
        return job

    def submit(self, job_id: int, kind: str) -> None:
        handed = self._dispatcher.submit(self._hand_over, job_id, kind)
        handed.add_done_callback(lambda f: self._finished(job_id, f))

    def drain(self, kind: str, building_ids: tuple[int, ...] = ()) -> list[Future]:
        """Claim and run the queued jobs of ``kind`` (of ``building_ids`` if given) on every
        slot of the backend until none is left; futures of each slot's {job id: status}."""
        return [
            self._dispatcher.submit(self._hand_over_drain, kind, building_ids).result()
            for _ in range(self.backend.slots())
        ]

    def resume_queued(self) -> None:
        """Claim and run what is queued, of every kind (at start-up on a shared database: jobs
        queued by a replica that died before running them)."""
        for kind in self._kinds:
            self.drain(kind)

    def _hand_over(self, job_id: int, kind: str) -> None:
        work, options = self._kinds[kind]
        future = self._submit(execute, job_id, work, options, self.terms)
        future.add_done_callback(lambda f: self._finished(job_id, f))
        if kind == CALIBRATION:
            future.add_done_callback(lambda f: adoption.after_calibrations(self, [job_id]))
        if kind == DIAGNOSIS and self.settings.auto_adopt:
            future.add_done_callback(lambda f: adoption.after_diagnosis(self, job_id, f))

    def _hand_over_drain(self, kind: str, building_ids: tuple[int, ...]) -> Future:
        work, options = self._kinds[kind]
        future = self._submit(drain, kind, work, options, self.terms, building_ids)
        future.add_done_callback(self._drained)
        if kind == CALIBRATION:
            future.add_done_callback(self._follow_up)
        return future

    def _submit(self, entry: Callable[..., Any], first: Any, work: Work, *rest: Any) -> Future:
        try:
            return self._executor.submit(*self._call(entry, first, work, *rest))
        except BrokenProcessPool:  # a worker died (killed, out of memory): start a new pool
            with self._lock:
                self._executor = self._new_executor()
            return self._executor.submit(*self._call(entry, first, work, *rest))

    def _call(self, entry: Callable[..., Any], first: Any, work: Work, *rest: Any) -> tuple:
        fn, arguments = self.backend.call(self.db, entry, first, work, *rest)
        return (fn, *arguments)

    def shutdown(self) -> None:
        """Cancel jobs not yet started (marked failed); let running ones finish."""
        self._stop.set()
        self._dispatcher.cancel_pending()
        self._executor.shutdown(wait=False, cancel_futures=True)
        self.backend.close()

    def _reap(self) -> None:
        """Fail running jobs whose lease expired (their process died) while the server runs."""
        while not self._stop.wait(max(self.terms.seconds / 2.0, 0.5)):
            try:
                failed = fail_abandoned(self.db)
                again = requeue_interrupted(self.db, self.settings, failed) if failed else []
            except SQLAlchemyError as exc:  # the database is away: try again at the next round
                log.warning("abandoned jobs not reaped", extra={"error": str(exc)})
                continue
            if again:  # nightly jobs of a dead process: run here, once each
                self.drain(CALIBRATION, tuple(again))

    def _finished(self, job_id: int, future: Future) -> None:
        # The worker records every failure itself; this catches a worker that died or could
        # not reach the database, so that no job stays "running" for ever.
        exc = None if future.cancelled() else future.exception()
        if not future.cancelled() and exc is None:
            return
        if isinstance(exc, LeaseLostError):  # the job was failed when its lease expired
            log.warning("job run fenced off", extra={"job_id": job_id, "error": str(exc)})
            return
        if isinstance(exc, ConflictError):  # another process claimed it first and runs it
            log.info("job claimed elsewhere", extra={"job_id": job_id, "error": str(exc)})
            return
        reason = INTERRUPTED if future.cancelled() else f"worker error: {describe(exc)}"
        try:
            with self.db.write() as session:
                repository.finish_job(session, job_id, FAILED, error=reason)
        except LeaseLostError:  # it had ended already
            return
        log.error("job ended abnormally", extra={"job_id": job_id, "error": reason})

    def _drained(self, future: Future) -> None:
        # A drain records each job's failure itself; a slot lost whole (its worker process
        # died) leaves its current job to the reaper, once the lease expires.
        if not future.cancelled() and future.exception() is not None:
            log.error("job slot ended abnormally", extra={"error": describe(future.exception())})

    def _follow_up(self, drained: Future) -> None:
        if not drained.cancelled() and drained.exception() is None:
            adoption.after_calibrations(self, list(drained.result()))

    def _new_executor(self) -> Executor:
        return self.backend.new_executor()


class Dispatcher:
    """One daemon thread that runs what is handed to it, in order, for the life of the process.

    Worker processes are started by the thread that submits to the pool, and a worker's
    parent-death signal fires when *that thread* ends: every hand-over to the pool goes through
    this thread, which never ends before the process does, so the signal fires only when the
    server dies (and not on a graceful stop, which lets running jobs finish).
    """

    def __init__(self) -> None:
        self._tasks: queue.SimpleQueue[tuple[Future, Callable[..., Any], tuple]] = (
            queue.SimpleQueue()
        )
        threading.Thread(target=self._run, name="dispatch", daemon=True).start()

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        future: Future = Future()
        self._tasks.put((future, fn, args))
        return future

    def cancel_pending(self) -> None:
        """Cancel what was not handed over yet (their callbacks run: the jobs are failed)."""
        while not self._tasks.empty():
            future, _, _ = self._tasks.get_nowait()
            future.cancel()
            future.set_running_or_notify_cancel()

    def _run(self) -> None:
        while True:
            future, fn, args = self._tasks.get()
            if not future.set_running_or_notify_cancel():
                continue
            try:
                future.set_result(fn(*args))
            except BaseException as exc:  # handed to the future's callbacks
                future.set_exception(exc)


def add_calibration(
    session: Session, building_id: int, trigger: str, model: str, days: int
) -> JobRecord:
    """A queued calibration of ``days``, or of the fewer days stored (the job's ``days`` says
    what is fitted, its ``options`` what was asked); ConflictError as for any job, or when the
    building has no measured data yet."""
    building = _measured_building(session, building_id)
    first = repository.building_summary(session, building_id).first_time
    used = calibration.days_used(days, first, building.last_measured_at, building.step_s)
    asked = None if used == days else {"days_requested": days}
    return repository.add_job(session, building_id, trigger, model, used, CALIBRATION, asked)


def _measured_building(session: Session, building_id: int) -> BuildingRecord:
    building = repository.get_building(session, building_id)
    if building.last_measured_at is None:
        raise ConflictError(
            f"building {building_id} has no measured t_in yet; upload measurements first"
        )
    if building.step_s is None:
        raise ConflictError(
            f"building {building_id} has no time step yet: it is known once two stored rows "
            "lie 60–3600 s apart; upload more measurements first"
        )
    return building


def fail_interrupted(db: Database) -> list[int]:
    """At start-up: jobs left queued by a previous server process, and running ones whose lease
    expired, failed (running ones still leased are failed by the reaper once it expires). On a
    database several processes share (PostgreSQL), queued jobs may be another live replica's:
    they stay queued for whichever process claims them."""
    return fail_abandoned(db, queued_too=db.engine.dialect.name == "sqlite")


def announce_mode(settings: Settings, db: Database, owner: str) -> None:
    """At start-up: SQLite runs one service process; say so, loudly when another process seems
    to share the file (a live lease of another owner, or several uvicorn workers asked for)."""
    if settings.several_processes:
        log.info("jobs are claimed from a queue replicas share", extra={"owner": owner})
        return
    with db.session() as session:
        others = session.scalars(
            select(JobRecord.lease_owner).where(
                JobRecord.status == RUNNING,
                JobRecord.lease_expires_at > utc_now(),
                JobRecord.lease_owner != owner,
            )
        ).all()
    workers = os.environ.get("WEB_CONCURRENCY", "1")
    if others or workers not in ("", "1"):
        log.warning(
            "SQLite runs one service process: several replicas (or uvicorn workers) need "
            "PostgreSQL (RCSERVICE_DATABASE_URL=postgresql+psycopg://...; docs/fleet.md)",
            extra={"other_lease_owners": sorted(set(others)), "web_concurrency": workers},
        )
    else:
        log.info("SQLite: single-process mode (several replicas need PostgreSQL)")


def fail_abandoned(db: Database, queued_too: bool = False) -> list[int]:
    """Fail the jobs no live process holds (see :func:`repository.fail_abandoned_jobs`)."""
    with db.write() as session:
        ids = repository.fail_abandoned_jobs(session, INTERRUPTED, queued_too)
    if ids:
        log.warning("marked interrupted jobs failed", extra={"job_ids": ids})
    return ids


def queue_retraining(
    db: Database, settings: Settings, trigger: str, among: tuple[int, ...] = ()
) -> list[int]:
    """A queued calibration for every building (``among`` these if given) with new data since
    its last one; returns their ids. Buildings that already have an active calibration are
    skipped, and so are those another process fitted meanwhile: each building is re-checked
    with its row locked, so replicas queueing at the same time queue it once.
    """
    with db.session() as session:
        building_ids = repository.buildings_with_new_data(session, INTERRUPTED, among)
    queued = []
    for building_id in building_ids:
        try:
            with db.write() as session:
                repository.lock_building(session, building_id)
                if not repository.buildings_with_new_data(session, INTERRUPTED, (building_id,)):
                    continue
                job = add_calibration(
                    session, building_id, trigger, settings.model, settings.training_days
                )
            queued.append(job.id)
        except ConflictError as exc:
            log.info("retraining skipped", extra={"building_id": building_id, "reason": str(exc)})
        except (ServiceError, RCEngineError) as exc:
            # One building's stored data must not stop the night for every other building.
            log.warning(
                "retraining not queued", extra={"building_id": building_id, "reason": str(exc)}
            )
    return queued


def requeue_interrupted(db: Database, settings: Settings, job_ids: list[int]) -> list[int]:
    """The buildings of nightly calibrations among ``job_ids`` (failed: their process died)
    queued again, once; returns the buildings queued."""
    with db.session() as session:
        jobs = [repository.get_job(session, job_id) for job_id in job_ids]
    again = []
    for job in jobs:
        nightly = job.kind == CALIBRATION and job.trigger in NIGHTLY_TRIGGERS
        if nightly and queue_retraining(db, settings, job.trigger, (job.building_id,)):
            again.append(job.building_id)
    return again
