"""Buildings: the CONTRACT.md §2 description in, the id and token out."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field, Strict

from .adoption import ModelInUse
from .common import LocalTime, with_examples

EXAMPLE = {
    "name": "office-torino",
    "location": {
        "latitude": 45.22,
        "longitude": 7.65,
        "altitude": 287.0,
        "timezone": "Europe/Rome",
    },
    "floor_area": 1050.0,
    "volume": 3150.0,
    "wall_area": 455.0,
    "internal_mass_area": 560.0,
    "windows": [
        {"azimuth": 90.0, "tilt": 90.0, "area": 45.6},
        {"azimuth": 270.0, "tilt": 90.0, "area": 45.6},
    ],
    "walls": [{"azimuth": 0.0, "tilt": 90.0, "area": 63.0}],
}
READ_EXAMPLE = {
    "id": 1,
    "name": "office-torino",
    "timezone": "Europe/Rome",
    "description": EXAMPLE,
    "created_at": "2017-01-09T06:15:00+01:00",
    "step_s": 900.0,
    "rows": 2112,
    "first_time": "2017-01-09T00:00:00+01:00",
    "last_time": "2017-01-30T23:45:00+01:00",
    "last_measured_time": "2017-01-29T23:45:00+01:00",
    "data_revision": 3,
    "current_parameter_set_id": 2,
}


# A number of the description: a JSON number only. Lax parsing read `true` as 1 m² and "300" as
# 300 m³; the engine, which also reads building files, refuses both.
Number = Annotated[float, Strict()]


class SurfaceIn(BaseModel):
    azimuth: Number = Field(description="Degrees clockwise from north (90 = east). [°]")
    tilt: Number = Field(description="Degrees from horizontal (90 = vertical). [°]")
    area: Number = Field(description="[m²]")


class LocationIn(BaseModel):
    latitude: Number = Field(description="[°]")
    longitude: Number = Field(description="[°]")
    altitude: Number | None = Field(None, description="[m]")
    timezone: str | None = Field(None, description="IANA name, e.g. Europe/Rome (default UTC)")


class BuildingCreate(BaseModel):
    """CONTRACT.md §2. Ranges are checked by ``rcengine.building.Building.from_dict``."""

    model_config = with_examples(EXAMPLE)

    # No control characters: PostgreSQL's text refuses NUL, and a name is shown in pages and logs.
    name: str = Field("building", max_length=200, pattern=r"^[^\x00-\x1f\x7f]*$")
    location: LocationIn
    floor_area: Number = Field(description="[m²]")
    volume: Number = Field(description="[m³]")
    wall_area: Number = Field(description="[m²]")
    internal_mass_area: Number | None = Field(None, description="[m²]")
    windows: list[SurfaceIn] = Field(default_factory=list)
    walls: list[SurfaceIn] = Field(default_factory=list)


class BuildingCreated(BaseModel):
    """The building's token is shown here once; the service keeps only its hash."""

    model_config = with_examples(
        {
            "id": 1,
            "name": "office-torino",
            "token": "0b3Xq1u8Yf3n8m0c2r3vJ8b9J1ZKq7w3fX4o5p6q7r8",
            "created_at": "2017-01-09T06:15:00+01:00",
            "warnings": [],
        }
    )

    id: int
    name: str
    token: str = Field(description="Bearer token for this building's calls; shown only once")
    created_at: LocalTime
    warnings: list[str] = Field(
        default_factory=list,
        description="Defaults the description leaves that change results (a missing time zone "
        "reads the building's local hours in UTC)",
    )


class TokenRotated(BaseModel):
    model_config = with_examples({"id": 1, "token": "mS0n2r9vJ8b9J1ZKq7w3fX4o5p6q7r80b3Xq1u8Yf3n"})

    id: int
    token: str


class BuildingRead(BaseModel):
    """A building with a summary of its stored data and current parameter set."""

    model_config = with_examples(READ_EXAMPLE, from_attributes=True)

    id: int
    name: str
    timezone: str
    description: dict
    created_at: LocalTime
    step_s: float | None = Field(description="Time step of the stored series. [s]")
    rows: int
    first_time: LocalTime | None
    last_time: LocalTime | None
    last_measured_time: LocalTime | None = Field(description="Latest row with a measured t_in")
    data_revision: int = Field(description="Incremented by every upload")
    current_parameter_set_id: int | None
    model: ModelInUse | None = Field(
        None,
        description="The model calibrations fit and where it came from (adopted from a "
        "diagnosis, or the base model); in GET /buildings/{id}, not in the list",
    )


class BuildingList(BaseModel):
    model_config = with_examples({"items": [READ_EXAMPLE]})

    items: list[BuildingRead]
