"""Jobs of every kind (calibrations, diagnoses): poll one; list a building's jobs of a kind."""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated

from fastapi import APIRouter, HTTPException, status

from ... import repository
from ...models import JOB_COLLECTIONS
from ...schemas.common import id_in_path
from ...schemas.jobs import JobList, JobRead
from ..answers import building_zone, job_read
from ..deps import ACCESS_ERRORS, BuildingDep, ContextDep, TokenBuildingDep

router = APIRouter(responses=ACCESS_ERRORS)
# Jobs listed per building and kind, newest first.
JOBS_LISTED = 100


@router.get(
    "/jobs/{job_id}",
    summary="A calibration or diagnosis job: queued | running | succeeded | failed",
    tags=["jobs"],
)
def read_job(
    job_id: Annotated[int, id_in_path("Job", 12)], ctx: ContextDep, owner: TokenBuildingDep
) -> JobRead:
    with ctx.db.session() as session:
        job = repository.get_job(session, job_id)
        if owner is not None and job.building_id != owner:
            raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job_id} not found")
        return job_read(session, job)


def _jobs_of(kind: str) -> Callable[..., JobList]:
    def list_jobs(building_id: BuildingDep, ctx: ContextDep) -> JobList:
        with ctx.db.session() as session:
            jobs = repository.list_jobs(session, building_id, JOBS_LISTED, kind)
            return JobList.model_validate(
                {"items": jobs}, context=building_zone(session, building_id)
            )

    return list_jobs


# GET /buildings/{id}/calibrations and /buildings/{id}/diagnoses, beside the POST that starts one.
for kind, resource in JOB_COLLECTIONS.items():
    router.add_api_route(
        f"/buildings/{{building_id}}/{resource}",
        _jobs_of(kind),
        methods=["GET"],
        summary=f"The building's {kind} jobs, newest first",
        tags=[resource],
        name=f"list_{resource}",
    )
