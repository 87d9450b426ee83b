"""Mismatch diagnoses: start one (202), list a building's jobs, read the latest report as JSON
or as its HTML page."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Body, Header, HTTPException, Query, Response, status
from fastapi.responses import HTMLResponse

from ... import repository
from ...bridge import local_time, parse_instant
from ...diagnosis import DiagnosisSpec
from ...models import DIAGNOSIS, DiagnosisRecord, JobRecord
from ...schemas.calibrations import JobList, JobRead
from ...schemas.common import error_responses
from ...schemas.diagnoses import DIAGNOSIS_EXAMPLE, DiagnosisRead, DiagnosisRequest
from ..deps import BuildingDep, ContextDep
from .jobs import building_jobs, queued

router = APIRouter(prefix="/buildings", tags=["diagnoses"])


@router.post(
    "/{building_id}/diagnoses",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=JobRead,
    summary="Start a mismatch diagnosis of the stored measurements; returns the job to poll",
    description=(
        "Runs `rcengine diagnose` (CONTRACT.md §3) on a window of the stored rows: fits the "
        "model on its first part, locates where it misses the later part, tests each candidate "
        "effect of the vocabulary and keeps those that improve the later period. Takes from "
        "seconds to about a minute per six months of 15-min data. The window is fixed now and "
        "shown in the job's `options`. At most one queued or running diagnosis per building "
        "(409 otherwise; a calibration may run beside it). Poll `GET /jobs/{job_id}` (also in "
        "the Location header), then read `GET /buildings/{id}/diagnosis`."
    ),
    responses=error_responses(401, 404, 409, 422),
)
def start_diagnosis(
    building_id: BuildingDep,
    ctx: ContextDep,
    response: Response,
    body: Annotated[DiagnosisRequest | None, Body()] = None,
) -> JobRead:
    body = body or DiagnosisRequest()
    spec = DiagnosisSpec(
        days=body.days,
        start=None if body.start is None else parse_instant(body.start, "start"),
        end=None if body.end is None else parse_instant(body.end, "end"),
        train_fraction=body.train_fraction,
        effects=None if body.effects is None else tuple(body.effects),
    )
    job = ctx.runner.create_diagnosis(building_id, body.model or ctx.settings.model, spec, "api")
    return queued(ctx, job, response)


@router.get(
    "/{building_id}/diagnoses",
    response_model=JobList,
    summary="The building's diagnosis jobs, newest first",
    responses=error_responses(401, 404),
)
def list_diagnoses(building_id: BuildingDep, ctx: ContextDep) -> JobList:
    return JobList(items=building_jobs(ctx, building_id, DIAGNOSIS))


@router.get(
    "/{building_id}/diagnosis",
    response_model=DiagnosisRead,
    summary="The latest diagnosis report: JSON (CONTRACT.md §3) or the HTML page",
    description=(
        "The report of the building's most recent successful diagnosis: every field of the "
        "`rcengine diagnose` JSON (`baseline`, `mismatch`, `findings`, `final`, ...) plus `id`, "
        "`job_id`, `created_at` and the `window` diagnosed. A failed diagnosis adds no report, "
        "so the previous one stays. `format=html`, or `Accept: text/html` without `format`, "
        "answers the self-contained HTML page (figures embedded). 404 until a diagnosis has "
        "succeeded."
    ),
    responses={
        **error_responses(401, 404),
        200: {
            "content": {
                "application/json": {"example": DIAGNOSIS_EXAMPLE},
                "text/html": {
                    "schema": {"type": "string"},
                    "example": "<!DOCTYPE html><html>…</html>",
                },
            }
        },
    },
)
def read_diagnosis(
    building_id: BuildingDep,
    ctx: ContextDep,
    format_: Annotated[
        Literal["json", "html"] | None,
        Query(
            alias="format",
            description="Answer as JSON or HTML (default: by Accept)",
            examples=["html"],
        ),
    ] = None,
    accept: Annotated[
        str | None, Header(description="text/html asks for the page", examples=["text/html"])
    ] = None,
) -> DiagnosisRead | Response:
    as_html = format_ == "html" or (format_ is None and "text/html" in (accept or ""))
    with ctx.db.session() as session:
        record = repository.latest_diagnosis(session, building_id)
        if record is None:
            active = repository.active_job(session, building_id, DIAGNOSIS)
            raise HTTPException(status.HTTP_404_NOT_FOUND, _none_yet(building_id, active))
        if as_html:
            return HTMLResponse(record.html)
        tz = repository.get_building(session, building_id).timezone
        return _read(record, tz)


def _none_yet(building_id: int, active: JobRecord | None) -> str:
    message = f"building {building_id} has no diagnosis report yet"
    if active is None:
        return f"{message}; start one with POST /buildings/{building_id}/diagnoses"
    return f"{message}; diagnosis job {active.id} is {active.status}: poll GET /jobs/{active.id}"


def _read(record: DiagnosisRecord, tz: str) -> DiagnosisRead:
    return DiagnosisRead.model_validate(
        {
            **record.report,
            "id": record.id,
            "building_id": record.building_id,
            "job_id": record.job_id,
            "created_at": local_time(record.created_at, tz),
            "window": {
                "start": local_time(record.window_start, tz),
                "end": local_time(record.window_end, tz),
                "train_fraction": record.settings["train_fraction"],
            },
            "settings": record.settings,
            "engine_version": record.engine_version,
        }
    )
