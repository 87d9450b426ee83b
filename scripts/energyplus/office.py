"""The reference office of the thesis (§2.4.1) as an EnergyPlus model.

Single storey, 35 m (E–W) × 30 m (N–S) × 3.5 m, three thermal zones in a row: the west room
(14 m, windows on the west facade), the hall (7 m) and the east room (14 m, windows on the east
facade); 1,050 m² of floor, 455 m² of external walls including 2 × 45.6 m² of double clear
glazing. Constructions of thesis Table 2.1; the roof sees no sun (thesis) but keeps wind and
sky; the floor is adiabatic (the thesis treats it as internal mass). Partitions dividing the
east room in two and the west room in three spaces: 560 m² of gypsum/air/gypsum internal mass,
one third in the east room, two thirds in the west room. Constant infiltration 0.3 ACH.
People 20 / 5 / 40 (east / hall / west) at 100 W/person, lights 3 / 1 / 3 W/m², on ASHRAE
90.1 office profiles with empty Sundays. Ideal-loads heating (no cooling) to 21 / 18 / 21 °C,
available 06:00–22:00 on weekdays and 06:00–18:00 on Saturdays; otherwise free-floating.

Heating is limited to 60 W/m² (63 kW), about twice the design load, so a Monday-morning
recovery ramps over an hour or two as in thesis Fig. 3.1 instead of jumping in one timestep.

Physics checks, printed by ``python scripts/make_energyplus_data.py --only office``
(1 Oct 2016 – 31 Mar 2017, Torino IWEC, EnergyPlus 25.2):

* Heating peak 63.0 kW = the capacity, reached in Monday-morning recoveries only (65 of 17,472
  steps); season heating 47.3 MWh, 45 kWh/m². Check: UA 1,225 W/K × 2,580 K·d (degree days
  at base 20 °C of the period) ≈ 76 MWh if held at 20 °C round the clock, less 21 MWh of
  free gains (people 6.5, lights 3.9, transmitted sun 11.0 MWh) = 55 MWh; intermittent
  heating (free-floating nights and weekends) explains the rest.
* The heated hours hold the setpoint: on weekdays 10:00–22:00 the area-weighted t_in never
  falls below 20.40 °C = (21 · 840 + 18 · 210) / 1050; Monday recoveries take 1.5 h (median).
* Free-floating nights are cold and fast: t_in falls 7.5 K on average (11.7 K at most) from
  22:00 to 06:00 on Monday–Thursday nights. Table 2.1 puts the wall and roof masses outside
  their insulation and covers the floor with wood, so little mass faces the air; the thesis's
  Fig. 3.1 shows the same (below 15 °C at 06:00).
* Rough UA: 1,225 W/K by hand (ISO 6946 films; walls 162, windows 248 with EnergyPlus's
  U = 2.72 W/(m²·K), roof 446, infiltration 369); a regression of daily means,
  q_hvac + q_occ + q_light = UA (t_in − t_out) − A_sol · ghi, gives 1,350 W/K and
  A_sol = 28 m² (the sky-facing roof also loses long-wave to the night sky, which the hand
  figure leaves out).
* Free-floating (``freefloat.csv``): t_in − t_out averages 2.2 K over the season; 1–13 Feb
  ranges 1.0–9.5 °C. The thesis's Fig. 3.9 shows 10–20 °C for those days, so its model lost
  less heat than this one built to Table 2.1 with 0.3 ACH (its infiltration and floor are not
  stated).
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date

from . import zones
from .geometry import SIDES, Box, VerticalRect
from .idf import (
    RunPeriod,
    SiteInfo,
    building_surface,
    constant_schedule,
    header,
    materials_and_constructions,
    output_variables,
    week_schedule,
    window_surface,
)
from .library import (
    EXTERIOR_WALL,
    FLOOR,
    NEVER,
    OFFICE_LIGHTING,
    OFFICE_OCCUPANCY,
    PARTITION,
    ROOF,
    WINDOW_DOUBLE_CLEAR,
    heating_availability,
)

HEIGHT = 3.5
DEPTH_NS = 30.0
WINDOW_WIDTH = 28.5
WINDOW_SILL = 0.9
WINDOW_HEAD = 2.5  # 28.5 m × 1.6 m = 45.6 m² per facade
INTERNAL_MASS_AREA = 560.0
INFILTRATION_ACH = 0.3
# Heating capacity per floor area: about twice the design load, so a Monday-morning recovery
# takes an hour or two rather than one timestep (thesis Fig. 3.1 shows a two-hour ramp). [W/m²]
HEATING_CAPACITY_W_M2 = 60.0

SEASON = RunPeriod(date(2016, 10, 1), date(2017, 3, 31))
# U-factor of the glazing unit as EnergyPlus computes it (eplusout.eio, WindowConstruction).
WINDOW_U = 2.72  # [W/(m²·K)]
# ISO 6946 surface resistances: outside, inside horizontal flow, inside upward flow. [m²·K/W]
R_SE, R_SI_WALL, R_SI_ROOF = 0.04, 0.13, 0.10
RHO_CP_AIR = 1.2 * 1005.0  # [J/(m³·K)]
OUTPUTS = (
    "Zone Mean Air Temperature",
    "Zone People Sensible Heating Rate",
    "Zone Lights Total Heating Rate",
    "Zone Ideal Loads Zone Sensible Heating Rate",
    "Zone Ideal Loads Zone Sensible Cooling Rate",
    "Site Outdoor Air Drybulb Temperature",
    "Site Direct Solar Radiation Rate per Area",
    "Site Diffuse Solar Radiation Rate per Area",
    "Site Solar Altitude Angle",
    "Site Wind Speed",
)


@dataclass(frozen=True)
class OfficeZone:
    """One thermal zone of the office. people [-], lights [W/m²], setpoint [°C],
    mass_fraction: share of the partition internal mass [-], window: facade with glazing."""

    name: str
    box: Box
    people: float
    lights: float
    setpoint: float
    mass_fraction: float
    window: str | None


ZONES = (
    OfficeZone("West Room", Box(0.0, 14.0, 0.0, DEPTH_NS, HEIGHT), 40, 3.0, 21.0, 2 / 3, "west"),
    OfficeZone("Hall", Box(14.0, 21.0, 0.0, DEPTH_NS, HEIGHT), 5, 1.0, 18.0, 0.0, None),
    OfficeZone("East Room", Box(21.0, 35.0, 0.0, DEPTH_NS, HEIGHT), 20, 3.0, 21.0, 1 / 3, "east"),
)


def zone_areas() -> dict[str, float]:
    """Floor area of each zone, the weights of the contract's mean air temperature. [m²]"""
    return {z.name: z.box.floor_area for z in ZONES}


