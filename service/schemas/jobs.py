"""Jobs: calibrations and diagnoses share one resource, ``/jobs/{job_id}``."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from .common import LocalTime, with_examples

JOB_EXAMPLE = {
    "id": 12,
    "building_id": 1,
    "kind": "calibration",
    "status": "succeeded",
    "outcome": "promoted",
    "trigger": "api",
    "model": "basic",
    "days": 7,
    "created_at": "2017-01-31T02:00:00+01:00",
    "started_at": "2017-01-31T02:00:01+01:00",
    "finished_at": "2017-01-31T02:00:03+01:00",
    "error": None,
    "parameter_set_id": 4,
    "diagnosis_id": None,
    "options": None,
    "details": {
        "reason": "held-out day RMSE 0.412 K is no worse than the current set's 0.530 K",
        "window": {
            "train_start": "2017-01-22T23:00:00+00:00",
            "holdout_start": "2017-01-29T23:00:00+00:00",
            "end": "2017-01-30T23:00:00+00:00",
            "step_s": 900.0,
        },
    },
}


class JobRead(BaseModel):
    """status: queued | running | succeeded | failed. A succeeded calibration's outcome says
    whether its parameter set was promoted to current or rejected (worse on the held-out day);
    a succeeded diagnosis points to its report."""

    model_config = with_examples(JOB_EXAMPLE, from_attributes=True)

    id: int
    building_id: int
    kind: str = Field(description="calibration | diagnosis")
    status: str
    outcome: str | None = Field(description="promoted | rejected (succeeded calibrations)")
    trigger: str = Field(description="api | schedule | cli")
    model: str
    days: int = Field(description="Days fitted (calibration) or days diagnosed (diagnosis)")
    created_at: LocalTime
    started_at: LocalTime | None
    finished_at: LocalTime | None
    error: str | None = Field(description="Why a failed job failed")
    parameter_set_id: int | None = Field(description="The set a calibration stored")
    diagnosis_id: int | None = Field(description="The report a diagnosis stored")
    options: dict[str, Any] | None = Field(
        description="What a diagnosis was asked: window (UTC), train_fraction, effects; "
        "days_requested when fewer days are stored than a job asked for (its days are those used)"
    )
    details: dict[str, Any] | None


class JobList(BaseModel):
    model_config = with_examples({"items": [JOB_EXAMPLE]})

    items: list[JobRead]
