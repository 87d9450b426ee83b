"""Jobs (calibrations and diagnoses): create, hand to the executor, recover after a restart,
nightly batch."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import Executor, Future
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from sqlalchemy.orm import Session

from . import calibration, diagnosis, repository
from .calibration import CalibrationOptions, describe, execute
from .core.config import Settings
from .core.db import Database
from .diagnosis import DiagnosisOptions, DiagnosisSpec
from .errors import ConflictError
from .models import ACTIVE_JOB_STATUSES, CALIBRATION, DIAGNOSIS, FAILED, BuildingRecord, JobRecord
from .pool import make_executor, warm_up

log = logging.getLogger(__name__)
INTERRUPTED = "interrupted: the server stopped before the job finished"


class JobRunner:
    """Owns the executor; ``create`` and ``create_diagnosis`` queue a job and hand it over at
    once. One executor runs both kinds."""

    def __init__(self, settings: Settings, db: Database):
        self.settings = settings
        self.db = db
        self.options = options_of(settings)
        # The worker entry of each kind of job and the settings it receives.
        self._entries: dict[str, tuple[Callable[..., None], Any]] = {
            CALIBRATION: (calibration.run_job, self.options),
            DIAGNOSIS: (diagnosis.run_job, diagnosis_options_of(settings)),
        }
        self._lock = threading.Lock()
        self._executor = self._new_executor()

    def create(self, building_id: int, model: str, days: int, trigger: str) -> JobRecord:
        """Queue a calibration and submit it; ConflictError if the building has one active or
        has no measured data yet."""
        with self.db.write() as session:
            _measured_building(session, building_id)
            job = repository.add_job(session, building_id, trigger, model, days)
        self.submit(job.id)
        return job

    def create_diagnosis(
        self, building_id: int, model: str, spec: DiagnosisSpec, trigger: str
    ) -> JobRecord:
        """Queue a diagnosis of the window ``spec`` asks for and submit it; ConflictError if
        the building has one active or has no measured data yet."""
        with self.db.write() as session:
            building = _measured_building(session, building_id)
            _, first_stored, _ = repository.measurement_summary(session, building_id)
            job_plan = diagnosis.plan(
                spec,
                first_stored,
                building.last_measured_at,
                building.step_s,
                self.settings.diagnosis_days,
            )
            job = repository.add_job(
                session,
                building_id,
                trigger,
                model,
                job_plan.days,
                DIAGNOSIS,
                job_plan.to_dict(),
            )
        self.submit(job.id, DIAGNOSIS)
        return job

    def submit(self, job_id: int, kind: str = CALIBRATION) -> None:
        entry, options = self._entries[kind]
        try:
            future = self._executor.submit(entry, self.db.url, job_id, options)
        except BrokenProcessPool:  # a worker died (killed, out of memory): start a new pool
            with self._lock:
                self._executor = self._new_executor()
            future = self._executor.submit(entry, self.db.url, job_id, options)
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


def options_of(settings: Settings) -> CalibrationOptions:
    return CalibrationOptions(preset=settings.preset, random_state=settings.random_state)


def diagnosis_options_of(settings: Settings) -> DiagnosisOptions:
    return DiagnosisOptions(preset=settings.diagnosis_preset, random_state=settings.random_state)


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
