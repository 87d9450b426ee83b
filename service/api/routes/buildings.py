"""Buildings: register (admin), read, list (admin), rotate a token (admin)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, status

from rcengine.building import Building

from ... import adoption, repository
from ...core.security import hash_token, new_token
from ...schemas.adoption import ModelInUse
from ...schemas.buildings import (
    BuildingCreate,
    BuildingCreated,
    BuildingList,
    BuildingRead,
    TokenRotated,
)
from ...schemas.common import error_responses, id_in_path, in_zone
from ..deps import ADMIN_ONLY, BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["buildings"])


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    summary="Register a building (admin token); returns its id and its own token",
    responses=error_responses(401, 403, 422),
    dependencies=[ADMIN_ONLY],
)
def create_building(body: BuildingCreate, ctx: ContextDep) -> BuildingCreated:
    building = Building.from_dict(body.model_dump(exclude_none=True))
    token = new_token()
    with ctx.db.write() as session:
        record = repository.add_building(
            session,
            building.name,
            building.to_dict(),
            building.location.timezone,
            hash_token(token),
        )
    return BuildingCreated.model_validate(
        {
            "id": record.id,
            "name": record.name,
            "token": token,
            "created_at": record.created_at,
            "warnings": list(building.notes),
        },
        context=in_zone(record.timezone),
    )


@router.get(
    "",
    summary="Every building (admin token)",
    responses=error_responses(401, 403),
    dependencies=[ADMIN_ONLY],
)
def list_buildings(ctx: ContextDep) -> BuildingList:
    with ctx.db.session() as session:
        rows = repository.building_summaries(session)
    return BuildingList(
        items=[BuildingRead.model_validate(row, context=in_zone(row.timezone)) for row in rows]
    )


@router.get(
    "/{building_id}",
    summary="A building, its stored data and current parameter set",
    responses=error_responses(401, 404),
)
def read_building(building_id: BuildingDep, ctx: ContextDep) -> BuildingRead:
    with ctx.db.session() as session:
        row = repository.building_summary(session, building_id)
        in_use = adoption.in_use(session, repository.get_building(session, building_id))
    zone = in_zone(row.timezone)
    body = BuildingRead.model_validate(row, context=zone)
    return body.model_copy(update={"model": ModelInUse.model_validate(in_use, context=zone)})


@router.post(
    "/{building_id}/token",
    summary="Replace a building's token (admin token); the old one stops working",
    responses=error_responses(401, 403, 404),
    dependencies=[ADMIN_ONLY],
)
def rotate_token(
    building_id: Annotated[int, id_in_path("Building", 1)], ctx: ContextDep
) -> TokenRotated:
    token = new_token()
    with ctx.db.write() as session:
        repository.set_token_hash(session, building_id, hash_token(token))
    ctx.tokens.forget(building_id)
    return TokenRotated(id=building_id, token=token)
