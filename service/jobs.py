"""Jobs (calibrations and diagnoses): one skeleton for every kind, recovery after a restart, the
nightly batch.

A job's life: :class:`JobRunner` stores it queued and hands it to the executor; in a worker,
:func:`execute` marks it running, runs the work of its kind, and stores what the work made in
the transaction that marks it succeeded — or, when the work raises, marks it failed with the
reason, the building's current set and latest report untouched. A kind supplies only its work
function (``calibration.work``, ``diagnosis.work``): ``work(db, job, options)`` returns a
:class:`Product`.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from concurrent.futures import Executor, Future
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol

from sqlalchemy.orm import Session

from rcengine.exceptions import RCEngineError

from . import calibration, diagnosis, repository
from .calibration import CalibrationOptions
from .core.config import Settings
from .core.db import Database
from .diagnosis import DiagnosisOptions, DiagnosisSpec
from .errors import ConflictError, ServiceError
from .models import (
    ACTIVE_JOB_STATUSES,
    CALIBRATION,
    DIAGNOSIS,
    FAILED,
    SUCCEEDED,
    BuildingRecord,
    JobRecord,
)
from .pool import make_executor, warm_up

log = logging.getLogger(__name__)
INTERRUPTED = "interrupted: the server stopped before the job finished"


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
        CALIBRATION: (calibration.work, CalibrationOptions(settings.preset, settings.random_state)),
        DIAGNOSIS: (
            diagnosis.work,
            DiagnosisOptions(settings.diagnosis_preset, settings.random_state),
        ),
    }


def run_job(database_url: str, job_id: int, work: Work, options: Any) -> None:
    """Worker entry: its own database engine, then :func:`execute`."""
    db = Database(database_url)
    try:
        execute(db, job_id, work, options)
    finally:
        db.dispose()


def execute(db: Database, job_id: int, work: Work, options: Any) -> str:
    """Run a queued job to its end; returns its final status. Never raises for failed work."""
    started = time.perf_counter()
    with db.write() as session:
        job = repository.start_job(session, job_id)
    context = {"job_id": job_id, "building_id": job.building_id}
    log.info("%s started", job.kind, extra=context)
    try:
        product = work(db, job, options)
    except Exception as exc:  # every failure is stored with its reason
        error = describe(exc)
        with db.write() as session:
            repository.finish_job(session, job_id, FAILED, error=error)
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
        repository.finish_job(
            session, job_id, SUCCEEDED, outcome=product.outcome, details=details
        )
    log.info(
        "%s finished",
        job.kind,
        extra={**context, "outcome": product.outcome, "details": details},
    )
    return SUCCEEDED


def describe(exc: BaseException) -> str:
    """A failure as one line for the job record."""
    return f"{type(exc).__name__}: {exc}"


class JobRunner:
    """Owns the executor; ``create_calibration`` and ``create_diagnosis`` queue a job and hand
    it over at once. One executor runs every kind."""

    def __init__(self, settings: Settings, db: Database):
        self.settings = settings
        self.db = db
        self._kinds = kinds(settings)
        self._lock = threading.Lock()
        self._executor = self._new_executor()

    def create_calibration(
        self, building_id: int, model: str, days: int, trigger: str
    ) -> JobRecord:
        """Queue a calibration on ``days`` before the held-out day and submit it; ConflictError
        if the building has one active or has no measured data yet."""
        with self.db.write() as session:
            _measured_building(session, building_id)
            job = repository.add_job(session, building_id, trigger, model, days, CALIBRATION)
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
            job = repository.add_job(
                session, building_id, trigger, model, window.days, DIAGNOSIS, window.to_dict()
            )
        self.submit(job.id, DIAGNOSIS)
        return job

    def submit(self, job_id: int, kind: str) -> None:
        work, options = self._kinds[kind]
        try:
            future = self._executor.submit(run_job, self.db.url, job_id, work, options)
        except BrokenProcessPool:  # a worker died (killed, out of memory): start a new pool
            with self._lock:
                self._executor = self._new_executor()
            future = self._executor.submit(run_job, self.db.url, job_id, work, options)
        future.add_done_callback(lambda f: self._finished(job_id, f))

    def shutdown(self) -> None:
        """Cancel jobs not yet started (marked failed); let running ones finish."""
        self._executor.shutdown(wait=False, cancel_futures=True)

    def _finished(self, job_id: int, future: Future) -> None:
        # The worker records every failure itself; this catches a worker that died or could
        # not reach the database, so that no job stays "running" for ever.
        exc = None if future.cancelled() else future.exception()
        if not future.cancelled() and exc is None:
            return
        reason = INTERRUPTED if future.cancelled() else f"worker error: {describe(exc)}"
        with self.db.write() as session:
            job = repository.get_job(session, job_id)
            if job.status in ACTIVE_JOB_STATUSES:
                repository.finish_job(session, job_id, FAILED, error=reason)
        log.error("job ended abnormally", extra={"job_id": job_id, "error": reason})

    def _new_executor(self) -> Executor:
        executor = make_executor(self.settings.workers, self.settings.log_level)
        if self.settings.workers > 0:
            executor.submit(warm_up)
        return executor


def _measured_building(session: Session, building_id: int) -> BuildingRecord:
    building = repository.get_building(session, building_id)
    if building.last_measured_at is None:
        raise ConflictError(
            f"building {building_id} has no measured t_in yet; upload measurements first"
        )
    return building


def fail_interrupted(db: Database) -> list[int]:
    """At start-up: jobs left queued or running by a previous server process failed."""
    with db.write() as session:
        ids = repository.fail_active_jobs(session, INTERRUPTED)
    if ids:
        log.warning("marked interrupted jobs failed", extra={"job_ids": ids})
    return ids


def queue_retraining(db: Database, settings: Settings, trigger: str) -> list[int]:
    """A queued calibration for every building with new data since its last one; returns their
    ids. Buildings that already have an active calibration are skipped.
    """
    with db.session() as session:
        building_ids = repository.buildings_with_new_data(session)
    queued = []
    for building_id in building_ids:
        try:
            with db.write() as session:
                job = repository.add_job(
                    session, building_id, trigger, settings.model, settings.training_days
                )
            queued.append(job.id)
        except ConflictError as exc:
            log.info("retraining skipped", extra={"building_id": building_id, "reason": str(exc)})
    return queued


def retrain_all_inline(db: Database, settings: Settings, trigger: str) -> dict[int, str]:
    """``rcservice retrain-all``: queue and run every due calibration here, one after another."""
    work, options = kinds(settings)[CALIBRATION]
    return {
        job_id: execute(db, job_id, work, options)
        for job_id in queue_retraining(db, settings, trigger)
    }
