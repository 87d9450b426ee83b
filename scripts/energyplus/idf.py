"""IDF text: objects, the surfaces of ``geometry`` and the blocks every model of ours shares."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import astuple, dataclass
from datetime import date, timedelta

from .geometry import Point3, VerticalRect
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


def building_ground_temperatures(site: SiteInfo) -> str:
    """The ground under the building at the EPW header's 4 m soil temperatures: under a
    building the ground is steadier (and in winter warmer) than the surface soil."""
    return idf_object("Site:GroundTemperature:BuildingSurface", *site.ground_temperatures[4.0])


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
        # Its fields are those of the object, in their order.
        return idf_object("WindowMaterial:SimpleGlazingSystem", *astuple(m))
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
