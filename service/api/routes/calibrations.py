"""Calibration jobs: start one (202), list a building's, poll one."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Body, HTTPException, Path, Response, status

from rcengine.models import MODELS

from ... import repository
from ...bridge import local_time
from ...models import JobRecord
from ...schemas.calibrations import CalibrationRequest, JobList, JobRead
from ...schemas.common import error_responses
from ..deps import BuildingDep, ContextDep, TokenBuildingDep

router = APIRouter(tags=["calibrations"])


@router.post(
    "/buildings/{building_id}/calibrations",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=JobRead,
    summary="Start a re-estimation on the last N days; returns the job to poll",
    description=(
        "Fits the model on the N days before the most recent measured day, scores the new and "
        "the current parameter set on that held-out day (day-ahead forecast RMSE), and makes the "
        "new set current only if it is no worse. At most one queued or running job per "
        "building (409 otherwise). Poll `GET /jobs/{job_id}` (also in the Location header)."
    ),
    responses=error_responses(401, 404, 409, 422),
)
def start_calibration(
    building_id: BuildingDep,
    ctx: ContextDep,
    response: Response,
    body: Annotated[CalibrationRequest | None, Body()] = None,
) -> JobRead:
    body = body or CalibrationRequest()
    model = body.model or ctx.settings.model
    if model not in MODELS:
        raise HTTPException(
            status.HTTP_422_UNPROCESSABLE_CONTENT,
            f"invalid model {model!r}; choose from {sorted(MODELS)}",
        )
    job = ctx.runner.create(building_id, model, body.days or ctx.settings.training_days, "api")
    response.headers["Location"] = f"/jobs/{job.id}"
    return _read(job, _timezone(ctx, building_id))


@router.get(
    "/buildings/{building_id}/calibrations",
    response_model=JobList,
    summary="The building's calibration jobs, newest first",
    responses=error_responses(401, 404),
)
def list_calibrations(building_id: BuildingDep, ctx: ContextDep) -> JobList:
    tz = _timezone(ctx, building_id)
    with ctx.db.session() as session:
        return JobList(
            items=[_read(j, tz) for j in repository.list_jobs(session, building_id, 100)]
        )


@router.get(
    "/jobs/{job_id}",
    response_model=JobRead,
    summary="A calibration job: queued | running | succeeded | failed",
    responses=error_responses(401, 404),
)
def read_job(
    job_id: Annotated[int, Path(examples=[12])], ctx: ContextDep, owner: TokenBuildingDep
) -> JobRead:
    with ctx.db.session() as session:
        job = repository.get_job(session, job_id)
        if owner is not None and job.building_id != owner:
            raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job_id} not found")
        return _read(job, repository.get_building(session, job.building_id).timezone)


def _timezone(ctx: ContextDep, building_id: int) -> str:
    with ctx.db.session() as session:
        return repository.get_building(session, building_id).timezone


def _read(job: JobRecord, tz: str) -> JobRead:
    details = job.details or {}
    return JobRead(
        id=job.id,
        building_id=job.building_id,
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
        details=job.details,
    )