def floor_area() -> float:
    return sum(zone_areas().values())


def volume() -> float:
    return sum(z.box.volume for z in ZONES)


def exterior_walls() -> list[VerticalRect]:
    """Gross exterior walls (windows included)."""
    return [z.box.wall(side) for z in ZONES for side in SIDES if _neighbour(z, side) is None]


def windows() -> list[VerticalRect]:
    return [w for w in map(_window, ZONES) if w is not None]


def _window(z: OfficeZone) -> VerticalRect | None:
    if z.window is None:
        return None
    return z.box.wall(z.window).window(WINDOW_WIDTH, WINDOW_SILL, WINDOW_HEAD)


def design_ua() -> dict[str, float]:
    """Steady-state conductance of each envelope element (ISO 6946 films). [W/K]"""
    glazed = sum(w.area for w in windows())
    opaque = sum(w.area for w in exterior_walls()) - glazed
    return {
        "walls": opaque / (1.0 / EXTERIOR_WALL.conductance + R_SE + R_SI_WALL),
        "windows": glazed * WINDOW_U,
        "roof": floor_area() / (1.0 / ROOF.conductance + R_SE + R_SI_ROOF),
        "infiltration": INFILTRATION_ACH * volume() / 3600.0 * RHO_CP_AIR,
    }


def office_idf(site: SiteInfo, period: RunPeriod = SEASON, heating: bool = True) -> str:
    """The whole IDF; ``heating=False`` gives the free-floating twin (thesis §3.3)."""
    availability = heating_availability((6, 22), (6, 18)) if heating else NEVER
    parts = [
        header("Office Torino", site, period, timesteps_per_hour=4),
        materials_and_constructions([EXTERIOR_WALL, FLOOR, ROOF, PARTITION, WINDOW_DOUBLE_CLEAR]),
        week_schedule("Occupancy", OFFICE_OCCUPANCY),
        week_schedule("Lighting", OFFICE_LIGHTING),
        week_schedule("Heating Availability", availability, "OnOff"),
        zones.activity_schedule(),
        zones.single_heating_control_schedule(),
    ]
    for z in ZONES:
        parts.append(_zone(z))
    parts.append(output_variables(OUTPUTS))
    return "".join(parts)


def _zone(z: OfficeZone) -> str:
    out = [zones.zone(z.name), *_envelope(z)]
    if z.mass_fraction > 0.0:
        out.append(
            zones.internal_mass(
                z.name, PARTITION.name, INTERNAL_MASS_AREA * z.mass_fraction, "Partitions"
            )
        )
    setpoint = f"{z.name} Setpoint"
    out += [
        zones.people(z.name, z.people, "Occupancy", "Activity"),
        zones.lights(z.name, z.lights, "Lighting"),
        zones.infiltration(z.name, INFILTRATION_ACH),
        constant_schedule(setpoint, z.setpoint),
        zones.ideal_loads_heating(
            z.name, setpoint, "Heating Availability", HEATING_CAPACITY_W_M2 * z.box.floor_area
        ),
    ]
    return "".join(out)


def _neighbour(z: OfficeZone, side: str) -> OfficeZone | None:
    """The zone on the other side of the ``side`` wall of ``z`` (east / west only)."""
    i = ZONES.index(z) + {"east": 1, "west": -1}.get(side, 0)
    if side not in ("east", "west") or not 0 <= i < len(ZONES):
        return None
    return ZONES[i]


def _envelope(z: OfficeZone) -> list[str]:
    box = z.box
    out = [
        building_surface(f"{z.name} Roof", "Roof", ROOF.name, z.name, box.roof(), sun=False),
        building_surface(
            f"{z.name} Floor", "Floor", FLOOR.name, z.name, box.floor(), boundary="Adiabatic"
        ),
    ]
    for side in SIDES:
        wall = box.wall(side)
        name = f"{z.name} {side.capitalize()} Wall"
        other = _neighbour(z, side)
        if other is not None:
            partner = f"{other.name} {_opposite(side).capitalize()} Wall"
            out.append(
                building_surface(
                    name,
                    "Wall",
                    PARTITION.name,
                    z.name,
                    wall.vertices(),
                    boundary="Surface",
                    boundary_object=partner,
                )
            )
            continue
        out.append(building_surface(name, "Wall", EXTERIOR_WALL.name, z.name, wall.vertices()))
        glass = _window(z)
        if z.window == side and glass is not None:
            out.append(window_surface(f"{z.name} Window", WINDOW_DOUBLE_CLEAR.name, name, glass))
    return out


def _opposite(side: str) -> str:
    return {"east": "west", "west": "east", "north": "south", "south": "north"}[side]
