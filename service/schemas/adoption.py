"""Adopted models: the model a building's calibrations fit, and the audit of adopt / revert."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from .common import LocalTime, with_examples

IN_USE_EXAMPLE = {
    "name": "basic+wind_infiltration",
    "source": "diagnosis",
    "base_model": "basic",
    "effects": ["wind_infiltration"],
    "diagnosis_id": 3,
    "required_columns": ["t_out", "ghi", "q_hvac", "q_occ", "q_light", "wind_speed"],
    "since": "2017-01-31T09:12:00+01:00",
    "by": "building",
}
CHANGE_EXAMPLE = {
    "id": 1,
    "building_id": 1,
    "action": "adopt",
    "diagnosis_id": 3,
    "model": "basic+wind_infiltration",
    "actor": "building",
    "changed": True,
    "calibration_job_id": 14,
    "detail": None,
    "created_at": "2017-01-31T09:12:00+01:00",
}


class ModelInUse(BaseModel):
    """The model every calibration of the building fits, and where it came from."""

    model_config = with_examples(IN_USE_EXAMPLE)

    name: str | None = Field(
        description="The adopted model; null: the base model (RCSERVICE_MODEL or the one a "
        "calibration request names)"
    )
    source: str = Field(description="base | diagnosis")
    base_model: str | None = None
    effects: list[str] = Field(description="Extensions adopted, in the order they were added")
    diagnosis_id: int | None = Field(description="The diagnosis the model was adopted from")
    required_columns: list[str] | None = Field(
        None, description="Columns the stored rows (future rows too) must hold for this model"
    )
    since: LocalTime | None = Field(description="When the model in use was adopted or reverted")
    by: str | None = Field(description="admin | building | auto: who adopted or reverted it")
    error: str | None = Field(
        None, description="Why the stored model cannot be read (written by another engine)"
    )


class ModelChangeRead(BaseModel):
    """One adopt or revert call (audited, also when it changed nothing)."""

    model_config = with_examples(CHANGE_EXAMPLE, from_attributes=True)

    id: int
    building_id: int
    action: str = Field(description="adopt | revert")
    diagnosis_id: int | None
    model: str | None = Field(description="The model in use after the call; null: base")
    actor: str = Field(description="admin | building | auto")
    changed: bool = Field(description="False: the call found the model already in that state")
    calibration_job_id: int | None = Field(
        description="The calibration the change started at once (poll GET /jobs/{id})"
    )
    detail: dict[str, Any] | None = Field(
        description="restored_parameter_set_id (revert); why no calibration could start"
    )
    created_at: LocalTime


class ModelChangeAnswer(ModelChangeRead):
    """The audited call and the model the building uses after it."""

    model_config = with_examples({**CHANGE_EXAMPLE, "model_in_use": IN_USE_EXAMPLE})

    model_in_use: ModelInUse


class ModelChangeList(BaseModel):
    model_config = with_examples({"items": [CHANGE_EXAMPLE]})

    items: list[ModelChangeRead]
