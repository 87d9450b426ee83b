"""Calibration jobs: start one (202); ``routes/jobs`` polls it and lists a building's."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Body, Response, status

from ... import adoption, repository
from ...errors import ConflictError
from ...schemas.calibrations import CalibrationRequest
from ...schemas.common import error_responses
from ...schemas.jobs import JobRead
from ..answers import queued
from ..deps import BuildingDep, ContextDep

router = APIRouter(tags=["calibrations"])


@router.post(
    "/buildings/{building_id}/calibrations",
    status_code=status.HTTP_202_ACCEPTED,
    summary="Start a re-estimation on the last N days; returns the job to poll",
    description=(
        "Fits the model on the N days before the most recent measured day, scores the new and "
        "the current parameter set on that held-out day (day-ahead forecast RMSE), and makes the "
        "new set current only if it is no worse. At most one queued or running calibration per "
        "building (409 otherwise). Poll `GET /jobs/{job_id}` (also in the Location header). "
        "While a diagnosed model is adopted, every calibration fits it (a `model` other than "
        "its base: 409, revert first)."
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
    with ctx.db.session() as session:
        spec = adoption.spec_of(repository.get_building(session, building_id))
    if spec is not None and body.model not in (None, spec.base_model):
        raise ConflictError(
            f"building {building_id} uses the adopted model '{spec.name}', which every "
            f"calibration fits; revert (POST /buildings/{building_id}/model/revert) to "
            f"calibrate '{body.model}'"
        )
    model = adoption.job_model(spec, body.model or ctx.settings.model)
    days = body.days or ctx.settings.training_days
    job = ctx.runner.create_calibration(building_id, model, days, "api")
    return queued(ctx, job, response)
