"""The job skeleton (service/jobs.py): a kind supplies only its work function; the skeleton marks
the job running, stores what the work made with the job's success, or the failure with its reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd
import pytest

from rcengine.diagnose import DiagnoseSettings
from service import diagnosis, repository
from service.core.db import Database
from service.errors import CalibrationError, ConflictError
from service.jobs import describe, execute, kinds
from service.models import CALIBRATION, DIAGNOSIS, FAILED, SUCCEEDED, JobRecord

# Storage, API and job tests run on SQLite and on a real PostgreSQL server (conftest).
ON_BOTH_DATABASES = True


@dataclass(frozen=True)
class Made:
    """A product of a fake kind: it stores nothing, and says what it was given."""

    given: object
    outcome: str | None = "promoted"

    def save(self, session, job: JobRecord) -> dict:
        return {"saved_for": job.id, "given": self.given}


def making(db: Database, job: JobRecord, options: object) -> Made:
    assert job.status == "running" and job.started_at is not None
    return Made(options)


def failing(db: Database, job: JobRecord, options: object) -> Made:
    raise CalibrationError("too little data")


@pytest.fixture
def queued_job(settings) -> tuple[Database, int]:
    db = Database(settings.database_url)
    db.migrate()
    with db.write() as session:
        building = repository.add_building(session, "b", {}, "Europe/Rome", "h" * 64)
        job = repository.add_job(session, building.id, "api", "basic", 1, CALIBRATION)
    yield db, job.id
    db.dispose()


def test_work_that_returns_is_stored_with_the_jobs_success(queued_job):
    db, job_id = queued_job
    assert execute(db, job_id, making, {"preset": "fast"}) == SUCCEEDED
    with db.session() as session:
        job = repository.get_job(session, job_id)
    assert (job.status, job.outcome, job.error) == (SUCCEEDED, "promoted", None)
    assert job.details["saved_for"] == job_id and job.details["given"] == {"preset": "fast"}
    assert job.details["duration_s"] >= 0.0
    assert job.started_at <= job.finished_at


def test_work_that_raises_fails_the_job_with_its_reason(queued_job):
    db, job_id = queued_job
    assert execute(db, job_id, failing, None) == FAILED
    with db.session() as session:
        job = repository.get_job(session, job_id)
    assert (job.status, job.outcome, job.details) == (FAILED, None, None)
    assert job.error == describe(CalibrationError("too little data"))
    assert job.error == "CalibrationError: too little data"


def test_a_job_runs_once(queued_job):
    db, job_id = queued_job
    execute(db, job_id, making, None)
    with pytest.raises(ConflictError, match="is succeeded, not queued"):
        execute(db, job_id, making, None)


def test_diagnoses_use_the_engines_preset_unless_the_service_names_one(settings):
    window = diagnosis.DiagnosisPlan(
        pd.Timestamp("2017-01-09", tz="UTC"), pd.Timestamp("2017-01-23", tz="UTC"), None, None
    )
    work, options = kinds(settings)[DIAGNOSIS]
    assert work is diagnosis.work
    assert diagnosis.engine_settings(window, options).preset == DiagnoseSettings().preset
    chosen = settings.model_copy(update={"diagnosis_preset": "modestpy"})
    _, options = kinds(chosen)[DIAGNOSIS]
    assert diagnosis.engine_settings(window, options).preset == "modestpy"
