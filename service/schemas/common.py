"""Bodies shared by every resource: errors, model names, times in the building's zone."""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any

import pandas as pd
from fastapi import Path
from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, ValidationInfo

from rcengine.io.timeseries import format_times
from rcengine.models import MODELS

# Largest id: PostgreSQL's INTEGER, the narrower of the two databases' id columns. A larger id
# in a path is refused (422 naming it) before it reaches a query the driver cannot bind.
MAX_ID = 2**31 - 1

# Key of the validation context that names the building's time zone (IANA name).
TIMEZONE = "timezone"


def in_zone(timezone: str) -> dict[str, str]:
    """Validation context that writes a record's times in ``timezone``: a response schema is
    built as ``Schema.model_validate(record, context=in_zone(building.timezone))``."""
    return {TIMEZONE: timezone}


def _in_building_zone(value: Any, info: ValidationInfo) -> Any:
    # Text passes: a body already built (FastAPI may validate a response again).
    if not isinstance(value, datetime):
        return value
    if not info.context or TIMEZONE not in info.context:
        raise ValueError("a time needs the building's time zone as validation context (in_zone)")
    return format_times(pd.DatetimeIndex([pd.Timestamp(value)]), info.context[TIMEZONE])[0]


# A stored instant in an answer: ISO 8601 with the UTC offset of the building's time zone.
LocalTime = Annotated[str, BeforeValidator(_in_building_zone)]


def id_in_path(what: str, example: int) -> Any:
    """A path parameter that is a stored id: 1 … MAX_ID."""
    return Path(description=f"{what} id", examples=[example], ge=1, le=MAX_ID)


def with_examples(*examples: dict[str, Any], **config: Any) -> ConfigDict:
    """Model configuration with the examples of the OpenAPI page."""
    return ConfigDict(json_schema_extra={"examples": list(examples)}, **config)


def _known_model(name: str | None) -> str | None:
    if name is not None and name not in MODELS:
        raise ValueError(f"invalid model {name!r}; choose from {sorted(MODELS)}")
    return name


ModelName = Annotated[
    str | None,
    AfterValidator(_known_model),
    Field(description="Model of the rcengine library (default: RCSERVICE_MODEL, basic)"),
]


class ProblemRead(BaseModel):
    row: int | None = Field(description="0-based index of the data row (None: the whole input)")
    column: str | None
    message: str


class ErrorRead(BaseModel):
    detail: str = Field(examples=["building 7 not found"])


class DataErrorRead(BaseModel):
    """422 for data that break CONTRACT.md §1: every problem with its row and column."""

    detail: str
    problems: list[ProblemRead]

    model_config = with_examples(
        {
            "detail": "invalid data: row 3, column 't_in': 500 °C is outside the physically "
            "possible range [-30, 60] °C",
            "problems": [
                {
                    "row": 3,
                    "column": "t_in",
                    "message": "500 °C is outside the physically possible range [-30, 60] °C",
                }
            ],
        }
    )


def error_responses(*codes: int) -> dict[int | str, dict]:
    """OpenAPI entries for the error statuses a route can answer, and those any route can: 400
    (a body that cannot be parsed) and 422 (a parameter or body field breaking its rule; the
    framework's own list-shaped 422 is replaced by this one, see ``api.errors``)."""
    text = {
        400: "The body cannot be parsed",
        401: "Missing or invalid bearer token",
        403: "Not allowed with this token",
        404: "No such resource for this token (another building's resources are not found)",
        409: "Conflicts with the current state",
        413: "Body larger than RCSERVICE_MAX_BODY_BYTES",
        415: "Unsupported Content-Type",
        422: "Invalid input: every problem named with its row and column",
    }
    return {
        code: {"model": DataErrorRead if code == 422 else ErrorRead, "description": text[code]}
        for code in sorted({400, *codes, 422})
    }
