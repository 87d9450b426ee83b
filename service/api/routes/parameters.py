"""Parameter sets: the history with fit metrics, one set, its params.json document."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter

from ... import repository
from ...schemas.common import id_in_path
from ...schemas.parameters import ParameterSetList, ParameterSetRead
from ..answers import building_zone
from ..deps import ACCESS_ERRORS, BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["parameters"], responses=ACCESS_ERRORS)
SetId = Annotated[int, id_in_path("Parameter-set", 4)]


@router.get(
    "/{building_id}/parameters",
    summary="Every parameter set of the building, newest first, the current one marked",
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
    summary="One parameter set with its values, bounds and metrics",
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
