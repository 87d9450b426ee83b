"""Calibration jobs: create, hand to the executor, recover after a restart, nightly batch."""

from __future__ import annotations

import logging
import threading
from concurrent.futures import Executor, Future
from concurrent.futures.process import BrokenProcessPool

from . import repository
from .calibration import CalibrationOptions, describe, execute, run_job
from .core.config import Settings
from .core.db import Database
from .errors import ConflictError
from .models import ACTIVE_JOB_STATUSES, FAILED, JobRecord
from .pool import make_executor, warm_up

log = logging.getLogger(__name__)
INTERRUPTED = "interrupted: the server stopped before the job finished"


class JobRunner:
    """Owns the executor; ``create`` queues a job and hands it over at once."""

    def __init__(self, settings: Settings, db: Database):
        self.settings = settings
        self.db = db
        self.options = options_of(settings)
        self._lock = threading.Lock()
        self._executor = self._new_executor()

    def create(self, building_id: int, model: str, days: int, trigger: str) -> JobRecord:
        """Queue a job and submit it; ConflictError if the building has one active or has no
        measured data yet."""
        with self.db.write() as session:
            if repository.get_building(session, building_id).last_measured_at is None:
                raise ConflictError(
                    f"building {building_id} has no measured t_in yet; upload measurements first"
                )
            job = repository.add_job(session, building_id, trigger, model, days)
        self.submit(job.id)
        return job

    def submit(self, job_id: int) -> None:
        try:
            future = self._executor.submit(run_job, self.db.url, job_id, self.options)
        except BrokenProcessPool:  # a worker died (killed, out of memory): start a new pool
            with self._lock:
                self._executor = self._new_executor()
            future = self._executor.submit(run_job, self.db.url, job_id, self.options)
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
        log.error("calibration job ended abnormally", extra={"job_id": job_id, "error": reason})

    def _new_executor(self) -> Executor:
        executor = make_executor(self.settings.workers, self.settings.log_level)
        if self.settings.workers > 0:
            executor.submit(warm_up)
        return executor


def options_of(settings: Settings) -> CalibrationOptions:
    return CalibrationOptions(preset=settings.preset, random_state=settings.random_state)


def fail_interrupted(db: Database) -> list[int]:
    """At start-up: jobs left queued or running by a previous server process failed."""
    with db.write() as session:
        ids = repository.fail_active_jobs(session, INTERRUPTED)
    if ids:
        log.warning("marked interrupted jobs failed", extra={"job_ids": ids})
    return ids


def queue_retraining(db: Database, settings: Settings, trigger: str) -> list[int]:
    """A queued job for every building with new data since its last job; returns their ids.

    Buildings that already have an active job are skipped.
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
    """``rcservice retrain-all``: queue and run every due job here, one after another."""
    options = options_of(settings)
    return {
        job_id: execute(db, job_id, options) for job_id in queue_retraining(db, settings, trigger)
    }
