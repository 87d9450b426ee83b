"""Answers several routers give (routers import nothing from one another): a job, and where to
poll one just queued; the time zone a building's answers are written in."""

from __future__ import annotations

from fastapi import Response
from sqlalchemy.orm import Session

from .. import repository
from ..context import ServiceContext
from ..models import JobRecord
from ..schemas.common import in_zone
from ..schemas.jobs import JobRead


def building_zone(session: Session, building_id: int) -> dict[str, str]:
    """Validation context that writes times in the building's time zone."""
    return in_zone(repository.get_building(session, building_id).timezone)


def job_read(session: Session, job: JobRecord) -> JobRead:
    return JobRead.model_validate(job, context=building_zone(session, job.building_id))


def queued(ctx: ServiceContext, job: JobRecord, response: Response) -> JobRead:
    """The answer to a call that queued ``job``: the job, and where to poll it (Location)."""
    response.headers["Location"] = f"/jobs/{job.id}"
    with ctx.db.session() as session:
        return job_read(session, job)
