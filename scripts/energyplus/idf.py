"""IDF text: objects, rectangular geometry and the blocks every model of ours shares.

Geometry is in world coordinates (x east, y north, z up, metres) with EnergyPlus's
``UpperLeftCorner, Counterclockwise`` vertex rule: a surface lists its corners anticlockwise as
seen from outside, starting at the upper-left one. A vertical rectangle is given by its two
bottom corners in the order left → right as seen from outside, which also fixes its outward
normal (the left→right direction turned 90° clockwise in plan).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import date, timedelta

from .library import (
    AirGap,
    Construction,
    Gas,
    Glazing,
    Layer,
    Material,
    SimpleGlazing,
    WeekSchedule,
)

Point2 = tuple[float, float]
Point3 = tuple[float, float, float]


def fmt(value: object) -> str:
    """One IDF field: floats without float noise, ``None`` as an empty (default) field."""
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def idf_object(class_name: str, *fields: object) -> str:
    """One IDF object, one field per line."""
    texts = [fmt(f) for f in fields]
    bad = [t for t in texts if "," in t or ";" in t or "!" in t]
    if bad:
        raise ValueError(f"{class_name}: IDF fields cannot hold ',', ';' or '!': {bad}")
    body = ",\n".join(f"    {t}" for t in texts)
    return f"{class_name},\n{body};\n"


# --- geometry -------------------------------------------------------------------------------


@dataclass(frozen=True)
class VerticalRect:
    """A vertical rectangle between two bottom corners (left → right seen from outside).

    left, right : plan coordinates of the bottom corners. [m]
    z_bottom, z_top : heights of the bottom and top edges. [m]
    """

    left: Point2
    right: Point2
    z_bottom: float
    z_top: float

    @property
    def width(self) -> float:
        return math.dist(self.left, self.right)

    @property
    def area(self) -> float:
        return self.width * (self.z_top - self.z_bottom)

    @property
    def azimuth(self) -> float:
        """Azimuth of the outward normal, clockwise from north (pvlib's convention). [°]"""
        dx, dy = self.right[0] - self.left[0], self.right[1] - self.left[1]
        normal_x, normal_y = dy, -dx  # left→right direction turned 90° clockwise
        return math.degrees(math.atan2(normal_x, normal_y)) % 360.0

    def vertices(self) -> list[Point3]:
        (x0, y0), (x1, y1) = self.left, self.right
        return [
            (x0, y0, self.z_top),
            (x0, y0, self.z_bottom),
            (x1, y1, self.z_bottom),
            (x1, y1, self.z_top),
        ]

    def window(self, width: float, sill: float, head: float) -> VerticalRect:
        """A centred opening of ``width`` between heights ``sill`` and ``head``. [m]"""
        margin = (self.width - width) / 2.0
        if margin <= 0.0 or not self.z_bottom < sill < head < self.z_top:
            raise ValueError(f"window {width} x ({sill}..{head}) m does not fit in the wall")
        ux = (self.right[0] - self.left[0]) / self.width
        uy = (self.right[1] - self.left[1]) / self.width
        left = (self.left[0] + margin * ux, self.left[1] + margin * uy)
        right = (self.right[0] - margin * ux, self.right[1] - margin * uy)
        return VerticalRect(left, right, sill, head)


@dataclass(frozen=True)
class Box:
    """A rectangular zone: plan x0..x1 (west → east), y0..y1 (south → north), height, floor
    level z0. [m]"""

    x0: float
    x1: float
    y0: float
    y1: float
    height: float
    z0: float = 0.0

    @property
    def floor_area(self) -> float:
        return (self.x1 - self.x0) * (self.y1 - self.y0)

    @property
    def volume(self) -> float:
        return self.floor_area * self.height

    def wall(self, side: str) -> VerticalRect:
        """The wall facing ``side`` (north, east, south or west)."""
        corners = {
            "south": ((self.x0, self.y0), (self.x1, self.y0)),
            "east": ((self.x1, self.y0), (self.x1, self.y1)),
            "north": ((self.x1, self.y1), (self.x0, self.y1)),
            "west": ((self.x0, self.y1), (self.x0, self.y0)),
        }
        left, right = corners[side]
        return VerticalRect(left, right, self.z0, self.z0 + self.height)

    def roof(self) -> list[Point3]:
        h = self.z0 + self.height
        return [
            (self.x0, self.y1, h),
            (self.x0, self.y0, h),
            (self.x1, self.y0, h),
            (self.x1, self.y1, h),
        ]

    def floor(self) -> list[Point3]:
        z = self.z0
        return [
            (self.x1, self.y1, z),
            (self.x1, self.y0, z),
            (self.x0, self.y0, z),
            (self.x0, self.y1, z),
        ]


SIDES = ("north", "east", "south", "west")


def building_surface(
    name: str,
    surface_type: str,
    construction: str,
    zone: str,
    vertices: Sequence[Point3],
    boundary: str = "Outdoors",
    boundary_object: str | None = None,
    sun: bool = True,
    wind: bool = True,
) -> str:
    """BuildingSurface:Detailed; ``boundary`` is EnergyPlus's Outside Boundary Condition."""
    exposed = boundary == "Outdoors"
    coords = [c for v in vertices for c in v]
    return idf_object(
        "BuildingSurface:Detailed",
        name,
        surface_type,
        construction,
        zone,
        None,
        boundary,
        boundary_object,
        "SunExposed" if exposed and sun else "NoSun",
        "WindExposed" if exposed and wind else "NoWind",
        "autocalculate",
        len(vertices),
        *coords,
    )


def window_surface(name: str, construction: str, wall_name: str, rect: VerticalRect) -> str:
    coords = [c for v in rect.vertices() for c in v]
    return idf_object(
        "FenestrationSurface:Detailed",
        name,
        "Window",
        construction,
        wall_name,
        None,
        "autocalculate",
        None,
        1,
        4,
        *coords,
    )


# --- shared blocks --------------------------------------------------------------------------


@dataclass(frozen=True)
class SiteInfo:
    """What the IDF needs from the EPW header.

    latitude, longitude [°], tz_offset_h: standard time offset from UTC [h], elevation [m],
    ground_temperatures: depth [m] → 12 monthly undisturbed soil temperatures [°C].
    """

    name: str
    latitude: float
    longitude: float
    tz_offset_h: float
    elevation: float
    ground_temperatures: dict[float, tuple[float, ...]]


@dataclass(frozen=True)
class RunPeriod:
    """Inclusive local calendar dates of the data wanted (the year fixes the weekdays)."""

    first_day: date
    last_day: date

    @property
    def simulated(self) -> tuple[date, date]:
        """Dates EnergyPlus is asked to simulate: one day more on each side.

        The day before gives the air temperature at the first midnight (EnergyPlus reports
        none for its first instant) and the day after gives the last interval's inputs.
        It also sidesteps an EnergyPlus 25.2 fault: a run that starts in a leap year and ends
        in the next one stops a day early (1 Oct 2016 – 31 Mar 2017 ends on 30 Mar).
        """
        return self.first_day - timedelta(days=1), self.last_day + timedelta(days=1)


def header(name: str, site: SiteInfo, period: RunPeriod, timesteps_per_hour: int) -> str:
    """Version, run control, site, run period, geometry rules and schedule limits."""
    first, last = period.simulated
    return "".join(
        [
            idf_object("Version", "25.2"),
            idf_object("SimulationControl", "No", "No", "No", "No", "Yes", "No"),
            # Convex box zones, so beam solar may be tracked onto the interior surfaces.
            idf_object(
                "Building", name, 0.0, "Suburbs", 0.04, 0.4, "FullInteriorAndExterior", 25, 6
            ),
            idf_object("Timestep", timesteps_per_hour),
            # Solar geometry every day: with the default 20-day update, which day's sun a week
            # uses depends on the run's length, and a short run would not reproduce the season.
            idf_object("ShadowCalculation", "PolygonClipping", "Periodic", 1),
            idf_object(
                "Site:Location",
                site.name,
                site.latitude,
                site.longitude,
                site.tz_offset_h,
                site.elevation,
            ),
            # No day-of-week field: EnergyPlus takes it from the begin year. No weather-file
            # holidays or daylight saving: the office runs on standard time, every weekday.
            idf_object(
                "RunPeriod",
                name,
                first.month,
                first.day,
                first.year,
                last.month,
                last.day,
                last.year,
                None,
                "No",
                "No",
                "No",
                "Yes",
                "Yes",
                "No",
                "Hour24",
            ),
            idf_object("GlobalGeometryRules", "UpperLeftCorner", "Counterclockwise", "Relative"),
            idf_object("ScheduleTypeLimits", "Fraction", 0.0, 1.0, "Continuous"),
            idf_object("ScheduleTypeLimits", "OnOff", 0, 1, "Discrete"),
            idf_object("ScheduleTypeLimits", "Any"),
            constant_schedule("AlwaysOn", 1, "OnOff"),
            constant_schedule("AlwaysOff", 0, "OnOff"),
        ]
    )


def constant_schedule(name: str, value: float, limits: str = "Any") -> str:
    return idf_object("Schedule:Constant", name, limits, value)


def sky_at_air_temperature() -> str:
    """The sky radiates at the outdoor air temperature: no long-wave loss to a cold sky."""
    return constant_schedule("Zero", 0.0) + idf_object(
        "WeatherProperty:SkyTemperature", None, "DifferenceScheduleDryBulbValue", "Zero", "No"
    )


def week_schedule(name: str, week: WeekSchedule, limits: str = "Fraction") -> str:
    """Schedule:Compact of a weekday / Saturday / Sunday profile (no holidays in our runs)."""
    fields: list[object] = [name, limits, "Through: 12/31"]
    days = (
        ("Weekdays SummerDesignDay WinterDesignDay", week.weekday),
        ("Saturday", week.saturday),
        ("Sunday Holidays AllOtherDays", week.sunday),
    )
    for label, day in days:
        fields.append(f"For: {label}")
        for until, value in day:
            fields.extend([f"Until: {until}", value])
    return idf_object("Schedule:Compact", *fields)


def layer_object(m: Layer) -> str:
    if isinstance(m, Material):
        return idf_object(
            "Material",
            m.name,
            m.roughness,
            m.thickness,
            m.conductivity,
            m.density,
            m.specific_heat,
            m.thermal_absorptance,
            m.solar_absorptance,
            m.visible_absorptance,
        )
    if isinstance(m, AirGap):
        return idf_object("Material:AirGap", m.name, m.resistance)
    if isinstance(m, Glazing):
        return idf_object(
            "WindowMaterial:Glazing",
            m.name,
            "SpectralAverage",
            None,
            m.thickness,
            m.solar_transmittance,
            m.solar_reflectance,
            m.solar_reflectance,
            m.visible_transmittance,
            m.visible_reflectance,
            m.visible_reflectance,
            0.0,
            m.emissivity,
            m.emissivity,
            m.conductivity,
        )
    if isinstance(m, Gas):
        return idf_object("WindowMaterial:Gas", m.name, m.gas, m.thickness)
    if isinstance(m, SimpleGlazing):
        return idf_object(
            "WindowMaterial:SimpleGlazingSystem",
            m.name,
            m.u_factor,
            m.shgc,
            m.visible_transmittance,
        )
    raise TypeError(f"not a layer: {m!r}")


def materials_and_constructions(constructions: Iterable[Construction]) -> str:
    """Every material layer once, then the constructions (outside → inside layer order)."""
    constructions = list(constructions)
    layers = {m.name: m for c in constructions for m in c.layers}
    return "".join(layer_object(m) for m in layers.values()) + "".join(
        idf_object("Construction", c.name, *(m.name for m in c.layers)) for c in constructions
    )


def output_variables(names: Iterable[str]) -> str:
    """Timestep outputs, written straight to eplusout.csv (no ESO post-processing needed)."""
    out = [idf_object("Output:Variable", "*", n, "Timestep") for n in names]
    # Output CSV: yes; every other file (MTR, ESO, EIO, tabular, SQLite, ...): no.
    out.append(idf_object("OutputControl:Files", "Yes", *["No"] * 25))
    return "".join(out)
