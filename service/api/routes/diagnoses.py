"""Mismatch diagnoses: start one (202; ``routes/jobs`` polls it and lists a building's), read
the latest report as JSON or as its HTML page."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Body, Header, HTTPException, Query, Response, status
from fastapi.responses import HTMLResponse

from rcengine.io.instants import parse_instant

from ... import repository
from ...diagnosis import DiagnosisSpec
from ...models import DIAGNOSIS, JobRecord
from ...schemas.common import error_responses
from ...schemas.diagnoses import DIAGNOSIS_EXAMPLE, DiagnosisRead, DiagnosisRequest
from ...schemas.jobs import JobRead
from ..answers import building_zone, queued
from ..deps import BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["diagnoses"])
# Columns of a stored diagnosis answered as they are.
SERVICE_FIELDS = ("id", "building_id", "job_id", "created_at", "settings", "engine_version")


@router.post(
    "/{building_id}/diagnoses",
    status_code=status.HTTP_202_ACCEPTED,
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
        context = building_zone(session, building_id)
    # The engine's report at the top level, beside what the service adds.
    return DiagnosisRead.model_validate(
        {
            **record.report,
            **{name: getattr(record, name) for name in SERVICE_FIELDS},
            "window": {
                "start": record.window_start,
                "end": record.window_end,
                "train_fraction": record.settings["train_fraction"],
            },
        },
        context=context,
    )


def _none_yet(building_id: int, active: JobRecord | None) -> str:
    message = f"building {building_id} has no diagnosis report yet"
    if active is None:
        return f"{message}; start one with POST /buildings/{building_id}/diagnoses"
    return f"{message}; diagnosis job {active.id} is {active.status}: poll GET /jobs/{active.id}"
