"""Buildings: register (admin), read, list (admin), rotate a token (admin)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, status
from sqlalchemy.orm import Session

from rcengine.building import Building

from ... import repository
from ...bridge import local_time
from ...core.security import hash_token, new_token
from ...models import BuildingRecord
from ...schemas.buildings import (
    BuildingCreate,
    BuildingCreated,
    BuildingList,
    BuildingRead,
    TokenRotated,
)
from ...schemas.common import error_responses
from ..deps import AdminDep, BuildingDep, ContextDep

router = APIRouter(prefix="/buildings", tags=["buildings"])


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    response_model=BuildingCreated,
    summary="Register a building (admin token); returns its id and its own token",
    responses=error_responses(401, 403, 422),
)
def create_building(body: BuildingCreate, ctx: ContextDep, _: AdminDep) -> BuildingCreated:
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
    return BuildingCreated(
        id=record.id,
        name=record.name,
        token=token,
        created_at=local_time(record.created_at, record.timezone),
    )


@router.get(
    "",
    response_model=BuildingList,
    summary="Every building (admin token)",
    responses=error_responses(401, 403),
)
def list_buildings(ctx: ContextDep, _: AdminDep) -> BuildingList:
    with ctx.db.session() as session:
        return BuildingList(items=[_read(session, b) for b in repository.list_buildings(session)])


@router.get(
    "/{building_id}",
    response_model=BuildingRead,
    summary="A building, its stored data and current parameter set",
    responses=error_responses(401, 404),
)
def read_building(building_id: BuildingDep, ctx: ContextDep) -> BuildingRead:
    with ctx.db.session() as session:
        return _read(session, repository.get_building(session, building_id))


@router.post(
    "/{building_id}/token",
    response_model=TokenRotated,
    summary="Replace a building's token (admin token); the old one stops working",
    responses=error_responses(401, 403, 404),
)
def rotate_token(
    building_id: Annotated[int, Path(description="Building id", examples=[1])],
    ctx: ContextDep,
    _: AdminDep,
) -> TokenRotated:
    token = new_token()
    with ctx.db.write() as session:
        repository.set_token_hash(session, building_id, hash_token(token))
    ctx.tokens.forget(building_id)
    return TokenRotated(id=building_id, token=token)


def _read(session: Session, record: BuildingRecord) -> BuildingRead:
    rows, first, last = repository.measurement_summary(session, record.id)
    current = repository.current_parameter_set(session, record.id)
    tz = record.timezone
    return BuildingRead(
        id=record.id,
        name=record.name,
        timezone=tz,
        description=record.description,
        created_at=local_time(record.created_at, tz),
        step_s=record.step_s,
        rows=rows,
        first_time=local_time(first, tz),
        last_time=local_time(last, tz),
        last_measured_time=local_time(record.last_measured_at, tz),
        data_revision=record.data_revision,
        current_parameter_set_id=None if current is None else current.id,
    )
