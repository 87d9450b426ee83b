"""Measurements: upload (JSON rows or CSV, validated whole, one transaction) and read back."""

from __future__ import annotations

import io
from collections.abc import Callable
from typing import Annotated

import pandas as pd
from fastapi import APIRouter, HTTPException, Query, Request, status
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import Response

from rcengine.columns import TIME
from rcengine.io.instants import parse_instant
from rcengine.io.timeseries import format_times, write_timeseries

from ... import bridge, ingest, repository
from ...context import ServiceContext
from ...schemas.common import error_responses, in_zone
from ...schemas.measurements import (
    EXAMPLE_CSV,
    MeasurementsRead,
    RemovalResult,
    UploadResult,
    upload_openapi,
)
from ..deps import BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["measurements"])

_JSON_TYPES = ("application/json", "")
_CSV_TYPES = ("text/csv", "application/csv", "text/plain")


@router.post(
    "/{building_id}/measurements",
    summary="Upsert rows by time (JSON rows or text/csv of CONTRACT.md §1)",
    description=(
        "The whole body is validated by the engine's validator and applied in one "
        "transaction: any bad row rejects the request (422, every problem named with its row "
        "and column) and nothing is stored. Rows whose time is stored already are updated; "
        "an empty value never erases a stored one (re-sending a forecast row keeps a measured "
        "t_in). Future rows (t_in empty) carry the weather forecast and planned q_hvac that "
        "forecasts use. Times must stay on the building's time grid."
    ),
    openapi_extra=upload_openapi(),
    responses=error_responses(401, 404, 413, 415, 422),
)
async def upload(building_id: BuildingDep, request: Request, ctx: ContextDep) -> UploadResult:
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media in _JSON_TYPES or media.endswith("+json"):
        parse = ingest.from_json
    elif media in _CSV_TYPES:
        parse = ingest.from_csv
    else:
        raise HTTPException(
            status.HTTP_415_UNSUPPORTED_MEDIA_TYPE,
            f"Content-Type {media!r} is not supported; send application/json "
            '({"rows": [...]}) or text/csv',
        )
    body = await request.body()
    result, tz = await run_in_threadpool(_parse_and_store, ctx, building_id, parse, body)
    return UploadResult.model_validate(result, context=in_zone(tz))


def _parse_and_store(
    ctx: ServiceContext, building_id: int, parse: Callable[[bytes], ingest.Upload], body: bytes
) -> tuple[ingest.UploadResult, str]:
    """Validate and store (CPU and database work, off the event loop); also the time zone."""
    result = ingest.store(ctx.db, building_id, parse(body))
    with ctx.db.session() as session:
        return result, repository.get_building(session, building_id).timezone


def _bound(value: str, name: str) -> pd.Timestamp:
    """A period's bound at the database's microseconds, rounded up: truncated, a start a
    nanosecond after a row's time took that row in (start ≤ time < end)."""
    return parse_instant(value, name).ceil("us")


TimeQuery = Query(description="ISO 8601 with offset", examples=["2017-01-09T00:00:00+01:00"])


@router.get(
    "/{building_id}/measurements",
    response_model=MeasurementsRead,
    summary="Stored rows with start ≤ time < end, as JSON rows or CSV (format=csv)",
    responses={
        **error_responses(401, 404, 422),
        200: {"content": {"text/csv": {"example": EXAMPLE_CSV}}},
    },
)
def read_measurements(
    building_id: BuildingDep,
    ctx: ContextDep,
    start: Annotated[str | None, TimeQuery] = None,
    end: Annotated[str | None, TimeQuery] = None,
    format_: Annotated[
        str, Query(alias="format", pattern="^(json|csv)$", examples=["json"])
    ] = "json",
):
    first = None if start is None else _bound(start, "start")
    last = None if end is None else _bound(end, "end")
    with ctx.db.session() as session:
        tz = repository.get_building(session, building_id).timezone
        frame = bridge.load_frame(session, building_id, first, last)
    if format_ == "csv":
        buffer = io.StringIO()
        write_timeseries(frame, buffer, tz)
        return Response(buffer.getvalue(), media_type="text/csv")
    rows = bridge.frame_to_rows(frame)
    for row, local in zip(rows, format_times(frame.index, tz), strict=True):
        row[TIME] = local
    return MeasurementsRead(rows=rows)


@router.delete(
    "/{building_id}/measurements",
    summary="Delete the stored rows with start ≤ time < end",
    description=(
        "Takes back rows a device sent wrongly (a clock a year off, a test run): an upload "
        "cannot, since an empty value never erases a stored one. Both bounds are required. The "
        "building's last measured time is read again from what remains; the parameter sets "
        "and reports are kept."
    ),
    responses=error_responses(401, 404, 422),
)
def delete_measurements(
    building_id: BuildingDep,
    ctx: ContextDep,
    start: Annotated[str, TimeQuery],
    end: Annotated[str, TimeQuery],
) -> RemovalResult:
    first, last = _bound(start, "start"), _bound(end, "end")
    result = ingest.remove(ctx.db, building_id, first, last)
    with ctx.db.session() as session:
        tz = repository.get_building(session, building_id).timezone
    return RemovalResult.model_validate(result, context=in_zone(tz))
