"""Building description (CONTRACT.md §2): location, areas and oriented surfaces."""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from rcengine.exceptions import BuildingError
from rcengine.io.jsonable import read_json


@dataclass(frozen=True)
class Surface:
    """A plane surface of the envelope.

    azimuth: degrees clockwise from north (90 = east, 180 = south). [°]
    tilt: degrees from horizontal (90 = vertical). [°]
    area: [m²]
    """

    azimuth: float
    tilt: float
    area: float


# Said wherever a description without a time zone is read: its local hours fall back to UTC.
NO_TIMEZONE = (
    "location.timezone is not given, so the building's local hours (its days, the split at "
    "local midnight, learnt schedules, the forecast's midnight) are read in UTC; give its IANA "
    'zone, e.g. "timezone": "Europe/Rome" (or "UTC" to keep UTC)'
)


@dataclass(frozen=True)
class Location:
    """latitude, longitude: [°]; altitude: [m]; timezone: IANA name, "UTC" where the description
    gives none (``timezone_given`` False)."""

    latitude: float
    longitude: float
    altitude: float = 0.0
    timezone: str = "UTC"
    timezone_given: bool = field(default=True, compare=False)


@dataclass(frozen=True)
class Building:
    """One thermal zone as the RC models see it.

    floor_area, wall_area, internal_mass_area: [m²]; volume: [m³].
    windows / walls: oriented glazing and opaque surfaces (optional).
    """

    name: str
    location: Location
    floor_area: float
    volume: float
    wall_area: float
    internal_mass_area: float
    windows: tuple[Surface, ...] = field(default_factory=tuple)
    walls: tuple[Surface, ...] = field(default_factory=tuple)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Building:
        """Validate and build from the contract JSON; errors name the field."""
        if not isinstance(data, dict):
            raise BuildingError("building description must be a JSON object")
        loc = data.get("location")
        if not isinstance(loc, dict):
            raise BuildingError(
                "field 'location' is required: {latitude, longitude, ...}", "location"
            )
        location = Location(
            latitude=_number(loc, "latitude", "location.latitude", -90.0, 90.0),
            longitude=_number(loc, "longitude", "location.longitude", -180.0, 180.0),
            altitude=_number(loc, "altitude", "location.altitude", -500.0, 9000.0, default=0.0),
            timezone=_timezone(loc.get("timezone", "UTC")),
            timezone_given="timezone" in loc,
        )
        return cls(
            name=str(data.get("name", "building")),
            location=location,
            floor_area=_number(data, "floor_area", "floor_area", 1e-3, 1e7),
            volume=_number(data, "volume", "volume", 1e-3, 1e8),
            wall_area=_number(data, "wall_area", "wall_area", 1e-3, 1e7),
            internal_mass_area=_number(
                data, "internal_mass_area", "internal_mass_area", 0.0, 1e8, default=0.0
            ),
            windows=_surfaces(data.get("windows", []), "windows"),
            walls=_surfaces(data.get("walls", []), "walls"),
        )

    @classmethod
    def from_json(cls, path: str | Path) -> Building:
        return cls.from_dict(read_json(path, BuildingError))

    @property
    def footprint_area(self) -> float:
        """The floor area on the ground: the horizontal projection Σ A·cos β of the opaque
        surfaces facing up (tilt β < 90°, the roof), at most ``floor_area``; ``floor_area``
        where ``walls`` lists no roof (one storey assumed). A multi-storey building stands on a
        slab of its footprint, not of its total floor area (ISO 13370 §8.1: A, the ground
        floor's area). [m²]"""
        roof = sum(s.area * math.cos(math.radians(s.tilt)) for s in self.walls if s.tilt < 90.0)
        return min(roof, self.floor_area) if roof > 0.0 else self.floor_area

    @property
    def notes(self) -> tuple[str, ...]:
        """What the description leaves to a default that changes results, to warn of."""
        return () if self.location.timezone_given else (NO_TIMEZONE,)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        del out["location"]["timezone_given"]
        out["windows"] = [asdict(s) for s in self.windows]
        out["walls"] = [asdict(s) for s in self.walls]
        return out


def _number(
    obj: dict, key: str, label: str, lower: float, upper: float, default: float | None = None
) -> float:
    if key not in obj or obj[key] is None:
        if default is None:
            raise BuildingError(f"field '{label}' is required", label)
        return default
    value = obj[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise BuildingError(f"field '{label}' must be a number, got {value!r}", label)
    if not lower <= value <= upper:
        raise BuildingError(f"field '{label}' = {value} is outside [{lower}, {upper}]", label)
    return float(value)


@functools.cache
def _zones() -> frozenset[str]:
    from zoneinfo import available_timezones

    return frozenset(available_timezones())


def _timezone(name: object) -> str:
    """An IANA zone name. Only the database's zones (``zoneinfo.available_timezones``): a path
    the loader would also open — a folder ("Europe"), "posixrules", "right/UTC" — is not a zone,
    and a folder or an over-long name raised an OS error instead of this one."""
    if not isinstance(name, str) or name == "localtime" or name not in _zones():
        raise BuildingError(
            f"field 'location.timezone': unknown time zone {str(name)[:80]!r}", "location.timezone"
        )
    return name


def _surfaces(items: object, label: str) -> tuple[Surface, ...]:
    if not isinstance(items, list):
        raise BuildingError(f"field '{label}' must be a list of {{azimuth, tilt, area}}", label)
    out = []
    for i, item in enumerate(items):
        if not isinstance(item, dict):
            raise BuildingError(f"field '{label}[{i}]' must be an object", f"{label}[{i}]")
        out.append(
            Surface(
                azimuth=_number(item, "azimuth", f"{label}[{i}].azimuth", -360.0, 360.0) % 360.0,
                tilt=_number(item, "tilt", f"{label}[{i}].tilt", 0.0, 180.0),
                area=_number(item, "area", f"{label}[{i}].area", 0.0, 1e7),
            )
        )
    return tuple(out)
