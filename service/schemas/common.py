"""Bodies shared by every resource: errors, model names."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, BaseModel, Field

from rcengine.models import MODELS


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

    model_config = {
        "json_schema_extra": {
            "examples": [
                {
                    "detail": "invalid data: row 3, column 't_in': 500 °C is outside the "
                    "physically possible range [-30, 60] °C",
                    "problems": [
                        {
                            "row": 3,
                            "column": "t_in",
                            "message": "500 °C is outside the physically possible range "
                            "[-30, 60] °C",
                        }
                    ],
                }
            ]
        }
    }


def error_responses(*codes: int) -> dict[int | str, dict]:
    """OpenAPI entries for the error statuses a route can answer."""
    text = {
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
        for code in codes
    }
