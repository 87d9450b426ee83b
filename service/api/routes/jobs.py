"""Jobs of every kind (calibrations, diagnoses): poll one; the record as its answer."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, HTTPException, Path, Response, status

from ... import repository
from ...bridge import local_time
from ...models import JobRecord
from ...schemas.calibrations import JobRead
from ...schemas.common import error_responses
from ..deps import ContextDep, TokenBuildingDep

router = APIRouter(tags=["jobs"])


@router.get(
    "/jobs/{job_id}",
    response_model=JobRead,
    summary="A calibration or diagnosis job: queued | running | succeeded | failed",
    responses=error_responses(401, 404),
)
def read_job(
    job_id: Annotated[int, Path(examples=[12])], ctx: ContextDep, owner: TokenBuildingDep
) -> JobRead:
    with ctx.db.session() as session:
        job = repository.get_job(session, job_id)
        if owner is not None and job.building_id != owner:
            raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job_id} not found")
        return job_read(job, repository.get_building(session, job.building_id).timezone)


def queued(ctx: ContextDep, job: JobRecord, response: Response) -> JobRead:
    """The answer to a call that queued ``job``: the job, and where to poll it (Location)."""
    response.headers["Location"] = f"/jobs/{job.id}"
    with ctx.db.session() as session:
        return job_read(job, repository.get_building(session, job.building_id).timezone)


def building_jobs(ctx: ContextDep, building_id: int, kind: str) -> list[JobRead]:
    """The building's last 100 jobs of ``kind``, newest first."""
    with ctx.db.session() as session:
        tz = repository.get_building(session, building_id).timezone
        return [job_read(j, tz) for j in repository.list_jobs(session, building_id, 100, kind)]


def job_read(job: JobRecord, tz: str) -> JobRead:
    details = job.details or {}
    return JobRead(
        id=job.id,
        building_id=job.building_id,
        kind=job.kind,
        status=job.status,
        outcome=job.outcome,
        trigger=job.trigger,
        model=job.model,
        days=job.days,
        created_at=local_time(job.created_at, tz),
        started_at=local_time(job.started_at, tz),
        finished_at=local_time(job.finished_at, tz),
        error=job.error,
        parameter_set_id=details.get("parameter_set_id"),
        diagnosis_id=details.get("diagnosis_id"),
        options=job.options,
        details=job.details,
    )
