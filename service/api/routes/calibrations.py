"""Calibration jobs: start one (202); ``routes/jobs`` polls it and lists a building's."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Body, Response, status

from ...schemas.calibrations import CalibrationRequest
from ...schemas.common import error_responses
from ...schemas.jobs import JobRead
from ..answers import queued
from ..deps import BuildingDep, ContextDep

router = APIRouter(tags=["calibrations"])


@router.post(
    "/buildings/{building_id}/calibrations",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=JobRead,
    summary="Start a re-estimation on the last N days; returns the job to poll",
    description=(
        "Fits the model on the N days before the most recent measured day, scores the new and "
        "the current parameter set on that held-out day (day-ahead forecast RMSE), and makes the "
        "new set current only if it is no worse. At most one queued or running calibration per "
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
    model, days = body.model or ctx.settings.model, body.days or ctx.settings.training_days
    job = ctx.runner.create_calibration(building_id, model, days, "api")
    return queued(ctx, job, response)
