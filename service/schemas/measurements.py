"""Measurements: rows of CONTRACT.md §1 as JSON or CSV, upload counts back."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, create_model

from rcengine.columns import COLUMNS, TIME

from .common import LocalTime, with_examples

EXAMPLE_ROWS = [
    {
        "time": "2017-01-09T06:15:00+01:00",
        "t_in": 19.8,
        "t_out": 2.1,
        "ghi": 0.0,
        "q_hvac": 35000.0,
        "q_occ": 0.0,
        "q_light": 136.5,
    },
    {
        "time": "2017-01-09T06:30:00+01:00",
        "t_in": None,
        "t_out": 2.3,
        "ghi": 5.0,
        "q_hvac": 35000.0,
        "q_occ": 0.0,
        "q_light": 136.5,
    },
]
EXAMPLE_CSV = (
    "time,t_in,t_out,ghi,q_hvac\n"
    "2017-01-09T06:15:00+01:00,19.8,2.1,0,35000\n"
    "2017-01-09T06:30:00+01:00,,2.3,5,35000\n"
)

# One row of §1, fields and their units taken from rcengine.columns (documentation only: the
# body is validated by the engine's validator, not by this model).
MeasurementRow = create_model(
    "MeasurementRow",
    **{TIME: (str, Field(description="ISO 8601 with UTC offset: start of the interval"))},
    **{
        c.name: (
            float | None,
            Field(
                None, description=f"{c.meaning} [{c.unit}]" + ("" if c.required else " (optional)")
            ),
        )
        for c in COLUMNS.values()
    },
)


def upload_openapi() -> dict[str, Any]:
    """The request body of ``POST /buildings/{id}/measurements`` for the OpenAPI document."""
    return {
        "requestBody": {
            "required": True,
            "content": {
                "application/json": {
                    "schema": {
                        "type": "object",
                        "required": ["rows"],
                        "properties": {
                            "rows": {"type": "array", "items": MeasurementRow.model_json_schema()}
                        },
                    },
                    "example": {"rows": EXAMPLE_ROWS},
                },
                "text/csv": {"schema": {"type": "string"}, "example": EXAMPLE_CSV},
            },
        }
    }


class UploadResult(BaseModel):
    """Counts of an accepted upload (a rejected one stores nothing and answers 422)."""

    model_config = with_examples(
        {
            "inserted": 96,
            "updated": 4,
            "rejected": 0,
            "rows": 100,
            "first_time": "2017-01-09T00:00:00+01:00",
            "last_time": "2017-01-10T00:45:00+01:00",
            "data_revision": 5,
        },
        from_attributes=True,
    )

    inserted: int
    updated: int = Field(description="Rows whose time was already stored")
    rejected: int = Field(0, description="Always 0: an upload is accepted or rejected whole")
    rows: int
    first_time: LocalTime
    last_time: LocalTime
    data_revision: int


class MeasurementsRead(BaseModel):
    model_config = with_examples({"rows": EXAMPLE_ROWS})

    rows: list[dict[str, Any]]


class RemovalResult(BaseModel):
    """What a deletion of stored rows did."""

    model_config = with_examples(
        {"deleted": 96, "last_measured_time": "2017-01-09T23:45:00+01:00", "data_revision": 6},
        from_attributes=True,
    )

    deleted: int = Field(description="Rows removed")
    last_measured_time: LocalTime | None = Field(
        description="The latest measured t_in still stored (null: none)"
    )
    data_revision: int
