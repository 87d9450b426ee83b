"""Parameter sets: the history with fit metrics, one set, its params.json document."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path

from ... import repository
from ...bridge import local_time
from ...models import ParameterSetRecord
from ...schemas.common import error_responses
from ...schemas.parameters import ParameterSetList, ParameterSetRead, ParameterValue
from ..deps import BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["parameters"])
SetId = Annotated[int, Path(description="Parameter-set id", examples=[4])]


@router.get(
    "/{building_id}/parameters",
    response_model=ParameterSetList,
    summary="Every parameter set of the building, newest first, the current one marked",
    responses=error_responses(401, 404),
)
def list_parameter_sets(building_id: BuildingDep, ctx: ContextDep) -> ParameterSetList:
    with ctx.db.session() as session:
        tz = repository.get_building(session, building_id).timezone
        items = [_read(r, tz) for r in repository.list_parameter_sets(session, building_id)]
    current = next((item.id for item in items if item.is_current), None)
    return ParameterSetList(current_id=current, items=items)


@router.get(
    "/{building_id}/parameters/{set_id}",
    response_model=ParameterSetRead,
    summary="One parameter set with its values, bounds and metrics",
    responses=error_responses(401, 404),
)
def read_parameter_set(
    building_id: BuildingDep, set_id: SetId, ctx: ContextDep
) -> ParameterSetRead:
    with ctx.db.session() as session:
        tz = repository.get_building(session, building_id).timezone
        return _read(repository.get_parameter_set(session, building_id, set_id), tz)


@router.get(
    "/{building_id}/parameters/{set_id}/document",
    summary="The set as params.json, as written by `rcengine fit` and read by `rcengine predict`",
    responses={
        **error_responses(401, 404),
        200: {
            "content": {"application/json": {"example": {"format_version": 1, "model": "basic"}}}
        },
    },
)
def parameter_set_document(
    building_id: BuildingDep, set_id: SetId, ctx: ContextDep
) -> dict[str, Any]:
    with ctx.db.session() as session:
        return repository.get_parameter_set(session, building_id, set_id).document


def _read(record: ParameterSetRecord, tz: str) -> ParameterSetRead:
    return ParameterSetRead(
        id=record.id,
        model=record.model,
        status=record.status,
        is_current=record.is_current,
        reason=record.reason,
        job_id=record.job_id,
        created_at=local_time(record.created_at, tz),
        train_start=local_time(record.train_start, tz),
        train_end=local_time(record.train_end, tz),
        rmse_train=record.rmse_train,
        rmse_holdout=record.rmse_holdout,
        metrics=record.metrics,
        engine_version=record.engine_version,
        parameters={name: ParameterValue(**p) for name, p in record.document["parameters"].items()},
    )
