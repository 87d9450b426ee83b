"""Parameter sets: the history with fit metrics, one set, its params.json document."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter

from ... import repository
from ...schemas.common import error_responses, id_in_path
from ...schemas.parameters import ParameterSetList, ParameterSetRead
from ..answers import building_zone
from ..deps import BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["parameters"])
SetId = Annotated[int, id_in_path("Parameter-set", 4)]


@router.get(
    "/{building_id}/parameters",
    response_model=ParameterSetList,
    summary="Every parameter set of the building, newest first, the current one marked",
    responses=error_responses(401, 404),
)
def list_parameter_sets(building_id: BuildingDep, ctx: ContextDep) -> ParameterSetList:
    with ctx.db.session() as session:
        context = building_zone(session, building_id)
        records = repository.list_parameter_sets(session, building_id)
    current = next((record.id for record in records if record.is_current), None)
    return ParameterSetList.model_validate(
        {"current_id": current, "items": records}, context=context
    )


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
        record = repository.get_parameter_set(session, building_id, set_id)
        return ParameterSetRead.model_validate(record, context=building_zone(session, building_id))


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
