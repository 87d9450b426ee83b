"""Adopt a diagnosis's model, revert to the base model, and read who did so when."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Query

from ... import adoption
from ...schemas.adoption import ModelChangeAnswer, ModelChangeList, ModelChangeRead
from ...schemas.common import id_in_path, in_zone
from ..answers import building_zone
from ..deps import ACCESS_ERRORS, BuildingDep, ContextDep, TokenBuildingDep

router = APIRouter(prefix="/buildings", tags=["diagnoses"], responses=ACCESS_ERRORS)

ADOPT_TEXT = (
    "Makes the diagnosis's final model (the base model plus every accepted extension, with its "
    "learnt schedules, clock, orientations and ground settings) the building's model: every "
    "calibration fits it from now on, and one starts at once (`calibration_job_id`). Its set is "
    "served only if it beats the current set on the held-out day, as any calibration's, so "
    "adopting a model that does not forecast better changes nothing served. Adopting the "
    "adopted diagnosis again changes nothing (`changed: false`); every call is audited. 422 if "
    "the diagnosis accepted no extension. With `finding`, the model the diagnosis refitted with "
    "that effect is adopted instead, whether it accepted it or not — for an engineer who knows "
    "the building has it where the record was too short to show it beyond the diagnosis's "
    "margins; the held-out day still decides what is served (422 if the diagnosis did not "
    "refit that effect)."
)
FindingQuery = Annotated[
    str | None,
    Query(
        description="Adopt the model the diagnosis refitted with this effect (a vocabulary id "
        "among its findings), accepted or not, instead of its final model",
        max_length=64,
        examples=["window_solar_gains"],
    ),
]
REVERT_TEXT = (
    "Back to the base model: calibrations fit it from now on (one starts at once), and the "
    "base-model set served before the adoption is served again now. Reverting a base model "
    "changes nothing (`changed: false`); every call is audited."
)


async def _actor(caller: TokenBuildingDep) -> str:
    """Who the audit row names: the admin token or the building's own."""
    return adoption.ADMIN if caller is None else adoption.BUILDING


ActorDep = Annotated[str, Depends(_actor)]


@router.post(
    "/{building_id}/diagnoses/{diagnosis_id}/adopt",
    summary="Adopt a diagnosis's model as the building's model",
    description=ADOPT_TEXT,
)
def adopt_diagnosis(
    building_id: BuildingDep,
    diagnosis_id: Annotated[int, id_in_path("Diagnosis", 3)],
    ctx: ContextDep,
    actor: ActorDep,
    finding: FindingQuery = None,
) -> ModelChangeAnswer:
    with ctx.db.write() as session:
        change = adoption.adopt(session, building_id, diagnosis_id, actor, finding)
    return _answer(ctx, building_id, change)


@router.post(
    "/{building_id}/model/revert",
    summary="Revert the building to its base model",
    description=REVERT_TEXT,
)
def revert_model(building_id: BuildingDep, ctx: ContextDep, actor: ActorDep) -> ModelChangeAnswer:
    with ctx.db.write() as session:
        change = adoption.revert(session, building_id, actor)
    return _answer(ctx, building_id, change)


@router.get(
    "/{building_id}/model/changes",
    summary="Every adopt and revert call: who, when, which diagnosis",
)
def model_changes(building_id: BuildingDep, ctx: ContextDep) -> ModelChangeList:
    with ctx.db.session() as session:
        rows = adoption.history(session, building_id)
        return ModelChangeList.model_validate(
            {"items": rows}, context=building_zone(session, building_id)
        )


def _answer(ctx: ContextDep, building_id: int, change: adoption.Change) -> ModelChangeAnswer:
    """Start the calibration a change calls for, then answer the audited call."""
    adoption.calibrate_now(ctx.runner, building_id, change)
    return change_answer(ctx, building_id, change.record.id)


def change_answer(ctx: ContextDep, building_id: int, change_id: int) -> ModelChangeAnswer:
    with ctx.db.session() as session:
        building = adoption.repository.get_building(session, building_id)
        record = session.get(adoption.ModelChangeRecord, change_id)
        in_use = adoption.in_use(session, building)
        zone = in_zone(building.timezone)
        body = ModelChangeRead.model_validate(record, context=zone).model_dump()
        return ModelChangeAnswer.model_validate({**body, "model_in_use": in_use}, context=zone)
