"""Parameter sets: history with fit metrics, the current one marked."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from .common import LocalTime, with_examples

SET_EXAMPLE = {
    "id": 4,
    "model": "basic",
    "status": "current",
    "is_current": True,
    "reason": None,
    "job_id": 12,
    "created_at": "2017-01-31T02:00:03+01:00",
    "train_start": "2017-01-23T00:00:00+01:00",
    "train_end": "2017-01-30T00:00:00+01:00",
    "rmse_train": 0.37,
    "rmse_holdout": 0.41,
    "metrics": {"train": {"rmse": 0.37}, "holdout": {"rmse": 0.41}},
    "engine_version": "0.1.0",
    "parameters": {
        "c_air": {
            "value": 5.1e6,
            "unit": "J/K",
            "lower": 1.17e5,
            "upper": 1.17e7,
            "description": "heat capacity of the indoor air and fast furniture",
        }
    },
}


class ParameterValue(BaseModel):
    value: float
    unit: str
    lower: float
    upper: float
    description: str = ""


class ParameterSetRead(BaseModel):
    """status: current | superseded (was current) | rejected (worse on its held-out day)."""

    model_config = with_examples(SET_EXAMPLE, from_attributes=True)

    id: int
    model: str
    status: str
    is_current: bool
    reason: str | None = Field(description="Why a rejected set was not promoted")
    job_id: int | None
    created_at: LocalTime
    train_start: LocalTime
    train_end: LocalTime
    rmse_train: float | None = Field(description="[K]")
    rmse_holdout: float | None = Field(description="Day-ahead forecast of the held-out day [K]")
    metrics: dict[str, Any] = Field(description="RMSE, MBE, CV(RMSE), NMBE, ASHRAE 14 verdict")
    engine_version: str
    parameters: dict[str, ParameterValue]


class ParameterSetList(BaseModel):
    model_config = with_examples({"current_id": 4, "items": [SET_EXAMPLE]})

    current_id: int | None
    items: list[ParameterSetRead]
